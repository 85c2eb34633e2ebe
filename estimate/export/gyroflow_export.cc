#include "estimate/export/gyroflow_export.h"

#include "model/lens_distortion.h"
#include "sim/readout_direction.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <variant>
#include <vector>

namespace shutterlab {
namespace {

// Gyroflow's camera axes against shutterlab's (OpenCV's: x right, y down, z forward): x right, y
// up, z back out of the lens (FrameTransform in Gyroflow's stabilization/frame_transform.rs turns
// its rotation into OpenCV's by negating the entries that couple x with y and z, which is this
// change of axes; no comment of Gyroflow's states it).
const Eigen::Matrix3d kGyroflowFromCamera = Eigen::Vector3d(1, -1, -1).asDiagonal();

// The gyro's mounting as Gyroflow applies it to each sample (IMUTransforms in
// gyro_source/imu_transforms.rs): w = R(rotation) * orient(imu_orientation, w_gyro), where orient
// sets output axis i to the input axis letter i names (lowercase: negated), and the project's
// "rotation" [pitch, roll, yaw] in degrees is R = Rz(roll) Ry(pitch) Rx(yaw). A mounting that
// turns axes onto axes is written as the letters alone (rotation null); any other as "XYZ" and
// the rotation.
nlohmann::json GyroflowMounting(const Eigen::Matrix3d& gyroflow_from_gyro) {
  const Eigen::Matrix3d& m = gyroflow_from_gyro;
  std::string letters;
  for (int row = 0; row < 3; ++row) {
    Eigen::Index col = 0;
    const double largest = m.row(row).cwiseAbs().maxCoeff(&col);
    if (std::abs(largest - 1.0) > 1e-9) break;  // not an axis onto an axis
    letters += static_cast<char>((m(row, col) > 0 ? 'X' : 'x') + col);
  }
  if (letters.size() == 3) return {{"imu_orientation", letters}, {"rotation", nullptr}};
  const double roll_rad = std::atan2(m(1, 0), m(0, 0));
  const double pitch_rad = std::asin(std::clamp(-m(2, 0), -1.0, 1.0));
  const double yaw_rad = std::atan2(m(2, 1), m(2, 2));
  return {{"imu_orientation", "XYZ"},
          {"rotation", {pitch_rad * kDegPerRad, roll_rad * kDegPerRad, yaw_rad * kDegPerRad}}};
}

nlohmann::json LensProfileJson(const ExportCamera& camera) {
  const RigModel& rig = camera.truth.rig;
  const PinholeCamera& c = rig.camera;
  const nlohmann::json matrix = {{c.fx, 0.0, c.cx}, {0.0, c.fy, c.cy}, {0.0, 0.0, 1.0}};
  nlohmann::json profile = {{"name", "shutterlab export"},
                            {"camera_brand", camera.make},
                            {"camera_model", camera.model},
                            {"calibrated_by", "shutterlab"},
                            {"calibrator_version", "shutterlab export"},
                            {"calib_dimension", {{"w", c.width}, {"h", c.height}}},
                            {"orig_dimension", {{"w", c.width}, {"h", c.height}}},
                            {"asymmetrical", true},
                            {"note", "exported from " + camera.source}};
  if (const auto* brown = std::get_if<BrownConrady>(&c.distortion)) {
    const auto& k = brown->coeffs;  // OpenCV's order, as Gyroflow's opencv_standard takes it
    profile["distortion_model"] = "opencv_standard";
    profile["use_opencv_standard"] = true;
    profile["calib_params"] = {{"camera_matrix", matrix},
                               {"distortion_coeffs", {k[0], k[1], k[2], k[3], k[4]}},
                               {"RMS_error", 0.0}};
  } else {
    const auto& k = std::get<Fisheye>(c.distortion).coeffs();
    profile["distortion_model"] = "opencv_fisheye";
    profile["fisheye_params"] = {{"camera_matrix", matrix},
                                 {"distortion_coeffs", {k[0], k[1], k[2], k[3]}},
                                 {"RMS_error", 0.0}};
  }
  if (camera.readout_known) {
    const bool bottom_up = rig.shutter.direction == ReadoutDirection::kBottomToTop;
    profile["frame_readout_time"] = (bottom_up ? -1e3 : 1e3) * rig.shutter.readout_s;
  }
  return profile;
}

}  // namespace

ExportOutput GyroflowExport(const ExportCamera& camera, const ExportOptions& options) {
  const RigModel& rig = camera.truth.rig;
  ExportOutput out;
  RequireCarried(IsRowReadout(rig.shutter.direction),
                 "Gyroflow corrects row readouts only; the camera reads " +
                     std::string(ReadoutDirectionName(rig.shutter.direction)),
                 options, &out.notes);
  RequireDetermined(camera, "time_offset", options, &out.notes);
  if (camera.readout_known) {
    RequireDetermined(camera, "readout_time", options, &out.notes);
    RequireDetermined(camera, "readout_direction", options, &out.notes);
  }
  RequireCarried(camera.truth.clock_rate_ppm == 0.0,
                 "a Gyroflow project's sync offset is constant here; the gyro clock runs " +
                     ExportNumber(camera.truth.clock_rate_ppm) + " ppm fast",
                 options, &out.notes);
  const nlohmann::json profile = LensProfileJson(camera);
  out.files.push_back({"lens_profile.json", profile.dump(2) + "\n", "Gyroflow's lens profile"});
  const double readout_ms = camera.readout_known ? 1e3 * rig.shutter.readout_s : 0.0;
  const double offset_ms = -1e3 * rig.time_offset_s - 0.5 * readout_ms;
  nlohmann::json project = {
      {"title", "Gyroflow data file"},
      {"version", 4},
      {"calibration_data", profile},
      {"stabilization",
       {{"frame_readout_time", readout_ms},
        {"frame_readout_direction", GyroflowReadoutDirectionName(rig.shutter.direction)}}},

      {"note",
       "shutterlab export: the lens, the readout and the sync offset; load the video and "
       "its gyro in Gyroflow, then these settings"}};
  if (camera.gyro_known) {
    project["offsets"] = {{"0", offset_ms}};
    project["gyro_source"] = GyroflowMounting(kGyroflowFromCamera * rig.cam_from_gyro);
  }
  out.files.push_back({"project.gyroflow", project.dump(2) + "\n",
                       "a Gyroflow project's lens, readout and sync offset"});
  out.notes.push_back("frame_readout_time " + FormatNumber("%.6g", readout_ms) +
                      " ms (the lens profile's is negative for a bottom-to-top readout)");
  if (camera.gyro_known) {
    out.notes.push_back("sync offset " + FormatNumber("%.6g", offset_ms) +
                        " ms = -1000 (time_offset_s + readout_s / 2): Gyroflow reads the gyro at "
                        "video time - offset and times a frame from its middle row, shutterlab "
                        "from its first");
  } else {
    out.notes.push_back(
        "no sync offset: the source relates no gyro to the camera (Gyroflow "
        "syncs it itself)");
  }
  out.notes.push_back(
      "asymmetrical: true keeps the principal point (Gyroflow puts it at the image "
      "centre otherwise)");
  if (camera.gyro_known) {
    const nlohmann::json mounting = project["gyro_source"];
    out.notes.push_back(
        "the gyro's mounting (R_CG) as gyro_source's imu_orientation " +
        mounting["imu_orientation"].get<std::string>() +
        (mounting["rotation"].is_null()
             ? std::string(" (axes onto axes: no rotation)")
             : " and rotation [pitch, roll, yaw] " + mounting["rotation"].dump() + " deg") +
        ", onto Gyroflow's camera axes (x right, y up, z back: shutterlab's with y and z "
        "negated, as read from Gyroflow's source and not checked against Gyroflow itself: if its "
        "stabilised preview turns the wrong way, set the orientation by hand); they apply to the "
        "gyro's axes as shutterlab read them, and replace a .gcsv's own orientation line");
  }
  AddSideNote("gyroflow", camera, &out);
  return out;
}

}  // namespace shutterlab
