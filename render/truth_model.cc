#include "render/truth_model.h"

#include "sim/check.h"
#include "sim/so3.h"
#include "sim/text_file.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

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

double TrueModel::RowGyroOffsetS(int64_t t_first_row_ns, double row) const {
  const double row_offset_s = rig.shutter.RowTimeOffsetS(row, rig.camera.height);
  // gyro = camera * (1 + k) + offset; the camera instant is t_first_row_ns + row_offset_s. Only the
  // small terms are in double: t_first_row_ns stays an exact integer (STYLE.md §3).
  const double k = clock_rate_ppm * 1e-6;
  return row_offset_s + k * (t_first_row_ns * 1e-9 + row_offset_s) + rig.time_offset_s;
}

const std::vector<std::string>& InjectionNames() {
  static const std::vector<std::string> names = {
      "time_offset", "readout_time",    "gyro_to_camera",    "gyro_scale", "gyro_bias",
      "velocity",    "lens_distortion", "readout_direction", "clock_rate"};
  return names;
}

namespace {

using nlohmann::json;

// VALUE as JSON when it parses, else comma-separated numbers, else a bare word.
json ParseValue(const std::string& text) {
  json j = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (!j.is_discarded()) return j;
  std::vector<std::string_view> fields;
  SplitFields(text, ',', &fields);
  json numbers = json::array();
  for (std::string_view f : fields) {
    const std::optional<double> x = ParseDouble(f);
    if (!x) return json(text);
    numbers.push_back(*x);
  }
  return numbers.size() == 1 ? numbers[0] : numbers;
}

double Scalar(const json& j, const std::string& name) {
  if (!j.is_number() || !std::isfinite(j.get<double>())) {
    throw std::invalid_argument("--inject " + name + ": expected a number, got " + j.dump());
  }
  return j.get<double>();
}

std::vector<double> Numbers(const json& j, const std::string& name, size_t n) {
  json flat = json::array();
  if (j.is_array()) {
    for (const json& e : j) {
      if (e.is_array()) {
        for (const json& x : e) flat.push_back(x);
      } else {
        flat.push_back(e);
      }
    }
  }
  if (flat.size() != n) {
    throw std::invalid_argument("--inject " + name + ": expected " + std::to_string(n) +
                                " numbers, got " + j.dump());
  }
  std::vector<double> out;
  for (const json& x : flat) out.push_back(Scalar(x, name));
  return out;
}

Eigen::Vector3d Vector3(const json& j, const std::string& name) {
  const std::vector<double> v = Numbers(j, name, 3);
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

}  // namespace

nlohmann::json ApplyInjection(const std::string& name_equals_value, TrueModel* model) {
  const size_t eq = name_equals_value.find('=');
  if (eq == std::string::npos) {
    throw std::invalid_argument("--inject '" + name_equals_value + "': expected NAME=VALUE");
  }
  const std::string name = name_equals_value.substr(0, eq);
  const json value = ParseValue(name_equals_value.substr(eq + 1));
  RigModel& rig = model->rig;
  json recorded;
  if (name == "time_offset") {
    rig.time_offset_s = Scalar(value, name);
    recorded = rig.time_offset_s;
  } else if (name == "readout_time") {
    rig.shutter.readout_s = Scalar(value, name);
    SHUTTERLAB_CHECK(rig.shutter.readout_s > 0) << "--inject readout_time must be positive";
    recorded = rig.shutter.readout_s;
  } else if (name == "gyro_to_camera") {
    const std::vector<double> m = Numbers(value, name, 9);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) rig.cam_from_gyro(r, c) = m[3 * r + c];
    }
    SHUTTERLAB_CHECK(IsRotationMatrix(rig.cam_from_gyro, 1e-6))
        << "--inject gyro_to_camera is not a rotation";
    recorded = json::array();
    for (int r = 0; r < 3; ++r) recorded.push_back({m[3 * r], m[3 * r + 1], m[3 * r + 2]});
  } else if (name == "gyro_scale") {
    model->gyro_scale = Vector3(value, name);
    recorded = {model->gyro_scale.x(), model->gyro_scale.y(), model->gyro_scale.z()};
  } else if (name == "gyro_bias") {
    model->gyro_bias_rad_s = Vector3(value, name);
    recorded = {model->gyro_bias_rad_s.x(), model->gyro_bias_rad_s.y(), model->gyro_bias_rad_s.z()};
  } else if (name == "velocity") {
    rig.velocity_mps = Vector3(value, name);
    recorded = {rig.velocity_mps.x(), rig.velocity_mps.y(), rig.velocity_mps.z()};
  } else if (name == "lens_distortion") {
    static const char* kNames[5] = {"k1", "k2", "p1", "p2", "k3"};
    rig.camera.dist.fill(0.0);
    recorded = json::object();
    if (value.is_object()) {
      for (const auto& [key, x] : value.items()) {
        int i = 0;
        while (i < 5 && key != kNames[i]) ++i;
        if (i == 5)
          throw std::invalid_argument("--inject lens_distortion: unknown coefficient '" + key +
                                      "'");
        rig.camera.dist[i] = Scalar(x, name);
      }
    } else {
      const json list = value.is_array() ? value : json::array({value});
      if (list.empty() || list.size() > 5) {
        throw std::invalid_argument(
            "--inject lens_distortion: expected k1[,k2[,p1,p2[,k3]]], got " + value.dump());
      }
      for (size_t i = 0; i < list.size(); ++i) rig.camera.dist[i] = Scalar(list[i], name);
    }
    for (int i = 0; i < 5; ++i) {
      if (i < 2 || rig.camera.dist[i] != 0.0) recorded[kNames[i]] = rig.camera.dist[i];
    }
  } else if (name == "readout_direction") {
    const std::string word = value.is_string() ? value.get<std::string>() : value.dump();
    const std::optional<ReadoutDirection> parsed = ParseReadoutDirection(word);
    if (!parsed || !IsRowReadout(*parsed)) {
      throw std::invalid_argument("--inject readout_direction: '" + word +
                                  "' is not top_to_bottom or bottom_to_top");
    }
    rig.shutter.direction = *parsed;
    recorded = word;
  } else if (name == "clock_rate") {
    model->clock_rate_ppm = Scalar(value, name);
    recorded = model->clock_rate_ppm;
  } else {
    std::string known;
    for (const std::string& n : InjectionNames()) known += (known.empty() ? "" : ", ") + n;
    throw std::invalid_argument("--inject: unknown effect '" + name + "' (known: " + known + ")");
  }
  model->Check();
  return recorded;
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
    : model_(model), world_from_cam_(CamRates(logged, model)) {
  model_.Check();
}

FrameMotion CameraMotion::Frame(int64_t t_first_row_ns,
                                std::optional<int64_t> anchor_first_row_ns) const {
  const int height = model_.rig.camera.height;
  FrameMotion motion;
  motion.world_from_cam.resize(height);
  motion.cam_center_m.resize(height);
  // The anchor: the true capture time of row 0 of the frame that defines the world.
  const int64_t anchor_ns = anchor_first_row_ns.value_or(t_first_row_ns);
  const double anchor_gyro_s = model_.RowGyroOffsetS(anchor_ns, 0);
  const Eigen::Quaterniond anchor_from_world =
      world_from_cam_.WorldFromBodyAt(anchor_ns, anchor_gyro_s).conjugate();
  // Gyro-clock seconds of an instant given as (t_first_row_ns, offset) relative to the anchor.
  const auto since_anchor_s = [&](double offset_s) {
    return (t_first_row_ns - anchor_ns) * 1e-9 + offset_s - anchor_gyro_s;
  };
  const double t0_gyro_s = model_.RowGyroOffsetS(t_first_row_ns, 0);
  motion.world_from_ref =
      (anchor_from_world * world_from_cam_.WorldFromBodyAt(t_first_row_ns, t0_gyro_s))
          .normalized()
          .toRotationMatrix();
  // c(t) = velocity * (t - t_anchor) with t the gyro-clock time, as FORMATS.md's t_v (under
  // clock_rate the gyro clock runs (1 + ppm 1e-6) times the camera's). The anchor's centre is 0.
  motion.ref_center_m = model_.rig.velocity_mps * since_anchor_s(t0_gyro_s);
  for (int v = 0; v < height; ++v) {
    const double row_gyro_s = model_.RowGyroOffsetS(t_first_row_ns, v);
    const Eigen::Quaterniond q =
        anchor_from_world * world_from_cam_.WorldFromBodyAt(t_first_row_ns, row_gyro_s);
    motion.world_from_cam[v] = q.normalized().toRotationMatrix();
    motion.cam_center_m[v] = model_.rig.velocity_mps * since_anchor_s(row_gyro_s);
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
