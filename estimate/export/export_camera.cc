#include "estimate/export/export_camera.h"

#include "model/camera.h"
#include "model/effects.h"
#include "model/reported_model.h"
#include "sim/check.h"
#include "sim/text_file.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <utility>
#include <variant>

namespace shutterlab {
namespace {

namespace fs = std::filesystem;

// A number, 3 numbers or a 3x3 matrix (a scalar effect's, gyro_scale's or bias's, the mounting's
// standard errors) with an entry that is not a number: the data did not determine the effect. A
// lens's declared coefficients have NaN standard errors by design (model/effects.h), and a
// direction has none: neither counts.
bool NotANumberIn(const EffectValue& stderr_value) {
  if (const double* x = std::get_if<double>(&stderr_value)) return !std::isfinite(*x);
  if (const auto* v = std::get_if<Eigen::Vector3d>(&stderr_value)) return !v->allFinite();
  if (const auto* m = std::get_if<Eigen::Matrix3d>(&stderr_value)) return !m->allFinite();
  return false;
}

// A value the report's model carries unfitted is the declared one. A claim of the report
// (validate's "claims") that the data contradicted, or a guess or an inference of the importer's
// (import.json's status) that they could not test, marks its effect as not determined; the
// source's own statement that they could not test is exported as stated, and the side note says
// so.
void MarkUntestedClaims(const ReportedModel& report, const std::set<std::string>& fitted,
                        ExportCamera* camera) {
  for (const ReportedClaim& claim : report.claims) {
    if (claim.effect.empty() || fitted.count(claim.effect) ||
        claim.verdict.rfind("claim holds", 0) == 0)
      continue;
    const std::string status = claim.status.empty() ? "claim" : claim.status;
    const std::string what = (claim.claim.empty() ? claim.effect : claim.claim) + " (" + status +
                             "), which the report's check found " +
                             (claim.verdict.empty() ? "no verdict for" : claim.verdict);
    const bool contradicted = claim.verdict.rfind("claim contradicted", 0) == 0;
    if (!contradicted && claim.status.rfind("source claim", 0) == 0) {
      camera->notes.push_back(claim.effect + " is the source's own " + what +
                              ": exported as stated");
    } else {
      camera->undetermined[claim.effect] = "the declared " + what;
    }
  }
}

ExportCamera FromReport(const std::string& path) {
  const ReportedModel report = ReadValidationReport(path);
  if (!report.fitted) {
    throw IoError(IoMessage(path, 0,
                            "the report has no \"fitted_model\" (a report of another tool or an "
                            "older version): export the dataset's camera.json instead"));
  }
  ExportCamera camera;
  camera.source = "validation report " + path;
  camera.truth = *report.fitted;
  std::set<std::string> fitted_names;
  for (const ReportedEffect& effect : report.effects) {
    const std::string name = Spec(effect.effect).name;
    fitted_names.insert(name);
    const EffectValue se = effect.covariance.size() == 0
                               ? EffectValue()
                               : EffectStderr(effect.effect, camera.truth, effect.covariance);
    if (NotANumberIn(se))
      camera.undetermined[name] = "fitted, with a standard error that is not a number";
    const double* scalar_se = std::get_if<double>(&se);
    const std::optional<double> scalar =
        scalar_se ? std::optional<double>(*scalar_se) : std::nullopt;
    if (effect.effect == Effect::kTimeOffset) camera.time_offset_stderr_s = scalar;
    if (effect.effect == Effect::kReadoutTime) camera.readout_stderr_s = scalar;
    if (effect.effect == Effect::kClockRate) camera.clock_rate_stderr_ppm = scalar;
    camera.fitted.push_back({name, Spec(effect.effect).unit, effect.value, se});
  }
  MarkUntestedClaims(report, fitted_names, &camera);
  return camera;
}

ExportCamera FromCameraJson(const std::string& path) {
  ExportCamera camera;
  camera.source = "camera.json " + path;
  camera.truth.rig = ReadRigModel(path);
  return camera;
}

// A photo's capture_time ({"camera_clock": "2024-07-16 09:41:37.000", "utc": ...} of analyze
// --photos --json) in ISO 8601: UTC with its Z when known, the camera clock's face without a zone
// otherwise; "" when it has none.
std::string IsoCaptureTime(const nlohmann::json& photo) {
  if (!photo.contains("capture_time") || !photo["capture_time"].is_object()) return "";
  const nlohmann::json& t = photo["capture_time"];
  const bool utc = t.contains("utc") && t["utc"].is_string();
  if (!utc && !(t.contains("camera_clock") && t["camera_clock"].is_string())) return "";
  std::string iso = t[utc ? "utc" : "camera_clock"].get<std::string>();
  const size_t space = iso.find(' ');
  if (space != std::string::npos) iso[space] = 'T';
  return utc ? iso + "Z" : iso;
}

}  // namespace

// The camera of the first photo with a size and a focal length, its readout: the whole camera
// where camera.json or a lens profile gave one ("camera"), else the principal point at the centre
// and no lens distortion (the photos' metadata give none).
ExportCamera ExportCameraFromPhotos(const nlohmann::json& photos, const std::string& source) {
  ExportCamera camera;
  camera.source = source;
  camera.gyro_known = false;
  bool have_camera = false;
  for (const nlohmann::json& p : photos) {
    if (!p.is_object() || p.contains("error")) continue;
    ExportPhoto photo;
    photo.name = p.value("name", "");
    photo.path = p.value("path", "");
    photo.width = p.value("width", 0);
    photo.height = p.value("height", 0);
    if (p.contains("readout_s") && p["readout_s"].is_number())
      photo.readout_s = p["readout_s"].get<double>();
    if (p.contains("speed_m_s") && p["speed_m_s"].is_number())
      photo.speed_m_s = p["speed_m_s"].get<double>();
    if (p.contains("focal_mm") && p["focal_mm"].is_number())
      photo.focal_mm = p["focal_mm"].get<double>();
    if (p.contains("focal_plane_px_per_mm") && p["focal_plane_px_per_mm"].is_number())
      photo.focal_plane_px_per_mm = p["focal_plane_px_per_mm"].get<double>();
    photo.capture_time = IsoCaptureTime(p);
    if (p.contains("flagged") && p["flagged"].is_object()) {
      for (const auto& [limit, flag] : p["flagged"].items())
        photo.flagged = photo.flagged || (flag.is_boolean() && flag.get<bool>());
    }
    const bool has_focal = p.contains("focal_px") && p["focal_px"].is_number();
    if (!have_camera && photo.width > 0 && photo.height > 0 && has_focal) {
      PinholeCamera& c = camera.truth.rig.camera;
      c.width = photo.width;
      c.height = photo.height;
      c.fx = c.fy = p["focal_px"].get<double>();
      c.cx = 0.5 * (photo.width - 1);
      c.cy = 0.5 * (photo.height - 1);
      if (p.contains("camera") && p["camera"].is_object()) {  // camera.json's or a lens profile's
        const nlohmann::json& given = p["camera"];
        c.fx = given.value("fx", c.fx);
        c.fy = given.value("fy", c.fy);
        c.cx = given.value("cx", c.cx);
        c.cy = given.value("cy", c.cy);
        if (given.contains("distortion")) c.distortion = DistortionFromJson(given["distortion"]);
        camera.camera_given = true;
      }
      camera.make = p.value("make", "");
      camera.model = p.value("model", "");
      camera.readout_known = photo.readout_s.has_value();
      camera.truth.rig.shutter.readout_s = photo.readout_s.value_or(0.0);
      have_camera = true;
    }
    camera.photos.push_back(std::move(photo));
  }
  if (!have_camera) {
    throw IoError(IoMessage(source, 0,
                            "no photo with a size and a focal length: nothing to export (give "
                            "analyze --photos --focal-px, or a camera.json)"));
  }
  return camera;
}

ExportCamera ReadExportSource(const std::string& path) {
  if (fs::is_directory(path)) {
    const std::string camera_json = (fs::path(path) / "camera.json").string();
    if (!fs::is_regular_file(camera_json)) {
      throw IoError(IoMessage(path, 0,
                              "a folder without camera.json: give a rig dataset, a correction's "
                              "output, a validation report or an analyze --photos --json result"));
    }
    ExportCamera camera = FromCameraJson(camera_json);
    if (fs::is_directory(fs::path(path) / "masks"))
      camera.masks_dir = fs::absolute(fs::path(path) / "masks").lexically_normal().string();
    const fs::path record = fs::path(path) / "correct.json";
    if (fs::is_regular_file(record)) {
      const nlohmann::json correct = nlohmann::json::parse(ReadFileToString(record.string()),
                                                           nullptr, /*allow_exceptions=*/false);
      const std::string root =
          correct.is_object() && correct.value("image_root", nlohmann::json()).is_string()
              ? correct["image_root"].get<std::string>()
              : "";
      if (!root.empty() && fs::is_directory(fs::path(path) / root))
        camera.images_dir = fs::absolute(fs::path(path) / root).lexically_normal().string();
    }
    return camera;
  }
  const std::string text = ReadFileToString(path);
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw IoError(IoMessage(path, 0, std::string("not JSON: ") + e.what()));
  }
  const std::string format = json.is_object() ? json.value("format", "") : "";
  if (format.rfind("validation/", 0) == 0) return FromReport(path);
  if (format.rfind("rig/", 0) == 0) return FromCameraJson(path);
  if (json.is_object() && json.contains("photos")) {
    const nlohmann::json& photos = json["photos"];
    const std::string source = "analyze --photos result " + path;
    if (photos.is_array()) return ExportCameraFromPhotos(photos, source);
    // With a LOG, the photos' result sits under "photos" beside analyze's own.
    if (photos.is_object() && photos.contains("photos") && photos["photos"].is_array())
      return ExportCameraFromPhotos(photos["photos"], source);
  }
  throw IoError(IoMessage(path, 0,
                          "not a validation report (validation/1), a camera.json (rig/1) or an "
                          "analyze --photos --json result"));
}

}  // namespace shutterlab
