#include "estimate/paper/plot_summary.h"

#include "sim/check.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace shutterlab {

MinMaxEnvelope::MinMaxEnvelope(size_t series, size_t buckets, size_t points, double x_first,
                               double x_last)
    : buckets_(buckets),
      keep_all_(points <= 2 * buckets),
      x0_(x_first),
      span_(x_last - x_first),
      lo_(series),
      hi_(series),
      y_(series) {
  SHUTTERLAB_CHECK(buckets > 0 && series > 0) << "an envelope needs buckets and series";
}

// DownsampleMinMax's bucket of x, the same expression.
size_t MinMaxEnvelope::Bucket(double x) const {
  return span_ > 0 ? std::min(buckets_ - 1, static_cast<size_t>((x - x0_) / span_ * buckets_)) : 0;
}

void MinMaxEnvelope::Add(double x, const double* y) {
  if (keep_all_) {
    x_.push_back(x);
    for (size_t k = 0; k < y_.size(); ++k) y_[k].push_back(y[k]);
    return;
  }
  const size_t bucket = Bucket(x);
  if (in_bucket_ > 0 && bucket != bucket_) CloseBucket();
  if (in_bucket_ == 0) {
    bucket_ = bucket;
    bucket_first_x_ = x;
  }
  bucket_last_x_ = x;
  // The first smallest and the first largest finite value, as DownsampleMinMax picks them.
  for (size_t k = 0; k < y_.size(); ++k) {
    if (!std::isfinite(y[k])) continue;
    if (!lo_[k].any || y[k] < lo_[k].value) lo_[k] = {y[k], in_bucket_, true};
    if (!hi_[k].any || y[k] > hi_[k].value) hi_[k] = {y[k], in_bucket_, true};
  }
  ++in_bucket_;
}

void MinMaxEnvelope::CloseBucket() {
  const bool single = in_bucket_ == 1;
  x_.push_back(bucket_first_x_);
  if (!single) x_.push_back(bucket_last_x_);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (size_t k = 0; k < y_.size(); ++k) {
    const Extreme& lo = lo_[k];
    const Extreme& hi = hi_[k];
    if (single) {
      y_[k].push_back(lo.any ? lo.value : nan);
    } else if (!lo.any) {
      y_[k].insert(y_[k].end(), {nan, nan});
    } else {
      // In the order they came.
      y_[k].push_back(lo.at <= hi.at ? lo.value : hi.value);
      y_[k].push_back(lo.at <= hi.at ? hi.value : lo.value);
    }
    lo_[k] = hi_[k] = Extreme{};
  }
  in_bucket_ = 0;
}

void MinMaxEnvelope::Finish() {
  if (in_bucket_ > 0) CloseBucket();
}

const std::vector<double>& MinMaxEnvelope::x() const { return x_; }
const std::vector<std::vector<double>>& MinMaxEnvelope::y() const { return y_; }

namespace {

// A positive double's bits: 11 exponent bits, then 52 of mantissa; the top 10 of those split an
// octave into 1024 equal bins, and the bits read as an integer grow with the value.
constexpr int kMantissaBitsKept = 10;
constexpr int kDroppedBits = 52 - kMantissaBitsKept;

uint64_t Bits(double value) {
  uint64_t bits;
  std::memcpy(&bits, &value, sizeof(bits));
  return bits;
}

double FromBits(uint64_t bits) {
  double value;
  std::memcpy(&value, &bits, sizeof(value));
  return value;
}

const uint64_t kFirstKey = Bits(std::ldexp(1.0, LogBinHistogram::kMinExponent)) >> kDroppedBits;
const uint64_t kEndKey = Bits(std::ldexp(1.0, LogBinHistogram::kMaxExponent)) >> kDroppedBits;

}  // namespace

LogBinHistogram::LogBinHistogram() : counts_(kEndKey - kFirstKey + 1, 0) {}

size_t LogBinHistogram::Index(double value) {
  if (!(value > 0.0)) return 0;  // 0, -0 (its sign bit would read as a huge key) and below
  const uint64_t key = Bits(value) >> kDroppedBits;
  if (key < kFirstKey) return 0;  // underflow: [0, 2^kMinExponent)
  return static_cast<size_t>(std::min(key, kEndKey - 1) - kFirstKey + 1);
}

// Bin 0 is [0, 2^kMinExponent); bin i > 0 starts at the double whose top bits are its key.
double LogBinHistogram::BinLow(size_t index) {
  if (index == 0) return 0.0;
  return FromBits((kFirstKey + index - 1) << kDroppedBits);
}

void LogBinHistogram::Merge(const LogBinHistogram& other) {
  for (size_t i = 0; i < counts_.size(); ++i) counts_[i] += other.counts_[i];
  total_ += other.total_;
}

double LogBinHistogram::Quantile(uint64_t rank) const {
  SHUTTERLAB_CHECK(rank < total_) << "quantile rank " << rank << " of " << total_ << " values";
  uint64_t before = 0;
  size_t i = 0;
  while (before + counts_[i] <= rank) before += counts_[i++];
  // The bin's values spread evenly over it, each at the middle of its share.
  const double low = BinLow(i), high = BinLow(i + 1);
  return low + (high - low) * ((rank - before) + 0.5) / counts_[i];
}

double LogBinHistogram::CountBelow(double x) const {
  if (x <= 0.0) return 0.0;
  const size_t bin = Index(std::min(x, std::numeric_limits<double>::max()));
  double below = 0.0;
  for (size_t i = 0; i < bin; ++i) below += counts_[i];
  const double low = BinLow(bin), high = BinLow(bin + 1);
  if (bin + 1 == counts_.size()) return below + (x > low ? counts_[bin] : 0.0);  // open-ended
  return below + counts_[bin] * std::min(1.0, (x - low) / (high - low));
}

void IntervalUnion::Add(double begin, double end) {
  if (!intervals_.empty() && begin - intervals_.back().second <= filled_gap_) {
    intervals_.back().second = std::max(intervals_.back().second, end);
    return;
  }
  intervals_.emplace_back(begin, end);
  if (max_intervals_ > 0 && intervals_.size() > max_intervals_) FillShortestGaps();
}

void IntervalUnion::FillShortestGaps() {
  std::vector<double> gaps;
  for (size_t i = 1; i < intervals_.size(); ++i)
    gaps.push_back(intervals_[i].first - intervals_[i - 1].second);
  // The gap below which filling leaves at most half the cap.
  const size_t keep = std::max<size_t>(1, max_intervals_ / 2);
  std::nth_element(gaps.begin(), gaps.end() - keep, gaps.end());
  filled_gap_ = std::max(filled_gap_, *(gaps.end() - keep));
  std::vector<std::pair<double, double>> merged;
  for (const auto& interval : intervals_) {
    if (!merged.empty() && interval.first - merged.back().second <= filled_gap_) {
      merged.back().second = std::max(merged.back().second, interval.second);
    } else {
      merged.push_back(interval);
    }
  }
  intervals_ = std::move(merged);
}

}  // namespace shutterlab
