#include "render/camera.h"

#include "sim/check.h"
#include "sim/so3.h"
#include "sim/text_file.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>

namespace shutterlab {

bool PinholeCamera::HasDistortion() const {
  for (double d : dist) {
    if (d != 0.0) return true;
  }
  return false;
}

Eigen::Matrix3d PinholeCamera::K() const {
  Eigen::Matrix3d k;
  k << fx, 0, cx, 0, fy, cy, 0, 0, 1;
  return k;
}

std::optional<Eigen::Vector2d> PinholeCamera::ImgFromCam(const Eigen::Vector3d& p_in_cam) const {
  if (!(p_in_cam.z() > 0)) return std::nullopt;
  double x = p_in_cam.x() / p_in_cam.z(), y = p_in_cam.y() / p_in_cam.z();
  if (HasDistortion()) {
    // OpenCV's model (calib3d docs, "Detailed description"): radial k1 k2 k3, tangential p1 p2.
    const double r2 = x * x + y * y;
    const double radial = 1 + r2 * (dist[0] + r2 * (dist[1] + r2 * dist[4]));
    const double xd = x * radial + 2 * dist[2] * x * y + dist[3] * (r2 + 2 * x * x);
    const double yd = y * radial + dist[2] * (r2 + 2 * y * y) + 2 * dist[3] * x * y;
    x = xd;
    y = yd;
  }
  return Eigen::Vector2d(fx * x + cx, fy * y + cy);
}

Eigen::Vector3d PinholeCamera::CamFromImg(const Eigen::Vector2d& px) const {
  const double xd = (px.x() - cx) / fx, yd = (px.y() - cy) / fy;
  if (!HasDistortion()) return Eigen::Vector3d(xd, yd, 1.0);
  // Newton iteration on the distortion map (converges where the map is invertible; the plain
  // fixed-point iteration OpenCV uses stalls for strong distortion at the corners).
  double x = xd, y = yd;
  for (int it = 0; it < 50; ++it) {
    const double r2 = x * x + y * y;
    const double k1 = dist[0], k2 = dist[1], p1 = dist[2], p2 = dist[3], k3 = dist[4];
    const double radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3));
    const double d_radial_d_r2 = k1 + r2 * (2 * k2 + 3 * r2 * k3);
    const double fx_ = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x) - xd;
    const double fy_ = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y - yd;
    const double j00 = radial + 2 * x * x * d_radial_d_r2 + 2 * p1 * y + 6 * p2 * x;
    const double j01 = 2 * x * y * d_radial_d_r2 + 2 * p1 * x + 2 * p2 * y;
    const double j10 = 2 * x * y * d_radial_d_r2 + 2 * p1 * x + 2 * p2 * y;
    const double j11 = radial + 2 * y * y * d_radial_d_r2 + 6 * p1 * y + 2 * p2 * x;
    const double det = j00 * j11 - j01 * j10;
    if (det == 0) break;
    const double dx = (j11 * fx_ - j01 * fy_) / det, dy = (j00 * fy_ - j10 * fx_) / det;
    x -= dx;
    y -= dy;
    if (std::abs(dx) + std::abs(dy) < 1e-15) break;
  }
  return Eigen::Vector3d(x, y, 1.0);
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
  for (double d : camera.dist) SHUTTERLAB_CHECK(std::isfinite(d)) << "distortion is not finite";
  SHUTTERLAB_CHECK(shutter.readout_s > 0 && shutter.readout_s < 10)
      << "readout_s=" << shutter.readout_s << " must be positive (and below 10 s)";
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

}  // namespace

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
  RigModel rig;
  try {
    if (!j.is_object()) throw std::invalid_argument("top level is not an object");
    if (j.contains("format") && j["format"] != "rig/1") {
      throw std::invalid_argument("format is " + j["format"].dump() + ", expected \"rig/1\"");
    }
    const json& image = j.at("image");
    rig.camera.width = static_cast<int>(Number(image, "width", "image"));
    rig.camera.height = static_cast<int>(Number(image, "height", "image"));
    const json& k = j.at("intrinsics");
    rig.camera.fx = Number(k, "fx", "intrinsics");
    rig.camera.fy = Number(k, "fy", "intrinsics");
    rig.camera.cx = Number(k, "cx", "intrinsics");
    rig.camera.cy = Number(k, "cy", "intrinsics");
    if (j.contains("distortion")) {
      const char* names[5] = {"k1", "k2", "p1", "p2", "k3"};
      for (int i = 0; i < 5; ++i) {
        if (j["distortion"].contains(names[i]))
          rig.camera.dist[i] = Number(j["distortion"], names[i], "distortion");
      }
    }
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
    rig.Check();
  } catch (const json::exception& e) {
    throw IoError(IoMessage(path, 0, std::string("malformed camera: ") + e.what()));
  } catch (const std::invalid_argument& e) {
    throw IoError(IoMessage(path, 0, e.what()));
  }
  return rig;
}

void WriteRigModel(const std::string& path, const RigModel& rig) {
  rig.Check();
  json j;
  j["format"] = "rig/1";
  j["image"] = {{"width", rig.camera.width}, {"height", rig.camera.height}};
  j["intrinsics"] = {
      {"fx", rig.camera.fx}, {"fy", rig.camera.fy}, {"cx", rig.camera.cx}, {"cy", rig.camera.cy}};
  j["distortion"] = {{"k1", rig.camera.dist[0]},
                     {"k2", rig.camera.dist[1]},
                     {"p1", rig.camera.dist[2]},
                     {"p2", rig.camera.dist[3]},
                     {"k3", rig.camera.dist[4]}};
  j["rolling_shutter"] = {{"readout_s", rig.shutter.readout_s},
                          {"direction", ReadoutDirectionName(rig.shutter.direction)}};
  j["gyro_to_camera"] = MatrixJson(rig.cam_from_gyro);
  j["time_offset_s"] = rig.time_offset_s;
  j["scene"] = {{"altitude_m", rig.altitude_m}};
  j["velocity_mps"] = {rig.velocity_mps.x(), rig.velocity_mps.y(), rig.velocity_mps.z()};
  if (!rig.mask.empty()) j["mask"] = rig.mask;
  WriteFileAtomically(path, j.dump(2) + "\n");
}

json MatrixJson(const Eigen::Matrix3d& m) {
  json rows = json::array();
  for (int r = 0; r < 3; ++r) rows.push_back({m(r, 0), m(r, 1), m(r, 2)});
  return rows;
}

}  // namespace shutterlab
