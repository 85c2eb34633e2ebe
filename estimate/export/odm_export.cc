#include "estimate/export/odm_export.h"

#include "model/lens_distortion.h"
#include "sim/readout_direction.h"
#include "sim/text_file.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <variant>

namespace shutterlab {

ExportOutput OdmExport(const ExportCamera& camera, const ExportOptions& options) {
  const RigModel& rig = camera.truth.rig;
  const PinholeCamera& c = rig.camera;
  ExportOutput out;
  const double s = std::max(c.width, c.height);
  nlohmann::json model = {{"width", c.width},
                          {"height", c.height},
                          {"focal_x", c.fx / s},
                          {"focal_y", c.fy / s},
                          {"c_x", (c.cx + 0.5 - 0.5 * c.width) / s},
                          {"c_y", (c.cy + 0.5 - 0.5 * c.height) / s}};
  if (const auto* brown = std::get_if<BrownConrady>(&c.distortion)) {
    const auto& k = brown->coeffs;  // k1 k2 p1 p2 k3
    model["projection_type"] = "brown";
    model["k1"] = k[0], model["k2"] = k[1], model["p1"] = k[2], model["p2"] = k[3];
    model["k3"] = k[4];
  } else {
    const auto& k = std::get<Fisheye>(c.distortion).coeffs();
    model["projection_type"] = "fisheye_opencv";
    model["k1"] = k[0], model["k2"] = k[1], model["k3"] = k[2], model["k4"] = k[3];
    out.notes.push_back(
        "ODM's --cameras drops k4 (opendm/camera.py): use "
        "camera_models_overrides.json, which OpenSfM reads whole");
  }
  const nlohmann::json overrides = {{"all", model}};
  out.files.push_back({"camera_models_overrides.json", overrides.dump(2) + "\n",
                       "OpenSfM's camera for every image, for the project's opensfm/ folder"});
  out.notes.push_back("focal lengths and principal point normalised by the larger side " +
                      ExportNumber(s) +
                      " px, from the image centre, with OpenSfM's half-pixel "
                      "shift (c_x = (cx + 0.5 - W/2) / S)");
  if (camera.readout_known) {
    RequireDetermined(camera, "readout_time", options, &out.notes);
    RequireDetermined(camera, "readout_direction", options, &out.notes);
    const bool top_down = rig.shutter.direction == ReadoutDirection::kTopToBottom;
    RequireCarried(top_down,
                   "ODM's rolling-shutter correction reads top to bottom; the camera reads " +
                       std::string(ReadoutDirectionName(rig.shutter.direction)) +
                       ": its readout options",
                   options, &out.notes);
  }
  if (camera.readout_known && rig.shutter.direction == ReadoutDirection::kTopToBottom) {
    const long readout_ms = std::lround(rig.shutter.readout_s * 1e3);
    out.files.push_back(
        {"odm_args.txt",
         "--rolling-shutter --rolling-shutter-readout " + std::to_string(readout_ms) + "\n",
         "ODM's rolling-shutter options"});
    out.notes.push_back("readout " + FormatNumber("%.6g", rig.shutter.readout_s * 1e3) +
                        " ms written as " + std::to_string(readout_ms) +
                        " ms: ODM takes whole milliseconds");
  } else if (!camera.readout_known) {
    out.notes.push_back(
        "no readout in the source: odm_args.txt not written (ODM then takes its "
        "own database's, or 30 ms)");
  }
  if (!camera.photos.empty()) {
    std::string list;
    for (const ExportPhoto& photo : camera.photos) {
      if (!photo.flagged) list += (photo.path.empty() ? photo.name : photo.path) + "\n";
    }
    out.files.push_back({"image_list.txt", list, "the photos not flagged, as OpenSfM lists them"});
  }
  AddSideNote("odm", camera, &out);
  return out;
}

}  // namespace shutterlab
