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
