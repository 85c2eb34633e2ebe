#include "io/opensfm_camera.h"

#include "sim/check.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>

namespace shutterlab {

using nlohmann::json;

bool IsOpenSfmCameras(const json& j) {
  if (!j.is_object() || j.empty()) return false;
  return std::all_of(j.begin(), j.end(), [](const json& camera) {
    return camera.is_object() && camera.contains("projection_type");
  });
}

OpenSfmCamera ReadOpenSfmCamera(const json& j, const std::string& path) {
  const auto fail = [&](const std::string& problem) { throw IoError(IoMessage(path, 0, problem)); };
  std::string key;
  if (j.contains("all")) {
    key = "all";
  } else if (j.size() == 1) {
    key = j.begin().key();
  } else {
    fail("OpenSfM cameras: " + std::to_string(j.size()) +
         " cameras; give a file with one (or the key \"all\")");
  }
  const json& c = j[key];
  const auto number = [&](const char* name, double fallback, bool required) {
    if (!c.contains(name) || c[name].is_null()) {
      if (required) fail("OpenSfM camera \"" + key + "\" has no " + name);
      return fallback;
    }
    if (!c[name].is_number() || !std::isfinite(c[name].get<double>()))
      fail("OpenSfM camera \"" + key + "\": " + name + " " + c[name].dump() + " is not a number");
    return c[name].get<double>();
  };
  OpenSfmCamera p;
  p.key = key;
  const double w = number("width", 0, true), h = number("height", 0, true);
  if (!(w > 0 && h > 0 && w <= 1e6 && h <= 1e6) || w != std::floor(w) || h != std::floor(h))
    fail("OpenSfM camera \"" + key + "\": width and height must be whole positive pixels");
  p.camera.width = static_cast<int>(w);
  p.camera.height = static_cast<int>(h);
  const double s = std::max(w, h);
  const std::string type =
      c["projection_type"].is_string() ? c["projection_type"].get<std::string>() : "";
  const bool one_focal = type == "perspective" || type == "fisheye";
  if (one_focal) {
    p.camera.fx = p.camera.fy = number("focal", 0, true) * s;
  } else {
    p.camera.fx = number("focal_x", 0, true) * s;
    p.camera.fy = number("focal_y", 0, true) * s;
  }
  // OpenSfM's normalised principal point, from the centre, with the pixel centres at +0.5.
  p.camera.cx = number("c_x", 0, !one_focal) * s + 0.5 * w - 0.5;
  p.camera.cy = number("c_y", 0, !one_focal) * s + 0.5 * h - 0.5;
  if (!(p.camera.fx > 0 && p.camera.fy > 0)) fail("OpenSfM camera \"" + key + "\": focal <= 0");
  const double k1 = number("k1", 0, false), k2 = number("k2", 0, false);
  if (type == "perspective") {
    p.camera.distortion = BrownConrady{{k1, k2, 0, 0, 0}};
  } else if (type == "brown") {
    p.camera.distortion = BrownConrady{
        {k1, k2, number("p1", 0, false), number("p2", 0, false), number("k3", 0, false)}};
  } else if (type == "fisheye") {
    p.camera.distortion = Fisheye({k1, k2, 0, 0});
  } else if (type == "fisheye_opencv") {
    p.camera.distortion = Fisheye({k1, k2, number("k3", 0, false), number("k4", 0, false)});
  } else {
    fail("OpenSfM projection_type " + c["projection_type"].dump() +
         " is not one shutterlab models (perspective, brown, fisheye, fisheye_opencv)");
  }
  return p;
}

}  // namespace shutterlab
