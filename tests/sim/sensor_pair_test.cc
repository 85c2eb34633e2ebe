// The pair of gyros: pairing on one clock, the mounting fitted from the motion (and left alone
// when the motion is too small to show it), and the fused noise: 1/sqrt(2) of either sensor's for
// two equal independent ones, the inverse-variance result for unequal ones.

#include "sim/sensor_pair.h"

#include "sim/so3.h"
#include "sim/units.h"
#include "tests/test_util.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace shutterlab {
namespace {

constexpr double kRateHz = 8000.0;
constexpr int64_t kPeriodNs = 125000;

// A sensor: rate(t) seen in its own axes (sensor_from_body), plus white noise of std sigma and a
// bias, sampled every period from offset_ns.
GyroTrace Sensor(const Eigen::Matrix3d& sensor_from_body, double sigma, const Eigen::Vector3d& bias,
                 int64_t offset_ns, double motion_rad_s, uint64_t seed, double duration_s = 4.0) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, sigma);
  std::vector<GyroSample> samples;
  for (int64_t k = 0; k * kPeriodNs < duration_s * 1e9; ++k) {
    const int64_t t_ns = offset_ns + k * kPeriodNs;
    const double t = t_ns * 1e-9;
    const Eigen::Vector3d body =
        motion_rad_s *
        Eigen::Vector3d(std::sin(2.1 * t), std::cos(3.7 * t), std::sin(5.3 * t + 1.0));
    samples.push_back({t_ns, sensor_from_body * body + bias +
                                 Eigen::Vector3d(normal(rng), normal(rng), normal(rng))});
  }
  return GyroTrace(std::move(samples));
}

double Std(const GyroTrace& trace, int axis) {
  double sum = 0, sum_sq = 0;
  for (const auto& s : trace.samples()) {
    sum += s.omega_rad_s[axis];
    sum_sq += s.omega_rad_s[axis] * s.omega_rad_s[axis];
  }
  const double n = static_cast<double>(trace.size());
  return std::sqrt(sum_sq / n - (sum / n) * (sum / n));
}

// The std of 32000 samples is known to about 1/sqrt(2 n) = 0.4 %; 2 % leaves room.
constexpr double kStdTolerance = 0.02;

TEST(SensorPair, TwoEqualIndependentStillSensorsFuseToOneOverRootTwo) {
  const double sigma = 0.006;
  const GyroTrace a = Sensor(Eigen::Matrix3d::Identity(), sigma, {0.01, -0.007, 0.004}, 0, 0.0, 1);
  const GyroTrace b =
      Sensor(Eigen::Matrix3d::Identity(), sigma, {-0.003, 0.002, 0.009}, 40000, 0.0, 2);
  SensorPairOptions options;
  options.still = BiasSegment{0.0, 4.0};
  const SensorPair pair = FuseSensorPair(a, b, options);
  EXPECT_EQ(pair.paired, a.size());
  EXPECT_FALSE(pair.mounting_fitted);  // noise only: nothing to fit the mounting on
  EXPECT_TRUE(pair.a_from_b.isIdentity(1e-12));
  for (int axis = 0; axis < 3; ++axis) {
    EXPECT_NEAR(pair.weight_a[axis], 0.5, 0.02);
    EXPECT_NEAR(Std(a, axis) / Std(pair.fused, axis), std::sqrt(2.0),
                std::sqrt(2.0) * kStdTolerance);
  }
  EXPECT_NEAR(pair.residual_rms_rad_s, sigma * std::sqrt(2.0),
              sigma * std::sqrt(2.0) * kStdTolerance);
}

TEST(SensorPair, UnequalSensorsAreWeighedByTheirStillVariance) {
  const double sigma_a = 0.004, sigma_b = 0.008;
  const GyroTrace a =
      Sensor(Eigen::Matrix3d::Identity(), sigma_a, Eigen::Vector3d::Zero(), 0, 0.0, 3);
  const GyroTrace b =
      Sensor(Eigen::Matrix3d::Identity(), sigma_b, Eigen::Vector3d::Zero(), 0, 0.0, 4);
  SensorPairOptions options;
  options.still = BiasSegment{0.0, 4.0};
  const SensorPair pair = FuseSensorPair(a, b, options);
  // w = sb^2 / (sa^2 + sb^2) = 0.8; the fused variance sa^2 sb^2 / (sa^2 + sb^2).
  const double expected_std = sigma_a * sigma_b / std::hypot(sigma_a, sigma_b);
  for (int axis = 0; axis < 3; ++axis) {
    EXPECT_NEAR(pair.weight_a[axis], 0.8, 0.02);
    EXPECT_NEAR(Std(pair.fused, axis), expected_std, expected_std * kStdTolerance);
  }
}

TEST(SensorPair, TheMountingIsFittedFromTheMotion) {
  // The second sensor turned 90 deg about z and tilted 10 deg about x against the first.
  const Eigen::Matrix3d b_from_a = (Eigen::AngleAxisd(10.0 * kPi / 180, Eigen::Vector3d::UnitX()) *
                                    Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitZ()))
                                       .toRotationMatrix();
  const GyroTrace a = Sensor(Eigen::Matrix3d::Identity(), 0.006, {0.01, 0.0, 0.0}, 0, 0.5, 5);
  const GyroTrace b = Sensor(b_from_a, 0.006, {0.0, 0.02, -0.01}, 30000, 0.5, 6);
  const SensorPair pair = FuseSensorPair(a, b, SensorPairOptions{});
  ASSERT_TRUE(pair.mounting_fitted);
  const double error_rad = Eigen::AngleAxisd(pair.a_from_b * b_from_a).angle();
  // Noise and the 30 us pairing offset leave a small error: well under 0.1 deg.
  EXPECT_LT(error_rad * 180 / kPi, 0.1);
  EXPECT_NEAR(pair.mounting_angle_deg, Eigen::AngleAxisd(b_from_a).angle() * 180 / kPi, 0.1);
  // The fused trace follows the first sensor's axes.
  double worst = 0;
  for (size_t k = 0; k < pair.fused.size(); k += 97) {
    worst = std::max(worst, (pair.fused[k].omega_rad_s - a[k].omega_rad_s).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst, 0.05);  // a few noise sigmas plus half the bias difference
}

TEST(SensorPair, SensorsOnDifferentClocksAreRefused) {
  const GyroTrace a =
      Sensor(Eigen::Matrix3d::Identity(), 0.006, Eigen::Vector3d::Zero(), 0, 0.0, 7, 0.1);
  const GyroTrace b =
      Sensor(Eigen::Matrix3d::Identity(), 0.006, Eigen::Vector3d::Zero(), 5000000000, 0.0, 8, 0.1);
  EXPECT_THROW(FuseSensorPair(a, b, SensorPairOptions{}), std::invalid_argument);
}

}  // namespace
}  // namespace shutterlab
