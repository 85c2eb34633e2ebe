#include "model/camera.h"

#include "sim/check.h"
#include "sim/so3.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>

namespace shutterlab {

bool PinholeCamera::HasDistortion() const { return shutterlab::HasDistortion(distortion); }

Eigen::Matrix3d PinholeCamera::K() const {
  Eigen::Matrix3d k;
  k << fx, 0, cx, 0, fy, cy, 0, 0, 1;
  return k;
}

std::optional<Eigen::Vector2d> PinholeCamera::ImgFromCam(const Eigen::Vector3d& p_in_cam) const {
  if (!HasDistortion()) {
    if (!(p_in_cam.z() > 0)) return std::nullopt;
    const double x = p_in_cam.x() / p_in_cam.z(), y = p_in_cam.y() / p_in_cam.z();
    return Eigen::Vector2d(fx * x + cx, fy * y + cy);
  }
  const std::optional<Eigen::Vector2d> x_d =
      std::visit([&](const auto& lens) { return lens.DistortedFromRay(p_in_cam); }, distortion);
  if (!x_d) return std::nullopt;
  return Eigen::Vector2d(fx * x_d->x() + cx, fy * x_d->y() + cy);
}

Eigen::Vector3d PinholeCamera::CamFromImg(const Eigen::Vector2d& px) const {
  const Eigen::Vector2d x_d((px.x() - cx) / fx, (px.y() - cy) / fy);
  if (!HasDistortion()) return Eigen::Vector3d(x_d.x(), x_d.y(), 1.0);
  return std::visit([&](const auto& lens) { return lens.RayFromDistorted(x_d); }, distortion);
}

bool PinholeCamera::DistortionMonotonicOverImage() const {
  const double dx = std::max(cx, width - 1 - cx) / fx;
  const double dy = std::max(cy, height - 1 - cy) / fy;
  const double corner = std::hypot(dx, dy);  // distorted normalised radius of the farthest corner
  if (const auto* brown = std::get_if<BrownConrady>(&distortion)) {
    // The undistorted corner radius can be larger than the distorted one: check well beyond it.
    return brown->MonotonicTo(1.5 * corner);
  }
  const Fisheye& fisheye = std::get<Fisheye>(distortion);
  if (fisheye.max_theta_rad() >= kPi) return true;
  const Eigen::Vector3d ray = fisheye.RayFromDistorted(Eigen::Vector2d(corner, 0.0));
  if (!ray.allFinite()) return false;
  return 1.2 * std::atan2(ray.x(), ray.z()) < fisheye.max_theta_rad();
}

double RollingShutter::RowTimeOffsetS(double row, int height) const {
  const double read_index = direction == ReadoutDirection::kTopToBottom ? row : (height - 1) - row;
  return read_index * readout_s / height;
}

void RigModel::Check() const {
  SHUTTERLAB_CHECK(camera.width > 0 && camera.height > 0)
      << "image size " << camera.width << "x" << camera.height << " must be positive";
  SHUTTERLAB_CHECK(camera.fx > 0 && camera.fy > 0 && std::isfinite(camera.fx) &&
                   std::isfinite(camera.fy))
      << "focal length fx=" << camera.fx << " fy=" << camera.fy << " must be positive";
  SHUTTERLAB_CHECK(std::isfinite(camera.cx) && std::isfinite(camera.cy))
      << "principal point is not finite";
  SHUTTERLAB_CHECK(DistortionFinite(camera.distortion)) << "distortion is not finite";
  // 0 is a global shutter: every row at t_first_row (what `correct` declares for its output).
  SHUTTERLAB_CHECK(shutter.readout_s >= 0 && shutter.readout_s < 10)
      << "readout_s=" << shutter.readout_s
      << " must be 0 (a global shutter) or positive (below 10 s)";
  SHUTTERLAB_CHECK(IsRowReadout(shutter.direction))
      << "readout direction " << ReadoutDirectionName(shutter.direction)
      << " is not top_to_bottom or bottom_to_top";
  SHUTTERLAB_CHECK(IsRotationMatrix(cam_from_gyro, 1e-6))
      << "gyro_to_camera is not a rotation matrix (orthonormal, det +1)";
  SHUTTERLAB_CHECK(std::isfinite(time_offset_s)) << "time_offset_s is not finite";
  SHUTTERLAB_CHECK(altitude_m > 0 && std::isfinite(altitude_m))
      << "altitude_m=" << altitude_m << " must be positive";
  SHUTTERLAB_CHECK(velocity_mps.allFinite()) << "velocity_mps is not finite";
}

namespace {

using nlohmann::json;

double Number(const json& j, const char* key, const std::string& where) {
  if (!j.contains(key)) throw std::invalid_argument(where + "." + key + " is missing");
  if (!j.at(key).is_number()) throw std::invalid_argument(where + "." + key + " is not a number");
  return j.at(key).get<double>();
}

// An image side in pixels: a whole number that fits an int. A cast of any larger double is
// undefined behaviour (fuzz/camera_json_fuzz found width 8.5e52).
int PixelCount(const json& j, const char* key, const std::string& where) {
  constexpr double kMaxSidePx = 1 << 20;
  const double value = Number(j, key, where);
  if (!(value >= 1 && value <= kMaxSidePx) || value != std::floor(value)) {
    throw std::invalid_argument(where + "." + key + " " + j.at(key).dump() +
                                " is not a whole number of pixels from 1 to 1048576");
  }
  return static_cast<int>(value);
}

// camera.json's coefficient names of each model, in the order the model holds them.
constexpr const char* kBrownNames[5] = {"k1", "k2", "p1", "p2", "k3"};
constexpr const char* kFisheyeNames[4] = {"k1", "k2", "k3", "k4"};

template <size_t N>
std::array<double, N> Coefficients(const json& j, const char* const (&names)[N],
                                   const std::string& model) {
  std::array<double, N> c{};
  for (const auto& item : j.items()) {
    const std::string& key = item.key();  // (a structured binding: clang 14 cannot capture it)
    if (key == "model") continue;
    const auto* at = std::find_if(std::begin(names), std::end(names),
                                  [&](const char* name) { return key == name; });
    if (at == std::end(names)) {
      std::string known;
      for (const char* name : names) known += std::string(known.empty() ? "" : " ") + name;
      throw std::invalid_argument("distortion." + key + " is not a coefficient of the " + model +
                                  " model (" + known + ")");
    }
    c[at - std::begin(names)] = Number(j, key.c_str(), "distortion");
  }
  return c;
}

}  // namespace

LensDistortion DistortionFromJson(const json& j) {
  if (!j.is_object()) throw std::invalid_argument("distortion is not an object");
  const std::string model = j.contains("model") && j["model"].is_string()
                                ? j["model"].get<std::string>()
                                : (j.contains("model") ? j["model"].dump() : "brown");
  if (model == "brown") return BrownConrady{Coefficients(j, kBrownNames, model)};
  if (model == "fisheye") return Fisheye(Coefficients(j, kFisheyeNames, model));
  throw std::invalid_argument("distortion.model '" + model + "' is not brown or fisheye");
}

json DistortionJson(const LensDistortion& lens) {
  json out = json::object();
  if (const auto* fisheye = std::get_if<Fisheye>(&lens)) {
    out["model"] = "fisheye";
    for (size_t i = 0; i < 4; ++i) out[kFisheyeNames[i]] = fisheye->coeffs()[i];
    return out;
  }
  // Brown-Conrady, the default: written without "model", as rig/1 files always were.
  for (size_t i = 0; i < 5; ++i) out[kBrownNames[i]] = std::get<BrownConrady>(lens).coeffs[i];
  return out;
}

const std::vector<std::string>& CameraJsonBoundNames() {
  static const std::vector<std::string> names = {"time_offset", "readout_time", "gyro_scale",
                                                 "gyro_bias",   "velocity",     "clock_rate"};
  return names;
}

// camera.json's "bounds": {"NAME": [lo, hi], ...} for effects that have physical bounds.
std::map<std::string, std::array<double, 2>> BoundsFromJson(const json& j) {
  if (!j.is_object()) throw std::invalid_argument("bounds is not an object of NAME: [lo, hi]");
  std::map<std::string, std::array<double, 2>> out;
  for (const auto& [name, range] : j.items()) {
    const std::vector<std::string>& known = CameraJsonBoundNames();
    if (std::find(known.begin(), known.end(), name) == known.end()) {
      std::string names;
      for (const std::string& k : known) names += (names.empty() ? "" : ", ") + k;
      throw std::invalid_argument("bounds: '" + name + "' is no effect with bounds (" + names +
                                  ")");
    }
    if (!range.is_array() || range.size() != 2 || !range[0].is_number() || !range[1].is_number() ||
        !(range[0].get<double>() < range[1].get<double>())) {
      throw std::invalid_argument("bounds: " + name +
                                  " is not [lo, hi] with lo below hi (in the effect's unit)");
    }
    out[name] = {range[0].get<double>(), range[1].get<double>()};
  }
  return out;
}

RigModel RigModelFromJson(const json& j) {
  RigModel rig;
  if (!j.is_object()) throw std::invalid_argument("top level is not an object");
  if (j.contains("format") && j["format"] != "rig/1") {
    throw std::invalid_argument("format is " + j["format"].dump() + ", expected \"rig/1\"");
  }
  try {
    const json& image = j.at("image");
    rig.camera.width = PixelCount(image, "width", "image");
    rig.camera.height = PixelCount(image, "height", "image");
    const json& k = j.at("intrinsics");
    rig.camera.fx = Number(k, "fx", "intrinsics");
    rig.camera.fy = Number(k, "fy", "intrinsics");
    rig.camera.cx = Number(k, "cx", "intrinsics");
    rig.camera.cy = Number(k, "cy", "intrinsics");
    if (j.contains("distortion")) rig.camera.distortion = DistortionFromJson(j["distortion"]);
    const json& rs = j.at("rolling_shutter");
    rig.shutter.readout_s = Number(rs, "readout_s", "rolling_shutter");
    const std::string direction =
        rs.value("direction", ReadoutDirectionName(ReadoutDirection::kTopToBottom));
    const std::optional<ReadoutDirection> parsed = ParseReadoutDirection(direction);
    if (!parsed || !IsRowReadout(*parsed)) {
      throw std::invalid_argument("rolling_shutter.direction '" + direction +
                                  "' is not top_to_bottom or bottom_to_top");
    }
    rig.shutter.direction = *parsed;
    if (j.contains("gyro_to_camera")) {
      const json& m = j["gyro_to_camera"];
      if (!m.is_array() || m.size() != 3)
        throw std::invalid_argument("gyro_to_camera is not a 3x3 array");
      for (int r = 0; r < 3; ++r) {
        if (!m[r].is_array() || m[r].size() != 3)
          throw std::invalid_argument("gyro_to_camera is not a 3x3 array");
        for (int c = 0; c < 3; ++c) {
          if (!m[r][c].is_number()) throw std::invalid_argument("gyro_to_camera has a non-number");
          rig.cam_from_gyro(r, c) = m[r][c].get<double>();
        }
      }
    }
    if (j.contains("time_offset_s")) rig.time_offset_s = Number(j, "time_offset_s", "camera");
    if (j.contains("scene")) rig.altitude_m = Number(j["scene"], "altitude_m", "scene");
    if (j.contains("velocity_mps")) {
      const json& v = j["velocity_mps"];
      if (!v.is_array() || v.size() != 3)
        throw std::invalid_argument("velocity_mps is not [vx, vy, vz]");
      for (int i = 0; i < 3; ++i) {
        if (!v[i].is_number()) throw std::invalid_argument("velocity_mps has a non-number");
        rig.velocity_mps[i] = v[i].get<double>();
      }
    }
    if (j.contains("mask")) {
      if (!j["mask"].is_string() || j["mask"].get<std::string>().empty()) {
        throw std::invalid_argument("mask is not a file name");
      }
      rig.mask = j["mask"].get<std::string>();
    }
    if (j.contains("bounds")) rig.bounds = BoundsFromJson(j["bounds"]);
  } catch (const json::exception& e) {
    throw std::invalid_argument(std::string("malformed camera: ") + e.what());
  }
  rig.Check();
  return rig;
}

RigModel ReadRigModel(const std::string& path) {
  const std::string text = ReadFileToString(path);
  json j;
  try {
    j = json::parse(text);
  } catch (const json::parse_error& e) {
    // nlohmann reports a byte offset; turn it into a line number for the message.
    const size_t offset = std::min<size_t>(e.byte, text.size());
    const long line = 1 + static_cast<long>(std::count(text.begin(), text.begin() + offset, '\n'));
    throw IoError(IoMessage(path, line, "invalid JSON"));
  } catch (const json::exception& e) {
    // A number too large for a double ("10e900") is nlohmann's out_of_range, not a parse_error.
    // Found by fuzz/camera_json_fuzz.
    throw IoError(IoMessage(path, 0, std::string("invalid JSON: ") + e.what()));
  }
  try {
    return RigModelFromJson(j);
  } catch (const std::invalid_argument& e) {
    throw IoError(IoMessage(path, 0, e.what()));
  }
}

json RigModelToJson(const RigModel& rig) {
  json j;
  j["format"] = "rig/1";
  j["image"] = {{"width", rig.camera.width}, {"height", rig.camera.height}};
  j["intrinsics"] = {
      {"fx", rig.camera.fx}, {"fy", rig.camera.fy}, {"cx", rig.camera.cx}, {"cy", rig.camera.cy}};
  j["distortion"] = DistortionJson(rig.camera.distortion);
  j["rolling_shutter"] = {{"readout_s", rig.shutter.readout_s},
                          {"direction", ReadoutDirectionName(rig.shutter.direction)}};
  j["gyro_to_camera"] = MatrixJson(rig.cam_from_gyro);
  j["time_offset_s"] = rig.time_offset_s;
  j["scene"] = {{"altitude_m", rig.altitude_m}};
  j["velocity_mps"] = {rig.velocity_mps.x(), rig.velocity_mps.y(), rig.velocity_mps.z()};
  if (!rig.mask.empty()) j["mask"] = rig.mask;
  for (const auto& [name, range] : rig.bounds) j["bounds"][name] = {range[0], range[1]};
  return j;
}

void WriteRigModel(const std::string& path, const RigModel& rig) {
  rig.Check();
  WriteFileAtomically(path, RigModelToJson(rig).dump(2) + "\n");
}

json MatrixJson(const Eigen::Matrix3d& m) {
  json rows = json::array();
  for (int r = 0; r < 3; ++r) rows.push_back({m(r, 0), m(r, 1), m(r, 2)});
  return rows;
}

}  // namespace shutterlab
