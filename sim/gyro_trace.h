#pragma once
// A gyro trace: body angular rates with their sample times.

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace shutterlab {

// The names of the three axes, of a gyro and of a camera alike, as every table and JSON spells
// them.
inline constexpr const char* kAxisNames[3] = {"x", "y", "z"};

struct GyroSample {
  int64_t t_ns;                 // sensor (gyro) clock, nanoseconds; non-decreasing within a trace
  Eigen::Vector3d omega_rad_s;  // angular rate about the sensor's own axes, rad/s
};

// Irregularities in the sampling of a trace, found once at construction.
struct SamplingReport {
  // Median of t[k+1]-t[k] (sim/interval_histogram.h: exact while the intervals take at most 65,536
  // distinct values); 0 for fewer than 2 samples.
  int64_t median_interval_ns = 0;
  // The interval the rate and the gaps are judged by (NominalIntervalNs).
  int64_t nominal_interval_ns = 0;
  // k such that t[k+1]-t[k] > kGapFactor * the interval between distinct times
  // (NominalIntervalNs of the samples less the duplicates: the median, or a burst-stamped
  // trace's stamp period).
  std::vector<size_t> gap_indices;
  size_t duplicate_timestamps = 0;  // count of k with t[k+1] == t[k]
  double RateHz() const { return nominal_interval_ns > 0 ? 1e9 / nominal_interval_ns : 0.0; }
  static constexpr double kGapFactor = 3.0;  // the paper's logger pauses while it writes a buffer
};

// The sample interval a trace of `samples` samples over span_ns is judged by (its rate, its gaps,
// the still search's windows): its median interval; or, when that is 0 because most samples share
// the time of the one before (a logger that stamps a burst of samples with one time), its span
// over its intervals: 1/3 ms for threes stamped every 1 ms, not 0 ("0 Hz", every step a gap).
// 0 for fewer than 2 samples or no span.
int64_t NominalIntervalNs(int64_t median_interval_ns, size_t samples, int64_t span_ns);

// Validates on construction (throws std::invalid_argument naming the sample index when a value is
// non-finite or a timestamp decreases); immutable afterwards.
class GyroTrace {
 public:
  GyroTrace() = default;
  explicit GyroTrace(std::vector<GyroSample> samples);

  const std::vector<GyroSample>& samples() const { return samples_; }
  size_t size() const { return samples_.size(); }
  bool empty() const { return samples_.empty(); }
  const GyroSample& operator[](size_t i) const { return samples_[i]; }
  int64_t t_begin_ns() const { return samples_.front().t_ns; }
  int64_t t_end_ns() const { return samples_.back().t_ns; }
  double DurationS() const { return empty() ? 0.0 : (t_end_ns() - t_begin_ns()) * 1e-9; }
  const SamplingReport& sampling() const { return sampling_; }

  // First index with t_ns >= t (size() if none).
  size_t LowerBound(int64_t t_ns) const;

 private:
  std::vector<GyroSample> samples_;
  SamplingReport sampling_;
};

// The samples of gyro within [begin_ns, end_ns] and the ones just outside them (so that the span
// stays covered), as a trace of its own.
GyroTrace GyroAround(const GyroTrace& gyro, int64_t begin_ns, int64_t end_ns);

// Seconds (double, as in files) to integer nanoseconds, rounded to nearest.
int64_t SecondsToNs(double t_s);

}  // namespace shutterlab
