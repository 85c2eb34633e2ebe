#include "sim/logs/log_clock.h"

#include "sim/civil_time.h"
#include "sim/logs/ulog.h"
#include "sim/logs/ulog_write.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace shutterlab {
namespace {

constexpr int64_t kUtcAtBootNs = 1'721'122'000'000'000'000;  // 2024-07-16, about

// Fixes at 5 Hz for 100 s on a log clock that runs 20 ppm slow, with +-1 ms uniform jitter (seeded)
// and one receiver message 5 s off.
std::vector<UtcFix> Fixes() {
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<int64_t> jitter(-1'000'000, 1'000'000);
  std::vector<UtcFix> fixes;
  for (int k = 0; k < 500; ++k) {
    const int64_t t_ns = 10'000'000'000 + k * 200'000'000LL;
    const int64_t drift_ns = std::llround(20e-6 * t_ns);
    fixes.push_back({t_ns, kUtcAtBootNs + t_ns + drift_ns + jitter(rng)});
  }
  fixes[3].utc_ns += 5'000'000'000;
  return fixes;
}

TEST(LogUtcClock, FitsOffsetAndRateAndRejectsAJump) {
  const auto clock = FitLogUtcClock(Fixes());
  ASSERT_TRUE(clock);
  EXPECT_EQ(clock->fixes, 499u);
  EXPECT_EQ(clock->rejected, 1u);
  // Slope sigma = jitter rms / (rms of t * sqrt(n)) = 0.58 ms / (28.9 s * 22.4) = 0.9 ppm: 3 sigma.
  EXPECT_NEAR(clock->rate, 20e-6, 2.7e-6);
  // Uniform +-1 ms: rms 1/sqrt(3) ms.
  EXPECT_NEAR(clock->rms_residual_s, 1e-3 / std::sqrt(3.0), 0.1e-3);
  EXPECT_LE(clock->max_residual_s, 1.1e-3);
  const int64_t t_ns = 60'000'000'000;
  EXPECT_NEAR(static_cast<double>(clock->UtcNsFromLog(t_ns) - (kUtcAtBootNs + t_ns + 1'200'000)),
              0.0, 0.2e6);
  EXPECT_NEAR(static_cast<double>(clock->LogNsFromUtc(clock->UtcNsFromLog(t_ns)) - t_ns), 0.0, 2.0);
  EXPECT_FALSE(FitLogUtcClock({}));
  const auto one = FitLogUtcClock({{5, 105}});
  ASSERT_TRUE(one);
  EXPECT_EQ(one->LogNsFromUtc(1105), 1005);
}

TEST(LogUtcClock, ULogGpsTimeRoundTrips) {
  test::TempDir dir;
  std::vector<GyroSample> samples;
  for (int i = 0; i < 100; ++i) samples.push_back({1'000'000 + i * 10'000'000LL, {0, 0, 0}});
  ULogWriteOptions options;
  options.utc_fixes = {{200'000'000, kUtcAtBootNs + 200'000'000},
                       {400'000'000, kUtcAtBootNs + 400'000'000}};
  WriteULog(dir / "gps.ulg", GyroTrace(samples), {}, options);
  const FlightLog log = ReadULog(dir / "gps.ulg");
  ASSERT_EQ(log.utc_fixes.size(), 2u);
  EXPECT_EQ(log.utc_fixes[1].t_ns, 400'000'000);
  EXPECT_EQ(log.utc_fixes[1].utc_ns, kUtcAtBootNs + 400'000'000);
}

}  // namespace
}  // namespace shutterlab
