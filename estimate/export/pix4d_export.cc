#include "estimate/export/pix4d_export.h"

#include "model/lens_distortion.h"
#include "sim/readout_direction.h"
#include "sim/text_file.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <stdexcept>
#include <string>
#include <variant>

namespace shutterlab {

ExportOutput Pix4dExport(const ExportCamera& camera, const ExportOptions& options) {
  const RigModel& rig = camera.truth.rig;
  const PinholeCamera& c = rig.camera;
  const auto* brown = std::get_if<BrownConrady>(&c.distortion);
  if (!brown) {
    throw std::invalid_argument(
        "OPF's fisheye model is Pix4D's polynomial, not OpenCV's: a fisheye lens is not exported "
        "to Pix4D (export it --to colmap or --to kalibr)");
  }
  ExportOutput out;
  const double focal_px = 0.5 * (c.fx + c.fy);
  // The mean focal length moves a corner's pixel by up to half the difference times its distance
  // from the principal point in focal lengths.
  const double corner_px =
      0.5 * std::abs(c.fx - c.fy) *
      std::max(std::hypot(c.cx, c.cy), std::hypot(c.width - c.cx, c.height - c.cy)) / focal_px;
  RequireCarried(c.fx == c.fy,
                 "OPF has one focal length; the camera's fx " + ExportNumber(c.fx) + " and fy " +
                     ExportNumber(c.fy) + " px differ (their mean moves the corners by up to " +
                     FormatNumber("%.2g", corner_px) + " px)",
                 options, &out.notes);
  const auto& k = brown->coeffs;  // OpenCV's k1 k2 p1 p2 k3
  nlohmann::json sensor = {{"id", 1},
                           {"internals",
                            {{"type", "perspective"},
                             {"principal_point_px", {c.cx + 0.5, c.cy + 0.5}},
                             {"focal_length_px", focal_px},
                             {"radial_distortion", {k[0], k[1], k[4]}},
                             {"tangential_distortion", {k[2], k[3]}}}}};
  nlohmann::json rolling = {{"readout_time_s", nullptr}};
  if (camera.readout_known) {
    RequireDetermined(camera, "readout_time", options, &out.notes);
    RequireDetermined(camera, "readout_direction", options, &out.notes);
    rolling = {{"shutter_type", rig.shutter.readout_s > 0.0 ? "rolling" : "global"},
               {"readout_time_s", rig.shutter.readout_s},
               {"readout_direction", ReadoutDirectionName(rig.shutter.direction)},
               {"frame_time_row", "first"}};
  }
  sensor["extensions"] = {{"SHUTTERLAB_rolling_shutter", rolling}};
  const nlohmann::json calibrated = {{"format", "application/opf-calibrated-cameras+json"},
                                     {"version", "1.0"},
                                     {"sensors", {sensor}},
                                     {"cameras", nlohmann::json::array()}};
  out.files.push_back({"calibrated_cameras.json", calibrated.dump(2) + "\n",
                       "OPF's calibrated camera (one sensor, no shots)"});
  out.notes.push_back(
      "principal_point_px = (cx + 0.5, cy + 0.5): OPF's (0, 0) is the top-left pixel's corner");
  out.notes.push_back("radial_distortion [k1, k2, k3], tangential_distortion [p1, p2] (OpenCV's)");
  if (c.fx != c.fy) out.notes.push_back("focal_length_px = (fx + fy) / 2");
  out.notes.push_back(
      "the readout is in the sensor's extension SHUTTERLAB_rolling_shutter: OPF has no field for "
      "it; its per-image rolling_shutter 3-vector and the XMP Camera:LineReadoutTime are not "
      "written (Pix4D documents neither their meaning nor their unit)");
  AddSideNote("pix4d", camera, &out);
  return out;
}

}  // namespace shutterlab
