#include "sim/gyro_trace.h"

#include "sim/check.h"
#include "sim/text_file.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace shutterlab {
namespace {

TEST(GyroTrace, RejectsDecreasingTimestamps) {
  std::vector<GyroSample> s = {{0, {0, 0, 0}}, {10, {0, 0, 0}}, {5, {0, 0, 0}}};
  EXPECT_THROW(GyroTrace{s}, std::invalid_argument);
}

TEST(GyroTrace, RejectsNonFiniteRates) {
  std::vector<GyroSample> s = {{0, {0, 0, 0}}, {10, {0, std::nan(""), 0}}};
  EXPECT_THROW(GyroTrace{s}, std::invalid_argument);
}

TEST(GyroTrace, ReportsGapsAndDuplicates) {
  std::vector<GyroSample> s;
  int64_t t = 0;
  for (int k = 0; k < 100; ++k) {
    s.push_back({t, {0, 0, 0}});
    t += (k == 40) ? 3'500'000 : (k == 70 ? 0 : 1'000'000);  // one 3.5x gap, one duplicate
  }
  const GyroTrace trace(s);
  EXPECT_EQ(trace.sampling().median_interval_ns, 1'000'000);
  ASSERT_EQ(trace.sampling().gap_indices.size(), 1u);
  EXPECT_EQ(trace.sampling().gap_indices[0], 40u);
  EXPECT_EQ(trace.sampling().duplicate_timestamps, 1u);
  EXPECT_NEAR(trace.sampling().RateHz(), 1000.0, 1e-9);
}

// A logger that stamps its samples in threes with one time, every 1 ms: a median interval of 0.
// Its rate is its samples over its span (3 kHz, not "0 Hz"), and its gaps are judged against its
// stamp period (every 1 ms step was a gap against a median of 0); a 0.5 s pause is the one gap.
TEST(GyroTrace, BurstStampedSamplesHaveTheirRateAndOnlyRealGaps) {
  std::vector<GyroSample> s;
  for (int k = 0; k < 30000; ++k) {
    const int64_t stamp_ms = k / 3 + (k >= 15000 ? 500 : 0);  // the pause after 5 s
    s.push_back({stamp_ms * 1'000'000, {0, 0, 0}});
  }
  const GyroTrace trace(s);
  EXPECT_EQ(trace.sampling().median_interval_ns, 0);
  EXPECT_EQ(trace.sampling().duplicate_timestamps, 20000u);
  // 30,000 samples over 10.499 s.
  EXPECT_EQ(trace.sampling().nominal_interval_ns, 10'499'000'000 / 29'999);
  EXPECT_NEAR(trace.sampling().RateHz(), 29999 / 10.499, 0.01);
  ASSERT_EQ(trace.sampling().gap_indices.size(), 1u);
  EXPECT_EQ(trace.sampling().gap_indices[0], 14999u);
  // NominalIntervalNs: the median when there is one; nothing for fewer than 2 samples or no span.
  EXPECT_EQ(NominalIntervalNs(1000, 5, 1'000'000), 1000);
  EXPECT_EQ(NominalIntervalNs(0, 4, 3000), 1000);
  EXPECT_EQ(NominalIntervalNs(0, 1, 3000), 0);
  EXPECT_EQ(NominalIntervalNs(0, 4, 0), 0);
}

TEST(GyroTrace, MedianIntervalIsExactForRegularAndIrregularClocks) {
  std::mt19937_64 rng(7);
  for (int distinct : {3, 1000}) {
    std::uniform_int_distribution<int64_t> interval(1000, 1000 + distinct - 1);
    std::vector<GyroSample> s;
    std::vector<int64_t> intervals;
    int64_t t = 0;
    for (int k = 0; k < 5001; ++k) {
      s.push_back({t, {0, 0, 0}});
      const int64_t dt = interval(rng);
      if (k < 5000) intervals.push_back(dt);
      t += dt;
    }
    std::sort(intervals.begin(), intervals.end());
    EXPECT_EQ(GyroTrace(s).sampling().median_interval_ns, intervals[intervals.size() / 2])
        << distinct << " distinct intervals";
  }
}

}  // namespace
}  // namespace shutterlab
