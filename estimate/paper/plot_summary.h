#pragma once
// Bounded summaries of series too long to hold, for plots: what a report draws of a log of any
// length, accumulated a value at a time in memory that does not grow with the series.
//  - MinMaxEnvelope: the min/max envelope over equal x spans that DownsampleMinMax
//    (estimate/report/html_report.h) cuts from the whole series, the same numbers exactly.
//  - LogBinHistogram: counts of non-negative values in bins 1/1024 of an octave wide (relative
//    width <= 0.1 %), from which quantiles and counts over any interval are read (interpolated
//    within a bin).
//  - IntervalUnion: ascending intervals merged where they overlap or touch; past a cap, the
//    shortest gaps are filled so that the count stays bounded (said by filled_gap()).

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace shutterlab {

class MinMaxEnvelope {
 public:
  // `series` values per point, `points` calls of Add to come with x from x_first to x_last
  // (ascending). With points <= 2 * buckets every point is kept, as DownsampleMinMax keeps a short
  // chart unchanged. Throws std::invalid_argument when buckets or series is 0.
  MinMaxEnvelope(size_t series, size_t buckets, size_t points, double x_first, double x_last);
  // The next point (x ascending); y holds `series` values (NaN: none).
  void Add(double x, const double* y);
  // The envelope so far, every point added: x, and per series its values (one per x).
  const std::vector<double>& x() const;
  const std::vector<std::vector<double>>& y() const;
  // After the last Add: closes the last bucket.
  void Finish();

 private:
  struct Extreme {
    double value = 0.0;
    size_t at = 0;  // the point's position within its bucket
    bool any = false;
  };
  size_t Bucket(double x) const;
  void CloseBucket();

  size_t buckets_;
  bool keep_all_;
  double x0_, span_;
  size_t bucket_ = 0, in_bucket_ = 0;  // the open bucket and how many points it holds
  double bucket_first_x_ = 0.0, bucket_last_x_ = 0.0;
  std::vector<Extreme> lo_, hi_;  // per series: the bucket's first smallest and largest value
  std::vector<double> x_;
  std::vector<std::vector<double>> y_;
};

class LogBinHistogram {
 public:
  // Bins: the top 10 mantissa bits of a double with its exponent, for values in
  // [2^kMinExponent, 2^kMaxExponent); smaller values (zero included) count in an underflow bin
  // [0, 2^kMinExponent), larger ones in the last bin.
  static constexpr int kMinExponent = -24, kMaxExponent = 48;
  LogBinHistogram();
  // value >= 0, finite.
  void Add(double value) { ++counts_[Index(value)], ++total_; }
  void Merge(const LogBinHistogram& other);
  uint64_t total() const { return total_; }
  // The value of the rank-th smallest (0-based, rank < total()), interpolated linearly within its
  // bin: within one bin width (< 0.1 %) of the exact order statistic.
  double Quantile(uint64_t rank) const;
  // How many values are below x, interpolated linearly within x's bin (a fraction at most one
  // bin's count from the exact count).
  double CountBelow(double x) const;
  bool operator==(const LogBinHistogram& other) const { return counts_ == other.counts_; }

 private:
  static size_t Index(double value);
  static double BinLow(size_t index);
  std::vector<uint64_t> counts_;
  uint64_t total_ = 0;
};

class IntervalUnion {
 public:
  // max_intervals: the most kept; past it the shortest gaps are filled until half remain, and from
  // then on gaps up to filled_gap() are filled as they come. 0: no cap.
  explicit IntervalUnion(size_t max_intervals = 0) : max_intervals_(max_intervals) {}
  // [begin, end], begin ascending: merged with the last interval when begin - its end <=
  // filled_gap() (at first 0: it starts at or before the end).
  void Add(double begin, double end);
  const std::vector<std::pair<double, double>>& intervals() const { return intervals_; }
  // The longest gap filled to keep the count bounded; 0 while every interval is as added.
  double filled_gap() const { return filled_gap_; }

 private:
  void FillShortestGaps();
  size_t max_intervals_;
  double filled_gap_ = 0.0;
  std::vector<std::pair<double, double>> intervals_;
};

}  // namespace shutterlab
