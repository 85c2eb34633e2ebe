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
#include <memory>
#include <random>
#include <string>
#include <vector>

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

// The pair read as streams (FitSensorPair, FusedPairSource) against FuseSensorPair on the traces
// held whole: the same sums in the same order, so every field and every fused sample to the bit.
// Chunks of a few samples put their edges everywhere.
void ExpectStreamedEqualsWhole(const GyroTrace& a, const GyroTrace& b,
                               const SensorPairOptions& options) {
  const SensorPair whole = FuseSensorPair(a, b, options);
  const int64_t b_interval_ns = b.sampling().median_interval_ns;
  for (const size_t chunk : {size_t{7}, size_t{4096}}) {
    SCOPED_TRACE("chunk " + std::to_string(chunk));
    const OpenGyroSource open_a = [&a, chunk] { return std::make_unique<TraceSource>(a, chunk); };
    const OpenGyroSource open_b = [&b, chunk] {
      return std::make_unique<TraceSource>(b, chunk + 3);
    };
    const SensorPair fit = FitSensorPair(open_a, open_b, b_interval_ns, options);
    EXPECT_EQ(fit.paired, whole.paired);
    EXPECT_EQ(fit.unpaired, whole.unpaired);
    EXPECT_EQ(fit.mounting_fitted, whole.mounting_fitted);
    EXPECT_EQ(fit.a_from_b, whole.a_from_b);
    EXPECT_EQ(fit.mounting_angle_deg, whole.mounting_angle_deg);
    EXPECT_EQ(fit.mounting_signal_ratio, whole.mounting_signal_ratio);
    EXPECT_EQ(fit.weight_a, whole.weight_a);
    EXPECT_EQ(fit.weights_from_still, whole.weights_from_still);
    EXPECT_EQ(fit.residual_rms_rad_s, whole.residual_rms_rad_s);
    EXPECT_TRUE(fit.fused.empty());
    std::unique_ptr<GyroSource> fused = FusedPairSource(open_a(), open_b(), fit, b_interval_ns);
    const GyroTrace streamed = ReadAllSamples(fused.get());
    ASSERT_EQ(streamed.size(), whole.fused.size());
    for (size_t k = 0; k < streamed.size(); ++k) {
      ASSERT_EQ(streamed[k].t_ns, whole.fused[k].t_ns) << k;
      ASSERT_EQ(streamed[k].omega_rad_s, whole.fused[k].omega_rad_s) << k;
    }
  }
}

TEST(SensorPair, StreamedEqualsTheWholeTracesToTheBit) {
  // Moving, the second turned against the first and sampled at half the rate, 0.2 s of it lost
  // (a's samples there have no partner); weights from a still segment.
  const Eigen::Matrix3d b_from_a =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  const GyroTrace a = Sensor(Eigen::Matrix3d::Identity(), 0.004, {0.01, 0.0, 0.0}, 0, 0.5, 9, 1.0);
  const GyroTrace b_full = Sensor(b_from_a, 0.008, {0.0, 0.02, -0.01}, 30000, 0.5, 10, 1.0);
  std::vector<GyroSample> b_samples;
  for (size_t k = 0; k < b_full.size(); k += 2) {
    if (b_full[k].t_ns < 400'000'000 || b_full[k].t_ns > 600'000'000)
      b_samples.push_back(b_full[k]);
  }
  const GyroTrace b(std::move(b_samples));
  SensorPairOptions options;
  options.still = BiasSegment{0.1, 0.35};
  const SensorPair whole = FuseSensorPair(a, b, options);
  ASSERT_TRUE(whole.mounting_fitted);
  ASSERT_TRUE(whole.weights_from_still);
  ASSERT_GT(whole.unpaired, 1000u);
  EXPECT_LT(Eigen::AngleAxisd(whole.a_from_b * b_from_a).angle() * 180 / kPi, 0.1);
  ExpectStreamedEqualsWhole(a, b, options);
  // Still sensors: the mounting cannot be fitted and the prior is kept; no still segment.
  const Eigen::Matrix3d prior = b_from_a.transpose();
  const GyroTrace still_a =
      Sensor(Eigen::Matrix3d::Identity(), 0.006, Eigen::Vector3d::Zero(), 0, 0.0, 11, 0.5);
  const GyroTrace still_b = Sensor(b_from_a, 0.006, Eigen::Vector3d::Zero(), 20000, 0.0, 12, 0.5);
  SensorPairOptions with_prior;
  with_prior.a_from_b_prior = prior;
  ASSERT_FALSE(FuseSensorPair(still_a, still_b, with_prior).mounting_fitted);
  ExpectStreamedEqualsWhole(still_a, still_b, with_prior);
}

TEST(SensorPair, StreamedRefusesWhatTheWholeRefuses) {
  const GyroTrace a =
      Sensor(Eigen::Matrix3d::Identity(), 0.006, Eigen::Vector3d::Zero(), 0, 0.0, 7, 0.1);
  const GyroTrace b =
      Sensor(Eigen::Matrix3d::Identity(), 0.006, Eigen::Vector3d::Zero(), 5000000000, 0.0, 8, 0.1);
  const OpenGyroSource open_a = [&a] { return std::make_unique<TraceSource>(a, 64); };
  const OpenGyroSource open_b = [&b] { return std::make_unique<TraceSource>(b, 64); };
  const OpenGyroSource open_empty = [] { return std::make_unique<TraceSource>(GyroTrace(), 64); };
  EXPECT_THROW(FitSensorPair(open_a, open_b, kPeriodNs, {}), std::invalid_argument);
  EXPECT_THROW(FitSensorPair(open_a, open_empty, kPeriodNs, {}), std::invalid_argument);
  EXPECT_THROW(FitSensorPair(open_empty, open_a, kPeriodNs, {}), std::invalid_argument);
}

}  // namespace
}  // namespace shutterlab
