#pragma once
// The declared camera and rig model (docs/FORMATS.md camera.json, "rig/1").
//
// Pixel convention (OpenCV): pixel (u, v) = (column, row); the centre of the top-left pixel is
// (0, 0). Camera frame: x right, y down, z along the optical axis into the scene.

#include "model/lens_distortion.h"
#include "sim/readout_direction.h"

#include <Eigen/Core>
#include <nlohmann/json_fwd.hpp>

#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

// Intrinsics: focal lengths and principal point, with one of the two lens distortion models of
// docs/FORMATS.md (model/lens_distortion.h: OpenCV's Brown-Conrady or fisheye).
struct PinholeCamera {
  int width = 0, height = 0;              // pixels
  double fx = 0, fy = 0, cx = 0, cy = 0;  // pixels
  LensDistortion distortion;              // Brown-Conrady with every coefficient 0 by default

  bool HasDistortion() const;
  Eigen::Matrix3d K() const;
  // Distorted pixel of a point in the camera frame; nullopt when the lens model gives it none
  // (Brown-Conrady: z <= 0, behind the camera; fisheye: at or beyond the angle where its
  // polynomial turns).
  std::optional<Eigen::Vector2d> ImgFromCam(const Eigen::Vector3d& p_in_cam) const;
  // Ray of a distorted pixel: (x, y, 1) whenever it points forward; a fisheye pixel 90 degrees or
  // more off the axis gives a unit vector with z <= 0, one outside the fisheye's image circle NaN
  // (model/lens_distortion.h). Undistortion by Newton's method to 1e-15.
  Eigen::Vector3d CamFromImg(const Eigen::Vector2d& px) const;
  // True when the distortion keeps the image in one piece well beyond its farthest corner (a fit
  // may not fold the image to explain data): Brown-Conrady's radial map increases out to 1.5 times
  // the corner's normalised radius; a fisheye's polynomial holds 20 % beyond the corner's angle.
  bool DistortionMonotonicOverImage() const;
};

// Rolling-shutter timing. The only place that knows how a row maps to a time.
struct RollingShutter {
  // s; row v is read at v * readout_s / height after row 0 (docs/FORMATS.md); 0: a global shutter
  double readout_s = 0.0;
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
  // io/rig_dataset.h ReadRigDataset.)
  std::string mask;
  // camera.json `bounds` (shutterlab extension): per effect name, the [lo, hi] its fitted value
  // may take, in the effect's unit, in place of the physical bounds (model/effects.h
  // PhysicalBounds) for a device known to differ. Only effects that have bounds.
  std::map<std::string, std::array<double, 2>> bounds;

  // Throws std::invalid_argument naming the first nonsensical field.
  void Check() const;
};

// The effect names camera.json's "bounds" may hold: those with physical bounds
// (model/effects.h PhysicalBounds; Effects.CameraJsonBoundsReplaceThePhysicalOnes holds the two
// lists equal: effects.h includes this header, so this one cannot ask it).
const std::vector<std::string>& CameraJsonBoundNames();

// Reads camera.json; throws IoError("PATH: field: problem") for anything malformed.
RigModel ReadRigModel(const std::string& path);
// Writes camera.json whole or not at all.
void WriteRigModel(const std::string& path, const RigModel& rig);
// camera.json's object, as ReadRigModel reads it (throws std::invalid_argument "field: problem")
// and WriteRigModel writes it (every key).
RigModel RigModelFromJson(const nlohmann::json& camera);
nlohmann::json RigModelToJson(const RigModel& rig);
// camera.json's "distortion" object (docs/FORMATS.md): "model" "brown" (the default) with k1 k2 p1
// p2 k3, or "fisheye" with k1 k2 k3 k4, each coefficient 0 when absent. Throws
// std::invalid_argument naming the first problem (an unknown model or coefficient, a non-number).
LensDistortion DistortionFromJson(const nlohmann::json& j);
// The same object as camera.json writes it (Brown-Conrady without "model", as rig/1 always was).
nlohmann::json DistortionJson(const LensDistortion& lens);
// A 3x3 matrix as camera.json writes gyro_to_camera: an array of its rows.
nlohmann::json MatrixJson(const Eigen::Matrix3d& m);

}  // namespace shutterlab
