#include "estimate/export/vins_export.h"

#include "model/lens_distortion.h"
#include "sim/readout_direction.h"
#include "sim/text_file.h"

#include <string>
#include <variant>

namespace shutterlab {
namespace {

// camodocal's camera: model_type, size and its parameter blocks.
std::string CameraYaml(const ExportCamera& camera, const ExportOptions& options,
                       std::vector<std::string>* notes) {
  const PinholeCamera& c = camera.truth.rig.camera;
  std::string yaml = "camera_name: camera\n";
  yaml += "image_width: " + std::to_string(c.width) + "\n";
  yaml += "image_height: " + std::to_string(c.height) + "\n";
  if (const auto* brown = std::get_if<BrownConrady>(&c.distortion)) {
    const auto& k = brown->coeffs;
    RequireCarried(k[4] == 0.0,
                   "VINS's PINHOLE model has no k3 (the lens has k3 = " + ExportNumber(k[4]) + ")",
                   options, notes);
    yaml = "model_type: PINHOLE\n" + yaml;
    yaml += "distortion_parameters:\n   k1: " + ExportNumber(k[0]) +
            "\n   k2: " + ExportNumber(k[1]) + "\n   p1: " + ExportNumber(k[2]) +
            "\n   p2: " + ExportNumber(k[3]) + "\n";
    yaml += "projection_parameters:\n   fx: " + ExportNumber(c.fx) +
            "\n   fy: " + ExportNumber(c.fy) + "\n   cx: " + ExportNumber(c.cx) +
            "\n   cy: " + ExportNumber(c.cy) + "\n";
    return yaml;
  }
  const auto& k = std::get<Fisheye>(c.distortion).coeffs();
  yaml = "model_type: KANNALA_BRANDT\n" + yaml;
  yaml += "projection_parameters:\n   k2: " + ExportNumber(k[0]) +
          "\n   k3: " + ExportNumber(k[1]) + "\n   k4: " + ExportNumber(k[2]) +
          "\n   k5: " + ExportNumber(k[3]) + "\n   mu: " + ExportNumber(c.fx) +
          "\n   mv: " + ExportNumber(c.fy) + "\n   u0: " + ExportNumber(c.cx) +
          "\n   v0: " + ExportNumber(c.cy) + "\n";
  notes->push_back(
      "KANNALA_BRANDT's k2..k5 are OpenCV's fisheye k1..k4 (camodocal's r(theta) = theta + "
      "k2 theta^3 + k3 theta^5 + k4 theta^7 + k5 theta^9)");
  return yaml;
}

}  // namespace

ExportOutput VinsExport(const ExportCamera& camera, const ExportOptions& options) {
  const RigModel& rig = camera.truth.rig;
  ExportOutput out;
  // Photos alone relate no gyro to the camera: VINS is told to calibrate the rotation and td itself
  // (estimate_extrinsic 2, estimate_td 1 from 0).
  const bool with_imu = camera.gyro_known;
  if (with_imu) RequireGyroRelation(camera, "VINS", "td", options, &out.notes);
  const bool rolling = camera.readout_known && rig.shutter.readout_s > 0.0;
  if (rolling) {
    RequireDetermined(camera, "readout_time", options, &out.notes);
    RequireDetermined(camera, "readout_direction", options, &out.notes);
    RequireCarried(rig.shutter.direction == ReadoutDirection::kTopToBottom,
                   "VINS's rolling shutter reads top to bottom; the camera reads " +
                       std::string(ReadoutDirectionName(rig.shutter.direction)),
                   options, &out.notes);
  }
  const bool top_down = rolling && rig.shutter.direction == ReadoutDirection::kTopToBottom;
  const double readout_s = top_down ? rig.shutter.readout_s : 0.0;
  const double td_s = with_imu ? rig.time_offset_s + 0.5 * readout_s : 0.0;
  std::string camera_yaml = "%YAML:1.0\n---\n# shutterlab export from " + camera.source + "\n";
  camera_yaml += CameraYaml(camera, options, &out.notes);
  const Eigen::Matrix3d r_gc = rig.cam_from_gyro.transpose();
  std::string yaml = "%YAML:1.0\n---\n# shutterlab export from " + camera.source +
                     "\n# the settings shutterlab determined; merge them into your VINS config\n";
  yaml += "cam0_calib: \"camera.yaml\"\n";
  yaml += "image_width: " + std::to_string(rig.camera.width) + "\n";
  yaml += "image_height: " + std::to_string(rig.camera.height) + "\n";
  if (with_imu) {
    yaml += "# 1: an initial guess; shutterlab fits the rotation, not the lever arm (0 here)\n";
    yaml += "estimate_extrinsic: 1\n";
    yaml += "extrinsicRotation: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: [";
    for (int i = 0; i < 9; ++i) yaml += (i ? ", " : "") + ExportNumber(r_gc(i / 3, i % 3));
    yaml += "]\n";
    yaml +=
        "extrinsicTranslation: !!opencv-matrix\n   rows: 3\n   cols: 1\n   dt: d\n   data: [0, "
        "0, 0]\n";
  } else {
    yaml += "# 2: no prior (the source relates no gyro to the camera): VINS calibrates it\n";
    yaml += "estimate_extrinsic: 2\n";
  }
  yaml += "estimate_td: " + std::string(with_imu ? "0" : "1") + "\n";
  yaml += "td: " + ExportNumber(td_s) + "\n";
  yaml += "rolling_shutter: " + std::string(top_down ? "1" : "0") + "\n";
  yaml += "rolling_shutter_tr: " + ExportNumber(readout_s) + "\n";
  out.files.push_back({"camera.yaml", camera_yaml, "VINS's camera (camodocal)"});
  out.files.push_back({"vins_config.yaml", yaml, "VINS's extrinsics, td and rolling shutter"});
  if (with_imu) {
    out.notes.push_back("extrinsicRotation = imu^R_cam = R_CG^T (shutterlab: w_C = R_CG w_G)");
    out.notes.push_back("td " + FormatNumber("%.6g", td_s) +
                        " s = time_offset_s + readout_s / 2: image clock + td = IMU clock, and "
                        "VINS times a frame from its middle row, shutterlab from its first");
  } else {
    out.notes.push_back(
        "the source relates no gyro to the camera (photos alone): estimate_extrinsic 2 and "
        "estimate_td 1 from td 0, so VINS calibrates the rotation and the time offset itself");
  }
  if (top_down)
    out.notes.push_back("rolling_shutter_tr " + FormatNumber("%.6g", readout_s) +
                        " s, the whole frame's readout");
  NoteGyroCalibrationNotCarried(camera, "a VINS config (VINS estimates the bias)", &out.notes);
  AddSideNote("vins", camera, &out);
  return out;
}

}  // namespace shutterlab
