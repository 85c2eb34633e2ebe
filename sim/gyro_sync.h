#pragma once
// Two gyro streams on two clocks put on one (`shutterlab sync A B`): the offset between the
// clocks, and over a long overlap their rate difference, found from the motion alone, as
// Twist-n-Sync (Faizullin et al., 2021) aligns two gyros: by cross-correlation of the rates.
//
// 1. Coarse: the magnitudes of the mean rate over each step of a common grid (kCoarseStep or the
//    slower stream's interval; the mean, so that a vibration does not alias into it; the same
//    whatever the mounting), less their means, cross-correlated over every lag that leaves
//    kMinOverlap of both (Eigen's FFT), each lag normalised by the energy of its own overlap. The
//    best lag must stand out: its correlation at least kMinPeakCorrelation, and the best lag away
//    from it (kDistinctLag) below kMaxRunnerUpShare of it; otherwise the motion is too weak or too
//    repetitive to align, and it is refused.
// 2. Mounting: b's samples shifted by the coarse offset and paired with the slower stream's
//    (sim/sensor_pair.h): the rotation a_from_b by Kabsch (fitted again at each offset of step 3's
//    grid and halfway through its Gauss-Newton).
// 3. Fine, on both streams smoothed alike (a 20 ms triangle: the derivatives below hold for the
//    motion under about 30 Hz, and a multirotor's vibration at 100 to 300 Hz would turn them
//    around): first the offset within a coarse step where the rates agree best, on a grid of half
//    the faster stream's interval (a vibration makes the residual a comb of minima a period apart);
//    then Gauss-Newton on w_a(t) = a_from_b w_b(t + offset(t)) + c at the slower stream's own
//    samples (the faster one interpolated linearly), offset(t) = offset + rate (t - t_mid); the
//    rate only over an overlap of at least min_rate_overlap_s, the bias difference c eliminated.
//    The derivatives are taken over 5 ms, not one sample: the sensors' noise would swamp them.
//    Standard errors: the larger of the residual's variance with the normal matrix (independent
//    residuals) and the sandwich with Newey-West's estimate of the scores' covariance (residuals
//    correlated in time: over the smoothing, and against a clip's frames over the motion).
//    residual_rms_rad_s is the streams' as read, not smoothed.

#include "sim/gyro_source.h"
#include "sim/gyro_trace.h"

#include <Eigen/Core>

#include <memory>
#include <optional>
#include <string>

namespace shutterlab {

struct GyroSyncOptions {
  // Searched both ways (s); 0: every lag that leaves the minimum overlap.
  double max_offset_s = 0.0;
  // The clock rate is fitted when the overlap is at least this long (s).
  double min_rate_overlap_s = 60.0;
  // The traces' names in messages (their files), and the caller's option that bounds the offset
  // (named in the advice; empty: the caller has none).
  std::string a_name = "A", b_name = "B";
  std::string bound_option;
};

struct GyroSync {
  // The same instant in both clocks: t_b = t_a + offset_s + rate_ppm 1e-6 (t_a - reference_a_s).
  double offset_s = 0.0, offset_stderr_s = 0.0;
  std::optional<double> rate_ppm, rate_stderr_ppm;         // fitted over a long overlap only
  double reference_a_s = 0.0;                              // the overlap's middle, a's clock (s)
  Eigen::Matrix3d a_from_b = Eigen::Matrix3d::Identity();  // w_a = a_from_b w_b (+ bias)
  bool mounting_fitted = false;  // false: motion about one axis only, identity kept
  double mounting_angle_deg = 0.0;
  double peak_correlation = 0.0;       // of the magnitudes at the coarse lag
  double runner_up_correlation = 0.0;  // the best lag away from it
  double overlap_s = 0.0;
  double faster_interval_s = 0.0, slower_interval_s = 0.0;  // the streams' nominal intervals
  double residual_rms_rad_s = 0.0;  // per axis, after the fine fit, the streams as read
  size_t residuals = 0;             // samples of the slower stream used
};

// The trace's rates averaged over window_s centred on each sample (prefix sums; the window shrinks
// at the ends).
GyroTrace BoxAverage(const GyroTrace& trace, double window_s);

// The instant t_b_s of b's clock on a's clock: the inverse of GyroSync's relation.
double ClockAFromB(const GyroSync& sync, double t_b_s);

// b's samples on a's clock (each time through ClockAFromB): a trace in memory, or a source chunk
// by chunk.
GyroTrace OnClockA(const GyroTrace& b, const GyroSync& sync);
std::unique_ptr<GyroSource> OnClockA(std::unique_ptr<GyroSource> b, const GyroSync& sync);

// Throws std::invalid_argument in one line when the traces overlap too little at every lag,
// hold too few samples, or their motion is too weak or too repetitive to align (saying which,
// with the correlations).
GyroSync SyncGyros(const GyroTrace& a, const GyroTrace& b, const GyroSyncOptions& options = {});

}  // namespace shutterlab
