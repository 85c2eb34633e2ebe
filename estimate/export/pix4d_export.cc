#include "estimate/export/pix4d_export.h"

#include "model/lens_distortion.h"
#include "sim/readout_direction.h"
#include "sim/text_file.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <variant>

namespace shutterlab {
namespace {

// A file name as a URI reference (RFC 3986): bytes other than unreserved ones and '/' as %XX.
std::string UriReference(const std::string& name) {
  std::string uri;
  for (const unsigned char c : name) {
    if (std::isalnum(c) || c == '-' || c == '.' || c == '_' || c == '~' || c == '/') {
      uri += static_cast<char>(c);
    } else {
      char escaped[4];
      std::snprintf(escaped, sizeof escaped, "%%%02X", c);
      uri += escaped;
    }
  }
  return uri;
}

// OPF's captures, one camera each, and camera list entries of the JPEG photos of the camera's size
// with a capture time; the notes say how many have none and that flagged photos keep theirs.
void AddCaptures(const ExportCamera& camera, nlohmann::json* captures, nlohmann::json* listed,
                 ExportOutput* out) {
  *captures = nlohmann::json::array();
  *listed = nlohmann::json::array();
  size_t left_out = 0, flagged = 0;
  const uint64_t photos = camera.photos.size();
  for (uint64_t k = 0; k < photos; ++k) {
    const ExportPhoto& p = camera.photos[k];
    if (p.width != camera.truth.rig.camera.width || p.height != camera.truth.rig.camera.height ||
        p.capture_time.empty() || !HasJpegExtension(p.name)) {
      ++left_out;
      continue;
    }
    if (p.flagged) ++flagged;
    // Unique in the project, the sensor's 1 included.
    const uint64_t camera_id = k + 2, capture_id = photos + k + 2;
    captures->push_back({{"id", capture_id},
                         {"reference_camera_id", camera_id},
                         {"cameras",
                          {{{"sensor_id", 1},
                            {"id", camera_id},
                            {"model_source", camera.camera_given ? "user" : "generic_from_exif"},
                            {"pixel_type", "uint8"},
                            {"pixel_range", {{"min", 0}, {"max", 255}}}}}},
                         {"rig_model_source", "not_applicable"},
                         {"time", p.capture_time}});
    listed->push_back({{"id", camera_id}, {"uri", UriReference(p.name)}});
  }
  if (flagged > 0) {
    // OPF's input cameras say what each capture is, not which to process: leaving a photo out
    // here would only lose its description, not keep Pix4D from using it.
    out->notes.push_back(
        "input_cameras.json describes the " + std::to_string(flagged) +
        " photo(s) flagged over a limit too (OPF's input cameras say what each capture is, not "
        "which to process): leave them out of the Pix4D project by hand, or correct them first "
        "with shutterlab correct; the ODM and COLMAP exports' image_list.txt leave them out");
  }
  if (left_out > 0) {
    out->notes.push_back(std::to_string(left_out) +
                         " photo(s) without a capture: not a JPEG of the camera's size, or "
                         "without a capture time");
  }
}

// OPF's input cameras and camera list of an analyze --photos result: the sensor (id 1, as the
// calibrated one; its pixel size from a photo's EXIF focal length in mm over the focal length in
// pixels, its shutter from the readout) and a capture of one camera for each JPEG photo of the
// camera's size with a capture time. Neither is written, and it is said, without a readout or a
// focal length in mm.
void AddInputCameras(const ExportCamera& camera, const nlohmann::json& internals,
                     ExportOutput* out) {
  const RigModel& rig = camera.truth.rig;
  const PinholeCamera& c = rig.camera;
  const auto of_camera = [&](const ExportPhoto& p) {
    return p.width == c.width && p.height == c.height;
  };
  // The pixel size as Pix4D finds it in EXIF: FocalPlaneXResolution, else the focal length in mm
  // over the focal length in pixels (which analyze takes from the 35 mm equivalent when it must).
  const auto first_of_camera = [&](auto has) {
    return std::find_if(camera.photos.begin(), camera.photos.end(),
                        [&](const ExportPhoto& p) { return of_camera(p) && has(p); });
  };
  auto sized = first_of_camera([](const ExportPhoto& p) {
    return p.focal_plane_px_per_mm && *p.focal_plane_px_per_mm > 0.0;
  });
  const bool focal_plane = sized != camera.photos.end();
  if (!focal_plane) {
    sized = first_of_camera([](const ExportPhoto& p) { return p.focal_mm && *p.focal_mm > 0.0; });
  }
  std::string lacking;
  if (!camera.readout_known) lacking = "a readout (OPF's shutter_type)";
  if (sized == camera.photos.end()) {
    lacking += std::string(lacking.empty() ? "" : " nor ") +
               "a FocalPlaneXResolution or focal length in mm (OPF's pixel_size_um)";
  }
  if (!lacking.empty()) {
    out->notes.push_back("input_cameras.json and camera_list.json not written: no photo gives " +
                         lacking + ", which OPF's input cameras require");
    return;
  }
  const double focal_px = 0.5 * (c.fx + c.fy);
  const double pixel_size_um =
      focal_plane ? 1000.0 / *sized->focal_plane_px_per_mm : 1000.0 * *sized->focal_mm / focal_px;
  const std::string name = camera.make.empty() ? "camera" : camera.make + " " + camera.model;
  const nlohmann::json sensor = {
      {"id", 1},
      {"name", name + " " + std::to_string(c.width) + "x" + std::to_string(c.height)},
      {"bands",
       {{{"name", "Red"}, {"weight", 0.2126}},
        {{"name", "Green"}, {"weight", 0.7152}},
        {{"name", "Blue"}, {"weight", 0.0722}}}},
      {"image_size_px", {c.width, c.height}},
      {"pixel_size_um", pixel_size_um},
      {"internals", internals},
      {"shutter_type", rig.shutter.readout_s > 0.0 ? "rolling" : "global"}};
  nlohmann::json captures, listed;
  AddCaptures(camera, &captures, &listed, out);
  const nlohmann::json input = {{"format", "application/opf-input-cameras+json"},
                                {"version", "1.0"},
                                {"sensors", {sensor}},
                                {"captures", captures}};
  const nlohmann::json list = {
      {"format", "application/opf-camera-list+json"}, {"version", "1.0"}, {"cameras", listed}};
  out->files.push_back({"input_cameras.json", input.dump(2) + "\n",
                        "OPF's input cameras (the sensor, a capture a photo)"});
  out->files.push_back({"camera_list.json", list.dump(2) + "\n", "OPF's camera list"});
  const std::string exif = " (" + sized->name + "'s EXIF)";
  out->notes.push_back("pixel_size_um = " + FormatNumber("%.3f", pixel_size_um) + " um = " +
                       (focal_plane
                            ? "1000 / FocalPlaneXResolution " +
                                  ExportNumber(*sized->focal_plane_px_per_mm) + " px/mm" + exif
                            : "1000 x FocalLength " + ExportNumber(*sized->focal_mm) + " mm" +
                                  exif + " / focal_length_px " + ExportNumber(focal_px)));
  out->notes.push_back(
      "camera_list.json names each photo by its file name (a URI reference relative to the "
      "file): keep it beside the photos; camera ids are sequential, project scope (no UID "
      "generator); captures carry no geolocation (EXIF gives no accuracy, which OPF requires: "
      "Pix4D reads the photos' own positions) and time is UTC where the camera's zone is known, "
      "the camera clock without a zone otherwise");
}

}  // namespace

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
  const nlohmann::json internals = {{"type", "perspective"},
                                    {"principal_point_px", {c.cx + 0.5, c.cy + 0.5}},
                                    {"focal_length_px", focal_px},
                                    {"radial_distortion", {k[0], k[1], k[4]}},
                                    {"tangential_distortion", {k[2], k[3]}}};
  nlohmann::json sensor = {{"id", 1}, {"internals", internals}};
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
  if (!camera.photos.empty()) AddInputCameras(camera, internals, &out);
  AddSideNote("pix4d", camera, &out);
  return out;
}

}  // namespace shutterlab
