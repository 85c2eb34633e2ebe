// Corner tracks (estimate/loop/corner_tracks.h) on an image pair with exact truth: a scene that
// shifts, a dark textured band that stays (a dashboard), a dark flat band with fresh noise in
// each image (what no track may claim to measure).

#include "estimate/loop/corner_tracks.h"

#include "estimate/loop/measure.h"
#include "tests/render/render_fixtures.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <random>

namespace shutterlab {
namespace {

constexpr int kSceneRows = 140, kFixedFrom = 150, kFixedTo = 200, kFlatFrom = 205;

// Grey level 20 with Gaussian noise of 1 level, fresh per seed.
cv::Mat FlatNoise(cv::Size size, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> noise(20.0f, 1.0f);
  cv::Mat out(size, CV_8U);
  for (int v = 0; v < size.height; ++v) {
    for (int u = 0; u < size.width; ++u) out.at<uchar>(v, u) = cv::saturate_cast<uchar>(noise(rng));
  }
  return out;
}

TEST(TrackCorners, SceneMovesDarkDashboardStaysFlatDarkIsUnmeasured) {
  const cv::Size size(320, 240);
  const cv::Mat scene = test::SmoothTexture(size, CV_8UC1, 3, 1.5);
  const cv::Point2d shift(2.3, -1.7);  // image(p) = ref(p + shift): d = shift
  cv::Mat ref = scene.clone(), image;
  cv::warpAffine(scene, image, cv::Matx23d(1, 0, shift.x, 0, 1, shift.y), size,
                 cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_REFLECT);
  // The dashboard: the same dark, low-contrast texture (grey 10..50) in both images.
  cv::Mat dash;
  test::SmoothTexture(size, CV_8UC1, 11, 1.5).convertTo(dash, CV_8U, 40.0 / 255.0, 10.0);
  const cv::Rect band(0, kFixedFrom, size.width, kFixedTo - kFixedFrom);
  dash(band).copyTo(ref(band));
  dash(band).copyTo(image(band));
  const cv::Rect flat(0, kFlatFrom, size.width, size.height - kFlatFrom);
  FlatNoise(size, 1)(flat).copyTo(ref(flat));
  FlatNoise(size, 2)(flat).copyTo(image(flat));

  MeasureOptions options;
  options.corner_tracks = true;
  const DisplacementMeasurement m = MeasureDisplacement(ref, image, options);
  int scene_tracks = 0, scene_off = 0, fixed_tracks = 0, fixed_off = 0, flat_tracks = 0;
  for (const MeasuredPoint& t : m.tracks) {
    EXPECT_EQ(t.weight, 1.0);
    if (t.v < kSceneRows) {
      ++scene_tracks;
      scene_off += std::hypot(t.dx - shift.x, t.dy - shift.y) > 0.1;
    } else if (t.v >= kFixedFrom + 10 && t.v < kFixedTo - 10) {
      ++fixed_tracks;
      fixed_off += std::hypot(t.dx, t.dy) > 0.1;
    } else if (t.v >= kFlatFrom + 10) {
      ++flat_tracks;
    }
  }
  EXPECT_GE(scene_tracks, 40);
  EXPECT_LE(scene_off, scene_tracks / 20) << scene_off << " of " << scene_tracks;
  EXPECT_GE(fixed_tracks, 10);
  EXPECT_EQ(fixed_off, 0) << fixed_off << " of " << fixed_tracks;
  EXPECT_EQ(flat_tracks, 0);
}

TEST(TrackCorners, OffUnlessAsked) {
  const cv::Mat texture = test::SmoothTexture({64, 48}, CV_8UC1);
  EXPECT_TRUE(MeasureDisplacement(texture, texture).tracks.empty());
}

}  // namespace
}  // namespace shutterlab
