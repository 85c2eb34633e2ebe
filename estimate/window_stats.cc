#include "estimate/window_stats.h"

#include <algorithm>
#include <cmath>

#include "sim/check.h"

namespace shutterlab {

std::vector<uint32_t> WindowEndsByDuration(const std::vector<int64_t>& t_ns, int64_t window_ns) {
  SHUTTERLAB_CHECK(window_ns > 0) << "window duration must be positive";
  SHUTTERLAB_CHECK(t_ns.size() < (1ull << 32)) << "trace too long for 32-bit window indices";
  std::vector<uint32_t> ends;
  if (t_ns.empty()) return ends;
  const int64_t t_last = t_ns.back();
  size_t e = 0;
  for (size_t k = 0; k < t_ns.size() && t_ns[k] + window_ns <= t_last; ++k) {
    while (e < t_ns.size() && t_ns[e] < t_ns[k] + window_ns) ++e;
    ends.push_back(static_cast<uint32_t>(e));
  }
  return ends;
}

std::vector<double> SlidingRangeBruteForce(const std::vector<double>& x,
                                           const std::vector<uint32_t>& window_end) {
  std::vector<double> out(window_end.size());
  for (size_t k = 0; k < window_end.size(); ++k) {
    SHUTTERLAB_CHECK(window_end[k] > k && window_end[k] <= x.size()) << "bad window " << k;
    const auto [lo, hi] = std::minmax_element(x.begin() + k, x.begin() + window_end[k]);
    out[k] = *hi - *lo;
  }
  return out;
}

std::vector<double> SlidingStdDevBruteForce(const std::vector<double>& x,
                                            const std::vector<uint32_t>& window_end) {
  std::vector<double> out(window_end.size());
  for (size_t k = 0; k < window_end.size(); ++k) {
    SHUTTERLAB_CHECK(window_end[k] > k && window_end[k] <= x.size()) << "bad window " << k;
    const size_t n = window_end[k] - k;
    double mean = 0;
    for (size_t i = k; i < window_end[k]; ++i) mean += x[i];
    mean /= n;
    double ss = 0;
    for (size_t i = k; i < window_end[k]; ++i) ss += (x[i] - mean) * (x[i] - mean);
    // Population standard deviation (divide by n), as numpy.std and the paper's tables.
    out[k] = std::sqrt(ss / n);
  }
  return out;
}

}  // namespace shutterlab
