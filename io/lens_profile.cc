#include "io/lens_profile.h"

#include "io/opensfm_camera.h"
#include "sim/check.h"
#include "sim/text_file.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>

namespace shutterlab {

namespace {

using nlohmann::json;

// Aspect ratios closer than this are the same (848x480 against 1920x1080 differ by 0.6 %).
constexpr double kAspectTolerance = 1e-3;
// A compatible setting's frame rate matches within this share.
constexpr double kFpsTolerance = 0.01;

[[noreturn]] void Fail(const std::string& path, const std::string& problem) {
  throw IoError(IoMessage(path, 0, problem));
}

double NumberOr(const json& j, const char* key, double fallback, const std::string& path) {
  if (!j.contains(key) || j[key].is_null()) return fallback;
  if (!j[key].is_number()) Fail(path, std::string(key) + " is not a number");
  return j[key].get<double>();
}

// An image dimension: a whole number of pixels, 0 when absent (the callers check it is positive).
int PixelsOr(const json& j, const char* key, const std::string& path) {
  const double px = NumberOr(j, key, 0.0, path);
  if (!(px >= 0 && px <= 1e6) || px != std::floor(px))
    Fail(path, std::string(key) + " " + j[key].dump() + " is not a size in pixels");
  return static_cast<int>(px);
}

std::string TextOr(const json& j, const char* key) {
  return j.contains(key) && j[key].is_string() ? j[key].get<std::string>() : "";
}

// frame_readout_time (ms) as a readout: its size, sign (Gyroflow's bottom-to-top) and nothing when
// null or 0 (profiles without a measurement write either).
void ReadReadout(const json& j, const char* key, ProfileReadout* out, const std::string& path) {
  const double ms = NumberOr(j, key, 0.0, path);
  if (!std::isfinite(ms) || std::abs(ms) >= 10000)
    Fail(path, std::string(key) + " " + j[key].dump() + " ms is not a readout time");
  if (ms == 0) return;
  out->readout_s = std::abs(ms) * 1e-3;
  out->direction = ms < 0 ? ReadoutDirection::kBottomToTop : ReadoutDirection::kTopToBottom;
}

// The 3x3 camera matrix of a params object: fx, fy, cx, cy (skew must be 0: rig/1 has none).
void ReadCameraMatrix(const json& params, const std::string& where, PinholeCamera* camera,
                      const std::string& path) {
  const json& m = params.contains("camera_matrix") ? params["camera_matrix"] : json();
  const auto entry = [&](int r, int c) {
    if (!m.is_array() || m.size() != 3 || !m[r].is_array() || m[r].size() != 3 ||
        !m[r][c].is_number())
      Fail(path, where + ".camera_matrix is not a 3x3 matrix of numbers");
    return m[r][c].get<double>();
  };
  camera->fx = entry(0, 0);
  camera->fy = entry(1, 1);
  camera->cx = entry(0, 2);
  camera->cy = entry(1, 2);
  if (entry(0, 1) != 0 || entry(1, 0) != 0 || entry(2, 0) != 0 || entry(2, 1) != 0 ||
      entry(2, 2) != 1)
    Fail(path, where + ".camera_matrix has skew or is not [[fx,0,cx],[0,fy,cy],[0,0,1]]");
  if (!(camera->fx > 0 && camera->fy > 0) || !std::isfinite(camera->fx) ||
      !std::isfinite(camera->fy) || !std::isfinite(camera->cx) || !std::isfinite(camera->cy))
    Fail(path, where + ".camera_matrix: focal lengths must be positive and finite");
}

std::vector<double> Coefficients(const json& params, const std::string& where,
                                 const std::string& path) {
  const json& d = params.contains("distortion_coeffs") ? params["distortion_coeffs"] : json();
  if (!d.is_array()) Fail(path, where + ".distortion_coeffs is not a list");
  std::vector<double> out;
  for (const json& c : d) {
    if (!c.is_number() || !std::isfinite(c.get<double>()))
      Fail(path, where + ".distortion_coeffs holds " + c.dump());
    out.push_back(c.get<double>());
  }
  return out;
}

// Which model the profile holds: Gyroflow's distortion_model when set, else its two flags.
void ReadLens(const json& j, LensProfile* p) {
  const std::string& path = p->path;
  std::string model = TextOr(j, "distortion_model");
  if (j.contains("distortion_model") && !j["distortion_model"].is_null() &&
      !j["distortion_model"].is_string())
    Fail(path, "distortion_model is not a name");
  if (model.empty()) {
    const bool standard =
        j.value("use_opencv_standard", false) && !j.value("use_opencv_fisheye", false);
    model = standard ? "opencv_standard" : "opencv_fisheye";
  }
  if (j.contains("digital_lens") && !j["digital_lens"].is_null())
    Fail(path,
         "digital_lens " + j["digital_lens"].dump() +
             ": an in-camera remapping after the lens (GoPro SuperView, ...) is not modelled");
  for (const char* key : {"input_horizontal_stretch", "input_vertical_stretch"}) {
    const double stretch = NumberOr(j, key, 1.0, path);
    if (stretch != 0 && std::abs(stretch - 1.0) > 1e-9)
      Fail(path, std::string(key) + " " + FormatNumber("%g", stretch) +
                     ": a profile of stretched (anamorphic) frames is not modelled");
  }
  if (model == "opencv_fisheye") {
    const json& params = j.contains("fisheye_params") ? j["fisheye_params"] : json::object();
    ReadCameraMatrix(params, "fisheye_params", &p->camera, path);
    const std::vector<double> k = Coefficients(params, "fisheye_params", path);
    if (k.size() != 4)
      Fail(path, "fisheye_params.distortion_coeffs has " + std::to_string(k.size()) +
                     " coefficients, the OpenCV fisheye model 4 (k1 k2 k3 k4)");
    p->camera.distortion = Fisheye({k[0], k[1], k[2], k[3]});
    p->rms_error_px = NumberOr(params, "RMS_error", 0.0, path);
  } else if (model == "opencv_standard") {
    const json& params = j.contains("calib_params") ? j["calib_params"] : json::object();
    ReadCameraMatrix(params, "calib_params", &p->camera, path);
    const std::vector<double> k = Coefficients(params, "calib_params", path);
    // OpenCV's k1 k2 p1 p2 [k3 [k4 k5 k6 ...]]: the rational and thin-prism terms must be 0.
    if (k.size() < 4) Fail(path, "calib_params.distortion_coeffs has fewer than 4 coefficients");
    for (size_t i = 5; i < k.size(); ++i) {
      if (k[i] != 0)
        Fail(path, "calib_params.distortion_coeffs[" + std::to_string(i) +
                       "] is not 0: OpenCV's rational / thin-prism terms are not modelled");
    }
    p->camera.distortion = BrownConrady{{k[0], k[1], k[2], k[3], k.size() > 4 ? k[4] : 0.0}};
    p->rms_error_px = NumberOr(params, "RMS_error", 0.0, path);
  } else {
    Fail(path, "distortion_model '" + model +
                   "' is not one shutterlab models (opencv_fisheye, opencv_standard)");
  }
}

ProfileReadout ReadCompatible(const json& c, const std::string& path) {
  if (!c.is_object()) Fail(path, "compatible_settings holds " + c.dump());
  ProfileReadout mode;
  mode.width = PixelsOr(c, "width", path);
  mode.height = PixelsOr(c, "height", path);
  mode.fps = NumberOr(c, "fps", 0, path);
  ReadReadout(c, "frame_readout_time", &mode, path);
  return mode;
}

std::string SizeText(int width, int height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

std::string ModeText(const ProfileReadout& mode) {
  return SizeText(mode.width, mode.height) +
         (mode.fps > 0 ? " at " + FormatNumber("%.3g", mode.fps) + " fps" : "");
}

LensProfile FromGyroflowProfile(const json& j, const std::string& path) {
  LensProfile p;
  p.path = path;
  try {
    p.name = TextOr(j, "name");
    if (p.name.empty()) {
      for (const char* key : {"camera_brand", "camera_model", "lens_model"}) {
        const std::string part = TextOr(j, key);
        if (!part.empty()) p.name += (p.name.empty() ? "" : " ") + part;
      }
    }
    if (p.name.empty()) p.name = std::filesystem::path(path).stem().string();
    p.calibrated_by = TextOr(j, "calibrated_by");
    p.official = j.value("official", false);
    const json& size = j.contains("calib_dimension") ? j["calib_dimension"] : json::object();
    p.mode.width = PixelsOr(size, "w", path);
    p.mode.height = PixelsOr(size, "h", path);
    if (p.mode.width <= 0 || p.mode.height <= 0)
      Fail(path, "calib_dimension " + size.dump() + " is not a positive size");
    p.mode.fps = NumberOr(j, "fps", 0, path);
    ReadReadout(j, "frame_readout_time", &p.mode, path);
    ReadLens(j, &p);
    p.camera.width = p.mode.width;
    p.camera.height = p.mode.height;
    if (j.contains("compatible_settings") && j["compatible_settings"].is_array()) {
      for (const json& c : j["compatible_settings"])
        p.compatible.push_back(ReadCompatible(c, path));
    }
  } catch (const json::exception& e) {
    Fail(path, std::string("malformed lens profile: ") + e.what());
  }
  return p;
}

// A Gyroflow project (.gyroflow, Gyroflow's src/core/lib.rs): its lens in "calibration_data" (a
// lens profile) and the readout set for the clip in "stabilization": frame_readout_time (ms) and
// frame_readout_direction (Gyroflow's name or number), which win over the profile's.
LensProfile FromGyroflowProject(const json& j, const std::string& path) {
  if (!j["calibration_data"].is_object())
    Fail(path, "a Gyroflow project whose calibration_data is not a lens profile");
  LensProfile p = FromGyroflowProfile(j["calibration_data"], path);
  p.name = "Gyroflow project's " + p.name;
  const json& s = j.contains("stabilization") ? j["stabilization"] : json::object();
  if (!s.is_object()) Fail(path, "stabilization is not an object");
  ProfileReadout readout = p.mode;
  readout.readout_s.reset();
  ReadReadout(s, "frame_readout_time", &readout, path);
  if (!readout.readout_s) return p;
  readout.direction = ReadoutDirection::kTopToBottom;
  if (s.contains("frame_readout_direction")) {
    const json& d = s["frame_readout_direction"];
    bool known = false;
    for (ReadoutDirection candidate :
         {ReadoutDirection::kTopToBottom, ReadoutDirection::kBottomToTop,
          ReadoutDirection::kLeftToRight, ReadoutDirection::kRightToLeft}) {
      if ((d.is_string() && d.get<std::string>() == GyroflowReadoutDirectionName(candidate)) ||
          (d.is_number_integer() && d.get<int>() == static_cast<int>(candidate))) {
        readout.direction = candidate;
        known = true;
      }
    }
    if (!known)
      Fail(path, "stabilization.frame_readout_direction " + d.dump() + " is not one of Gyroflow's");
  }
  p.mode = readout;
  return p;
}

}  // namespace

LensProfile ReadLensProfile(const std::string& path) {
  const std::string text = ReadFileToString(path);
  json j = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded() || !j.is_object())
    Fail(path, "not a lens profile, a Gyroflow project or OpenSfM cameras (a JSON object)");
  try {
    if (IsOpenSfmCameras(j)) {
      const OpenSfmCamera opensfm = ReadOpenSfmCamera(j, path);
      LensProfile p;
      p.path = path;
      p.name = "OpenSfM camera " + opensfm.key;
      p.camera = opensfm.camera;
      p.mode.width = p.camera.width;
      p.mode.height = p.camera.height;
      return p;
    }
    if (j.contains("calibration_data")) return FromGyroflowProject(j, path);
  } catch (const json::exception& e) {
    Fail(path, std::string("malformed camera: ") + e.what());
  }
  return FromGyroflowProfile(j, path);
}

LensProfileUse ScaleLensProfile(const LensProfile& profile, int width, int height,
                                std::optional<double> fps) {
  SHUTTERLAB_CHECK(width > 0 && height > 0) << "image size " << width << "x" << height;
  LensProfileUse use;
  use.path = profile.path;
  use.name = profile.name;
  use.calib_width = profile.camera.width;
  use.calib_height = profile.camera.height;
  use.width = width;
  use.height = height;
  use.scale_x = static_cast<double>(width) / profile.camera.width;
  use.scale_y = static_cast<double>(height) / profile.camera.height;
  use.aspect_differs = std::abs(use.scale_x / use.scale_y - 1.0) > kAspectTolerance;
  PinholeCamera& c = use.camera;
  c = profile.camera;
  c.width = width;
  c.height = height;
  c.fx = profile.camera.fx * use.scale_x;
  c.fy = profile.camera.fy * use.scale_y;
  c.cx = (profile.camera.cx + 0.5) * use.scale_x - 0.5;
  c.cy = (profile.camera.cy + 0.5) * use.scale_y - 0.5;
  std::string line = "lens profile " + profile.name + " (" + LensModelName(c.distortion) +
                     ", calibrated at " + SizeText(use.calib_width, use.calib_height);
  if (!profile.calibrated_by.empty()) line += " by " + profile.calibrated_by;
  line += profile.official ? ", official" : "";
  line += ", RMS " + FormatNumber("%.2f", profile.rms_error_px) + " px)";
  if (width == use.calib_width && height == use.calib_height) {
    line += " used at its own size";
  } else {
    line += " scaled to " + SizeText(width, height) + ": fx " + FormatNumber("%.1f", c.fx) +
            ", fy " + FormatNumber("%.1f", c.fy) + ", cx " + FormatNumber("%.1f", c.cx) + ", cy " +
            FormatNumber("%.1f", c.cy);
  }
  use.notes.push_back(line);
  if (use.aspect_differs) {
    use.notes.push_back(
        "the image's aspect " + FormatNumber("%.4f", static_cast<double>(width) / height) +
        " differs from the profile's " +
        FormatNumber("%.4f", static_cast<double>(use.calib_width) / use.calib_height) + " by " +
        FormatNumber("%.2f", 100.0 * std::abs(use.scale_x / use.scale_y - 1.0)) +
        " %: x and y scaled apart (" + FormatNumber("%.4f", use.scale_x) + ", " +
        FormatNumber("%.4f", use.scale_y) +
        "), as for a stretched copy; were the image a crop, one focal length would be off by as "
        "much");
  }
  // The readout: a compatible setting of this very size (and frame rate), else the profile's own.
  const auto fps_matches = [&](double mode_fps) {
    return !fps || mode_fps <= 0 || std::abs(mode_fps / *fps - 1.0) <= kFpsTolerance;
  };
  for (const ProfileReadout& mode : profile.compatible) {
    if (mode.readout_s && mode.width == width && mode.height == height && fps_matches(mode.fps)) {
      use.readout = mode;
      break;
    }
  }
  if (!use.readout && profile.mode.readout_s) use.readout = profile.mode;
  if (use.readout) {
    use.notes.push_back("the profile's frame readout " +
                        FormatNumber("%.3f", *use.readout->readout_s * 1e3) + " ms (" +
                        ReadoutDirectionName(use.readout->direction) + ", stated for " +
                        ModeText(*use.readout) + ")");
  } else {
    use.notes.push_back("the profile states no frame readout");
  }
  return use;
}

void ApplyLensProfile(LensProfileUse* use, RigModel* rig, bool keep_readout) {
  SHUTTERLAB_CHECK(rig->camera.width == use->width && rig->camera.height == use->height)
      << "the profile was scaled to " << use->width << "x" << use->height << ", the rig is "
      << rig->camera.width << "x" << rig->camera.height;
  rig->camera = use->camera;
  if (!use->readout) return;
  if (keep_readout) {
    use->notes.push_back("readout " + FormatNumber("%.3f", rig->shutter.readout_s * 1e3) +
                         " ms kept (it wins over the profile's)");
    use->readout.reset();
    return;
  }
  use->notes.push_back("readout " + FormatNumber("%.3f", *use->readout->readout_s * 1e3) + " ms " +
                       ReadoutDirectionName(use->readout->direction) +
                       " from the profile replaces " +
                       FormatNumber("%.3f", rig->shutter.readout_s * 1e3) + " ms " +
                       ReadoutDirectionName(rig->shutter.direction));
  rig->shutter.readout_s = *use->readout->readout_s;
  rig->shutter.direction = use->readout->direction;
}

nlohmann::json LensProfileUseJson(const LensProfileUse& use) {
  json j;
  j["path"] = use.path;
  j["name"] = use.name;
  j["model"] = LensModelName(use.camera.distortion);
  j["calibration_size"] = {use.calib_width, use.calib_height};
  j["image_size"] = {use.width, use.height};
  j["scale"] = {use.scale_x, use.scale_y};
  j["aspect_differs"] = use.aspect_differs;
  j["intrinsics"] = {
      {"fx", use.camera.fx}, {"fy", use.camera.fy}, {"cx", use.camera.cx}, {"cy", use.camera.cy}};
  j["distortion"] = DistortionJson(use.camera.distortion);
  j["readout_s"] = use.readout ? json(*use.readout->readout_s) : json(nullptr);
  j["readout_source"] = use.readout ? "frame_readout_time for " + ModeText(*use.readout) : "";
  j["notes"] = use.notes;
  return j;
}

}  // namespace shutterlab
