#include "estimate/loop/corner_tracks.h"

#include "sim/check.h"

#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include <algorithm>
#include <cmath>

namespace shutterlab {
namespace {

// Shi-Tomasi window, its local-maximum neighbourhood and the border no corner is taken from, px.
constexpr int kEigenBlockPx = 7;
constexpr int kLocalMaxPx = 9;
constexpr int kBorderPx = 4;
// Pyramidal Lucas-Kanade: window, levels (a 21 px window at level 3 reaches about 80 px).
constexpr int kLkWindowPx = 21;
constexpr int kLkLevels = 3;
// The second start lies at least this far from the first, px.
constexpr double kMinStartGapPx = 2.0;

struct Corner {
  float eig = 0.0f;
  cv::Point2f p;
};

// The corners of grey (CV_32F, 0..1), as the header says.
std::vector<cv::Point2f> FindCorners(const cv::Mat& grey, const cv::Mat& mask) {
  cv::Mat eig, local_max;
  // OpenCV scales a float image's derivatives so that eig is the block's mean squared gradient
  // in the weaker direction, (grey fraction / px)^2.
  cv::cornerMinEigenVal(grey, eig, kEigenBlockPx, 3);
  cv::dilate(eig, local_max, cv::getStructuringElement(cv::MORPH_RECT, {kLocalMaxPx, kLocalMaxPx}));
  const float floor = static_cast<float>(kMinCornerGradient * kMinCornerGradient);
  const int tiles_x = (grey.cols + kTileCornerPx - 1) / kTileCornerPx;
  const int tiles_y = (grey.rows + kTileCornerPx - 1) / kTileCornerPx;
  std::vector<std::vector<Corner>> tiles(static_cast<size_t>(tiles_x) * tiles_y);
  for (int v = kBorderPx; v < grey.rows - kBorderPx; ++v) {
    const float* e = eig.ptr<float>(v);
    const float* m = local_max.ptr<float>(v);
    const uchar* use = mask.empty() ? nullptr : mask.ptr<uchar>(v);
    for (int u = kBorderPx; u < grey.cols - kBorderPx; ++u) {
      if (e[u] < floor || e[u] < m[u] || (use != nullptr && use[u] == 0)) continue;
      tiles[static_cast<size_t>(v / kTileCornerPx) * tiles_x + u / kTileCornerPx].push_back(
          {e[u], cv::Point2f(static_cast<float>(u), static_cast<float>(v))});
    }
  }
  std::vector<cv::Point2f> corners;
  for (std::vector<Corner>& tile : tiles) {
    std::sort(tile.begin(), tile.end(), [](const Corner& a, const Corner& b) {
      return a.eig > b.eig ||
             (a.eig == b.eig && (a.p.y < b.p.y || (a.p.y == b.p.y && a.p.x < b.p.x)));
    });
    for (size_t i = 0; i < tile.size() && i < static_cast<size_t>(kCornersPerTile); ++i) {
      if (tile[i].eig < kMinCornerFraction * tile.front().eig) break;
      corners.push_back(tile[i].p);
    }
  }
  return corners;
}

std::vector<cv::Mat> Pyramid(const cv::Mat& grey) {
  cv::Mat grey8;
  grey.convertTo(grey8, CV_8U, 255.0);
  std::vector<cv::Mat> pyramid;
  cv::buildOpticalFlowPyramid(grey8, pyramid, {kLkWindowPx, kLkWindowPx}, kLkLevels);
  return pyramid;
}

bool Inside(const cv::Point2f& p, const cv::Mat& image) {
  return p.x >= 0 && p.y >= 0 && p.x <= image.cols - 1 && p.y <= image.rows - 1;
}

}  // namespace

std::vector<MeasuredPoint> TrackCorners(const cv::Mat& grey_ref, const cv::Mat& grey_img,
                                        const cv::Mat& dense_flow, const cv::Mat& mask) {
  SHUTTERLAB_CHECK(grey_ref.type() == CV_32F && grey_img.type() == CV_32F &&
                   grey_ref.size() == grey_img.size())
      << "corner tracks need two grey float images of one size";
  SHUTTERLAB_CHECK(dense_flow.type() == CV_32FC2 && dense_flow.size() == grey_img.size())
      << "corner tracks need the dense flow of the image";
  const std::vector<cv::Point2f> corners = FindCorners(grey_img, mask);
  std::vector<MeasuredPoint> tracks;
  if (corners.empty()) return tracks;
  const std::vector<cv::Mat> img = Pyramid(grey_img), ref = Pyramid(grey_ref);
  const cv::TermCriteria stop(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30, 0.01);
  const cv::Size window(kLkWindowPx, kLkWindowPx);
  // Start 1: no motion.
  std::vector<cv::Point2f> at_rest;
  std::vector<uchar> ok_rest, ok_dense, ok_back;
  std::vector<float> err;
  cv::calcOpticalFlowPyrLK(img, ref, corners, at_rest, ok_rest, err, window, kLkLevels, stop);
  // Start 2: the dense flow's match, or a start kMinStartGapPx diagonally off where that is
  // closer to start 1 (or missing): two starts at one place would test nothing.
  std::vector<cv::Point2f> from_dense(corners.size());
  for (size_t i = 0; i < corners.size(); ++i) {
    const cv::Vec2f d = dense_flow.at<cv::Vec2f>(cvRound(corners[i].y), cvRound(corners[i].x));
    const bool apart = std::isfinite(d[0]) && std::isfinite(d[1]) && cv::norm(d) >= kMinStartGapPx;
    const float diagonal = static_cast<float>(kMinStartGapPx / std::sqrt(2.0));
    from_dense[i] =
        corners[i] + (apart ? cv::Point2f(d[0], d[1]) : cv::Point2f(diagonal, diagonal));
  }
  cv::calcOpticalFlowPyrLK(img, ref, corners, from_dense, ok_dense, err, window, kLkLevels, stop,
                           cv::OPTFLOW_USE_INITIAL_FLOW);
  // Back from the first start's match, itself started at no motion.
  std::vector<cv::Point2f> back;
  cv::calcOpticalFlowPyrLK(ref, img, at_rest, back, ok_back, err, window, kLkLevels, stop);
  for (size_t i = 0; i < corners.size(); ++i) {
    if (!ok_rest[i] || !ok_dense[i] || !ok_back[i] || !Inside(at_rest[i], grey_ref)) continue;
    if (cv::norm(at_rest[i] - from_dense[i]) > kMaxStartSpreadPx) continue;
    if (cv::norm(back[i] - corners[i]) > kMaxRoundTripTrackPx) continue;
    const cv::Point2f d = at_rest[i] - corners[i];
    tracks.push_back({corners[i].x, corners[i].y, d.x, d.y, 1.0});
  }
  return tracks;
}

}  // namespace shutterlab
