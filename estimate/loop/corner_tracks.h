#pragma once
// Sparse corner tracks between two images: the measurements the camera-fixed check trusts where
// the dense flow may not (estimate/loop/point_screen.h check 1).
//
// Dense flow fills a dark, nearly textureless region (a car's dashboard, a shaded gimbal arm) with
// motion dragged along from the textured scene beside it: such a region then seems to move with
// the scene although it stays with the camera. A track here is kept only where the image itself
// pins the match down:
//  - corners: per tile of kTileCornerPx, the strongest local maxima of the structure tensor's
//    smaller eigenvalue (Shi-Tomasi) that reach kMinCornerFraction of the tile's own strongest and
//    an absolute floor (kMinCornerGradient), so a dark tile has corners of its own as long as it
//    has texture at all (a global threshold would leave it none beside the bright street);
//  - pyramidal Lucas-Kanade from the later image to the earlier one, started twice: at no motion
//    and at the dense flow's match (or 2 px off where that is nearer). Texture pins a match when
//    both starts converge to one answer (within kMaxStartSpreadPx); on a flat patch each start
//    stays near where it began;
//  - forward-backward: the match tracked back must return within kMaxRoundTripPx.
// A point where any of these fails is not measured (left out, not taken as scene).

#include "estimate/loop/measured_point.h"

#include <opencv2/core.hpp>

#include <vector>

namespace shutterlab {

inline constexpr int kTileCornerPx = 32;
inline constexpr int kCornersPerTile = 2;
inline constexpr double kMinCornerFraction = 0.1;
inline constexpr double kMinCornerGradient = 2.5 / 255.0;  // grey fraction per px
inline constexpr double kMaxStartSpreadPx = 0.5;
inline constexpr double kMaxRoundTripTrackPx = 0.5;

// grey_ref, grey_img: CV_32F in 0..1, one size; dense_flow: CV_32FC2 from grey_img to grey_ref
// (d = p_ref - p), NaN allowed; mask: CV_8U, non-zero = may be used, or empty. Each track is a
// MeasuredPoint at a pixel p of grey_img with (dx, dy) = its match in grey_ref - p, weight 1.
std::vector<MeasuredPoint> TrackCorners(const cv::Mat& grey_ref, const cv::Mat& grey_img,
                                        const cv::Mat& dense_flow, const cv::Mat& mask);

}  // namespace shutterlab
