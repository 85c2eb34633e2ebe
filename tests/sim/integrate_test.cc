#include "sim/integrate.h"

#include "sim/bias.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <cmath>

namespace shutterlab {
namespace {

// A constant rate integrates exactly under the trapezoid rule: only rounding remains.
constexpr double kExactTol = 1e-10;

GyroTrace ConstantRate(const Eigen::Vector3d& omega, double rate_hz, double duration_s) {
  std::vector<GyroSample> samples;
  const int64_t period_ns = static_cast<int64_t>(std::llround(1e9 / rate_hz));
  for (int64_t k = 0; k * period_ns <= static_cast<int64_t>(duration_s * 1e9); ++k) {
    samples.push_back({1'000'000'000 + k * period_ns, omega});
  }
  return GyroTrace(std::move(samples));
}

TEST(IntegratePerAxis, ConstantRateIsExact) {
  const Eigen::Vector3d omega(0.1, -0.2, 0.05);
  const GyroTrace trace = ConstantRate(omega, 1000.0, 2.0);
  const PerAxisAngles angles = IntegratePerAxis(trace, Eigen::Vector3d::Zero());
  ASSERT_EQ(angles.size(), trace.size());
  const double t_s = (trace.t_end_ns() - trace.t_begin_ns()) * 1e-9;
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(angles.angle_rad[a][0], 0.0);
    EXPECT_NEAR(angles.angle_rad[a].back(), omega[a] * t_s, kExactTol);
  }
}

TEST(IntegratePerAxis, BiasIsSubtracted) {
  const Eigen::Vector3d omega(0.01, 0.01, 0.01);
  const GyroTrace trace = ConstantRate(omega, 500.0, 1.0);
  const PerAxisAngles angles = IntegratePerAxis(trace, omega);
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(angles.angle_rad[a].back(), 0.0, kExactTol);
}

TEST(OrientationTrace, ConstantRateMatchesClosedForm) {
  const Eigen::Vector3d omega(0.3, -0.1, 0.7);
  const GyroTrace trace = ConstantRate(omega, 2000.0, 1.0);
  const OrientationTrace orientation(trace);
  for (double tau : {0.0, 0.0001234, 0.25, 0.5000005, 1.0}) {
    const Eigen::Quaterniond expected = ExpSO3(omega * tau);
    test::ExpectRotationNear(orientation.WorldFromBodyAt(trace.t_begin_ns(), tau), expected,
                             kExactTol);
  }
}

TEST(OrientationTrace, SinusoidalRateMatchesAnalyticAngle) {
  // Rotation about a fixed axis: the angle is the integral of the rate, whatever its shape.
  const Eigen::Vector3d axis = Eigen::Vector3d(1, 2, -1).normalized();
  const double amplitude = 2.0, freq_hz = 3.0, rate_hz = 4000.0;
  std::vector<GyroSample> samples;
  for (int k = 0; k <= 4000; ++k) {
    const double t = k / rate_hz;
    samples.push_back({k * 250'000LL, axis * amplitude * std::sin(2 * M_PI * freq_hz * t)});
  }
  const OrientationTrace orientation{GyroTrace(samples)};
  for (double t : {0.1, 0.33, 0.777, 1.0}) {
    const double angle = amplitude / (2 * M_PI * freq_hz) * (1 - std::cos(2 * M_PI * freq_hz * t));
    // Trapezoid error ~ dt^2/12 * max|rate''| * T.
    test::ExpectRotationNear(orientation.WorldFromBodyAt(0, t), ExpSO3(axis * angle), 2e-6);
  }
}

TEST(OrientationTrace, LookupOutsideTraceFailsLoudly) {
  const GyroTrace trace = ConstantRate(Eigen::Vector3d::Zero(), 100.0, 1.0);
  const OrientationTrace orientation(trace);
  EXPECT_THROW(orientation.WorldFromBodyAt(trace.t_begin_ns() - 1), std::out_of_range);
  EXPECT_THROW(orientation.WorldFromBodyAt(trace.t_end_ns(), 1e-10), std::out_of_range);
  EXPECT_NO_THROW(orientation.WorldFromBodyAt(trace.t_end_ns()));
}

TEST(EstimateBias, RecoversConstantBiasAndFirstIndexAfter) {
  const Eigen::Vector3d bias(0.001, -0.002, 0.0005);
  const GyroTrace trace = ConstantRate(bias, 1000.0, 10.0);
  const BiasEstimate estimate = EstimateBias(trace, {0.0, 5.0});
  EXPECT_LE((estimate.bias_rad_s - bias).norm(), 1e-15);
  EXPECT_EQ(estimate.samples, 5000u);
  EXPECT_EQ(estimate.first_after, 5000u);
}

// [begin_s, end_s): a sample at exactly end_s is outside (the still segment's Allan deviation used
// to take it in), one at exactly begin_s inside.
TEST(EstimateBias, SegmentIsHalfOpen) {
  const GyroTrace trace = ConstantRate(Eigen::Vector3d::Zero(), 1000.0, 10.0);  // t = k ms
  const SampleRange range = SamplesInSegment(trace, {1.0, 2.0});
  EXPECT_EQ(trace[range.begin].t_ns - trace.t_begin_ns(), 1'000'000'000);
  EXPECT_EQ(range.end - range.begin, 1000u);
  EXPECT_EQ(trace[range.end].t_ns - trace.t_begin_ns(), 2'000'000'000);
  EXPECT_EQ(SamplesInSegment(trace, {0.0, 5.0}).end, EstimateBias(trace, {0.0, 5.0}).first_after);
}

TEST(EstimateBias, RejectsSegmentWithTooFewSamples) {
  const GyroTrace trace = ConstantRate(Eigen::Vector3d::Zero(), 100.0, 1.0);
  EXPECT_THROW(EstimateBias(trace, {2.0, 5.0}), std::invalid_argument);
  // Seconds as the contract has it, or any duration; a bare side is seconds.
  EXPECT_DOUBLE_EQ(ParseBiasSegment("500ms:3s").begin_s, 0.5);
  EXPECT_DOUBLE_EQ(ParseBiasSegment("1:1500ms").begin_s, 1.0);
  EXPECT_DOUBLE_EQ(ParseBiasSegment("1:1500ms").end_s, 1.5);
  EXPECT_DOUBLE_EQ(ParseBiasSegment("0:5").end_s, 5.0);
  EXPECT_THROW(ParseBiasSegment("0:5m"), std::invalid_argument);  // a length
  EXPECT_THROW(ParseBiasSegment("5"), std::invalid_argument);
  EXPECT_THROW(ParseBiasSegment("3:1"), std::invalid_argument);
  const BiasSegment s = ParseBiasSegment("0.5:4");
  EXPECT_EQ(s.begin_s, 0.5);
  EXPECT_EQ(s.end_s, 4.0);
}

}  // namespace
}  // namespace shutterlab
