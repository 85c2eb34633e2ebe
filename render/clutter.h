#pragma once
// Known-answer clutter for renders: what real footage holds besides the scene, so that validate
// can be tested on it with exact truth (render --camera-fixed-patch, --moving-patch).
//  - A camera-fixed patch: the bottom rows of every frame show a texture that moves with the camera
//    (a car's dashboard, landing gear, a gimbal arm): the same pixels in every frame and in every
//    reference. Its true displacement is 0.
//  - A moving patch: a textured square on the ground that drives across it at its own speed, seen
//    by every row at that row's own capture time (so it is rolling-shutter consistent, as a car in
//    the street is). No single camera motion explains it; the truth leaves it out (NaN).

#include "render/rs_warp.h"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <vector>

namespace shutterlab {

struct ClutterOptions {
  // Share of the image rows, at the bottom, that the camera-fixed patch covers; 0: none.
  double camera_fixed_share = 0.0;
  // Speed of the moving patch over the ground, m/s along the world x axis; 0: none.
  double moving_patch_mps = 0.0;
  bool any() const { return camera_fixed_share > 0 || moving_patch_mps > 0; }
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

// The camera-fixed patch of a frame size and pixel type (rows_from..height-1 hold the texture):
// a dark, well-textured surface, the same bytes for the same size and type.
struct CameraFixedPatch {
  int rows_from = 0;  // first covered row
  cv::Mat texture;    // the frame's size and type; only rows_from.. are painted
};
CameraFixedPatch MakeCameraFixedPatch(cv::Size frame_size, int type, double share);
// Paints it over *image (the frame's size and type); *truth (CV_32FC2, may be empty) gets 0 there.
void PaintCameraFixed(const CameraFixedPatch& patch, cv::Mat* image, cv::Mat* truth);

// A square on the ground in scene pixels (docs/FORMATS.md "The scene image"): its top-left corner
// at time t (s, the render's own clock) is start_px + velocity_px_s * t.
struct MovingPatch {
  Eigen::Vector2d start_px = Eigen::Vector2d::Zero();
  Eigen::Vector2d velocity_px_s = Eigen::Vector2d::Zero();
  int side_px = 0;
  cv::Mat texture;  // side_px x side_px, the frame's type
};
// A patch of side 20 % of the frame height, at speed_mps along x (scene pixels per metre are
// fx / altitude_m), whose centre passes the scene point `centre_px` at time t_mid_s.
MovingPatch MakeMovingPatch(const PinholeCamera& camera, double altitude_m, double speed_mps,
                            const Eigen::Vector2d& centre_px, double t_mid_s, int type);
// Paints the patch over *image where row v (captured at row_time_s[v]) sees it; *truth (CV_32FC2,
// may be empty) gets NaN there. The geometry is the frame's (the scene pixel each pixel sees).
void PaintMovingPatch(const MovingPatch& patch, const FrameGeometry& geometry,
                      const std::vector<double>& row_time_s, cv::Mat* image, cv::Mat* truth);

}  // namespace shutterlab
