#include "sim/logs/flight_log.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace shutterlab {
namespace {

constexpr int64_t kSecondNs = 1'000'000'000;

TEST(NavigationAt, VelocityIsLinearBetweenSamplesAndAbsentAcrossAGap) {
  const std::vector<VelocitySample> samples = {
      {10 * kSecondNs, Eigen::Vector3d(1.0, 2.0, 0.0)},
      {10 * kSecondNs + kSecondNs / 2, Eigen::Vector3d(3.0, -2.0, 1.0)},
      {13 * kSecondNs, Eigen::Vector3d(5.0, 0.0, 0.0)}};  // 2.5 s after the one before
  // A quarter of the way from the first to the second: (1.5, 1, 0.25).
  const auto quarter = VelocityAt(samples, 10 * kSecondNs + kSecondNs / 8);
  ASSERT_TRUE(quarter.has_value());
  EXPECT_NEAR((*quarter - Eigen::Vector3d(1.5, 1.0, 0.25)).norm(), 0.0, 1e-12);
  EXPECT_EQ(*VelocityAt(samples, 10 * kSecondNs), samples[0].ned_mps) << "on a sample";
  // Within a second before the first or after the last: the nearest sample's.
  EXPECT_EQ(*VelocityAt(samples, 9 * kSecondNs + 1), samples[0].ned_mps);
  EXPECT_EQ(*VelocityAt(samples, 14 * kSecondNs), samples[2].ned_mps);
  EXPECT_FALSE(VelocityAt(samples, 9 * kSecondNs - 1).has_value()) << "over a second before";
  EXPECT_FALSE(VelocityAt(samples, 14 * kSecondNs + 1).has_value()) << "over a second after";
  EXPECT_FALSE(VelocityAt(samples, 12 * kSecondNs).has_value()) << "inside a 2.5 s gap";
  EXPECT_FALSE(VelocityAt({}, 0).has_value());
}

TEST(NavigationAt, AttitudeTurnsAtAConstantRateBetweenSamples) {
  // Yaw 10 deg, then 50 deg 0.4 s later: at 0.1 s, a quarter of the way, yaw 20 deg.
  const auto yaw = [](double deg) {
    return Eigen::Quaterniond(Eigen::AngleAxisd(deg * M_PI / 180, Eigen::Vector3d::UnitZ()));
  };
  const std::vector<AttitudeSample> samples = {{kSecondNs, yaw(10)},
                                               {kSecondNs + 400'000'000, yaw(50)}};
  const auto at = AttitudeAt(samples, kSecondNs + 100'000'000);
  ASSERT_TRUE(at.has_value());
  EXPECT_NEAR(at->angularDistance(yaw(20)), 0.0, 1e-12);
  EXPECT_NEAR(AttitudeAt(samples, kSecondNs + 900'000'000)->angularDistance(yaw(50)), 0.0, 1e-12);
  EXPECT_FALSE(AttitudeAt(samples, 3 * kSecondNs).has_value());
}

}  // namespace
}  // namespace shutterlab
