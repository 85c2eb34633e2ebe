#include "estimate/paper/plot_summary.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <utility>
#include <vector>

namespace shutterlab {
namespace {

// Quantiles and counts against the sorted values: within one bin (1/1024 of an octave) of the
// order statistic, and counts below any x within the one bin x falls in.
TEST(LogBinHistogram, QuantilesAndCountsWithinOneBinOfTheSortedValues) {
  std::mt19937 rng(9);
  std::lognormal_distribution<double> spread(2.0, 3.0);
  std::vector<double> values = {0.0, 0.0, 1e-9};  // zeros and an underflow land in bin 0
  for (int i = 0; i < 20000; ++i) values.push_back(spread(rng));
  values.push_back(1e300);  // past the last bin: counted there
  LogBinHistogram histogram;
  for (double v : values) histogram.Add(v);
  std::sort(values.begin(), values.end());
  ASSERT_EQ(histogram.total(), values.size());
  for (const size_t rank :
       {size_t{0}, size_t{3}, size_t{100}, size_t{10000}, size_t{19900}, values.size() - 2}) {
    const double exact = values[rank];
    EXPECT_NEAR(histogram.Quantile(rank), exact, std::max(exact / 1024.0, 6e-8)) << rank;
  }
  for (const double x : {1e-3, 0.5, 1.0, 7.389, 100.0, 1e4}) {
    const double exact = std::lower_bound(values.begin(), values.end(), x) - values.begin();
    // The values in x's bin: the most the interpolation can be off by.
    const double in_bin = std::lower_bound(values.begin(), values.end(), x * (1 + 1.0 / 512)) -
                          std::lower_bound(values.begin(), values.end(), x * (1 - 1.0 / 512));
    EXPECT_NEAR(histogram.CountBelow(x), exact, in_bin + 1e-9) << x;
  }
  EXPECT_EQ(histogram.CountBelow(0.0), 0.0);
  // Powers of two start a bin: the count below one is exact.
  const double below_8 = std::lower_bound(values.begin(), values.end(), 8.0) - values.begin();
  EXPECT_EQ(histogram.CountBelow(8.0), below_8);
  LogBinHistogram twice = histogram;
  twice.Merge(histogram);
  EXPECT_EQ(twice.total(), 2 * histogram.total());
  EXPECT_EQ(twice.CountBelow(8.0), 2 * below_8);
  EXPECT_THROW(histogram.Quantile(values.size()), std::invalid_argument);
}

// Without a cap, the union of sorted intervals as FlaggedIntervalsS merges them; with one, the
// count stays under it, every interval added stays covered, and only gaps up to filled_gap() are
// filled.
TEST(IntervalUnion, MergesTouchingIntervalsAndFillsShortGapsPastTheCap) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> step(0.0, 1.0), length(0.0, 0.6);
  std::vector<std::pair<double, double>> added;
  double t = 0.0;
  for (int i = 0; i < 5000; ++i) {
    t += step(rng) * (i % 100 == 0 ? 50.0 : 1.0);
    added.emplace_back(t, t + length(rng));
  }
  added.emplace_back(added.back().second, added.back().second + 1.0);  // touching: merged
  IntervalUnion exact, capped(40);
  for (const auto& [a, b] : added) {
    exact.Add(a, b);
    capped.Add(a, b);
    ASSERT_LE(capped.intervals().size(), 40u);
  }
  EXPECT_EQ(exact.filled_gap(), 0.0);
  std::vector<std::pair<double, double>> merged;
  for (const auto& [a, b] : added) {
    if (!merged.empty() && a <= merged.back().second) {
      merged.back().second = std::max(merged.back().second, b);
    } else {
      merged.emplace_back(a, b);
    }
  }
  EXPECT_EQ(exact.intervals(), merged);
  ASSERT_GT(merged.size(), 40u);
  EXPECT_GT(capped.filled_gap(), 0.0);
  const auto& kept = capped.intervals();
  for (size_t i = 1; i < kept.size(); ++i)
    EXPECT_GT(kept[i].first - kept[i - 1].second, capped.filled_gap());
  for (const auto& [a, b] : added) {
    const auto it = std::upper_bound(kept.begin(), kept.end(), std::make_pair(a, 1e300));
    ASSERT_NE(it, kept.begin());
    EXPECT_LE(std::prev(it)->first, a);
    EXPECT_GE(std::prev(it)->second, b);
  }
  // The long gaps (every 100th step, up to 50 s) survive.
  EXPECT_GE(kept.size(), 20u);
}

}  // namespace
}  // namespace shutterlab
