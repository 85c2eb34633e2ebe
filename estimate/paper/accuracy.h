#pragma once
// The source paper's accuracy test (its Table 3): the gyro sits on a total station that is turned
// by a known angle several times, still in between. Each turn's angle is measured from the mean
// per-axis angles just before and just after it and compared with the reference.
//
// The paper picked the turns by hand; here they are detected: the bias-corrected rate is smoothed
// (moving average of the vector over smooth_s), and a turn is where its magnitude rises above
// enter_factor times the still noise level, extended both ways while it stays above exit_factor
// times that level (hysteresis). The still noise level is the RMS of the same smoothed magnitude
// over the bias segment. Turns separated by less than min_still_s are one turn.

#include "sim/bias.h"
#include "sim/gyro_trace.h"

#include <Eigen/Core>

#include <cstddef>
#include <string>
#include <vector>

namespace shutterlab {

struct AccuracyOptions {
  double reference_deg = 1.0;  // the turn angle set on the total station, degrees
  int average_samples = 100;   // samples averaged just before and just after each turn
  BiasSegment bias;            // still segment for the bias, seconds after the first sample
  bool zero_bias = false;      // the rates are bias-free (calibrated): no segment, every sample
  double smooth_s = 0.010;     // moving-average length for detection, s
  double enter_factor = 8.0;   // a turn starts above enter_factor * still noise level
  double exit_factor = 3.0;    // ... and extends while above exit_factor * still noise level
  // Floor of the still noise level, rad/s: a noiseless trace still needs a non-zero threshold
  // (1e-7 rad/s = 0.02 deg/h, far below any MEMS gyro's noise).
  double min_noise_rad_s = 1e-7;
  double guard_s = 0.020;      // still time between a turn and its averaging windows, s: leaves out
                               // the turn's slow start and end that stay below the exit threshold
  double min_still_s = 0.200;  // motions closer than this belong to one turn, s
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

// One detected turn. Angles are the per-axis integrated angles (docs/FORMATS.md), arcsec, x y z.
struct DetectedRotation {
  double t_start_s = 0.0;  // motion start and end, seconds after the trace's first sample
  double t_end_s = 0.0;
  Eigen::Vector3d before_arcsec = Eigen::Vector3d::Zero();  // mean over the samples just before
  Eigen::Vector3d after_arcsec = Eigen::Vector3d::Zero();   // mean over the samples just after
  // theta of R = Rz(a) Ry(b) Rx(g) built from the differences (a = z, b = y, g = x): the paper's.
  double theta_arcsec = 0.0;
  double difference_arcsec = 0.0;  // theta_arcsec - reference
  // The norm of the per-axis differences: for a turn about an axis fixed in the sensor the per-axis
  // angles are exactly the rotation vector, so this is the exact turn angle.
  double theta_vector_arcsec = 0.0;
  // Angle between the mean SO(3) orientations (sim/integrate.h OrientationTrace) before and after.
  double theta_so3_arcsec = 0.0;
};

struct AccuracyResult {
  double reference_deg = 0.0;
  int average_samples = 0;
  double noise_level_rad_s = 0.0;  // still noise level of the smoothed rate magnitude
  double enter_rad_s = 0.0;        // detection thresholds
  double exit_rad_s = 0.0;
  std::vector<DetectedRotation> rotations;
  // Motions found but left out because the still time around them could not hold the averaging
  // windows (too close to the bias segment, the trace's end, or another motion); start times, s.
  std::vector<double> skipped_t_s;
  // Mean and sample standard deviation of difference_arcsec (std 0 for a single turn).
  double difference_mean_arcsec = 0.0;
  double difference_std_arcsec = 0.0;
};

// Detects the turns after the bias segment and measures each. Throws std::invalid_argument when
// the options are bad, the bias segment is too short, or no measurable turn is found (the message
// says why and gives the threshold). Its JSON is written at the edge
// (estimate/report/analysis_json.h AccuracyToJson).
AccuracyResult AnalyzeAccuracy(const GyroTrace& trace, const AccuracyOptions& options);

// Table for a person in the paper's Table 3 layout: one row per turn; before x y z, after x y z,
// theta and difference (arcsec); then the SO(3) comparison and the mean and std of the differences.
std::string AccuracyTable(const AccuracyResult& result);

}  // namespace shutterlab
