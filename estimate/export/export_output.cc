#include "estimate/export/export_output.h"

#include "model/camera.h"
#include "model/effects.h"
#include "model/lens_distortion.h"
#include "sim/check.h"
#include "sim/readout_direction.h"
#include "sim/text_file.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <variant>

namespace shutterlab {

std::string ExportNumber(double value) {
  char text[40];
  for (int digits = 15; digits <= 17; ++digits) {
    std::snprintf(text, sizeof text, "%.*g", digits, value);
    if (std::strtod(text, nullptr) == value) break;
  }
  return text;
}

void RequireDetermined(const ExportCamera& camera, const std::string& name,
                       const ExportOptions& options, std::vector<std::string>* notes) {
  const auto why = camera.undetermined.find(name);
  if (why == camera.undetermined.end()) return;
  const std::string what = name + " was not determined by the data (" + why->second + ")";
  if (!options.force) throw std::invalid_argument(what + ": not exported (--force writes it)");
  notes->push_back(what + "; written anyway (--force)");
}

void RequireCarried(bool carried, const std::string& what, const ExportOptions& options,
                    std::vector<std::string>* notes) {
  if (carried) return;
  if (!options.force) throw std::invalid_argument(what + " (--force writes the rest)");
  notes->push_back(what + "; the rest written (--force)");
}

void RequireGyroRelation(const ExportCamera& camera, const std::string& tool,
                         const std::string& offset_name, const ExportOptions& options,
                         std::vector<std::string>* notes) {
  RequireCarried(camera.gyro_known,
                 "the source relates no gyro to the camera (photos alone): " + tool +
                     " needs the mounting and the " + offset_name +
                     ", from a validation report (--force: identity and 0)",
                 options, notes);
  RequireDetermined(camera, "time_offset", options, notes);
  RequireDetermined(camera, "gyro_to_camera", options, notes);
  RequireCarried(camera.truth.clock_rate_ppm == 0.0,
                 tool + "'s " + offset_name + " is constant; the gyro clock runs " +
                     ExportNumber(camera.truth.clock_rate_ppm) + " ppm fast",
                 options, notes);
}

void NoteGyroCalibrationNotCarried(const ExportCamera& camera, const std::string& file,
                                   std::vector<std::string>* notes) {
  if (camera.truth.gyro_scale == Eigen::Vector3d::Ones() &&
      camera.truth.gyro_bias_rad_s == Eigen::Vector3d::Zero())
    return;
  notes->push_back("the gyro's scale and bias are not part of " + file +
                   ": see the side note's model");
}

namespace {

std::string LensText(const LensDistortion& lens) {
  std::string text = LensModelName(lens);
  if (const auto* brown = std::get_if<BrownConrady>(&lens)) {
    const char* names[] = {"k1", "k2", "p1", "p2", "k3"};
    for (int i = 0; i < 5; ++i)
      text += std::string(" ") + names[i] + " " + ExportNumber(brown->coeffs[i]);
  } else {
    const auto& k = std::get<Fisheye>(lens).coeffs();
    for (int i = 0; i < 4; ++i) text += " k" + std::to_string(i + 1) + " " + ExportNumber(k[i]);
  }
  return text;
}

}  // namespace

void AddSideNote(const char* format, const ExportCamera& camera, ExportOutput* output) {
  const RigModel& rig = camera.truth.rig;
  const PinholeCamera& c = rig.camera;
  std::string text = std::string("shutterlab export --to ") + format + "\n";
  text += "source: " + camera.source + "\n";
  if (!camera.make.empty() || !camera.model.empty())
    text += "camera: " + camera.make + " " + camera.model + "\n";
  text +=
      "as shutterlab holds it (docs/FORMATS.md: OpenCV pixel centres, the top-left pixel's at "
      "(0, 0); a frame's time is its first row read's; gyro clock = camera clock + "
      "time_offset_s):\n";
  text += "  image " + std::to_string(c.width) + " x " + std::to_string(c.height) + " px, fx " +
          ExportNumber(c.fx) + ", fy " + ExportNumber(c.fy) + ", cx " + ExportNumber(c.cx) +
          ", cy " + ExportNumber(c.cy) + " px\n";
  text += "  lens " + LensText(c.distortion) + "\n";
  // A standard error where the source gives one (a validation report's covariance): the files of
  // most tools have no place for it.
  const auto stderr_text = [](const std::optional<double>& se) {
    return se && std::isfinite(*se) ? " +- " + ExportNumber(*se) : std::string();
  };
  text += camera.readout_known ? "  readout " + ExportNumber(rig.shutter.readout_s) +
                                     stderr_text(camera.readout_stderr_s) + " s, " +
                                     ReadoutDirectionName(rig.shutter.direction) + "\n"
                               : std::string("  readout unknown\n");
  text += "  time_offset " + ExportNumber(rig.time_offset_s) +
          stderr_text(camera.time_offset_stderr_s) + " s, clock_rate " +
          ExportNumber(camera.truth.clock_rate_ppm) + stderr_text(camera.clock_rate_stderr_ppm) +
          " ppm (+- one standard error, where the source gives it)\n";
  if (!camera.fitted.empty()) {
    text +=
        "  fitted by the source, each with one standard error in its value's shape (null: not "
        "determined; none: the source gives none):\n";
    for (const ExportCamera::Fitted& f : camera.fitted) {
      const bool has_stderr = !std::holds_alternative<std::monostate>(f.stderr_value);
      text += "    " + f.name + " " + EffectValueText(f.value) + " +- " +
              (has_stderr ? EffectValueText(f.stderr_value) : std::string("none")) +
              (f.unit.empty() ? "" : " " + f.unit) + "\n";
    }
  }
  const Eigen::Matrix3d& r = rig.cam_from_gyro;
  text += "  gyro_to_camera (R_CG, rows)";
  for (int i = 0; i < 3; ++i) {
    text += " [" + ExportNumber(r(i, 0)) + ", " + ExportNumber(r(i, 1)) + ", " +
            ExportNumber(r(i, 2)) + "]";
  }
  text += "\n";
  if (!camera.photos.empty()) text += "  photos " + std::to_string(camera.photos.size()) + "\n";
  text += "notes:\n";
  for (const std::string& note : camera.notes) text += "  - " + note + "\n";
  for (const std::string& note : output->notes) text += "  - " + note + "\n";
  output->files.push_back({"shutterlab_export.txt", text, "what was exported, from what, and how"});
}

std::vector<std::string> WriteExport(const ExportOutput& output, const std::string& out_dir) {
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec) throw IoError(IoMessage(out_dir, 0, "cannot create the folder: " + ec.message()));
  std::vector<std::string> written;
  for (const ExportFile& file : output.files) {
    const std::filesystem::path path = std::filesystem::path(out_dir) / file.name;
    std::filesystem::create_directories(path.parent_path(), ec);
    WriteFileAtomically(path.string(), file.text);
    written.push_back(path.string());
  }
  return written;
}

}  // namespace shutterlab
