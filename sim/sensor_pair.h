#pragma once
// Two gyros on one clock (the source paper's idea of a second sensor on the Pi's second SPI bus):
// their samples paired, the mounting between them fitted from the motion, and one fused trace.
//
// Pairing: each sample of a takes b's sample nearest in time, when one lies within half of b's
// median interval. Nearest, not interpolated: interpolating b would average its neighbours'
// noise and overstate the fused gain.
// Mounting: w_a = a_from_b * w_b + (a constant: the bias difference), fitted by the Kabsch / Wahba
// solution on the paired rates about their means (the SVD of their cross-covariance, with the
// determinant forced to +1; Markley, "Attitude determination using vector observations and the
// singular value decomposition", 1988). It needs motion about two axes at least: it is fitted when
// the second-largest variance of a's rates exceeds kMountingSignalRatio times the per-axis
// variance left after the fit, and otherwise the prior is kept (a still recording shows nothing
// of the mounting).
// Fusion: per axis of a, fused = w a + (1 - w) (a_from_b b), w = var_b / (var_a + var_b) from each
// sensor's variance over a still segment (inverse-variance weights, the best linear fusion of two
// independent errors), or 1/2 without one. For two equal independent sensors the fused noise is
// 1 / sqrt(2) of either's.

#include "sim/bias.h"
#include "sim/gyro_source.h"
#include "sim/gyro_trace.h"

#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>

namespace shutterlab {

inline constexpr double kMountingSignalRatio = 25.0;

struct SensorPairOptions {
  // Where both sensors were still, seconds after a's first sample: the variances that weigh the
  // fusion. nullopt: equal weights.
  std::optional<BiasSegment> still;
  // The mounting kept when the motion cannot show it: w_a = a_from_b_prior * w_b.
  Eigen::Matrix3d a_from_b_prior = Eigen::Matrix3d::Identity();
  // Throws std::invalid_argument unless the prior is a rotation.
  void Check() const;
};

struct SensorPair {
  GyroTrace fused;  // a's axes, rad/s, at a's times (paired samples only)
  // b ran on a clock of its own, put on a's from the motion (--sync-second, sim/gyro_sync.h):
  // b's clock = a's + clock_offset_s, with its standard error; nullopt: one clock.
  std::optional<double> clock_offset_s;
  double clock_offset_stderr_s = 0.0;
  Eigen::Matrix3d a_from_b = Eigen::Matrix3d::Identity();  // as applied
  bool mounting_fitted = false;
  double mounting_angle_deg = 0.0;  // the rotation angle of a_from_b
  // Second-largest variance of a's rates over the per-axis residual variance of the fit.
  double mounting_signal_ratio = 0.0;
  Eigen::Vector3d weight_a = Eigen::Vector3d::Constant(0.5);
  bool weights_from_still = false;
  size_t paired = 0, unpaired = 0;  // a's samples with and without a partner
  // RMS per axis of a - a_from_b b about its mean, rad/s: both sensors' noise (and any motion the
  // mounting does not explain).
  double residual_rms_rad_s = 0.0;
};

// The rotation R minimising sum |da - R db|^2 over pairs of centred rates, from h = sum db da^T
// (Kabsch; the determinant forced to +1).
Eigen::Matrix3d KabschRotation(const Eigen::Matrix3d& h);

// Throws std::invalid_argument when fewer than 10 samples pair up.
SensorPair FuseSensorPair(const GyroTrace& a, const GyroTrace& b, const SensorPairOptions& options);

// A fresh source of a trace from its start, each call.
using OpenGyroSource = std::function<std::unique_ptr<GyroSource>()>;

// FuseSensorPair's estimate on two traces too long to hold, read as streams: every field but
// fused (left empty) equal to FuseSensorPair's to the bit (the same sums in the same order).
// b_median_interval_ns: b's median sample interval (GyroTrace::sampling, or a streamed trace's
// TraceSampling), which sets the pairing's reach. Reads both traces three times (the means; the
// cross-covariance; the fit's residual and the variances), in memory bounded by a chunk of each
// whatever their length. Throws std::invalid_argument as FuseSensorPair does.
SensorPair FitSensorPair(const OpenGyroSource& open_a, const OpenGyroSource& open_b,
                         int64_t b_median_interval_ns, const SensorPairOptions& options);

// A fitted pair's fused trace as a stream (FuseSensorPair's `fused`, chunk by chunk): a's samples
// with a partner in b, fused with pair's mounting and weights. a and b are fresh sources of the
// traces pair was fitted on.
std::unique_ptr<GyroSource> FusedPairSource(std::unique_ptr<GyroSource> a,
                                            std::unique_ptr<GyroSource> b, const SensorPair& pair,
                                            int64_t b_median_interval_ns);

// Two lines for a person: the pairing, the mounting and the weights.
std::string SensorPairText(const SensorPair& pair, const std::string& a_name,
                           const std::string& b_name);

}  // namespace shutterlab
