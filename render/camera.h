#pragma once
// The declared camera and rig model (docs/FORMATS.md camera.json, "rig/1").
//
// Pixel convention (OpenCV): pixel (u, v) = (column, row); the centre of the top-left pixel is
// (0, 0). Camera frame: x right, y down, z along the optical axis into the scene.

#include "sim/readout_direction.h"

#include <Eigen/Core>
#include <nlohmann/json_fwd.hpp>

#include <array>
#include <optional>
#include <string>

namespace shutterlab {

// Pinhole intrinsics with OpenCV's Brown-Conrady distortion (k1, k2, p1, p2, k3).
struct PinholeCamera {
  int width = 0, height = 0;              // pixels
  double fx = 0, fy = 0, cx = 0, cy = 0;  // pixels
  std::array<double, 5> dist{};           // k1, k2, p1, p2, k3 (dimensionless)

  bool HasDistortion() const;
  Eigen::Matrix3d K() const;
  // Distorted pixel of a point in the camera frame; nullopt when z <= 0 (behind the camera).
  std::optional<Eigen::Vector2d> ImgFromCam(const Eigen::Vector3d& p_in_cam) const;
  // Ray (z = 1) of a distorted pixel; undistortion by fixed-point iteration to 1e-12.
  Eigen::Vector3d CamFromImg(const Eigen::Vector2d& px) const;
};

// Rolling-shutter timing. The only place that knows how a row maps to a time.
struct RollingShutter {
  double readout_s =
      0.0;  // s; row v is read at v * readout_s / height after row 0 (docs/FORMATS.md)
  ReadoutDirection direction = ReadoutDirection::kTopToBottom;  // a row order (IsRowReadout)
  // Seconds after t_first_row at which image row `row` of an image `height` rows tall is captured.
  double RowTimeOffsetS(double row, int height) const;
};

// Everything camera.json declares.
struct RigModel {
  PinholeCamera camera;
  RollingShutter shutter;
  Eigen::Matrix3d cam_from_gyro = Eigen::Matrix3d::Identity();  // R_CG: w_C = R_CG * w_G
  double time_offset_s = 0.0;  // gyro clock = camera clock + time_offset_s
  double altitude_m = 50.0;    // ground plane z_W = altitude_m
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();  // world frame, constant within a frame
  // docs/FORMATS.md v1.1 `mask`: a single-channel image of the camera's size, relative to the
  // dataset folder; non-zero = may be used. Empty: every pixel may be used. (Read by
  // render/rig_dataset.h ReadRigDataset.)
  std::string mask;

  // Throws std::invalid_argument naming the first nonsensical field.
  void Check() const;
};

// Reads camera.json; throws IoError("PATH: field: problem") for anything malformed.
RigModel ReadRigModel(const std::string& path);
// Writes camera.json whole or not at all.
void WriteRigModel(const std::string& path, const RigModel& rig);
// A 3x3 matrix as camera.json writes gyro_to_camera: an array of its rows.
nlohmann::json MatrixJson(const Eigen::Matrix3d& m);

}  // namespace shutterlab
