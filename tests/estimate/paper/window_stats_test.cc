#include "estimate/paper/window_stats.h"

#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <stdexcept>
#include <vector>

namespace shutterlab {
namespace {

// The fast sigma restarts its sums whenever their worst-case rounding could exceed 5e-10 of the
// window sigma; 1e-8 leaves room for the brute force's own rounding and is far below anything we
// report.
constexpr double kStdDevRelTol = 1e-8;

std::vector<double> RandomSignal(size_t n, uint64_t seed, double scale = 1.0) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, scale);
  std::vector<double> x(n);
  for (double& v : x) v = normal(rng);
  return x;
}

void ExpectStdDevNear(const std::vector<double>& fast, const std::vector<double>& brute) {
  ASSERT_EQ(fast.size(), brute.size());
  for (size_t k = 0; k < fast.size(); ++k) {
    ASSERT_NEAR(fast[k], brute[k], kStdDevRelTol * brute[k] + 1e-300) << "window " << k;
  }
}

TEST(WindowStats, RangeEqualsBruteForceOnRandomDataFixedCount) {
  // Longer than one 16384-window chunk, and a window longer than a chunk.
  const auto x = RandomSignal(40000, 1);
  for (size_t count : {1, 2, 3, 7, 10, 120, 1000, 39000}) {
    const auto ends = WindowEndsByCount(x.size(), count);
    EXPECT_EQ(SlidingRange(x, ends), SlidingRangeBruteForce(x, ends)) << "count " << count;
    EXPECT_EQ(SlidingRangeByCount(x, count), SlidingRangeBruteForce(x, ends));
  }
}

TEST(WindowStats, RangeEqualsBruteForceWithJitterGapsAndDuplicates) {
  const size_t n = 60000;
  const auto t = test::IrregularTimes(n, 2);
  const auto x = RandomSignal(n, 3);
  for (int64_t window_ns : {500000, 1000000, 10000000, 20000000, 120000000}) {
    const auto ends = WindowEndsByDuration(t, window_ns);
    ASSERT_FALSE(ends.empty());
    // Gaps make some windows much shorter than others: the block fallback must cover them.
    size_t shortest = SIZE_MAX, longest = 0;
    for (size_t k = 0; k < ends.size(); ++k) {
      shortest = std::min<size_t>(shortest, ends[k] - k);
      longest = std::max<size_t>(longest, ends[k] - k);
    }
    if (window_ns >= 10000000) {
      EXPECT_LT(shortest, longest / 2) << "test data has no gaps";
    }
    EXPECT_EQ(SlidingRange(x, ends), SlidingRangeBruteForce(x, ends)) << window_ns;
  }
}

TEST(WindowStats, RangeOfRampIsSlopeTimesSpan) {
  // Known answer: x_i = 0.5 i, window of N samples spans N-1 steps.
  std::vector<double> x(1000);
  for (size_t i = 0; i < x.size(); ++i) x[i] = 0.5 * i;
  for (double r : SlidingRangeByCount(x, 25)) EXPECT_EQ(r, 12.0);
}

TEST(WindowStats, OneSampleWindowHasZeroRangeAndSigma) {
  const auto x = RandomSignal(1000, 4);
  for (double r : SlidingRangeByCount(x, 1)) EXPECT_EQ(r, 0.0);
  for (double s : SlidingStdDevByCount(x, 1)) EXPECT_EQ(s, 0.0);
}

TEST(WindowStats, WindowEqualToWholeTrace) {
  const auto x = RandomSignal(3000, 5);
  const auto range = SlidingRangeByCount(x, x.size());
  ASSERT_EQ(range.size(), 1u);
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  EXPECT_EQ(range[0], *hi - *lo);
  const auto sigma = SlidingStdDevByCount(x, x.size());
  ExpectStdDevNear(sigma, SlidingStdDevBruteForce(x, WindowEndsByCount(x.size(), x.size())));

  // By duration: the only window that fits is [t_0, t_last), which leaves the last sample out.
  std::vector<int64_t> t(x.size());
  for (size_t i = 0; i < t.size(); ++i) t[i] = static_cast<int64_t>(i) * 1000;
  const auto ends = WindowEndsByDuration(t, t.back() - t.front());
  ASSERT_EQ(ends.size(), 1u);
  EXPECT_EQ(ends[0], x.size() - 1);
}

TEST(WindowStats, WindowLongerThanTraceIsAnError) {
  const auto x = RandomSignal(100, 6);
  EXPECT_THROW(SlidingRangeByCount(x, 101), std::invalid_argument);
  EXPECT_THROW(SlidingStdDevByCount(x, 101), std::invalid_argument);
  EXPECT_THROW(SlidingRangeByCount(x, 0), std::invalid_argument);
  std::vector<int64_t> t(100);
  for (size_t i = 0; i < t.size(); ++i) t[i] = static_cast<int64_t>(i) * 1000;
  EXPECT_TRUE(WindowEndsByDuration(t, 100000).empty());  // longer than the 99 us span: no window
}

TEST(WindowStats, MalformedWindowEndsAreRejected) {
  const auto x = RandomSignal(10, 7);
  EXPECT_THROW(SlidingRange(x, {5, 4}), std::invalid_argument);  // decreasing
  EXPECT_THROW(SlidingRange(x, {0}), std::invalid_argument);     // empty window
  EXPECT_THROW(SlidingRange(x, {11}), std::invalid_argument);    // past the end
  EXPECT_THROW(SlidingStdDev(x, {5, 4}), std::invalid_argument);
}

TEST(WindowStats, StdDevMatchesBruteForceOnRandomData) {
  const auto x = RandomSignal(30000, 8, 3.0);
  for (size_t count : {2, 10, 120, 5000}) {
    const auto ends = WindowEndsByCount(x.size(), count);
    ExpectStdDevNear(SlidingStdDev(x, ends), SlidingStdDevBruteForce(x, ends));
  }
  const auto t = test::IrregularTimes(x.size(), 9);
  const auto ends = WindowEndsByDuration(t, 20000000);
  ExpectStdDevNear(SlidingStdDev(x, ends), SlidingStdDevBruteForce(x, ends));
}

// An integrated angle far from zero and drifting (bias residue), with a window sigma of ~1e-6 rad:
// the hard case for running sums. Naive sums of x and x^2 lose every digit here (checked below, so
// that this test can tell a stable method from an unstable one).
TEST(WindowStats, StdDevIsStableOnDriftingSignal) {
  const size_t n = 400000;
  auto x = RandomSignal(n, 10, 1e-6);
  for (size_t i = 0; i < n; ++i) x[i] += 100.0 + 2e-5 * static_cast<double>(i);  // 100 rad + drift
  const size_t count = 120;
  const auto ends = WindowEndsByCount(n, count);
  const auto brute = SlidingStdDevBruteForce(x, ends);
  ExpectStdDevNear(SlidingStdDev(x, ends), brute);

  // Naive running sums on the same data: error orders of magnitude above the tolerance.
  double s1 = 0, s2 = 0, worst_rel = 0;
  for (size_t i = 0; i < n; ++i) {
    s1 += x[i];
    s2 += x[i] * x[i];
    if (i >= count) {
      s1 -= x[i - count];
      s2 -= x[i - count] * x[i - count];
    }
    if (i + 1 >= count) {
      const double mean = s1 / count;
      const double naive = std::sqrt(std::max(0.0, s2 / count - mean * mean));
      const double b = brute[i + 1 - count];
      worst_rel = std::max(worst_rel, std::abs(naive - b) / b);
    }
  }
  EXPECT_GT(worst_rel, 1e3 * kStdDevRelTol);
}

TEST(WindowStats, StdDevOfConstantIsZero) {
  std::vector<double> x(5000, 1234.5678);
  for (double s : SlidingStdDevByCount(x, 50)) EXPECT_EQ(s, 0.0);
}

TEST(WindowStats, KernelChunkedMatchesWholeRun) {
  // The streaming kernel with a local ends array (as estimate/paper/flight uses it) equals
  // SlidingRange.
  const auto x = RandomSignal(20000, 11);
  const auto t = test::IrregularTimes(x.size(), 12);
  const auto ends = WindowEndsByDuration(t, 15000000);
  const auto whole = SlidingRange(x, ends);
  SlidingRangeKernel kernel;
  std::vector<double> out(ends.size());
  for (size_t k0 = 0; k0 < ends.size(); k0 += 777) {
    const size_t k1 = std::min(ends.size(), k0 + 777);
    std::vector<uint32_t> local(ends.begin() + k0, ends.begin() + k1);
    kernel.Run(x.data(), local.data(), k0, k1, out.data() + k0);
  }
  EXPECT_EQ(out, whole);

  // Three signals in one pass give each signal's own ranges.
  const auto y = RandomSignal(x.size(), 13), z = RandomSignal(x.size(), 14);
  std::array<std::vector<double>, 3> three;
  for (auto& o : three) o.resize(ends.size());
  for (size_t k0 = 0; k0 < ends.size(); k0 += 777) {
    const size_t k1 = std::min(ends.size(), k0 + 777);
    kernel.Run3({x.data(), y.data(), z.data()}, ends.data() + k0, k0, k1,
                {three[0].data() + k0, three[1].data() + k0, three[2].data() + k0});
  }
  EXPECT_EQ(three[0], whole);
  EXPECT_EQ(three[1], SlidingRangeBruteForce(y, ends));
  EXPECT_EQ(three[2], SlidingRangeBruteForce(z, ends));
}

TEST(WindowStats, KernelSetsOfSeveralDurationsMatchBruteForce) {
  // Windows of 3, 15 and 40 ms over the same irregular samples (gaps make some windows shorter
  // than the shared block), swept a chunk of starts at a time as estimate/paper/flight does: each
  // set's ranges equal its brute-force twin's, bit for bit, including the chunks where a longer set
  // has no window left.
  const auto x = RandomSignal(20000, 21), y = RandomSignal(20000, 22), z = RandomSignal(20000, 23);
  const auto t = test::IrregularTimes(x.size(), 24);
  std::vector<std::vector<uint32_t>> ends;
  for (int64_t window_ns : {3000000, 15000000, 40000000})
    ends.push_back(WindowEndsByDuration(t, window_ns));
  std::vector<std::array<std::vector<double>, 3>> got(ends.size());
  for (size_t d = 0; d < ends.size(); ++d) {
    for (auto& axis : got[d]) axis.assign(ends[d].size(), -1.0);
  }
  SlidingRangeKernel kernel;
  for (size_t k0 = 0; k0 < ends[0].size(); k0 += 777) {
    std::vector<SlidingRangeKernel::WindowSet> sets(ends.size());
    for (size_t d = 0; d < ends.size(); ++d) {
      sets[d].count = k0 < ends[d].size() ? std::min<size_t>(777, ends[d].size() - k0) : 0;
      sets[d].ends = sets[d].count > 0 ? ends[d].data() + k0 : nullptr;
      for (int a = 0; a < 3; ++a) sets[d].out[a] = got[d][a].data() + k0;
    }
    kernel.Run3Sets({x.data(), y.data(), z.data()}, k0, sets);
  }
  for (size_t d = 0; d < ends.size(); ++d) {
    EXPECT_EQ(got[d][0], SlidingRangeBruteForce(x, ends[d])) << "set " << d;
    EXPECT_EQ(got[d][1], SlidingRangeBruteForce(y, ends[d])) << "set " << d;
    EXPECT_EQ(got[d][2], SlidingRangeBruteForce(z, ends[d])) << "set " << d;
  }
}

TEST(WindowStats, KernelOnTiesSignedZerosAndOverflowEqualsBrute) {
  // Values drawn from a few, so that windows hold ties and +0 beside -0, and now and then +-1e308,
  // whose range overflows to infinity: the three-axis kernel (SSE2 lane pairs on x86; the
  // portable form in window_stats_portable_tests) gives the brute force's ranges.
  const double values[] = {-2.0, -1.0, -0.0, 0.0, 1.0, 2.0};
  std::mt19937_64 rng(31);
  std::array<std::vector<double>, 3> x;
  for (auto& axis : x) {
    axis.resize(6000);
    for (double& v : axis) v = rng() % 50 == 0 ? (rng() % 2 ? 1e308 : -1e308) : values[rng() % 6];
  }
  const auto ends = WindowEndsByDuration(test::IrregularTimes(x[0].size(), 32), 6000000);
  std::array<std::vector<double>, 3> got;
  for (auto& axis : got) axis.resize(ends.size());
  SlidingRangeKernel kernel;
  for (size_t k0 = 0; k0 < ends.size(); k0 += 1000) {
    const size_t k1 = std::min(ends.size(), k0 + 1000);
    kernel.Run3({x[0].data(), x[1].data(), x[2].data()}, ends.data() + k0, k0, k1,
                {got[0].data() + k0, got[1].data() + k0, got[2].data() + k0});
  }
  size_t infinite = 0;
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(got[a], SlidingRangeBruteForce(x[a], ends)) << "axis " << a;
    infinite += std::count_if(got[a].begin(), got[a].end(), [](double r) { return std::isinf(r); });
  }
  EXPECT_GT(infinite, 0u);
  EXPECT_LT(infinite, 3 * ends.size());
}

}  // namespace
}  // namespace shutterlab
