#include "model/truth_model.h"

#include "sim/check.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <utility>

namespace shutterlab {

void TrueModel::Check() const {
  rig.Check();
  SHUTTERLAB_CHECK(gyro_scale.allFinite() && (gyro_scale.array() > 0).all())
      << "gyro_scale must be positive, got " << gyro_scale.transpose();
  SHUTTERLAB_CHECK(gyro_bias_rad_s.allFinite()) << "gyro_bias is not finite";
  SHUTTERLAB_CHECK(std::isfinite(clock_rate_ppm) && std::abs(clock_rate_ppm) < 1e5)
      << "clock_rate " << clock_rate_ppm << " ppm is not a plausible clock error";
}

Eigen::Vector3d TrueModel::CamRate(const Eigen::Vector3d& logged_omega_rad_s) const {
  return rig.cam_from_gyro * gyro_scale.cwiseProduct(logged_omega_rad_s - gyro_bias_rad_s);
}

bool TrueModel::SameCamRates(const TrueModel& other) const {
  return rig.cam_from_gyro == other.rig.cam_from_gyro && gyro_scale == other.gyro_scale &&
         gyro_bias_rad_s == other.gyro_bias_rad_s;
}

double TrueModel::RowGyroOffsetS(int64_t t_first_row_ns, double row) const {
  const double row_offset_s = rig.shutter.RowTimeOffsetS(row, rig.camera.height);
  // gyro = camera * (1 + k) + offset; the camera instant is t_first_row_ns + row_offset_s. Only the
  // small terms are in double: t_first_row_ns stays an exact integer (time is int64 ns; doubles
  // only for small offsets).
  const double k = clock_rate_ppm * 1e-6;
  return row_offset_s + k * (t_first_row_ns * 1e-9 + row_offset_s) + rig.time_offset_s;
}

bool FrameMotion::HasTranslation() const {
  for (const Eigen::Vector3d& c : cam_center_m) {
    if (c != ref_center_m) return true;
  }
  return false;
}

FrameMotion FrameMotion::Reference() const {
  FrameMotion global = *this;
  std::fill(global.world_from_cam.begin(), global.world_from_cam.end(), world_from_ref);
  std::fill(global.cam_center_m.begin(), global.cam_center_m.end(), ref_center_m);
  return global;
}

namespace {

GyroTrace CamRates(const GyroTrace& logged, const TrueModel& model) {
  std::vector<GyroSample> samples = logged.samples();
  for (GyroSample& s : samples) s.omega_rad_s = model.CamRate(s.omega_rad_s);
  return GyroTrace(std::move(samples));
}

}  // namespace

CameraMotion::CameraMotion(const GyroTrace& logged, const TrueModel& model)
    : model_(model),
      world_from_cam_(std::make_shared<const OrientationTrace>(CamRates(logged, model))) {
  model_.Check();
}

CameraMotion::CameraMotion(const TrueModel& model, OrientationTrace world_from_cam)
    : model_(model),
      world_from_cam_(std::make_shared<const OrientationTrace>(std::move(world_from_cam))) {
  model_.Check();
}

CameraMotion::CameraMotion(const TrueModel& model, const CameraMotion& same_rates)
    : model_(model), world_from_cam_(same_rates.world_from_cam_) {
  model_.Check();
  SHUTTERLAB_CHECK(model_.SameCamRates(same_rates.model_))
      << "a camera motion shares the integrated rates of a model with the same mounting, gyro "
         "scale and bias only";
}

FrameMotion CameraMotion::Frame(int64_t t_first_row_ns, std::optional<int64_t> anchor_first_row_ns,
                                const std::optional<Eigen::Vector3d>& velocity_mps) const {
  return FrameOfRows(t_first_row_ns, anchor_first_row_ns, velocity_mps, nullptr);
}

FrameMotion CameraMotion::FrameAtRows(int64_t t_first_row_ns, const std::vector<bool>& rows) const {
  SHUTTERLAB_CHECK(static_cast<int>(rows.size()) == model_.rig.camera.height)
      << "row flags for " << rows.size() << " rows, the camera has " << model_.rig.camera.height;
  return FrameOfRows(t_first_row_ns, std::nullopt, std::nullopt, &rows);
}

FrameMotion CameraMotion::FrameOfRows(int64_t t_first_row_ns,
                                      std::optional<int64_t> anchor_first_row_ns,
                                      const std::optional<Eigen::Vector3d>& velocity_mps,
                                      const std::vector<bool>* rows) const {
  const int height = model_.rig.camera.height;
  FrameMotion motion;
  motion.world_from_cam.assign(height, Eigen::Matrix3d::Identity());
  motion.cam_center_m.assign(height, Eigen::Vector3d::Zero());
  // The anchor: the true capture time of row 0 of the frame that defines the world.
  const int64_t anchor_ns = anchor_first_row_ns.value_or(t_first_row_ns);
  const double anchor_gyro_s = model_.RowGyroOffsetS(anchor_ns, 0);
  const Eigen::Quaterniond anchor_from_world =
      world_from_cam_->WorldFromBodyAt(anchor_ns, anchor_gyro_s).conjugate();
  // Gyro-clock seconds of an instant given as (t_first_row_ns, offset) relative to the anchor.
  const auto since_anchor_s = [&](double offset_s) {
    return (t_first_row_ns - anchor_ns) * 1e-9 + offset_s - anchor_gyro_s;
  };
  const double t0_gyro_s = model_.RowGyroOffsetS(t_first_row_ns, 0);
  motion.world_from_ref =
      (anchor_from_world * world_from_cam_->WorldFromBodyAt(t_first_row_ns, t0_gyro_s))
          .normalized()
          .toRotationMatrix();
  // c(t) = velocity * (t - t_anchor) with t the gyro-clock time, as docs/FORMATS.md's t_v (under
  // clock_rate the gyro clock runs (1 + ppm 1e-6) times the camera's). The anchor's centre is 0.
  const Eigen::Vector3d velocity = velocity_mps.value_or(model_.rig.velocity_mps);
  motion.ref_center_m = velocity * since_anchor_s(t0_gyro_s);
  for (int v = 0; v < height; ++v) {
    // The first and last rows always: their times bound the readout, which outside the trace
    // throws as Frame's does.
    if (rows && !(*rows)[v] && v != 0 && v != height - 1) continue;
    const double row_gyro_s = model_.RowGyroOffsetS(t_first_row_ns, v);
    const Eigen::Quaterniond q =
        anchor_from_world * world_from_cam_->WorldFromBodyAt(t_first_row_ns, row_gyro_s);
    motion.world_from_cam[v] = q.normalized().toRotationMatrix();
    motion.cam_center_m[v] = velocity * since_anchor_s(row_gyro_s);
  }
  if (!anchor_first_row_ns) {
    // Exactly the identity and the origin (not a rounding away from them): the rotation-only
    // renderer and the per-frame reference rely on it.
    motion.world_from_ref.setIdentity();
    motion.ref_center_m.setZero();
  }
  return motion;
}

Eigen::Matrix3d FrameMotion::WorldFromCamAtRow(double row) const {
  const int last = static_cast<int>(world_from_cam.size()) - 1;
  SHUTTERLAB_CHECK(last >= 0 && row >= 0 && row <= last)
      << "row " << row << " outside the frame's 0.." << last;
  const int r0 = std::min(static_cast<int>(row), std::max(0, last - 1));
  const double a = row - r0;
  if (a == 0.0 || last == 0) return world_from_cam[r0];
  const Eigen::Quaterniond q0(world_from_cam[r0]), q1(world_from_cam[r0 + 1]);
  return q0.slerp(a, q1).toRotationMatrix();
}

Eigen::Vector3d FrameMotion::CamCenterAtRow(double row) const {
  const int last = static_cast<int>(cam_center_m.size()) - 1;
  SHUTTERLAB_CHECK(last >= 0 && row >= 0 && row <= last)
      << "row " << row << " outside the frame's 0.." << last;
  const int r0 = std::min(static_cast<int>(row), std::max(0, last - 1));
  const double a = row - r0;
  if (a == 0.0 || last == 0) return cam_center_m[r0];
  return (1 - a) * cam_center_m[r0] + a * cam_center_m[r0 + 1];
}

}  // namespace shutterlab
