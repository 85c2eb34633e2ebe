#pragma once
// What a gyro trace itself shows was lost or is doubtful, whatever file it came from: gaps,
// duplicated timestamps, sample-rate changes and saturation. Readers add what only the bytes show
// (truncation, corrupt records, partial batches); sim/logs/flight_log_io.h joins the two lists.
//
// The audit takes the trace as a stream (TraceAuditor: chunk by chunk, memory bounded by one
// second of samples), so that a log of any length is audited while it is read; AuditTrace is the
// same for a trace held whole.

#include "sim/gyro_trace.h"
#include "sim/interval_histogram.h"
#include "sim/log_warning.h"

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

// Full-scale ranges of MEMS gyros (deg/s). When a log does not state its range, a peak that lands
// on one of these is taken as the range (the same for every axis of one sensor).
inline constexpr double kCommonGyroFullScalesDps[] = {125, 250, 500, 1000, 2000, 4000};

struct TraceAuditOptions {
  // The sensor's full scale when the log states it (raw counts: the configured range).
  std::optional<double> full_scale_rad_s;
  // A sample is clipped when within this fraction of the full scale.
  double saturation_margin = 0.02;
  // Consecutive 1 s blocks whose median sample interval differs by more than this factor make a
  // sample-rate change.
  double rate_change_factor = 1.25;
};

// How a streamed trace was sampled: what GyroTrace::sampling() says of a trace held whole.
struct TraceSampling {
  size_t samples = 0;
  int64_t t_begin_ns = 0, t_end_ns = 0;  // first and last sample (0 when empty)
  int64_t median_interval_ns = 0;        // as SamplingReport
  int64_t nominal_interval_ns = 0;       // as SamplingReport (NominalIntervalNs)
  size_t gaps = 0;                       // as SamplingReport::gap_indices counts them
  size_t duplicate_timestamps = 0;
  double RateHz() const { return nominal_interval_ns > 0 ? 1e9 / nominal_interval_ns : 0.0; }
  double DurationS() const { return (t_end_ns - t_begin_ns) * 1e-9; }
  // The same of a trace held whole (its GyroTrace::sampling).
  static TraceSampling Of(const GyroTrace& trace);
};

// The audit of a trace fed chunk by chunk, in time order.
//
// One warning per kind of loss (gap, duplicate_time, rate_change, saturated per axis), each with
// its count, the time of the first occurrence and a line with the times on the trace's clock, e.g.
//   gap: "3 interval(s) over 3x the median 1.000 ms, 0.412 s missing in all; longest 0.300 s at
//         12.345 s"
//   saturated: "axis y, 1 sample(s) within 2 % of the +-2000 deg/s full scale (where the peak
//         lands), peak 2023 deg/s, from 239.159 s to 239.159 s: the rotation there is
//         under-reported"
// A gap is judged against the local rate (the median interval of 1 s blocks), so a rate change is
// not a run of gaps. Nothing is said of a trace of fewer than 2 samples.
class TraceAuditor {
 public:
  explicit TraceAuditor(TraceAuditOptions options = {});
  // The next samples. Throws std::invalid_argument as GyroTrace does (counting samples from the
  // first Add) when a rate is not finite or a time goes back.
  void Add(const GyroSample* samples, size_t count);
  void Add(const std::vector<GyroSample>& samples) { Add(samples.data(), samples.size()); }
  // The warnings, empty when nothing is wrong. Call once, after the last Add.
  std::vector<LogWarning> Finish();
  // The sampling so far (complete after the last Add).
  TraceSampling Sampling() const;

 private:
  struct Interval {
    int64_t dt_ns;
    int64_t t_before_ns;  // the sample the interval starts at
  };
  struct Saturation {  // samples at or above one candidate full scale's limit, per axis
    std::array<size_t, 3> count{};
    std::array<int64_t, 3> first_ns{}, last_ns{};
  };
  void Step(const GyroSample& s);  // one sample, checked (Add's path for a refused chunk)
  size_t AddTimesOfBlock(const GyroSample* samples, size_t i, size_t count);
  void NoteSaturation(const GyroSample& s);
  void CloseBlock(bool at_end);
  void Judge(const Interval& interval, int64_t local_ns);
  void NoteBlockRate(int64_t median_ns, int64_t begin_ns);
  std::optional<LogWarning> GapWarning() const;
  std::optional<LogWarning> RateChangeWarning() const;
  std::vector<LogWarning> SaturationWarnings() const;

  TraceAuditOptions options_;
  std::vector<double> full_scales_rad_s_;  // candidates, ascending: stated, or the common ones
  std::vector<double> limits_rad_s_;       // (1 - margin) x each
  size_t samples_ = 0;
  int64_t t_begin_ns_ = 0, t_last_ns_ = 0;
  IntervalHistogram intervals_;
  size_t duplicates_ = 0;
  int64_t first_duplicate_ns_ = 0;
  // The current 1 s block: the times of its samples (the intervals between them, the last of
  // which leads into the sample that opens the next block), and the interval that led into it.
  std::vector<int64_t> block_t_ns_;
  std::optional<Interval> into_block_;
  std::optional<int64_t> previous_median_ns_;  // of the last block that kept its own rate
  // Gaps found so far.
  size_t gaps_ = 0;
  int64_t missing_ns_ = 0, longest_ns_ = 0, longest_at_ns_ = 0, first_gap_at_ns_ = 0;
  // Runs of blocks at one rate: the first ones (rate and where they begin) and how many.
  struct Run {
    int64_t median_ns, begin_ns;
  };
  std::vector<Run> runs_;  // at most kMaxRateChangesListed + 2
  size_t run_count_ = 0;
  int64_t last_run_median_ns_ = 0;
  // Saturation: the peak per axis, and per candidate full scale the samples at its limit.
  std::array<double, 3> peak_{};
  std::vector<Saturation> saturation_;
};

// AuditTrace(trace) = a TraceAuditor fed the whole trace.
std::vector<LogWarning> AuditTrace(const GyroTrace& trace, const TraceAuditOptions& options = {});

// The full scale (rad/s) that clipped a trace whose largest |rate| over all axes is peak_rad_s,
// when one shows: the stated one, or the common range that the peak lands on within
// [1 - margin, 1 + 2.5 margin] of it.
std::optional<double> SaturationFullScale(double peak_rad_s, const TraceAuditOptions& options);
std::optional<double> SaturationFullScale(const GyroTrace& trace, const TraceAuditOptions& options);

}  // namespace shutterlab
