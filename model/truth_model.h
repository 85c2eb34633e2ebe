#pragma once
// The TRUE sensor model a render uses, and the camera motion it implies for each frame.
//
// The declared model (camera.json, RigModel) is what a dataset says about itself; `render --inject`
// makes the truth differ from it by the effects of docs/FORMATS.md's table (model/effects.h).
// Everything the renderer and its ground truth need about time and motion is computed here, once
// per frame.
//
// Orientation choice (documented in docs/FORMATS.md terms): the world frame is re-anchored for
// every frame so that the frame's row 0 (the top row) looks exactly nadir:
//   world_from_cam(t) = R_int(t_0)^-1 * R_int(t),
// R_int the SO(3) integration of the true body rates from the first gyro sample, t_0 the true
// capture time of row 0. A frame far into a flight therefore never drifts off the scene, and the
// reference image of every frame is the same nadir view. The camera centre is likewise re-anchored:
// c(t) = velocity_mps * (t - t_0) (t on the gyro clock, as docs/FORMATS.md's t_v), zero at row 0.

#include "model/camera.h"
#include "sim/gyro_trace.h"
#include "sim/integrate.h"

#include <Eigen/Core>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

// The rig as it really is, plus the gyro errors that camera.json cannot declare.
struct TrueModel {
  RigModel rig;  // true intrinsics, distortion, readout, direction, R_CG, time offset, velocity
  // True gyro rate (gyro axes) = gyro_scale (per axis) * (logged rate - gyro_bias_rad_s).
  Eigen::Vector3d gyro_scale = Eigen::Vector3d::Ones();
  Eigen::Vector3d gyro_bias_rad_s = Eigen::Vector3d::Zero();
  // Gyro clock = camera clock * (1 + clock_rate_ppm * 1e-6) + rig.time_offset_s.
  double clock_rate_ppm = 0.0;

  // Throws std::invalid_argument naming the first nonsensical field.
  void Check() const;
  // The true rate in the camera frame for a logged gyro-axis rate: R_CG * scale * (w - bias).
  Eigen::Vector3d CamRate(const Eigen::Vector3d& logged_omega_rad_s) const;
  // True when `other`'s CamRate is this one's (the same mounting, gyro scale and bias), so that
  // both integrate a log to the same orientation trace.
  bool SameCamRates(const TrueModel& other) const;
  // Gyro-clock seconds after t_first_row_ns (on the gyro clock) at which image row `row` is
  // captured, for a frame whose first-read row is at camera time t_first_row_ns.
  double RowGyroOffsetS(int64_t t_first_row_ns, double row) const;
};

// Per-row camera pose of one frame (see the header comment for the frame anchoring).
struct FrameMotion {
  // world_from_cam and cam_center_m at a fractional image row (0 <= row <= height - 1): slerp and
  // lerp between the two neighbouring rows (rows ~30 us apart: the second-order difference from the
  // integrated trace is ~1e-8 rad). Video pairs match at fractional rows.
  Eigen::Matrix3d WorldFromCamAtRow(double row) const;
  Eigen::Vector3d CamCenterAtRow(double row) const;

  std::vector<Eigen::Matrix3d> world_from_cam;  // one per image row v, at the row's capture time
  std::vector<Eigen::Vector3d> cam_center_m;    // one per image row: c(t_v), world frame, m
  Eigen::Matrix3d world_from_ref = Eigen::Matrix3d::Identity();  // R(t_0), the reference view
  Eigen::Vector3d ref_center_m = Eigen::Vector3d::Zero();        // c(t_0)
  bool HasTranslation() const;  // any row centre differs from the reference centre
  // A global-shutter frame: every row at the reference pose (renders the reference image).
  FrameMotion Reference() const;
};

// Integrates the true body rates of a logged gyro trace once, for all frames of a flight.
class CameraMotion {
 public:
  CameraMotion(const GyroTrace& logged, const TrueModel& model);
  // The same from the orientation of the camera (model.CamRate of the logged rates, integrated
  // from the trace's first sample) already integrated: a stretch of a trace streamed past gives,
  // for frames inside it, the frames of the whole trace.
  CameraMotion(const TrueModel& model, OrientationTrace world_from_cam);
  // The motion under `model` of a camera whose rates are `same_rates`' (the same CamRate: mounting,
  // gyro scale and bias equal), sharing its integrated trace instead of integrating it again: a
  // draw of a model that differs in its readout, offset or lens. Throws std::invalid_argument
  // when the rates differ.
  CameraMotion(const TrueModel& model, const CameraMotion& same_rates);
  // The motion of a frame whose first-read row is captured at camera time t_first_row_ns, in the
  // world of its own row 0 (the header's anchoring). With anchor_first_row_ns, in the world of
  // that frame's row 0 instead: every frame of a video shares one world (the first frame's), so
  // consecutive frames see the same ground from continuing poses; world_from_ref / ref_center_m
  // are then this frame's row-0 pose in that world. velocity_mps: this frame's own velocity in
  // place of the model's (a photo's recorded flight speed), in the same world. Throws
  // std::out_of_range when the readout (or the anchor) lies outside the gyro trace.
  FrameMotion Frame(int64_t t_first_row_ns,
                    std::optional<int64_t> anchor_first_row_ns = std::nullopt,
                    const std::optional<Eigen::Vector3d>& velocity_mps = std::nullopt) const;
  // Frame(t_first_row_ns) with only the rows marked in `rows` (one flag per image row), and the
  // first and last rows, filled, each exactly as Frame fills it (and throwing as Frame does); the
  // others are left the identity and the origin. For a caller that reads those rows only (a
  // prediction evaluated at a grid of pixels, drawn many times).
  FrameMotion FrameAtRows(int64_t t_first_row_ns, const std::vector<bool>& rows) const;
  const TrueModel& model() const { return model_; }

 private:
  // Frame, of every row where `rows` is null.
  FrameMotion FrameOfRows(int64_t t_first_row_ns, std::optional<int64_t> anchor_first_row_ns,
                          const std::optional<Eigen::Vector3d>& velocity_mps,
                          const std::vector<bool>* rows) const;

  TrueModel model_;
  // R_int, camera frame, gyro clock; shared by the motions of models with the same rates.
  std::shared_ptr<const OrientationTrace> world_from_cam_;
};

}  // namespace shutterlab
