#pragma once
// The distribution of a trace's sampling intervals, gathered one interval at a time in bounded
// memory: the median interval (the trace's rate) and the count of gaps over a multiple of it. One
// place for both, whether the trace is held whole (GyroTrace) or streamed (TraceAuditor).

#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

namespace shutterlab {

class IntervalHistogram {
 public:
  // Intervals are counted exactly while they take at most this many distinct values (the real
  // logs we know take a few, a clock tick or two, up to some thousands for a jittery phone clock).
  // Beyond it they are counted in buckets 2^-kBucketBits of their value wide, so that memory stays
  // bounded (a few MB) for any trace; the median is then exact to 1/4096 relative.
  static constexpr size_t kMaxExactValues = 1 << 16;
  static constexpr int kBucketBits = 12;

  void Add(int64_t interval_ns) {
    const int64_t key = exact_ ? interval_ns : Bucket(interval_ns);
    if (key == run_value_) {
      ++run_count_;
      return;
    }
    Flush();
    run_value_ = key;
    run_count_ = 1;
  }
  // The same as `count` calls of Add(interval_ns), in O(1) once the value is the current run's
  // (a caller that sees runs of equal intervals counts them itself and hands them over here).
  void AddRun(int64_t interval_ns, size_t count) {
    while (count > 0) {
      const int64_t key = exact_ ? interval_ns : Bucket(interval_ns);
      if (key == run_value_) {  // Add would only count it, so would every further one
        run_count_ += count;
        return;
      }
      Add(interval_ns);
      --count;
    }
  }
  size_t count() const { return counted_ + run_count_; }
  // The interval at sorted position count() / 2 (for an even count the upper of the two middle
  // ones, a value that occurs), as UpperMedian of all the intervals gives; 0 when empty.
  int64_t Median() const;
  // How many intervals exceed threshold_ns.
  size_t CountAbove(double threshold_ns) const;
  // False once the distinct values overflowed into buckets.
  bool exact() const { return exact_; }

 private:
  static int64_t Bucket(int64_t interval_ns);
  void Flush();
  // Every (value, count), ascending, the current run included.
  std::vector<std::pair<int64_t, size_t>> Sorted() const;

  // Few distinct values (the usual case) stay in a small sorted vector; more go to the map.
  static constexpr size_t kSmallValues = 64;
  std::vector<std::pair<int64_t, size_t>> small_;
  std::unordered_map<int64_t, size_t> large_;
  size_t counted_ = 0;  // intervals in small_ or large_
  int64_t run_value_ = 0;
  size_t run_count_ = 0;  // a run of equal intervals not yet counted in small_ or large_
  bool exact_ = true;
};

}  // namespace shutterlab
