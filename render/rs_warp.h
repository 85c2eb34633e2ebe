#pragma once
// Rolling-shutter rendering from a scene image, and its exact ground truth (docs/FORMATS.md "The
// model", "The scene image", "Frame distortion D").
//
// For a rolling-shutter pixel p = (u, v) the ray d_W = R_v K^-1 p (K^-1 undistorts when the true
// lens has distortion) leaves c_v and meets the ground z_W = altitude_m at X. The scene pixel is
// K_scene X / altitude_m, K_scene = the rig's fx, fy with principal point ((W_s-1)/2, (H_s-1)/2);
// the reference pixel is p_ref ~ K R_0^T (X - c_0) and the displacement d(p) = p_ref - p.
//
// Two rendering paths give the same picture:
//  - rotation only, no lens distortion: X / altitude ~ R_v K^-1 p, so the scene pixel is one 3x3
//    homography H_v = K_scene R_v K^-1 per row, evaluated along the row as
//    (a + u b) / (a_z + u b_z), a and b from H_v: no per-pixel rotation maths; its coordinates go
//    straight to fixed point and into the sampler, a row chunk at a time (no full-size map);
//  - general (velocity or lens distortion): the model above, exact per pixel in double.
// Sampling is bilinear (integer images: coordinates rounded to 1/128 px, fixed-point weights, an
// SSE2 kernel for 8-bit RGB; float images: float weights) or bicubic (OpenCV's A = -0.75 kernel,
// float weights). Border: scene pixels outside the scene read as 0 (black), each tap separately,
// as OpenCV's BORDER_CONSTANT with value 0; a ray that misses the ground gives 0.
// Work is split over rows (cv::parallel_for_); every row is computed the same way whatever the
// thread count, so the output is bit-identical for any number of threads.

#include "model/camera.h"
#include "model/truth_model.h"
#include "render/warp_kernel.h"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <optional>
#include <vector>

namespace shutterlab {

// The per-pixel geometry of one frame under the true model.
class FrameGeometry {
 public:
  // camera: the true intrinsics and distortion; scene_size: the scene image's size (its centre is
  // the principal point of K_scene). motion must have one pose per image row.
  FrameGeometry(const PinholeCamera& camera, double altitude_m, const FrameMotion& motion,
                cv::Size scene_size);

  // True when every row's scene map is a homography (no translation, no distortion).
  bool RotationOnly() const { return rotation_only_; }
  // H_v: scene pixel ~ H_v * (u, v, 1) (valid for RotationOnly() frames).
  Eigen::Matrix3d SceneFromImageHomography(int v) const;
  // Ground point seen by pixel (u, v) at row v's capture time; nullopt when the ray misses the
  // ground.
  std::optional<Eigen::Vector3d> GroundPoint(double u, int v) const;
  // Scene pixel seen by (u, v); nullopt when the ray misses the ground.
  std::optional<Eigen::Vector2d> ScenePixel(double u, int v) const;
  // Reference pixel of the ground point that (u, v) sees; nullopt when it is not in front of the
  // reference camera or the ray misses the ground.
  std::optional<Eigen::Vector2d> RefPixel(double u, int v) const;

  const PinholeCamera& camera() const { return camera_; }
  const FrameMotion& motion() const { return motion_; }
  double altitude_m() const { return altitude_m_; }

  // Fills xs, ys (size camera().width) with the scene pixel of each pixel of row v (NaN where the
  // ray misses the ground). Uses the homography for RotationOnly() frames.
  void SceneRow(int v, float* xs, float* ys) const;
  // The same in fixed point (round(x * 2^frac_bits)), straight from the row's homography, for the
  // `count` columns from u_begin (count < 0: to the row's end) into xi[0..count), yi[0..count);
  // INT_MIN where a coordinate is beyond 2^30 / 2^frac_bits px. Returns false (writing nothing)
  // unless RotationOnly() and those columns all look at the ground: then use SceneRow.
  bool SceneRowFixed(int v, int frac_bits, int* xi, int* yi, int u_begin = 0, int count = -1) const;

 private:
  PinholeCamera camera_;
  double altitude_m_;
  FrameMotion motion_;
  Eigen::Matrix3d scene_k_;
  Eigen::Matrix3d inv_k_;
  bool rotation_only_;
};

// Renders the frame: out (resized/retyped if needed; reuse it to avoid page faults) gets the
// scene's type and the camera's size. scene: CV_8U, CV_16U or CV_32F, 1, 3 or 4 channels.
void RenderFrame(const cv::Mat& scene, const FrameGeometry& geometry, Interpolation interpolation,
                 cv::Mat* out);

// The displacement field d(p) = p_ref - p of every pixel, CV_32FC2 (dx, dy), NaN where undefined.
cv::Mat DisplacementField(const FrameGeometry& geometry);

// Video pairs (docs/FORMATS.md "Video datasets"): for every pixel p of the later frame, the match q
// in the earlier frame of the ground point it sees, both frames rolling shutter and in one world
// (CameraMotion::Frame with a shared anchor). q's row w sets the earlier frame's pose, so q solves
// q = project(X, pose(w)), w = q.y: a fixed point iterated to kVideoMatchTolPx. The field is
// q - p, CV_32FC2, NaN where the ray misses the ground, the match falls outside the earlier frame's
// rows [0, height - 1], or the iteration does not settle.
cv::Mat VideoDisplacementField(const FrameGeometry& later, const FrameGeometry& earlier);
// The same for one pixel of the later frame.
std::optional<Eigen::Vector2d> VideoMatch(const FrameGeometry& later, const FrameGeometry& earlier,
                                          double u, int v);
constexpr double kVideoMatchTolPx = 1e-7;

// docs/FORMATS.md "Frame distortion D" of a displacement field: the largest, over columns, diameter
// of the column's displacement vectors, px (NaN entries are skipped).
double FrameDistortionPx(const cv::Mat& displacement);

}  // namespace shutterlab
