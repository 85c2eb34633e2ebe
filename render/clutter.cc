#include "render/clutter.h"

#include "render/ground_texture.h"
#include "sim/check.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace shutterlab {

void ClutterOptions::Check() const {
  SHUTTERLAB_CHECK(camera_fixed_share >= 0 && camera_fixed_share <= 0.9)
      << "the camera-fixed patch covers 0 to 0.9 of the rows, got " << camera_fixed_share;
  SHUTTERLAB_CHECK(std::isfinite(moving_patch_mps) && moving_patch_mps >= 0 &&
                   moving_patch_mps <= 1000)
      << "the moving patch's speed must be 0 to 1000 m/s, got " << moving_patch_mps;
}

namespace {

// An RGB 8-bit texture in a frame's pixel type: grey is the channels' mean, 16-bit and float scale
// the same levels to their full range (float 0..1), a fourth channel is opaque.
cv::Mat InFrameType(const cv::Mat& rgb8, int type) {
  const int channels = CV_MAT_CN(type), depth = CV_MAT_DEPTH(type);
  cv::Mat converted;
  if (channels == 1) {
    cv::transform(rgb8, converted, cv::Matx13f(1.f / 3, 1.f / 3, 1.f / 3));
  } else if (channels == 4) {
    cv::cvtColor(rgb8, converted, cv::COLOR_RGB2RGBA);
  } else {
    converted = rgb8;
  }
  const double scale = depth == CV_16U ? 257.0 : depth == CV_32F ? 1.0 / 255.0 : 1.0;
  cv::Mat out;
  converted.convertTo(out, depth, scale);
  return out;
}

}  // namespace

CameraFixedPatch MakeCameraFixedPatch(cv::Size frame_size, int type, double share) {
  CameraFixedPatch patch;
  patch.rows_from = frame_size.height - static_cast<int>(std::lround(share * frame_size.height));
  GroundTextureOptions options;
  options.width_px = std::max(64, frame_size.width);
  options.height_px = std::max(64, frame_size.height);
  options.seed = 17;
  options.ground_sample_distance_m = 0.01;  // fine grain: texture in every flow patch
  cv::Mat rgb8 = MakeGroundTexture(options)(cv::Rect(cv::Point(0, 0), frame_size)).clone();
  // Dark and dull, as a dashboard is, yet never black (measure leaves black pixels out).
  rgb8.convertTo(rgb8, CV_8U, 0.45, 20.0);
  patch.texture = InFrameType(rgb8, type);
  return patch;
}

void PaintCameraFixed(const CameraFixedPatch& patch, cv::Mat* image, cv::Mat* truth) {
  SHUTTERLAB_CHECK(image->size() == patch.texture.size() && image->type() == patch.texture.type())
      << "the camera-fixed patch was made for another frame size or type";
  const cv::Rect rows(0, patch.rows_from, image->cols, image->rows - patch.rows_from);
  if (rows.height <= 0) return;
  patch.texture(rows).copyTo((*image)(rows));
  if (truth != nullptr && !truth->empty()) (*truth)(rows).setTo(cv::Scalar(0, 0));
}

MovingPatch MakeMovingPatch(const PinholeCamera& camera, double altitude_m, double speed_mps,
                            const Eigen::Vector2d& centre_px, double t_mid_s, int type) {
  MovingPatch patch;
  patch.side_px = std::max(8, static_cast<int>(std::lround(0.2 * camera.height)));
  patch.velocity_px_s = Eigen::Vector2d(speed_mps * camera.fx / altitude_m, 0.0);
  patch.start_px =
      centre_px - Eigen::Vector2d::Constant(0.5 * patch.side_px) - patch.velocity_px_s * t_mid_s;
  GroundTextureOptions options;
  options.width_px = options.height_px = std::max(64, patch.side_px);
  options.seed = 29;
  options.ground_sample_distance_m = 0.01;
  const cv::Mat rgb8 =
      MakeGroundTexture(options)(cv::Rect(0, 0, patch.side_px, patch.side_px)).clone();
  patch.texture = InFrameType(rgb8, type);
  return patch;
}

void PaintMovingPatch(const MovingPatch& patch, const FrameGeometry& geometry,
                      const std::vector<double>& row_time_s, cv::Mat* image, cv::Mat* truth) {
  const int width = image->cols, height = image->rows;
  SHUTTERLAB_CHECK(static_cast<int>(row_time_s.size()) == height)
      << "one row time per image row is needed";
  SHUTTERLAB_CHECK(patch.texture.type() == image->type())
      << "the moving patch was made for another pixel type";
  // Where each pixel looks in the patch's texture (-1: not at the patch), then one remap.
  cv::Mat map_x(height, width, CV_32F, cv::Scalar(-1)), map_y(height, width, CV_32F);
  cv::Mat inside(height, width, CV_8U, cv::Scalar(0));
  std::vector<float> xs(width), ys(width);
  const double last = patch.side_px - 1;
  bool any = false;
  for (int v = 0; v < height; ++v) {
    geometry.SceneRow(v, xs.data(), ys.data());
    const Eigen::Vector2d corner = patch.start_px + patch.velocity_px_s * row_time_s[v];
    float* mx = map_x.ptr<float>(v);
    float* my = map_y.ptr<float>(v);
    uchar* in = inside.ptr<uchar>(v);
    for (int u = 0; u < width; ++u) {
      const double x = xs[u] - corner.x(), y = ys[u] - corner.y();
      if (!(x >= 0 && x <= last && y >= 0 && y <= last)) continue;
      mx[u] = static_cast<float>(x);
      my[u] = static_cast<float>(y);
      in[u] = 255;
      any = true;
    }
  }
  if (!any) return;
  cv::Mat painted;
  cv::remap(patch.texture, painted, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  painted.copyTo(*image, inside);
  if (truth != nullptr && !truth->empty()) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    truth->setTo(cv::Scalar(nan, nan), inside);
  }
}

}  // namespace shutterlab
