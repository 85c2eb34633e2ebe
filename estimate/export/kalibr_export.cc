#include "estimate/export/kalibr_export.h"

#include "model/lens_distortion.h"
#include "sim/readout_direction.h"
#include "sim/text_file.h"

#include <string>
#include <variant>
#include <vector>

namespace shutterlab {
namespace {

std::string YamlList(const std::vector<double>& values) {
  std::string text = "[";
  for (size_t i = 0; i < values.size(); ++i) text += (i ? ", " : "") + ExportNumber(values[i]);
  return text + "]";
}

}  // namespace

ExportOutput KalibrExport(const ExportCamera& camera, const ExportOptions& options) {
  const RigModel& rig = camera.truth.rig;
  const PinholeCamera& c = rig.camera;
  ExportOutput out;
  std::string distortion_model;
  std::vector<double> coeffs;
  if (const auto* brown = std::get_if<BrownConrady>(&c.distortion)) {
    const auto& k = brown->coeffs;
    RequireCarried(k[4] == 0.0,
                   "Kalibr's radtan model has no k3 (the lens has k3 = " + ExportNumber(k[4]) + ")",
                   options, &out.notes);
    distortion_model = "radtan";
    coeffs = {k[0], k[1], k[2], k[3]};
  } else {
    const auto& k = std::get<Fisheye>(c.distortion).coeffs();
    distortion_model = "equidistant";
    coeffs = {k[0], k[1], k[2], k[3]};
  }
  // Photos alone relate no gyro to the camera: the camera chain alone, what Kalibr's camera-IMU
  // calibration starts from (kalibr_calibrate_imu_camera --cams), which then finds T_cam_imu and
  // the time shift.
  const bool with_imu = camera.gyro_known;
  if (with_imu) RequireGyroRelation(camera, "Kalibr", "time shift", options, &out.notes);
  std::string yaml = "# shutterlab export from " + camera.source + "\ncam0:\n";
  yaml += "  camera_model: pinhole\n";
  yaml += "  intrinsics: " + YamlList({c.fx, c.fy, c.cx, c.cy}) + "\n";
  yaml += "  distortion_model: " + distortion_model + "\n";
  yaml += "  distortion_coeffs: " + YamlList(coeffs) + "\n";
  yaml += "  resolution: [" + std::to_string(c.width) + ", " + std::to_string(c.height) + "]\n";
  if (with_imu) {
    yaml += "  T_cam_imu:\n";
    const Eigen::Matrix3d& r = rig.cam_from_gyro;
    for (int i = 0; i < 3; ++i) yaml += "  - " + YamlList({r(i, 0), r(i, 1), r(i, 2), 0.0}) + "\n";
    yaml += "  - [0.0, 0.0, 0.0, 1.0]\n";
    yaml += "  timeshift_cam_imu: " + ExportNumber(rig.time_offset_s) + "\n";
  }
  if (camera.readout_known && rig.shutter.readout_s > 0.0) {
    RequireDetermined(camera, "readout_time", options, &out.notes);
    RequireDetermined(camera, "readout_direction", options, &out.notes);
    const bool top_down = rig.shutter.direction == ReadoutDirection::kTopToBottom;
    RequireCarried(top_down,
                   "Kalibr's rolling shutter reads top to bottom; the camera reads " +
                       std::string(ReadoutDirectionName(rig.shutter.direction)) +
                       ": its line delay",
                   options, &out.notes);
  }
  if (camera.readout_known && rig.shutter.readout_s > 0.0 &&
      rig.shutter.direction == ReadoutDirection::kTopToBottom) {
    const double line_delay_ns = rig.shutter.readout_s / c.height * 1e9;
    yaml += "  line_delay_nanoseconds: " + ExportNumber(line_delay_ns) + "\n";
    out.notes.push_back(
        "line_delay_nanoseconds = readout / height = " + FormatNumber("%.6g", line_delay_ns) +
        " ns; row v at v * line delay after the "
        "frame's time, the first row's, as in shutterlab");
  }
  yaml += "  rostopic: /cam0/image_raw\n";
  if (!with_imu) {
    out.files.push_back({"camchain.yaml", yaml, "Kalibr's camera chain (the camera alone)"});
    out.notes.push_back(
        "the camera alone: the source relates no gyro to it (photos alone), so no T_cam_imu or "
        "timeshift_cam_imu; kalibr_calibrate_imu_camera --cams camchain.yaml finds them");
    AddSideNote("kalibr", camera, &out);
    return out;
  }
  out.files.push_back({"camchain-imucam.yaml", yaml, "Kalibr's camera-IMU chain"});
  out.notes.push_back(
      "timeshift_cam_imu = time_offset_s (t_imu = t_cam + shift, shutterlab's "
      "gyro clock = camera clock + time_offset_s)");
  out.notes.push_back(
      "T_cam_imu: R_CG (w_C = R_CG w_G) with no translation (shutterlab fits none)");
  NoteGyroCalibrationNotCarried(camera, "camchain-imucam.yaml", &out.notes);
  AddSideNote("kalibr", camera, &out);
  return out;
}

}  // namespace shutterlab
