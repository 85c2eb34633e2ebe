#include "estimate/effect_model.h"

#include "sim/check.h"
#include "sim/integrate.h"
#include "sim/so3.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

namespace shutterlab {

namespace {

using nlohmann::json;

json Array3(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }

void CheckName(const std::string& name) {
  const std::vector<std::string>& names = InjectionNames();
  SHUTTERLAB_CHECK(std::find(names.begin(), names.end(), name) != names.end())
      << "unknown effect '" << name << "'";
}

}  // namespace

int EffectParameterCount(const std::string& name) {
  CheckName(name);
  if (name == "time_offset" || name == "readout_time") return 1;
  if (name == "lens_distortion" || name == "clock_rate") return 2;
  if (name == "readout_direction") return 0;
  return 3;  // gyro_to_camera, gyro_scale, gyro_bias, velocity
}

void ApplyEffect(const std::string& name, const double* x, TrueModel* model) {
  RigModel& rig = model->rig;
  if (name == "time_offset") {
    rig.time_offset_s += x[0];
  } else if (name == "readout_time") {
    rig.shutter.readout_s += x[0];
  } else if (name == "gyro_to_camera") {
    rig.cam_from_gyro =
        ExpSO3(Eigen::Vector3d(x[0], x[1], x[2])).toRotationMatrix() * rig.cam_from_gyro;
  } else if (name == "gyro_scale") {
    model->gyro_scale += Eigen::Vector3d(x[0], x[1], x[2]);
  } else if (name == "gyro_bias") {
    model->gyro_bias_rad_s += Eigen::Vector3d(x[0], x[1], x[2]);
  } else if (name == "velocity") {
    rig.velocity_mps += Eigen::Vector3d(x[0], x[1], x[2]);
  } else if (name == "lens_distortion") {
    rig.camera.dist[0] += x[0];
    rig.camera.dist[1] += x[1];
  } else if (name == "readout_direction") {
    rig.shutter.direction = rig.shutter.direction == ReadoutDirection::kTopToBottom
                                ? ReadoutDirection::kBottomToTop
                                : ReadoutDirection::kTopToBottom;
  } else if (name == "clock_rate") {
    // A clock rate is only defined together with an offset: FORMATS.md counts it from camera time
    // 0, which a log's clock may have passed long ago (frames at t = 1000 s: 3 ppm is 3 ms).
    model->clock_rate_ppm += x[0];
    rig.time_offset_s += x[1];
  } else {
    CheckName(name);
  }
}

double EffectStep(const std::string& name, int i, double frames_span_s) {
  // Steps small enough that the model is linear over them (the displacements move by ~1e-3 px) and
  // large enough that rounding (~1e-13 px) is far below the differences.
  if (name == "time_offset" || name == "readout_time") return 1e-5;  // s
  if (name == "gyro_to_camera") return 1e-4;                         // rad
  if (name == "gyro_scale") return 1e-4;
  if (name == "gyro_bias") return 1e-4;  // rad/s
  if (name == "velocity") return 1e-2;   // m/s
  if (name == "lens_distortion") return 1e-4;
  if (name == "clock_rate") {
    return i == 0 ? 1e-5 / std::max(frames_span_s, 1.0) * 1e6 : 1e-5;  // ppm, s
  }
  CheckName(name);
  return 1.0;
}

json EffectValue(const std::string& name, const TrueModel& model) {
  const RigModel& rig = model.rig;
  if (name == "time_offset") return rig.time_offset_s;
  if (name == "readout_time") return rig.shutter.readout_s;
  if (name == "gyro_to_camera") {
    json m = json::array();
    for (int r = 0; r < 3; ++r) {
      m.push_back({rig.cam_from_gyro(r, 0), rig.cam_from_gyro(r, 1), rig.cam_from_gyro(r, 2)});
    }
    return m;
  }
  if (name == "gyro_scale") return Array3(model.gyro_scale);
  if (name == "gyro_bias") return Array3(model.gyro_bias_rad_s);
  if (name == "velocity") return Array3(rig.velocity_mps);
  if (name == "lens_distortion") return {{"k1", rig.camera.dist[0]}, {"k2", rig.camera.dist[1]}};
  if (name == "readout_direction") {
    return rig.shutter.direction == ReadoutDirection::kTopToBottom ? "top_to_bottom"
                                                                   : "bottom_to_top";
  }
  if (name == "clock_rate") return model.clock_rate_ppm;
  CheckName(name);
  return nullptr;
}

json EffectStderr(const std::string& name, const TrueModel& model,
                  const Eigen::MatrixXd& covariance) {
  const int n = EffectParameterCount(name);
  if (n == 0) return nullptr;
  SHUTTERLAB_CHECK(covariance.rows() == n && covariance.cols() == n)
      << name << ": covariance is " << covariance.rows() << "x" << covariance.cols();
  const Eigen::VectorXd sd = covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  if (name == "gyro_to_camera") {
    // R = Exp(x) R_0 with x near 0: dR/dx_k = Hat(e_k) R (first order), entry by entry.
    const Eigen::Matrix3d& r = model.rig.cam_from_gyro;
    Eigen::Matrix<double, 9, 3> d_entries_d_x;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Matrix3d d = Hat(Eigen::Vector3d::Unit(k)) * r;
      for (int i = 0; i < 9; ++i) d_entries_d_x(i, k) = d(i / 3, i % 3);
    }
    const Eigen::Matrix<double, 9, 9> cov = d_entries_d_x * covariance * d_entries_d_x.transpose();
    json m = json::array();
    for (int row = 0; row < 3; ++row) {
      json line = json::array();
      for (int col = 0; col < 3; ++col) {
        line.push_back(std::sqrt(std::max(0.0, cov(3 * row + col, 3 * row + col))));
      }
      m.push_back(line);
    }
    return m;
  }
  if (n == 1 || name == "clock_rate") return sd[0];  // clock_rate: the rate's, not the offset's
  if (name == "lens_distortion") return {{"k1", sd[0]}, {"k2", sd[1]}};
  return json::array({sd[0], sd[1], sd[2]});
}

std::string EffectUnit(const std::string& name) {
  CheckName(name);
  if (name == "time_offset" || name == "readout_time") return "s";
  if (name == "gyro_bias") return "rad/s";
  if (name == "velocity") return "m/s";
  if (name == "clock_rate") return "ppm";
  return "";
}

DisplacementPredictor::DisplacementPredictor(const GyroTrace& gyro,
                                             const std::vector<FramePoints>& frames)
    : gyro_(gyro) {
  SHUTTERLAB_CHECK(gyro.size() >= 2) << "the gyro trace needs at least two samples";
  for (const FramePoints& f : frames) {
    Frame frame;
    frame.t_first_row_ns = f.t_first_row_ns;
    frame.first = points_;
    for (const MeasuredPoint& p : f.points) frame.rows.push_back(p.v);
    std::sort(frame.rows.begin(), frame.rows.end());
    frame.rows.erase(std::unique(frame.rows.begin(), frame.rows.end()), frame.rows.end());
    for (const MeasuredPoint& p : f.points) {
      frame.px.emplace_back(p.u, p.v);
      frame.row_of_point.push_back(static_cast<int>(
          std::lower_bound(frame.rows.begin(), frame.rows.end(), p.v) - frame.rows.begin()));
    }
    points_ += f.points.size();
    frames_span_s_ = std::max(frames_span_s_, std::abs(f.t_first_row_ns * 1e-9));
    frames_.push_back(std::move(frame));
  }
}

void DisplacementPredictor::RefreshRays(const PinholeCamera& camera) const {
  if (rays_valid_ && camera.fx == rays_camera_.fx && camera.fy == rays_camera_.fy &&
      camera.cx == rays_camera_.cx && camera.cy == rays_camera_.cy &&
      camera.dist == rays_camera_.dist) {
    return;
  }
  rays_.resize(points_);
  for (const Frame& frame : frames_) {
    for (size_t i = 0; i < frame.px.size(); ++i)
      rays_[frame.first + i] = camera.CamFromImg(frame.px[i]);
  }
  rays_camera_ = camera;
  rays_valid_ = true;
}

namespace {

// True when OrientationTrace::WorldFromBodyAt(t_ns, offset_s) over samples [front, back] would
// answer (the same whole-ns / fraction split, so the two agree at the ends).
bool InSpan(int64_t t_ns, double offset_s, int64_t front_ns, int64_t back_ns) {
  const double offset_ns = offset_s * 1e9;
  if (!std::isfinite(offset_ns) || std::abs(offset_ns) >= 9e18) return false;
  const int64_t whole_ns = static_cast<int64_t>(std::floor(offset_ns));
  const int64_t t = t_ns + whole_ns;
  const double frac_ns = offset_ns - static_cast<double>(whole_ns);
  return !(t < front_ns || t > back_ns || (t == back_ns && frac_ns > 0.0));
}

}  // namespace

void DisplacementPredictor::Predict(const TrueModel& model,
                                    std::vector<Eigen::Vector2d>* out) const {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  out->assign(points_, Eigen::Vector2d(kNaN, kNaN));
  const PinholeCamera& camera = model.rig.camera;
  RefreshRays(camera);
  const std::vector<GyroSample>& samples = gyro_.samples();
  std::vector<double> row_offset_s;
  std::vector<Eigen::Matrix3d> row_rotation;
  std::vector<uint8_t> row_ok;
  for (const Frame& frame : frames_) {
    if (frame.px.empty()) continue;
    const int64_t t_first = frame.t_first_row_ns;
    // Gyro-clock offsets (from t_first on the camera clock) of row 0 and of every point row.
    const double t0_offset_s = model.RowGyroOffsetS(t_first, 0);
    row_offset_s.resize(frame.rows.size());
    double lo_s = t0_offset_s, hi_s = t0_offset_s;
    for (size_t r = 0; r < frame.rows.size(); ++r) {
      row_offset_s[r] = model.RowGyroOffsetS(t_first, frame.rows[r]);
      lo_s = std::min(lo_s, row_offset_s[r]);
      hi_s = std::max(hi_s, row_offset_s[r]);
    }
    if (!std::isfinite(lo_s) || !std::isfinite(hi_s) || std::abs(lo_s) > 1e9 ||
        std::abs(hi_s) > 1e9) {
      continue;
    }
    // The samples that cover [lo, hi]: from the last one at or before lo to the first one at or
    // after hi (one more on each side: the lookup's whole-ns rounding stays inside).
    const int64_t lo_ns = t_first + static_cast<int64_t>(std::floor(lo_s * 1e9));
    const int64_t hi_ns = t_first + static_cast<int64_t>(std::ceil(hi_s * 1e9));
    size_t begin = gyro_.LowerBound(lo_ns);
    begin = begin > 0 ? begin - 1 : 0;
    size_t end = std::min(gyro_.LowerBound(hi_ns) + 1, samples.size() - 1);
    if (end <= begin) end = std::min(begin + 1, samples.size() - 1);
    if (end <= begin) continue;
    std::vector<GyroSample> span(samples.begin() + begin, samples.begin() + end + 1);
    for (GyroSample& s : span) s.omega_rad_s = model.CamRate(s.omega_rad_s);
    const OrientationTrace trace{GyroTrace(std::move(span))};
    const int64_t front_ns = trace.t_ns().front(), back_ns = trace.t_ns().back();
    // Whole frame undefined when row 0 (the reference) is outside the trace (the renderer throws);
    // single rows outside are undefined on their own.
    if (!InSpan(t_first, t0_offset_s, front_ns, back_ns)) continue;
    // As CameraMotion::Frame: R_v = R(t_0)^-1 R(t_v), c_v = velocity * (t_v - t_0).
    const Eigen::Quaterniond ref_from_world =
        trace.WorldFromBodyAt(t_first, t0_offset_s).conjugate();
    row_rotation.resize(frame.rows.size());
    row_ok.assign(frame.rows.size(), 0);
    for (size_t r = 0; r < frame.rows.size(); ++r) {
      if (!InSpan(t_first, row_offset_s[r], front_ns, back_ns)) continue;
      const Eigen::Quaterniond q = ref_from_world * trace.WorldFromBodyAt(t_first, row_offset_s[r]);
      row_rotation[r] = q.normalized().toRotationMatrix();
      row_ok[r] = 1;
    }
    // As FrameGeometry::GroundPoint / RefPixel (the reference pose is the identity at c(t_0) = 0).
    const double altitude_m = model.rig.altitude_m;
    for (size_t i = 0; i < frame.px.size(); ++i) {
      const int r = frame.row_of_point[i];
      if (!row_ok[r]) continue;
      const Eigen::Vector3d ray_w = row_rotation[r] * rays_[frame.first + i];
      const Eigen::Vector3d c = model.rig.velocity_mps * (row_offset_s[r] - t0_offset_s);
      const double s = (altitude_m - c.z()) / ray_w.z();
      if (!(s > 0) || !std::isfinite(s)) continue;
      const Eigen::Vector3d x = c + s * ray_w;
      const std::optional<Eigen::Vector2d> ref = camera.ImgFromCam(x);
      if (!ref) continue;
      (*out)[frame.first + i] = *ref - frame.px[i];
    }
  }
}

}  // namespace shutterlab
