#pragma once
// A procedural nadir ground texture, made here so that the demo and tests need nobody's photos:
// farmland with a hamlet as a mapping drone sees it from about 50 m. Fields with crop rows in
// varied directions, straight roads with painted lines, roofs with ridges and shading, trees with
// shadows, and grain everywhere, so that dense optical flow finds texture in every 16x16 block and
// a rolling-shutter wobble shows on the many straight edges.
//
// Deterministic: the same options give the same bytes on any machine. Only the metre-to-pixel
// sizes use floating point (divisions, which IEEE rounds the same everywhere); every pixel value
// comes from integer arithmetic and the file's own hash and PCG random generator.

#include <opencv2/core.hpp>

#include <cstdint>

namespace shutterlab {

struct GroundTextureOptions {
  int width_px = 4000;
  int height_px = 3000;
  uint64_t seed = 1;
  // Metres of ground per pixel: the sizes of roads, roofs, trees, fields and crop rows scale with
  // it. 0.02: a 4000 px frame spans 80 m (a 1-inch 20 MP camera at about 50 m).
  double ground_sample_distance_m = 0.02;
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

// The texture as CV_8UC3 in R, G, B channel order (as io/image_io.h reads and writes images),
// height_px rows of width_px.
cv::Mat MakeGroundTexture(const GroundTextureOptions& options);

}  // namespace shutterlab
