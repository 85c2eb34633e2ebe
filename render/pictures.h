#pragma once
// Pictures for people: a heatmap of the displacement magnitude with a scale bar, a side-by-side
// panel per frame, and a tiled overview of a flight. All return 8-bit RGB (R, G, B channel order,
// as io/image_io.h writes it).

#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace shutterlab {

// Colour map (viridis) of |d| for a CV_32FC2 displacement field, 0 .. max_px (max_px <= 0: the
// field's own maximum), with a scale bar labelled in pixels to the right. NaN pixels are black.
cv::Mat DisplacementHeatmap(const cv::Mat& displacement, double max_px = 0.0);

// Any 8U/16U/32F grey or RGB image as 8-bit RGB (16-bit scaled by 1/257, float clamped to 0..255).
cv::Mat ToRgb8(const cv::Mat& image);

// The image shrunk by the largest whole factor k that keeps at least min_width columns, each pixel
// the mean of a k x k block (OpenCV's INTER_AREA on whole blocks; the last width % k columns and
// height % k rows are left out; k at most the height), the image itself (not a copy) when k is 1;
// min_width below 1 counts as 1. A picture of a 12 MP photo 500
// pixels wide takes 15 ms so, a resize to any width 37 ms.
cv::Mat ShrinkByWholeFactor(const cv::Mat& image, int min_width);

// Panels placed left to right at a common height, each with its caption along the top.
cv::Mat SideBySide(const std::vector<cv::Mat>& panels, const std::vector<std::string>& captions);

// Tiles, each scaled to tile_width, in a grid `columns` wide, each with its caption.
cv::Mat TiledOverview(const std::vector<cv::Mat>& tiles, const std::vector<std::string>& captions,
                      int tile_width = 480, int columns = 4);

}  // namespace shutterlab
