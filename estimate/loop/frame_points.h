#pragma once
// The measured points of one frame (or one video pair) as the effect model and the fit take them.

#include "estimate/loop/measure.h"

#include <cstdint>
#include <optional>
#include <vector>

namespace shutterlab {

// The earlier frame of a video pair (docs/FORMATS.md "Video datasets").
struct EarlierFrame {
  int64_t frame = 0;
  int64_t t_first_row_ns = 0;  // camera clock (frames.csv)
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
};

}  // namespace shutterlab
