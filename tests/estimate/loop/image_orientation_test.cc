// The stabiliser's own rotation (estimate/loop/image_orientation.h) on synthetic pairs with exact
// truth: a camera that re-renders every frame to hold the first frame's view, and writes the
// rotation it applied in axes and a sense of its own.

#include "estimate/loop/image_orientation.h"

#include "estimate/loop/effect_fit.h"
#include "estimate/loop/effect_model.h"
#include "sim/integrate.h"
#include "tests/estimate/loop/effect_fixtures.h"

#include <gtest/gtest.h>

#include <map>
#include <random>
#include <vector>

namespace shutterlab {
namespace {

constexpr int kOrientationStepPx = 16, kPairs = 8;
constexpr double kOrientationNoisePx = 0.05;
double FrameS(int k) { return 12.6 + k / 30.0; }

struct Stabilised {
  std::vector<FramePoints> pairs;              // measured, cam_from_image not known (identity)
  std::map<int64_t, Eigen::Quaterniond> iori;  // as the camera wrote it
  ImageOrientationCheck truth_reading;
};

// The camera keeps half of its turning since frame 0 out of the picture (S_k = the rotation back
// by half of it): IORI written in the axes `written_axes` and the inverse sense.
Stabilised MakeStabilised(const TrueModel& model, const GyroTrace& gyro) {
  Stabilised out;
  out.truth_reading.axes = AxisRotations()[7];
  out.truth_reading.inverse = true;
  std::vector<GyroSample> rates = gyro.samples();
  for (GyroSample& s : rates) s.omega_rad_s = model.CamRate(s.omega_rad_s);
  const OrientationTrace orientation{GyroTrace(std::move(rates))};
  std::vector<Eigen::Matrix3d> s(kPairs + 1);
  for (int k = 0; k <= kPairs; ++k) {
    const Eigen::Quaterniond turned =
        orientation.WorldFromBodyAt(SecondsToNs(FrameS(0))).conjugate() *
        orientation.WorldFromBodyAt(SecondsToNs(FrameS(k)));
    s[k] = Eigen::Quaterniond::Identity().slerp(0.5, turned.conjugate()).toRotationMatrix();
    // S = A Q^-1 A^T  <=>  Q = (A^T S A)^-1.
    const Eigen::Matrix3d a = out.truth_reading.axes;
    out.iori[k] = Eigen::Quaterniond(Eigen::Matrix3d(a.transpose() * s[k] * a).transpose());
  }
  out.pairs = test::MeasuredVideoPairs(model, gyro, kPairs, kOrientationStepPx, kOrientationNoisePx,
                                       3, FrameS(0), s);
  return out;
}

TEST(ImageOrientation, FindsTheReadingAndTheImageThenFollowsTheGyro) {
  const GyroTrace gyro = test::FlightTrace(14.0, 3);
  TrueModel model;
  model.rig = test::VideoRig();
  Stabilised clip = MakeStabilised(model, gyro);
  const std::vector<double> noise(kPairs, kOrientationNoisePx);
  const PointScreen before = ScreenPoints(model, gyro, clip.pairs, noise, kOrientationStepPx, {});
  ASSERT_TRUE(before.gyro_follow.determined) << before.gyro_follow.verdict;
  EXPECT_FALSE(before.gyro_follow.follows) << before.gyro_follow.verdict;

  ImageOrientationCheck check =
      TestImageOrientation(model, gyro, clip.pairs, before.rotation, clip.iori);
  EXPECT_FALSE(check.holds) << "judged only on the screening with the reading applied";
  EXPECT_TRUE(check.axes.isApprox(clip.truth_reading.axes)) << check.axes;
  EXPECT_TRUE(check.inverse);
  EXPECT_GT(check.share, 0.95) << check.verdict;
  EXPECT_NEAR(check.gain, 1.0, 0.05) << check.verdict;

  EXPECT_TRUE(ApplyImageOrientation(check, clip.iori, &clip.pairs).empty());
  const PointScreen after = ScreenPoints(model, gyro, clip.pairs, noise, kOrientationStepPx, {});
  // The stabilised camera turns too little for the screening's test: the rotations decide.
  EXPECT_FALSE(after.gyro_follow.determined) << after.gyro_follow.verdict;
  JudgeImageOrientation(before.gyro_follow, after.gyro_follow, &check);
  EXPECT_TRUE(check.holds) << check.verdict;
  EXPECT_LT(check.raw_gain, 0.7) << check.verdict;
  // Applied, the declared model explains the points to the noise.
  const LoopResult fit = FitEffects(model, gyro, clip.pairs, kOrientationNoisePx, {});
  EXPECT_LT(fit.after.rms_px, 1.3 * kOrientationNoisePx);
}

// A written rotation that has nothing to do with the images does not hold.
TEST(ImageOrientation, AnUnrelatedRotationDoesNotHold) {
  const GyroTrace gyro = test::FlightTrace(14.0, 3);
  TrueModel model;
  model.rig = test::VideoRig();
  Stabilised clip = MakeStabilised(model, gyro);
  std::mt19937_64 rng(9);
  std::normal_distribution<double> angle(0.0, 0.05);
  for (auto& [frame, q] : clip.iori) {
    q = Eigen::Quaterniond(Eigen::AngleAxisd(angle(rng), Eigen::Vector3d::UnitX()) *
                           Eigen::AngleAxisd(angle(rng), Eigen::Vector3d::UnitY()));
  }
  const std::vector<double> noise(kPairs, kOrientationNoisePx);
  const PointScreen before = ScreenPoints(model, gyro, clip.pairs, noise, kOrientationStepPx, {});
  ImageOrientationCheck check =
      TestImageOrientation(model, gyro, clip.pairs, before.rotation, clip.iori);
  ApplyImageOrientation(check, clip.iori, &clip.pairs);
  const PointScreen after = ScreenPoints(model, gyro, clip.pairs, noise, kOrientationStepPx, {});
  JudgeImageOrientation(before.gyro_follow, after.gyro_follow, &check);
  EXPECT_FALSE(check.holds) << check.verdict;
}

}  // namespace
}  // namespace shutterlab
