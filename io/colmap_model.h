#pragma once
// A COLMAP sparse reconstruction in its text form (COLMAP's doc/format.rst, "Output Format":
// cameras.txt, images.txt, points3D.txt in one folder; `colmap model_converter --output_type TXT`
// writes it from the binary form the mapper writes). What scoring a reconstruction needs: each
// registered image's pose and name, each point's position, mean reprojection error and track.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace shutterlab {

struct ColmapImage {
  int64_t id = 0;
  // cam_from_world: x_cam = R(q) x_world + t (COLMAP's QW QX QY QZ, TX TY TZ).
  Eigen::Quaterniond cam_from_world_q = Eigen::Quaterniond::Identity();
  Eigen::Vector3d cam_from_world_t = Eigen::Vector3d::Zero();
  int64_t camera_id = 0;
  std::string name;         // the image's path relative to COLMAP's --image_path
  size_t observations = 0;  // its 2D points that see a 3D point

  Eigen::Vector3d CenterM() const;       // -R^T t, the model's units
  Eigen::Matrix3d WorldFromCam() const;  // R^T
};

struct ColmapPoint {
  int64_t id = 0;
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
  double error_px = 0.0;  // its mean reprojection error over the track
  size_t track_length = 0;
};

struct ColmapModel {
  size_t cameras = 0;
  std::vector<ColmapImage> images;
  std::vector<ColmapPoint> points;
  // The mean reprojection error over every observation (each point's error weighted by its
  // track), px; 0 without points.
  double MeanReprojectionErrorPx() const;
};

// Reads DIR/cameras.txt, images.txt, points3D.txt. Throws IoError("PATH:LINE: problem") for a
// missing file (naming model_converter where DIR holds the binary form) or a malformed line.
ColmapModel ReadColmapTextModel(const std::string& dir);

}  // namespace shutterlab
