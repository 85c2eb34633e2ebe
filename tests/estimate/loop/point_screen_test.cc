// The screening before the loop (estimate/loop/point_screen.h) on synthetic points with exact
// truth: a camera-fixed region, points that move on their own, an image that does not follow the
// gyro.

#include "estimate/loop/point_screen.h"

#include "estimate/loop/effect_fit.h"
#include "tests/estimate/loop/effect_fixtures.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace shutterlab {
namespace {

constexpr int kScreenStepPx = 16;
constexpr double kScreenNoisePx = 0.05;  // rms length

// Video pairs of the video rig at 30 fps from 12.6 s of the flight (its liveliest stretch), points
// on a 16 px grid, measured as `truth` moves them plus Gaussian noise (kScreenNoisePx rms length).
std::vector<FramePoints> ScreenPairs(const TrueModel& truth, const GyroTrace& gyro, int pairs,
                                     uint64_t seed = 1) {
  return test::MeasuredVideoPairs(truth, gyro, pairs, kScreenStepPx, kScreenNoisePx, seed);
}

std::vector<Eigen::Vector2d> Predicted(const TrueModel& model, const GyroTrace& gyro,
                                       const std::vector<FramePoints>& frames) {
  std::vector<Eigen::Vector2d> all;
  for (const FramePoints& f : frames) {
    const std::vector<Eigen::Vector2d> d = PredictDisplacements(model, gyro, f);
    all.insert(all.end(), d.begin(), d.end());
  }
  return all;
}

TrueModel Declared() {
  TrueModel model;
  model.rig = test::VideoRig();
  return model;
}

TEST(DetectCameraFixed, FindsTheRowsThatStayAndNothingElse) {
  const GyroTrace gyro = test::FlightTrace(14.0, 3);
  const TrueModel model = Declared();
  std::vector<FramePoints> pairs = ScreenPairs(model, gyro, 6);
  // The bottom quarter moves with the camera: measured 0 (plus noise) wherever the scene moves.
  const int fixed_from = model.rig.camera.height * 3 / 4;
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, kScreenNoisePx / std::sqrt(2.0));
  for (FramePoints& f : pairs) {
    for (MeasuredPoint& p : f.points) {
      if (p.v >= fixed_from) p.dx = noise(rng), p.dy = noise(rng);
    }
  }
  const std::vector<double> noise_px(pairs.size(), kScreenNoisePx);
  const CameraFixedRegion region =
      DetectCameraFixed(pairs, Predicted(model, gyro, pairs), noise_px, model.rig.camera.width,
                        model.rig.camera.height, kScreenStepPx);
  ASSERT_FALSE(region.whole_image);
  int wrong = 0, found = 0, fixed_cells = 0;
  for (int r = 0; r < region.rows; ++r) {
    for (int c = 0; c < region.cols; ++c) {
      const size_t k = static_cast<size_t>(r) * region.cols + c;
      if (region.testable[k] == 0) continue;
      const bool fixed = (r * kScreenStepPx + kScreenStepPx / 2) >= fixed_from;
      fixed_cells += fixed;
      found += fixed && region.fixed[k];
      wrong += !fixed && region.fixed[k];
    }
  }
  EXPECT_EQ(wrong, 0);
  EXPECT_GE(found, 0.95 * fixed_cells) << found << " of " << fixed_cells;
  EXPECT_TRUE(region.Contains(100, fixed_from + 10));
  EXPECT_FALSE(region.Contains(100, 20));
}

// A dashboard whose top rows have texture (they measure 0) and whose lower rows measure nothing
// (dark and flat): the lower rows join the region through the cells that measure nothing, up to
// the scene. A hole that measures nothing in the scene stays out, even beside 3 cells that stay
// (too few to grow).
TEST(DetectCameraFixed, CellsThatMeasureNothingJoinTheRegionBelowIt) {
  const GyroTrace gyro = test::FlightTrace(14.0, 3);
  const TrueModel model = Declared();
  std::vector<FramePoints> pairs = ScreenPairs(model, gyro, 6);
  const int height = model.rig.camera.height, width = model.rig.camera.width;
  const int fixed_from = height * 3 / 4, flat_from = fixed_from + 3 * kScreenStepPx;
  const auto in_hole = [&](const MeasuredPoint& p) {  // a flat patch in the scene
    return p.u >= 4 * kScreenStepPx && p.u < 8 * kScreenStepPx && p.v >= 4 * kScreenStepPx &&
           p.v < 8 * kScreenStepPx;
  };
  const auto in_small = [&](const MeasuredPoint& p) {  // three cells beside the hole that stay
    return p.u >= 8 * kScreenStepPx && p.u < 11 * kScreenStepPx && p.v >= 4 * kScreenStepPx &&
           p.v < 5 * kScreenStepPx;
  };
  for (FramePoints& f : pairs) {
    std::vector<MeasuredPoint> kept;
    for (MeasuredPoint p : f.points) {
      if (p.v >= flat_from || in_hole(p)) continue;  // nothing measured
      if (p.v >= fixed_from || in_small(p)) p.dx = p.dy = 0.0;
      kept.push_back(p);
    }
    f.points = std::move(kept);
  }
  const CameraFixedRegion region = DetectCameraFixed(
      pairs, Predicted(model, gyro, pairs), std::vector<double>(pairs.size(), kScreenNoisePx),
      width, height, kScreenStepPx);
  ASSERT_FALSE(region.whole_image);
  for (int v = flat_from + kScreenStepPx / 2; v < height; v += kScreenStepPx) {
    for (int u = kScreenStepPx / 2; u < width; u += kScreenStepPx) {
      EXPECT_TRUE(region.Contains(u, v)) << u << ", " << v;
    }
  }
  EXPECT_GT(region.cells_joined, 0u);
  EXPECT_FALSE(region.Contains(6 * kScreenStepPx, 6 * kScreenStepPx));  // the hole
  EXPECT_TRUE(
      region.Contains(9 * kScreenStepPx + 8, 4 * kScreenStepPx + 8));    // the 3 cells themselves
  EXPECT_FALSE(region.Contains(width / 2, fixed_from - kScreenStepPx));  // the scene above
}

TEST(DetectCameraFixed, AWholeImageThatStaysIsNoRegion) {
  const GyroTrace gyro = test::FlightTrace(14.0, 3);
  const TrueModel model = Declared();
  std::vector<FramePoints> pairs = ScreenPairs(model, gyro, 6);
  for (FramePoints& f : pairs) {
    for (MeasuredPoint& p : f.points) p.dx = p.dy = 0.0;
  }
  const CameraFixedRegion region = DetectCameraFixed(
      pairs, Predicted(model, gyro, pairs), std::vector<double>(pairs.size(), kScreenNoisePx),
      model.rig.camera.width, model.rig.camera.height, kScreenStepPx);
  EXPECT_TRUE(region.whole_image);
}

// A clip 3 ms late and 20 % slower to read out than declared (what the loop will fit) with a
// block of points 2-3 px off (a car): the consensus absorbs the first as its rate correction and
// leaves out the car only.
TEST(RotationConsensus, LeavesOutWhatMovesOnItsOwnNotWhatTheLoopWillFit) {
  const GyroTrace gyro = test::FlightTrace(14.0, 3);
  TrueModel truth = Declared();
  truth.rig.time_offset_s = 0.003;
  truth.rig.shutter.readout_s *= 1.2;
  std::vector<FramePoints> pairs = ScreenPairs(truth, gyro, 6);
  const auto in_car = [](const MeasuredPoint& p) {
    return p.u > 200 && p.u < 300 && p.v > 100 && p.v < 180;
  };
  size_t car_points = 0;
  for (FramePoints& f : pairs) {
    for (MeasuredPoint& p : f.points) {
      if (!in_car(p)) continue;
      p.dx += 2.5;
      p.dy -= 1.5;
      ++car_points;
    }
  }
  ASSERT_GT(car_points, 100u);
  const TrueModel declared = Declared();
  size_t total = 0;
  for (const FramePoints& f : pairs) total += f.points.size();
  std::vector<PointStatus> status(total, PointStatus::kKept);
  const std::vector<FrameConsensus> consensus =
      RotationConsensus(declared, pairs, Predicted(declared, gyro, pairs),
                        std::vector<double>(pairs.size(), kScreenNoisePx), &status);
  size_t k = 0, car_left_out = 0, scene_left_out = 0;
  for (const FramePoints& f : pairs) {
    for (const MeasuredPoint& p : f.points) {
      const bool out = status[k++] == PointStatus::kMoving;
      (in_car(p) ? car_left_out : scene_left_out) += out;
    }
  }
  EXPECT_EQ(car_left_out, car_points);
  EXPECT_LT(scene_left_out, 0.005 * (total - car_points)) << scene_left_out;
  for (const FrameConsensus& c : consensus) EXPECT_TRUE(c.determined);
}

// An image whose rotation is a fifth of the gyro's (a stabiliser that keeps a fifth) against one
// that follows it.
TEST(CheckImageFollowsGyro, AStabilisedImageDoesNotFollow) {
  const GyroTrace gyro = test::FlightTrace(14.0, 3);
  const TrueModel declared = Declared();
  TrueModel stabilised = declared;
  stabilised.gyro_scale = Eigen::Vector3d::Constant(0.2);
  const std::vector<double> noise(8, kScreenNoisePx);
  const PointScreen follows = ScreenPoints(declared, gyro, ScreenPairs(declared, gyro, 8), noise,
                                           kScreenStepPx, ScreenOptions{});
  ASSERT_TRUE(follows.gyro_follow.determined) << follows.gyro_follow.verdict;
  EXPECT_TRUE(follows.gyro_follow.follows);
  EXPECT_NEAR(follows.gyro_follow.gain, 1.0, 0.05);
  const PointScreen screen = ScreenPoints(declared, gyro, ScreenPairs(stabilised, gyro, 8), noise,
                                          kScreenStepPx, ScreenOptions{});
  ASSERT_TRUE(screen.gyro_follow.determined) << screen.gyro_follow.verdict;
  EXPECT_FALSE(screen.gyro_follow.follows) << screen.gyro_follow.verdict;
  EXPECT_NEAR(screen.gyro_follow.gain, 0.2, 0.05);
  // The whole image stays far behind the gyro: no camera-fixed region is made of it.
  EXPECT_EQ(screen.camera_fixed_share, 0.0);
}

}  // namespace
}  // namespace shutterlab
