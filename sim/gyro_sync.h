#pragma once
// Two gyro streams on two clocks put on one (`shutterlab sync A B`): the offset between the
// clocks, and over a long overlap their rate difference, found from the motion alone, as
// Twist-n-Sync (Faizullin et al., 2021) aligns two gyros: by cross-correlation of the rates.
//
// 1. Coarse: the rates' magnitudes |w| (the same whatever the mounting) on a common grid
//    (kCoarseStep or the slower stream's interval), less their means, cross-correlated over
//    every lag that leaves kMinOverlap of both (Eigen's FFT), each lag normalised by the energy
//    of its own overlap. The best lag must stand out: its correlation at least
//    kMinPeakCorrelation, and the best lag away from it (kDistinctLag) below kMaxRunnerUpShare of
//    it; otherwise the motion is too weak or too repetitive to align, and it is refused.
// 2. Mounting: b's samples shifted by the coarse offset and paired with a's (sim/sensor_pair.h):
//    the rotation a_from_b by Kabsch (fitted again halfway through step 3, at the fine offset).
// 3. Fine: Gauss-Newton on w_a(t) = a_from_b w_b(t + offset(t)) + c at the slower stream's own
//    samples (the faster one interpolated linearly, so that the residuals stay as independent as
//    the sensors' noise), offset(t) = offset + rate (t - t_mid); the rate only over an overlap of
//    at least min_rate_overlap_s, the bias difference c eliminated. The derivatives are taken over
//    5 ms, not one sample: the sensors' noise would swamp them. Standard errors from the
//    residual's variance and the normal matrix (independent residuals assumed: the synthetic
//    tests check that they hold).

#include "sim/gyro_trace.h"

#include <Eigen/Core>

#include <optional>

namespace shutterlab {

struct GyroSyncOptions {
  // Searched both ways (s); 0: every lag that leaves the minimum overlap.
  double max_offset_s = 0.0;
  // The clock rate is fitted when the overlap is at least this long (s).
  double min_rate_overlap_s = 60.0;
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
  double residual_rms_rad_s = 0.0;                          // per axis, after the fine fit
  size_t residuals = 0;                                     // samples of the slower stream used
};

// Throws std::invalid_argument in one line when the traces overlap too little at every lag,
// hold too few samples, or their motion is too weak or too repetitive to align (saying which,
// with the correlations).
GyroSync SyncGyros(const GyroTrace& a, const GyroTrace& b, const GyroSyncOptions& options = {});

}  // namespace shutterlab
