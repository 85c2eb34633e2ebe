#include "estimate/export/colmap_export.h"

#include "model/lens_distortion.h"
#include "sim/readout_direction.h"

#include <string>
#include <variant>
#include <vector>

namespace shutterlab {

ExportOutput ColmapExport(const ExportCamera& camera, const ExportOptions&) {
  const RigModel& rig = camera.truth.rig;
  const PinholeCamera& c = rig.camera;
  ExportOutput out;
  // COLMAP's pixel coordinates start at the top-left corner of the image; OpenCV's at the
  // top-left pixel's centre.
  std::vector<double> params = {c.fx, c.fy, c.cx + 0.5, c.cy + 0.5};
  std::string model;
  if (const auto* brown = std::get_if<BrownConrady>(&c.distortion)) {
    const auto& k = brown->coeffs;  // k1 k2 p1 p2 k3
    params.insert(params.end(), {k[0], k[1], k[2], k[3]});
    if (k[4] != 0.0) {
      model = "FULL_OPENCV";  // k3 and a rational part (k4..k6) held at 0
      params.insert(params.end(), {k[4], 0.0, 0.0, 0.0});
    } else {
      model = "OPENCV";
    }
  } else {
    const auto& k = std::get<Fisheye>(c.distortion).coeffs();
    model = "OPENCV_FISHEYE";
    params.insert(params.end(), k.begin(), k.end());
    out.notes.push_back(
        "COLMAP's OPENCV_FISHEYE takes theta = atan(r): rays 90 degrees or more off the axis have "
        "no pixel there");
  }
  std::string line = "1 " + model + " " + std::to_string(c.width) + " " + std::to_string(c.height);
  std::string csv;
  for (size_t i = 0; i < params.size(); ++i) {
    line += " " + ExportNumber(params[i]);
    csv += (i ? "," : "") + ExportNumber(params[i]);
  }
  std::string readout = camera.readout_known ? ExportNumber(rig.shutter.readout_s) + " s " +
                                                   ReadoutDirectionName(rig.shutter.direction)
                                             : std::string("unknown");
  const std::string cameras =
      "# Camera list with one line of data per camera:\n"
      "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
      "# Number of cameras: 1\n"
      "# shutterlab export from " +
      camera.source +
      "\n"
      "# rolling-shutter readout " +
      readout + " (COLMAP does not model it)\n" + line + "\n";
  out.files.push_back({"cameras.txt", cameras, "COLMAP's camera, as a text model"});
  out.files.push_back({"images.txt", "# Image list with two lines of data per image:\n", "empty"});
  out.files.push_back(
      {"points3D.txt", "# 3D point list with one line of data per point:\n", "empty"});
  std::string args = "--ImageReader.camera_model " + model + " --ImageReader.camera_params " + csv +
                     " --ImageReader.single_camera 1";
  if (!camera.photos.empty()) {
    std::string list;
    size_t excluded = 0;
    for (const ExportPhoto& photo : camera.photos) {
      if (photo.flagged) {
        ++excluded;
        continue;
      }
      list += photo.name + "\n";
    }
    out.files.push_back({"image_list.txt", list, "the photos not flagged, for --image_list_path"});
    args += " --image_list_path image_list.txt";
    out.notes.push_back("image_list.txt leaves out the " + std::to_string(excluded) +
                        " photo(s) flagged over a limit");
  }
  if (!camera.images_dir.empty()) {
    args += " --image_path " + camera.images_dir;
    out.notes.push_back("--image_path: the corrected photos (" + camera.images_dir + ")");
  }
  if (!camera.masks_dir.empty()) {
    args += " --ImageReader.mask_path " + camera.masks_dir;
    out.notes.push_back("--ImageReader.mask_path: the correction's masks (" + camera.masks_dir +
                        "), 0 where a corrected pixel has no source: COLMAP extracts no feature "
                        "there");
  }
  out.files.push_back({"colmap_args.txt", args + "\n", "feature_extractor's options"});
  out.notes.push_back("cx, cy + 0.5 px: COLMAP puts the top-left pixel's centre at (0.5, 0.5)");
  out.notes.push_back(
      "COLMAP has no rolling-shutter model: the readout is not carried (correct "
      "the images first with shutterlab correct, or leave the flagged ones out)");
  AddSideNote("colmap", camera, &out);
  return out;
}

}  // namespace shutterlab
