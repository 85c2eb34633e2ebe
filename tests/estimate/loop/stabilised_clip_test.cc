// The image against the gyro per camera axis (estimate/loop/point_screen.h check 3) on clips that
// a stabiliser re-rendered (render/stabiliser.h), with exact truth: render --video's three modes
// over the video tests' flight (tests/estimate/loop/validate_fixtures.h MakeClip).

#include "estimate/loop/validate.h"
#include "render/stabiliser.h"
#include "tests/estimate/loop/validate_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace shutterlab {
namespace {

std::string AxesSummary(const GyroFollowCheck& check) {
  std::string text = check.verdict + "\n";
  for (int a = 0; a < 3; ++a) {
    const AxisFollow& f = check.axes[a];
    text += "axis " + std::to_string(a) + ": gain " + std::to_string(f.gain) + ", row " +
            std::to_string(f.row_norm) + " +- " + std::to_string(f.row_norm_stderr) + ", fast " +
            std::to_string(f.fast_row_norm) + " +- " + std::to_string(f.fast_row_norm_stderr) +
            (f.follows ? " follows" : " DOES NOT FOLLOW") + "\n";
  }
  return text;
}

ValidationResult ValidateStabilised(StabiliserMode mode, std::vector<std::string> injections = {}) {
  test::TempDir dir;
  test::ClipSpec spec;
  spec.injections = std::move(injections);
  spec.stabiliser.mode = mode;
  return test::ValidateWithoutResiduals(test::MakeClip(dir, spec));
}

// Horizon levelling held to the first frame (roll-lock): the image does not follow the gyro about
// camera z (the optical axis) and follows it about x and y; with the image's own roll taken for z,
// the loop on the gyro about x and y names no effect and ends at the noise.
TEST(Stabiliser, RollLockedClipNamesNoEffectAndSaysWhichAxis) {
  if (test::kAsan) GTEST_SKIP() << "reduced set under ASan (ValidateReport.ARollLocked* runs)";
  const ValidationResult r = ValidateStabilised(StabiliserMode::kRollLock);
  ASSERT_TRUE(r.axes_not_following.has_value()) << AxesSummary(r.screen.gyro_follow);
  const GyroFollowCheck& axes = *r.axes_not_following;
  const std::string report = AxesSummary(axes) + test::LoopSummary(r);
  EXPECT_EQ(axes.AxesNotFollowing(), std::vector<int>{2}) << report;
  EXPECT_LT(axes.axes[2].row_norm, 0.1) << report;
  EXPECT_NEAR(axes.axes[0].row_norm, 1.0, 0.05) << report;
  EXPECT_NEAR(axes.axes[1].row_norm, 1.0, 0.05) << report;
  EXPECT_FALSE(ReRenderedByStabiliser(r)) << report;
  EXPECT_TRUE(r.loop.effects.empty()) << report;
  EXPECT_FALSE(r.loop.unexplained) << report;
  EXPECT_EQ(r.preferred, "rotation_only") << report;
}

// Horizon levelling that smooths the roll (sigma 0.5 s): the fast part of the roll is gone, the
// slow part kept; the same answer.
TEST(Stabiliser, RollSmoothedClipNamesNoEffectAndSaysWhichAxis) {
  if (test::kAsan) GTEST_SKIP() << "reduced set under ASan";
  const ValidationResult r = ValidateStabilised(StabiliserMode::kRoll);
  ASSERT_TRUE(r.axes_not_following.has_value()) << AxesSummary(r.screen.gyro_follow);
  const std::string report = AxesSummary(*r.axes_not_following) + test::LoopSummary(r);
  EXPECT_EQ(r.axes_not_following->AxesNotFollowing(), std::vector<int>{2}) << report;
  EXPECT_TRUE(r.axes_not_following->axes[2].fast_determined) << report;
  EXPECT_LT(r.axes_not_following->axes[2].fast_row_norm, 0.1) << report;
  EXPECT_TRUE(r.loop.effects.empty()) << report;
  EXPECT_FALSE(r.loop.unexplained) << report;
}

// The loop runs on the axes that follow: a clock offset camera.json does not declare is found on
// a roll-locked clip as on a plain one (ValidateVideo.RecoversTimeOffset's tolerance).
TEST(Stabiliser, RollLockedClipStillShowsATimeOffset) {
  if (test::kAsan) GTEST_SKIP() << "reduced set under ASan";
  const ValidationResult r = ValidateStabilised(StabiliserMode::kRollLock, {"time_offset=4ms"});
  ASSERT_TRUE(r.axes_not_following.has_value()) << AxesSummary(r.screen.gyro_follow);
  const std::string report = AxesSummary(*r.axes_not_following) + test::LoopSummary(r);
  EXPECT_EQ(r.axes_not_following->AxesNotFollowing(), std::vector<int>{2}) << report;
  ASSERT_EQ(r.loop.effects.size(), 1u) << report;
  EXPECT_EQ(Spec(r.loop.effects.front().effect).name, "time_offset") << report;
  EXPECT_NEAR(r.loop.model.rig.time_offset_s, 0.004, 0.3e-3) << report;
  EXPECT_FALSE(r.loop.unexplained) << report;
}

// Whole-image smoothing: no axis follows; the image is the stabiliser's, no effect is named, and
// the pair-translation model is not preferred (a stabiliser's rendering holds no translation).
TEST(Stabiliser, WholeImageSmoothingFollowsOnNoAxis) {
  if (test::kAsan) GTEST_SKIP() << "reduced set under ASan (ValidateReport.ARollLocked* runs)";
  const ValidationResult r = ValidateStabilised(StabiliserMode::kWhole);
  const GyroFollowCheck& follow = r.screen.gyro_follow;
  const std::string report = AxesSummary(follow) + test::LoopSummary(r);
  EXPECT_FALSE(r.axes_not_following.has_value()) << report;
  ASSERT_TRUE(follow.determined) << report;
  EXPECT_FALSE(follow.follows) << report;
  EXPECT_EQ(follow.AxesNotFollowing().size(), 3u) << report;
  EXPECT_TRUE(ReRenderedByStabiliser(r)) << report;
  EXPECT_TRUE(r.loop.effects.empty()) << report;
  EXPECT_EQ(r.preferred, "rotation_only") << report;
}

// A wrong axis mapping (x and y swapped, z reversed: ValidateVideo.RecoversAWronglyLabelledGyro's)
// turns the rows of the rate map but keeps their length: no stabiliser is named, whatever the
// consensus makes of the large correction about z, and the loop finds the mapping.
TEST(Stabiliser, AWrongAxisMappingIsNoStabiliser) {
  if (test::kAsan) GTEST_SKIP() << "reduced set under ASan";
  test::TempDir dir;
  test::ClipSpec spec;
  spec.injections = {"gyro_to_camera=0,1,0,1,0,0,0,0,-1"};
  const ValidationResult r = test::ValidateWithoutResiduals(test::MakeClip(dir, spec));
  const std::string report =
      AxesSummary(r.axes_not_following.value_or(r.screen.gyro_follow)) + test::LoopSummary(r);
  EXPECT_FALSE(r.axes_not_following.has_value()) << report;
  EXPECT_TRUE(r.screen.gyro_follow.follows) << report;
  EXPECT_FALSE(ReRenderedByStabiliser(r)) << report;
  ASSERT_EQ(r.loop.effects.size(), 1u) << report;
  EXPECT_EQ(Spec(r.loop.effects.front().effect).name, "gyro_to_camera") << report;
}

}  // namespace
}  // namespace shutterlab
