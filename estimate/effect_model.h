#pragma once
// The candidate effects of FORMATS.md's table as parameters of a TrueModel, and a fast predictor of
// the displacement d(p) = p_ref - p of many measured points under any TrueModel.
//
// The predictor computes exactly what the renderer's truth computes (CameraMotion::Frame +
// FrameGeometry::RefPixel): the same row times (TrueModel::RowGyroOffsetS), the same orientation
// integration (OrientationTrace over the true camera-frame rates), the same ray / ground-plane /
// reprojection arithmetic. Only the start of the integration differs: the renderer integrates from
// the first gyro sample of the log, the predictor from the last sample at or before the frame's
// first row time, which is the same relative rotation R(t_0)^T R(t_v) up to rounding (~1e-15).
// That keeps one evaluation proportional to the points and the readout span, not the log length.

#include "estimate/effect_fit.h"
#include "render/camera.h"
#include "render/truth_model.h"
#include "sim/gyro_trace.h"

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace shutterlab {

// Number of continuous parameters of a FORMATS.md effect when it is fitted:
//   time_offset 1 (s), readout_time 1 (s), gyro_to_camera 3 (rotation vector, rad, applied on the
//   camera side: R_CG = Exp(x) * R_CG_declared), gyro_scale 3, gyro_bias 3 (rad/s), velocity 3
//   (m/s), lens_distortion 2 (k1, k2), clock_rate 2 (ppm, and the time offset that goes with it,
//   s), readout_direction 0 (a discrete flip).
// Throws std::invalid_argument for a name that is not in the table.
int EffectParameterCount(const std::string& name);

// Applies an effect's parameters to *model. x holds EffectParameterCount(name) values, each a delta
// from the model's current value (readout_direction: flips the direction, x unused).
void ApplyEffect(const std::string& name, const double* x, TrueModel* model);

// Central-difference step of parameter i of the effect, in its own unit. frames_span_s: the largest
// |camera time| of the frames (a clock-rate step moves the latest frame by ~10 us).
double EffectStep(const std::string& name, int i, double frames_span_s);

// The effect's FORMATS.md value read from a model (time_offset: the true time_offset_s, ...).
nlohmann::json EffectValue(const std::string& name, const TrueModel& model);
// Standard errors in the same shape as EffectValue, from the covariance of its parameters
// (gyro_to_camera: per matrix entry, first order in the rotation vector). Null for
// readout_direction.
nlohmann::json EffectStderr(const std::string& name, const TrueModel& model,
                            const Eigen::MatrixXd& covariance);
// FORMATS.md unit of the value ("s", "rad/s", "m/s", "ppm", "" when dimensionless).
std::string EffectUnit(const std::string& name);

// Predicts the displacement of every measured point of a set of frames under any TrueModel.
// Rays (K^-1 p, undistorted) are cached while the intrinsics and distortion do not change, so an
// evaluation that only changes gyro-side or timing parameters re-integrates the frames' readout
// spans and re-projects, nothing else. Not thread-safe (the ray cache).
class DisplacementPredictor {
 public:
  DisplacementPredictor(const GyroTrace& gyro, const std::vector<FramePoints>& frames);

  // d(p) for every point, frame after frame in the order given, points in their order; NaN where
  // the ray misses the ground, the reference point is behind the camera, or a needed instant lies
  // outside the gyro trace.
  void Predict(const TrueModel& model, std::vector<Eigen::Vector2d>* out) const;

  size_t point_count() const { return points_; }
  // Largest |t_first_row| of the frames, s (camera clock).
  double frames_span_s() const { return frames_span_s_; }

 private:
  struct Frame {
    int64_t t_first_row_ns = 0;
    std::vector<double> rows;         // distinct v of the frame's points, ascending
    std::vector<int> row_of_point;    // index into rows, per point
    std::vector<Eigen::Vector2d> px;  // (u, v) per point
    size_t first = 0;                 // index of the frame's first point in the output
  };
  void RefreshRays(const PinholeCamera& camera) const;

  const GyroTrace& gyro_;
  std::vector<Frame> frames_;
  size_t points_ = 0;
  double frames_span_s_ = 0.0;
  mutable bool rays_valid_ = false;
  mutable PinholeCamera rays_camera_;
  mutable std::vector<Eigen::Vector3d> rays_;  // CamFromImg of every point, output order
};

}  // namespace shutterlab
