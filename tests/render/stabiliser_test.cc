// The stabiliser's per-frame rotations (render/stabiliser.h) on motions with known answers.

#include "render/stabiliser.h"

#include "sim/so3.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace shutterlab {
namespace {

// 31 frames at 30 fps of a camera turning at a constant rate (camera axes), 3 rows each.
struct Turning {
  std::vector<FrameMotion> motions;
  std::vector<double> t_s;
};
Turning ConstantRate(const Eigen::Vector3d& rate_rad_s) {
  Turning out;
  for (int k = 0; k <= 30; ++k) {
    const double t = k / 30.0;
    FrameMotion m;
    m.world_from_cam.assign(3, ExpSO3(rate_rad_s * t).toRotationMatrix());
    m.cam_center_m.assign(3, Eigen::Vector3d::Zero());
    out.motions.push_back(m);
    out.t_s.push_back(t);
  }
  return out;
}

// The turned frames' rotation from frame k-1 to k, camera axes.
Eigen::Vector3d Step(const Turning& c, const std::vector<Eigen::Matrix3d>& s, size_t k) {
  const Eigen::Matrix3d a = c.motions[k - 1].world_from_cam[1] * s[k - 1];
  const Eigen::Matrix3d b = c.motions[k].world_from_cam[1] * s[k];
  return LogSO3(Eigen::Quaterniond(a.transpose() * b));
}

TEST(StabiliserRotations, RollLockHoldsTheRollAndKeepsTheOtherAxes) {
  const Turning c = ConstantRate({0.3, -0.2, 0.6});
  StabiliserOptions options;
  options.mode = StabiliserMode::kRollLock;
  const std::vector<Eigen::Matrix3d> s = StabiliserRotations(options, c.motions, c.t_s);
  EXPECT_TRUE(s[0].isIdentity(1e-12));
  for (size_t k = 1; k < s.size(); ++k) {
    const Eigen::Vector3d step = Step(c, s, k);
    // The roll per frame was 0.02 rad; what stays is second order (x and y turned by the roll).
    EXPECT_LT(std::abs(step.z()), 2e-4) << k;
    EXPECT_NEAR(std::hypot(step.x(), step.y()), std::hypot(0.3, 0.2) / 30.0, 1e-4) << k;
  }
}

// Smoothing keeps a constant rate (a straight line is its own Gaussian average) away from the
// clip's ends, and removes a wobble.
TEST(StabiliserRotations, SmoothingKeepsAConstantRate) {
  const Turning c = ConstantRate({0.3, -0.2, 0.6});
  for (StabiliserMode mode : {StabiliserMode::kRoll, StabiliserMode::kWhole}) {
    StabiliserOptions options;
    options.mode = mode;
    options.window_s = 0.1;
    const std::vector<Eigen::Matrix3d> s = StabiliserRotations(options, c.motions, c.t_s);
    for (size_t k = 12; k + 12 < s.size(); ++k) {
      EXPECT_LT(LogSO3(Eigen::Quaterniond(s[k])).norm(), 1e-3) << StabiliserModeName(mode) << k;
    }
  }
}

TEST(StabiliserRotations, RollSmoothingRemovesAFastRoll) {
  Turning c = ConstantRate(Eigen::Vector3d::Zero());
  for (size_t k = 0; k < c.motions.size(); ++k) {
    // A 0.02 rad roll alternating frame to frame (15 Hz) on a slow pitch.
    const double roll = (k % 2 ? 0.02 : -0.02);
    c.motions[k].world_from_cam.assign(
        3, (ExpSO3(Eigen::Vector3d(0.1 * c.t_s[k], 0, 0)) * ExpSO3(Eigen::Vector3d(0, 0, roll)))
               .toRotationMatrix());
  }
  StabiliserOptions options;
  options.mode = StabiliserMode::kRoll;
  options.window_s = 0.2;
  const std::vector<Eigen::Matrix3d> s = StabiliserRotations(options, c.motions, c.t_s);
  for (size_t k = 8; k + 8 < s.size(); ++k) {
    const Eigen::Vector3d step = Step(c, s, k);
    EXPECT_LT(std::abs(step.z()), 2e-3) << k;      // the 0.04 rad steps are gone
    EXPECT_NEAR(step.x(), 0.1 / 30.0, 2e-4) << k;  // the pitch is kept
  }
}

TEST(StabiliserRotations, ModeNamesRoundTrip) {
  for (StabiliserMode m : {StabiliserMode::kOff, StabiliserMode::kWhole, StabiliserMode::kRoll,
                           StabiliserMode::kRollLock}) {
    EXPECT_EQ(ParseStabiliserMode(StabiliserModeName(m)), m);
  }
  EXPECT_FALSE(ParseStabiliserMode("horizon").has_value());
  StabiliserOptions bad;
  bad.window_s = 0.0;
  EXPECT_THROW(bad.Check(), std::invalid_argument);
}

}  // namespace
}  // namespace shutterlab
