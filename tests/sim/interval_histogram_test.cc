#include "sim/interval_histogram.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

namespace shutterlab {
namespace {

// AddRun(v, n) is n calls of Add(v): the same median and counts, also across the switch to
// buckets once the distinct values overflow, with runs of every length in between.
TEST(IntervalHistogram, AddRunIsRepeatedAdd) {
  std::mt19937_64 rng(18);
  for (int trial = 0; trial < 6; ++trial) {
    IntervalHistogram one_by_one, in_runs;
    // Trials 4 and 5 take more distinct values than are counted exactly.
    const bool many = trial >= 4;
    const size_t runs = many ? 3 * IntervalHistogram::kMaxExactValues : 2000;
    for (size_t r = 0; r < runs; ++r) {
      const int64_t value = rng() % 3 == 0 ? 1'000'000 : static_cast<int64_t>(rng() % 50'000'000);
      const size_t count = rng() % 4 == 0 ? 0 : 1 + rng() % (many || rng() % 2 ? 3 : 500);
      for (size_t i = 0; i < count; ++i) one_by_one.Add(value);
      in_runs.AddRun(value, count);
    }
    EXPECT_EQ(in_runs.count(), one_by_one.count()) << trial;
    EXPECT_EQ(in_runs.exact(), one_by_one.exact()) << trial;
    EXPECT_EQ(in_runs.exact(), trial < 4) << trial;
    EXPECT_EQ(in_runs.Median(), one_by_one.Median()) << trial;
    for (double threshold : {0.0, 999'999.0, 3e6, 2.5e7})
      EXPECT_EQ(in_runs.CountAbove(threshold), one_by_one.CountAbove(threshold)) << trial;
  }
}

}  // namespace
}  // namespace shutterlab
