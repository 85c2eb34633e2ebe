#pragma once
// A gyro trace: body angular rates with their sample times.

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace shutterlab {

struct GyroSample {
  int64_t t_ns;                 // sensor (gyro) clock, nanoseconds; non-decreasing within a trace
  Eigen::Vector3d omega_rad_s;  // angular rate about the sensor's own axes, rad/s
};

// Irregularities in the sampling of a trace, found once at construction.
struct SamplingReport {
  // Median of t[k+1]-t[k] (sim/interval_histogram.h: exact while the intervals take at most 65,536
  // distinct values); 0 for fewer than 2 samples.
  int64_t median_interval_ns = 0;
  std::vector<size_t> gap_indices;  // k such that t[k+1]-t[k] > kGapFactor * median interval
  size_t duplicate_timestamps = 0;  // count of k with t[k+1] == t[k]
  double RateHz() const { return median_interval_ns > 0 ? 1e9 / median_interval_ns : 0.0; }
  static constexpr double kGapFactor = 3.0;  // the paper's logger pauses while it writes a buffer
};

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

// Seconds (double, as in files) to integer nanoseconds, rounded to nearest.
int64_t SecondsToNs(double t_s);

}  // namespace shutterlab
