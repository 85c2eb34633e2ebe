#include "sim/logs/gyro_candidates.h"

#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

using internal::ChooseGyroSource;
using internal::GyroCandidate;

// n samples at `rate_hz` from t0_ns, sample k turning at (k, -k, 0.5 k) mrad/s so that a dropped
// or moved sample can be found again by its value.
GyroCandidate Stream(const std::string& name, int preference, double rate_hz, size_t n,
                     int64_t t0_ns = 1'000'000'000) {
  GyroCandidate c;
  c.name = name;
  c.preference = preference;
  const int64_t period_ns = std::llround(1e9 / rate_hz);
  for (size_t k = 0; k < n; ++k) {
    const double v = 1e-3 * static_cast<double>(k);
    c.samples.push_back({t0_ns + static_cast<int64_t>(k) * period_ns, {v, -v, 0.5 * v}});
  }
  return c;
}

bool HasWarning(const FlightLog& log, const std::string& text) {
  return test::AnyWarningContains(log.warnings, text);
}

TEST(GyroCandidates, BadTimesValuesAndSpikesAreDroppedAndCounted) {
  GyroCandidate c = Stream("GYR", 0, 1000.0, 100);
  const int64_t t_of_50 = c.samples[50].t_ns;
  c.samples[10].t_ns = 0;                                                    // no time
  c.samples[20].omega_rad_s.x() = std::numeric_limits<double>::quiet_NaN();  // no value
  c.samples[50].t_ns += 3'000'000'000;  // a corrupted time, 3 s ahead of both neighbours
  c.samples[50].omega_rad_s.x() = 7.0;
  c.samples[0].t_ns = c.samples[2].t_ns + 1;        // the first sample after its successors
  AddCandidateSample(std::nullopt, {1, 2, 3}, &c);  // a time beyond int64 ns: counted, not kept
  FlightLog log;
  ASSERT_TRUE(ChooseGyroSource({c}, &log));
  EXPECT_EQ(log.gyro_source, "GYR");
  ASSERT_EQ(log.gyro.size(), 96u);
  EXPECT_EQ(log.records_skipped, 5u);
  EXPECT_TRUE(HasWarning(log, "GYR: 1 samples with a zero timestamp dropped"));
  EXPECT_TRUE(HasWarning(log, "GYR: 1 samples with an unreadable timestamp"));
  EXPECT_TRUE(HasWarning(log, "GYR: 1 samples with a non-finite rate dropped"));
  EXPECT_TRUE(
      HasWarning(log, "GYR: 2 samples with a timestamp out of line with their neighbours dropped"));
  // What is left is the rest, in order, with its own values: sample 1 first, no sample at 50's
  // time, the spike's value gone.
  EXPECT_EQ(log.gyro.samples().front().omega_rad_s.x(), 1e-3);
  for (const GyroSample& s : log.gyro.samples()) {
    EXPECT_NE(s.t_ns, t_of_50);
    EXPECT_NE(s.omega_rad_s.x(), 7.0);
  }
  // The median interval, not the gaps, gives the rate.
  EXPECT_EQ(log.gyro_sources_available, std::vector<std::string>{"GYR (1000.0 Hz, 96 samples)"});
}

TEST(GyroCandidates, AnEndSampleMinutesAwayIsDropped) {
  GyroCandidate c = Stream("IMU", 0, 200.0, 50);
  c.samples.push_back({c.samples.back().t_ns + 120'000'000'000, {0, 0, 0}});
  FlightLog log;
  ASSERT_TRUE(ChooseGyroSource({c}, &log));
  EXPECT_EQ(log.gyro.size(), 50u);
  EXPECT_EQ(log.records_skipped, 1u);
  EXPECT_TRUE(HasWarning(log, "IMU: 1 samples more than 60 s beyond the rest dropped"));
}

TEST(GyroCandidates, TheHighestRateWinsOverABetterPreference) {
  FlightLog log;
  ASSERT_TRUE(ChooseGyroSource({Stream("sensor_gyro.x,y,z", 0, 200.0, 40),
                                Stream("sensor_combined.gyro_rad", 3, 1000.0, 200),
                                Stream("vehicle_angular_velocity.xyz", 2, 500.0, 100)},
                               &log));
  EXPECT_EQ(log.gyro_source, "sensor_combined.gyro_rad");
  EXPECT_EQ(log.gyro.size(), 200u);
  EXPECT_EQ(log.gyro_sources_available,
            (std::vector<std::string>{"sensor_combined.gyro_rad (1000.0 Hz, 200 samples)",
                                      "vehicle_angular_velocity.xyz (500.0 Hz, 100 samples)",
                                      "sensor_gyro.x,y,z (200.0 Hz, 40 samples)"}));
  EXPECT_TRUE(log.warnings.empty());
  EXPECT_EQ(log.records_skipped, 0u);
}

TEST(GyroCandidates, WithinTenPercentOfTheBestRateThePreferenceDecides) {
  // 950 Hz is within 10 % of 1000 Hz and preferred; 880 Hz is not within it, however preferred.
  FlightLog log;
  ASSERT_TRUE(ChooseGyroSource({Stream("fast", 1, 1000.0, 300), Stream("raw", 0, 950.0, 285),
                                Stream("rawest", -1, 880.0, 264)},
                               &log));
  EXPECT_EQ(log.gyro_source, "raw");
  ASSERT_EQ(log.gyro_sources_available.size(), 3u);
  EXPECT_EQ(log.gyro_sources_available[0].rfind("raw (", 0), 0u);   // the chosen one first,
  EXPECT_EQ(log.gyro_sources_available[1].rfind("fast (", 0), 0u);  // then by rate
  EXPECT_EQ(log.gyro_sources_available[2].rfind("rawest (", 0), 0u);
}

TEST(GyroCandidates, EqualPreferenceWithinTheBandTakesTheLongerStream) {
  FlightLog log;
  ASSERT_TRUE(
      ChooseGyroSource({Stream("GYR", 0, 1000.0, 100), Stream("GYR/1", 0, 990.0, 400)}, &log));
  EXPECT_EQ(log.gyro_source, "GYR/1");
  EXPECT_EQ(log.gyro.size(), 400u);
}

TEST(GyroCandidates, NoCandidateWithTwoSamplesIsNoGyro) {
  GyroCandidate zero_times = Stream("GYR", 0, 1000.0, 5);
  for (GyroSample& s : zero_times.samples) s.t_ns = 0;
  FlightLog log;
  EXPECT_FALSE(ChooseGyroSource({Stream("IMU", 0, 400.0, 1), zero_times}, &log));
  EXPECT_FALSE(ChooseGyroSource({}, &log));
  EXPECT_TRUE(log.gyro_source.empty());
}

}  // namespace
}  // namespace shutterlab
