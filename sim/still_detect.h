#pragma once
// Automatic still-segment detection, for a bias segment without --bias A:B.
//
// Method (a variance detector in the spirit of Tedaldi et al., "A robust and easy to implement
// method for IMU calibration without external equipments", ICRA 2014, which thresholds a moving
// variance against that of a known static interval; here the static interval is found, not given):
//  1. Windows of N = window_s / median sample interval consecutive samples, one starting at every
//     sample: per-axis mean m_j and the sum over axes of the variances v_j (O(n) by prefix sums).
//  2. The quiet level: of the stretches of min_duration_s whose variance is within 1.5x the
//     least, the one with the smallest mean rate is the reference (a constant rotation is as quiet
//     as stillness; a still gyro reads only its bias, usually smaller than motion).
//     Its overall mean m_ref is the bias estimate; the spread of m_j and v_j over the windows
//     inside it measures how much a still window's statistics wander. Measuring that spread
//     empirically (rather than from sigma / sqrt(N)) keeps it right for low-pass-filtered,
//     correlated noise and for quantised counts.
//  3. Window j is still when every axis has |m_j - m_ref| <= k * spread(m) and
//     v_j <= mean(v) + k * spread(v), spreads floored at kMinSpreadRadS (noise-free input).
//  4. A run of still windows j = a..b covers samples a .. b+N-1; the segment is [t_a, t_{b+N}) (its
//     end the first sample that is not still, or one interval past the last sample).
//  5. The longest run, or with `first` the first run lasting >= min_duration_s.
// The reference must itself look still: its window means may wander at most kMaxWanderRatio times
// the in-window variance, else there is no still segment (std::invalid_argument).
// Assumes the trace holds a still stretch of min_duration_s that is its quietest (a slow constant
// rotation with the same noise is indistinguishable by the gyro alone and may win).

#include "sim/bias.h"
#include "sim/gyro_source.h"
#include "sim/gyro_trace.h"

#include <functional>
#include <memory>

namespace shutterlab {

struct StillDetectOptions {
  double window_s = 0.1;        // moving window for the mean and variance
  double k_sigma = 7.0;         // how many spreads a still window may deviate (5 split 3.5% of
                                // synthetic still segments on noise; 6 and up none of 200)
  double min_duration_s = 2.0;  // shortest acceptable still segment (and the reference stretch)
  bool first = false;           // first segment >= min_duration_s instead of the longest
  void Check() const;           // throws std::invalid_argument naming the first bad field
};

struct StillSegment {
  BiasSegment segment;      // seconds after the trace's first sample, [begin_s, end_s)
  size_t first_sample = 0;  // index range of the still samples [first_sample, end_sample)
  size_t end_sample = 0;
  size_t window_samples = 0;  // N
  Eigen::Vector3d quiet_mean_rad_s =
      Eigen::Vector3d::Zero();  // m_ref, the reference stretch's mean
};

// Finds the still segment. Throws std::invalid_argument when the window or min_duration_s is longer
// than the trace, or when no still run lasts min_duration_s (the message names the longest found).
StillSegment DetectStillSegment(const GyroTrace& trace, const StillDetectOptions& options = {});
// The same on a trace too long to hold: open() gives a fresh source of it each time, read five
// times (length, mean and rate; the least stretch variance; the reference; its windows' spread,
// up to its end; the still runs), in memory bounded by the stretch (min_duration_s of samples)
// whatever the trace's length. The result and the refusals are the same, to the bit, as for the
// trace held whole: the same sums are formed in the same order.
StillSegment DetectStillSegment(const std::function<std::unique_ptr<GyroSource>()>& open,
                                const StillDetectOptions& options = {});

// Largest accepted ratio of the variance of the window means over the reference stretch to the mean
// in-window variance (both summed over axes). White noise gives 1/N; noise low-passed to a
// correlation time near the window approaches 1; smooth motion gives far more. Use a longer
// window_s for strongly filtered gyros.
inline constexpr double kMaxWanderRatio = 0.5;

// Spread floor, rad/s: keeps thresholds above zero for noise-free synthetic traces.
inline constexpr double kMinSpreadRadS = 1e-12;

}  // namespace shutterlab
