#pragma once
// A displacement measured at one pixel: what `measure` (estimate/loop/measure.h) and the corner
// tracks (estimate/loop/corner_tracks.h) hand to the screening and the fit.

namespace shutterlab {

// One measured displacement at a rolling-shutter pixel (u, v): d = (dx, dy) = p_ref - p, pixels.
struct MeasuredPoint {
  double u = 0.0, v = 0.0;    // rolling-shutter pixel (column, row)
  double dx = 0.0, dy = 0.0;  // measured displacement, px
  double weight = 1.0;        // confidence, 0..1 (1: well textured, consistent)
};

}  // namespace shutterlab
