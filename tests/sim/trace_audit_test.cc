#include "sim/trace_audit.h"

#include "sim/units.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace shutterlab {
namespace {

// n samples every interval_ns from t0_ns, all at rate (rad/s).
std::vector<GyroSample> Regular(size_t n, int64_t interval_ns, int64_t t0_ns = 0,
                                const Eigen::Vector3d& rate = Eigen::Vector3d::Zero()) {
  std::vector<GyroSample> samples;
  for (size_t k = 0; k < n; ++k)
    samples.push_back({t0_ns + static_cast<int64_t>(k) * interval_ns, rate});
  return samples;
}

std::string Joined(const std::vector<LogWarning>& warnings) {
  std::string all;
  for (const LogWarning& w : warnings) all += WarningLine(w) + "\n";
  return all;
}

TEST(AuditTrace, CleanTraceHasNothingToSay) {
  EXPECT_TRUE(AuditTrace(GyroTrace(Regular(5000, 1'000'000))).empty());
  EXPECT_TRUE(AuditTrace(GyroTrace()).empty());
}

TEST(AuditTrace, GapsWithCountMissingTimeAndTheLongest) {
  std::vector<GyroSample> samples = Regular(1000, 1'000'000);
  // Two pauses of the logger: 50 ms after sample 199 and 300 ms after sample 599.
  for (size_t k = 200; k < samples.size(); ++k) samples[k].t_ns += 49'000'000;
  for (size_t k = 600; k < samples.size(); ++k) samples[k].t_ns += 299'000'000;
  const std::vector<LogWarning> lines = AuditTrace(GyroTrace(samples));
  ASSERT_EQ(lines.size(), 1u) << Joined(lines);
  EXPECT_EQ(lines[0].kind, "gap");
  EXPECT_EQ(lines[0].message,
            "2 interval(s) over 3x the median 1.000 ms, 0.348 s missing in all; longest 0.300 s at "
            "0.648 s");
  EXPECT_EQ(lines[0].count, 2u);
  EXPECT_DOUBLE_EQ(*lines[0].t_s, 0.199);
}

TEST(AuditTrace, DuplicatedTimestamps) {
  std::vector<GyroSample> samples = Regular(100, 1'000'000);
  samples[50].t_ns = samples[49].t_ns;
  samples[51].t_ns = samples[49].t_ns;
  const std::vector<LogWarning> lines = AuditTrace(GyroTrace(samples));
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(WarningLine(lines.back()),
            "duplicate_time: 2 sample(s) share the time of the one before");
  EXPECT_DOUBLE_EQ(*lines.back().t_s, 0.049);
}

TEST(AuditTrace, SampleRateChangesAreListedWithTheirTimes) {
  // 3 s at 1 kHz, then 3 s at 250 Hz, then 2 s at 1 kHz.
  std::vector<GyroSample> samples = Regular(3000, 1'000'000);
  for (const GyroSample& s : Regular(750, 4'000'000, 3'000'000'000)) samples.push_back(s);
  for (const GyroSample& s : Regular(2000, 1'000'000, 6'000'000'000)) samples.push_back(s);
  const std::vector<LogWarning> lines = AuditTrace(GyroTrace(samples));
  ASSERT_EQ(lines.size(), 1u) << Joined(lines);
  EXPECT_EQ(WarningLine(lines[0]),
            "rate_change: sample rate changes 2 time(s): 1000 Hz, then 250 Hz from 3.000 s, then "
            "1000 Hz from 6.000 s");
  EXPECT_DOUBLE_EQ(*lines[0].t_s, 3.0);
}

TEST(AuditTrace, JitterIsNotARateChange) {
  std::vector<GyroSample> samples = Regular(8000, 1'000'000);
  for (size_t k = 0; k < samples.size(); ++k)
    samples[k].t_ns += (k * 7919 % 400) * 1000;  // +-0.2 ms
  EXPECT_TRUE(AuditTrace(GyroTrace(samples)).empty());
}

TEST(AuditTrace, SaturationAtAStatedFullScale) {
  const double full_scale = 250.0 * kRadPerDeg;
  std::vector<GyroSample> samples = Regular(1000, 1'000'000);
  for (size_t k = 400; k < 410; ++k) samples[k].omega_rad_s.z() = -full_scale;  // clipped
  samples[500].omega_rad_s.x() = 0.97 * full_scale;                             // not clipped
  TraceAuditOptions options;
  options.full_scale_rad_s = full_scale;
  const std::vector<LogWarning> lines = AuditTrace(GyroTrace(samples), options);
  ASSERT_EQ(lines.size(), 1u) << Joined(lines);
  EXPECT_EQ(WarningLine(lines[0]),
            "saturated: axis z, 10 sample(s) within 2 % of the +-250 deg/s full scale, peak 250 "
            "deg/s, from 0.400 s to 0.409 s: the rotation there is under-reported");
  EXPECT_EQ(lines[0].count, 10u);
  EXPECT_DOUBLE_EQ(*lines[0].t_s, 0.4);
}

TEST(AuditTrace, SaturationWhereThePeakLandsOnACommonFullScale) {
  std::vector<GyroSample> samples = Regular(1000, 20'000'000);
  samples[300].omega_rad_s = Eigen::Vector3d(1164, 2023, 1016) * kRadPerDeg;
  // The range is one for all axes: the 2023 deg/s peak says +-2000, so z's 1016 deg/s is not
  // clipped at +-1000.
  ASSERT_EQ(SaturationFullScale(GyroTrace(samples), {}), 2000.0 * kRadPerDeg);
  const std::vector<LogWarning> lines = AuditTrace(GyroTrace(samples));
  ASSERT_EQ(lines.size(), 1u) << Joined(lines);
  EXPECT_EQ(WarningLine(lines[0]).rfind("saturated: axis y, 1 sample(s) within 2 % of the +-2000 "
                                        "deg/s full scale (where the peak lands), peak 2023 deg/s, "
                                        "from 6.000 s",
                                        0),
            0u)
      << WarningLine(lines[0]);
  // A peak between the common ranges says nothing.
  samples[300].omega_rad_s = Eigen::Vector3d(0, 1500, 0) * kRadPerDeg;
  EXPECT_FALSE(SaturationFullScale(GyroTrace(samples), {}).has_value());
  EXPECT_TRUE(AuditTrace(GyroTrace(samples)).empty());
}

}  // namespace
}  // namespace shutterlab
