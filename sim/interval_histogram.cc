#include "sim/interval_histogram.h"

#include <algorithm>

namespace shutterlab {

int64_t IntervalHistogram::Bucket(int64_t interval_ns) {
  if (interval_ns < (int64_t{1} << kBucketBits)) return interval_ns;
  const int bits = 64 - __builtin_clzll(static_cast<unsigned long long>(interval_ns));
  const int drop = bits - kBucketBits;
  return (interval_ns >> drop) << drop;
}

void IntervalHistogram::Flush() {
  if (run_count_ == 0) return;
  counted_ += run_count_;
  if (large_.empty()) {
    auto it = std::lower_bound(small_.begin(), small_.end(), run_value_,
                               [](const auto& entry, int64_t v) { return entry.first < v; });
    if (it != small_.end() && it->first == run_value_) {
      it->second += run_count_;
    } else if (small_.size() < kSmallValues) {
      small_.insert(it, {run_value_, run_count_});
    } else {
      large_.insert(small_.begin(), small_.end());
      small_.clear();
      large_[run_value_] += run_count_;
    }
  } else {
    large_[run_value_] += run_count_;
    if (exact_ && large_.size() > kMaxExactValues) {
      // Too many distinct values to keep: count them in buckets from here on.
      std::unordered_map<int64_t, size_t> buckets;
      for (const auto& [value, n] : large_) buckets[Bucket(value)] += n;
      large_ = std::move(buckets);
      exact_ = false;
    }
  }
  run_count_ = 0;
}

std::vector<std::pair<int64_t, size_t>> IntervalHistogram::Sorted() const {
  std::vector<std::pair<int64_t, size_t>> all = small_;
  all.insert(all.end(), large_.begin(), large_.end());
  if (run_count_ > 0) all.emplace_back(run_value_, run_count_);
  std::sort(all.begin(), all.end());
  return all;
}

int64_t IntervalHistogram::Median() const {
  const size_t n = count();
  if (n == 0) return 0;
  size_t seen = 0;
  const auto all = Sorted();
  for (const auto& [value, count] : all) {
    seen += count;
    if (seen > n / 2) return value;
  }
  return all.back().first;
}

size_t IntervalHistogram::CountAbove(double threshold_ns) const {
  size_t above = 0;
  for (const auto& [value, count] : Sorted()) {
    if (static_cast<double>(value) > threshold_ns) above += count;
  }
  return above;
}

}  // namespace shutterlab
