#pragma once
// The measured points of one frame (or one video pair) as the effect model and the fit take them.

#include "estimate/loop/measure.h"

#include <Eigen/Core>

#include <cstdint>
#include <optional>
#include <vector>

namespace shutterlab {

// The earlier frame of a video pair (docs/FORMATS.md "Video datasets").
struct EarlierFrame {
  int64_t frame = 0;
  int64_t t_first_row_ns = 0;                                    // camera clock (frames.csv)
  Eigen::Matrix3d cam_from_image = Eigen::Matrix3d::Identity();  // as FramePoints'
};

// The measured points of one frame of a rig dataset.
struct FramePoints {
  int64_t frame = 0;
  int64_t t_first_row_ns = 0;  // camera clock (frames.csv)
  std::vector<MeasuredPoint> points;
  // Video pairs: the points' matches lie in this earlier frame, and (dx, dy) of each point is its
  // match q minus the point p (both rolling shutter). Absent for reference datasets, where (dx, dy)
  // is d(p) = p_ref - p.
  std::optional<EarlierFrame> earlier;
  // Video of a camera that re-rendered its image (a stabiliser with its per-frame rotation, GoPro
  // IORI): the rotation from the image's virtual camera frame to the physical one, x_cam =
  // cam_from_image x_image, constant over the frame. Identity for footage nobody re-rendered.
  Eigen::Matrix3d cam_from_image = Eigen::Matrix3d::Identity();
  // Sparse corner tracks of the same frame or pair, (dx, dy) as `points` (MeasureOptions::
  // corner_tracks): evidence for the camera-fixed check only, never fitted. Empty: not tracked.
  std::vector<MeasuredPoint> tracks;
};

}  // namespace shutterlab
