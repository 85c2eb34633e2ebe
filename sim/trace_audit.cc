#include "sim/trace_audit.h"

#include "sim/check.h"
#include "sim/gyro_trace.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <algorithm>
#include <cmath>

namespace shutterlab {
namespace {

// The trace is cut into blocks of this length, each with its median sample interval: the local
// rate, against which a gap is judged (a log that changes rate is not full of gaps) and rate
// changes are found. A block of fewer than kMinBlockIntervals intervals says little about the
// rate: it joins the block before it.
constexpr int64_t kRateBlockNs = 1'000'000'000;
constexpr size_t kMinBlockIntervals = 8;
constexpr size_t kMaxRateChangesListed = 4;

// An interval is a gap when it is longer than kGapFactor times the local one (none when the local
// interval is 0: times stamped alike).
bool IsGap(int64_t dt_ns, int64_t local_ns) {
  return local_ns != 0 && dt_ns > SamplingReport::kGapFactor * local_ns;
}

// The candidate full scales (rad/s, ascending): the stated one, or the common ones.
std::vector<double> FullScaleCandidates(const TraceAuditOptions& options) {
  if (options.full_scale_rad_s) return {*options.full_scale_rad_s};
  std::vector<double> candidates;
  for (double full_scale_dps : kCommonGyroFullScalesDps)
    candidates.push_back(full_scale_dps * kRadPerDeg);
  return candidates;
}

}  // namespace

TraceAuditor::TraceAuditor(TraceAuditOptions options)
    : options_(std::move(options)), full_scales_rad_s_(FullScaleCandidates(options_)) {
  for (double full_scale : full_scales_rad_s_)
    limits_rad_s_.push_back((1.0 - options_.saturation_margin) * full_scale);
  saturation_.resize(full_scales_rad_s_.size());
}

void TraceAuditor::Add(const GyroSample* samples, size_t count) {
  if (count == 0) return;
  // The whole chunk at once when nothing in it is refused: every rate finite and no time going
  // back (their peaks on the way). Otherwise sample by sample, which refuses the first bad one
  // with its message.
  bool finite = true, ordered = true;
  double chunk_peak[3] = {0.0, 0.0, 0.0};
  int64_t previous_ns = samples_ > 0 ? t_last_ns_ : samples[0].t_ns;
  for (size_t i = 0; i < count; ++i) {
    const GyroSample& s = samples[i];
    for (int a = 0; a < 3; ++a) {
      const double w = s.omega_rad_s[a];
      finite &= w - w == 0.0;  // false for inf and nan
      chunk_peak[a] = std::max(chunk_peak[a], std::abs(w));
    }
    ordered &= s.t_ns >= previous_ns;
    previous_ns = s.t_ns;
  }
  if (!finite || !ordered) {
    for (size_t i = 0; i < count; ++i) Step(samples[i]);
    return;
  }
  if (std::max({chunk_peak[0], chunk_peak[1], chunk_peak[2]}) >= limits_rad_s_[0]) {
    for (size_t i = 0; i < count; ++i) NoteSaturation(samples[i]);
  }
  for (int a = 0; a < 3; ++a) peak_[a] = std::max(peak_[a], chunk_peak[a]);
  size_t i = 0;
  if (samples_ == 0) {
    t_begin_ns_ = t_last_ns_ = samples[0].t_ns;
    block_t_ns_.push_back(samples[0].t_ns);
    i = 1;
  }
  samples_ += count;
  while (i < count) i = AddTimesOfBlock(samples, i, count);
}

// The times of samples [i, count) that the current 1 s block takes, up to the one that closes it
// (included; the block is then closed) or the chunk's end; returns where the rest begins. What
// Step does per sample, with the running values in locals.
size_t TraceAuditor::AddTimesOfBlock(const GyroSample* samples, size_t i, size_t count) {
  const int64_t block_begin_ns = block_t_ns_.front();
  size_t stop = i;
  while (stop < count && samples[stop].t_ns - block_begin_ns < kRateBlockNs) ++stop;
  const bool closes = stop < count;
  stop += closes;  // the closing sample belongs to the block
  const size_t old_size = block_t_ns_.size();
  block_t_ns_.resize(old_size + (stop - i));
  int64_t* block_t = block_t_ns_.data() + old_size;  // sample k goes to block_t[k - i]
  int64_t last_ns = t_last_ns_, run_ns = 0;
  size_t run = 0, duplicates = duplicates_;
  for (size_t k = i; k < stop; ++k) {
    const int64_t t = samples[k].t_ns;
    const int64_t dt = t - last_ns;
    if (dt == 0 && duplicates++ == 0) first_duplicate_ns_ = t;
    if (dt != run_ns) {  // intervals reach the histogram as runs of equal ones
      intervals_.AddRun(run_ns, run);
      run_ns = dt;
      run = 0;
    }
    ++run;
    block_t[k - i] = t;
    last_ns = t;
  }
  intervals_.AddRun(run_ns, run);
  t_last_ns_ = last_ns;
  duplicates_ = duplicates;
  if (closes) CloseBlock(/*at_end=*/false);
  return stop;
}

void TraceAuditor::NoteSaturation(const GyroSample& s) {
  const Eigen::Vector3d v = s.omega_rad_s.cwiseAbs();
  if (v.maxCoeff() < limits_rad_s_[0]) return;  // below every full scale: the usual case
  for (int a = 0; a < 3; ++a) {
    for (size_t c = 0; c < limits_rad_s_.size() && v[a] >= limits_rad_s_[c]; ++c) {
      Saturation& at = saturation_[c];
      if (at.count[a]++ == 0) at.first_ns[a] = s.t_ns;
      at.last_ns[a] = s.t_ns;
    }
  }
}

void TraceAuditor::Step(const GyroSample& s) {
  const size_t index = samples_++;
  SHUTTERLAB_CHECK(s.omega_rad_s.allFinite())
      << "gyro sample " << index << " has a non-finite rate";
  if (index == 0) {
    t_begin_ns_ = t_last_ns_ = s.t_ns;
    block_t_ns_.push_back(s.t_ns);
  } else {
    const int64_t dt = s.t_ns - t_last_ns_;
    SHUTTERLAB_CHECK(dt >= 0) << "gyro sample " << index << " goes back in time by " << -dt * 1e-9
                              << " s";
    if (dt == 0 && duplicates_++ == 0) first_duplicate_ns_ = s.t_ns;
    intervals_.Add(dt);
    block_t_ns_.push_back(s.t_ns);
    t_last_ns_ = s.t_ns;
    if (s.t_ns - block_t_ns_.front() >= kRateBlockNs) CloseBlock(/*at_end=*/false);
  }
  for (int a = 0; a < 3; ++a) peak_[a] = std::max(peak_[a], std::abs(s.omega_rad_s[a]));
  NoteSaturation(s);
}

// Closes the block [block_begin, this sample) and judges the intervals into its samples: the one
// that led into it (from the block before) and those inside; the last one pushed leads out of it
// (into the sample that opens the next block) unless the trace ends here.
void TraceAuditor::CloseBlock(bool at_end) {
  const std::vector<int64_t>& t = block_t_ns_;
  const size_t pushed = t.size() - 1;                  // intervals between the block's times
  const size_t inside = at_end ? pushed : pushed - 1;  // the last one leads out of the block
  const auto interval = [&t](size_t i) { return Interval{t[i + 1] - t[i], t[i]}; };
  if (pushed < kMinBlockIntervals && previous_median_ns_) {
    // Joins the block before: judged at its rate, which it does not change.
    if (into_block_) Judge(*into_block_, *previous_median_ns_);
    for (size_t i = 0; i < inside; ++i) Judge(interval(i), *previous_median_ns_);
  } else if (pushed > 0) {
    // The shortest and longest interval first: a block of equal ones (a logger that stamps a
    // fixed period) is its own median, without the selection, and no interval inside a block
    // whose longest is no gap needs judging.
    int64_t shortest_ns = t[1] - t[0], longest_ns = shortest_ns;
    for (size_t i = 1; i < pushed; ++i) {
      shortest_ns = std::min(shortest_ns, t[i + 1] - t[i]);
      longest_ns = std::max(longest_ns, t[i + 1] - t[i]);
    }
    int64_t median_ns = shortest_ns;
    if (shortest_ns != longest_ns) {
      std::vector<int64_t> dts(pushed);
      for (size_t i = 0; i < pushed; ++i) dts[i] = t[i + 1] - t[i];
      median_ns = UpperMedian(std::move(dts));
    }
    // The interval into the block joins two blocks: the slower rate judges it.
    if (into_block_) Judge(*into_block_, std::max(median_ns, previous_median_ns_.value_or(0)));
    if (IsGap(longest_ns, median_ns)) {
      for (size_t i = 0; i < inside; ++i) Judge(interval(i), median_ns);
    }
    // A block stamped in bursts (median 0) runs at its samples over its span, not "0 Hz".
    NoteBlockRate(NominalIntervalNs(median_ns, t.size(), t.back() - t.front()), t.front());
    previous_median_ns_ = median_ns;
  }
  if (!at_end) into_block_ = interval(pushed - 1);
  const int64_t next_begin_ns = t.back();
  block_t_ns_.clear();
  block_t_ns_.push_back(next_begin_ns);
}

void TraceAuditor::Judge(const Interval& interval, int64_t local_ns) {
  if (!IsGap(interval.dt_ns, local_ns)) return;
  if (gaps_++ == 0) first_gap_at_ns_ = interval.t_before_ns;
  missing_ns_ += interval.dt_ns - local_ns;
  if (interval.dt_ns > longest_ns_) {
    longest_ns_ = interval.dt_ns;
    longest_at_ns_ = interval.t_before_ns;
  }
}

// A block whose rate differs from the current run's by more than the factor starts a new run.
void TraceAuditor::NoteBlockRate(int64_t median_ns, int64_t begin_ns) {
  if (run_count_ > 0) {
    if (median_ns == last_run_median_ns_) return;  // also two blocks each stamped at one time
    const double ratio = static_cast<double>(median_ns) / std::max<int64_t>(1, last_run_median_ns_);
    if (ratio < options_.rate_change_factor && ratio > 1.0 / options_.rate_change_factor) return;
  }
  ++run_count_;
  last_run_median_ns_ = median_ns;
  if (runs_.size() < kMaxRateChangesListed + 2) runs_.push_back({median_ns, begin_ns});
}

std::optional<LogWarning> TraceAuditor::GapWarning() const {
  if (gaps_ == 0) return std::nullopt;
  return LogWarning{"gap",
                    std::to_string(gaps_) + " interval(s) over " +
                        FormatNumber("%g", SamplingReport::kGapFactor) + "x the median " +
                        FormatNumber("%.3f", intervals_.Median() * 1e-6) + " ms, " +
                        FormatNumber("%.3f", missing_ns_ * 1e-9) + " s missing in all; longest " +
                        FormatNumber("%.3f", longest_ns_ * 1e-9) + " s at " +
                        SecondsText(longest_at_ns_),
                    first_gap_at_ns_ * 1e-9, gaps_};
}

std::optional<LogWarning> TraceAuditor::RateChangeWarning() const {
  if (run_count_ < 2) return std::nullopt;
  std::string line = "sample rate changes " + std::to_string(run_count_ - 1) + " time(s):";
  for (size_t r = 0; r < runs_.size() && r <= kMaxRateChangesListed; ++r) {
    const double rate_hz = runs_[r].median_ns > 0 ? 1e9 / runs_[r].median_ns : 0;
    line += (r ? ", then " : " ") + FormatNumber("%.4g", rate_hz) + " Hz" +
            (r ? " from " + SecondsText(runs_[r].begin_ns) : "");
  }
  if (run_count_ > kMaxRateChangesListed + 1) line += ", ...";
  return LogWarning{"rate_change", line, runs_[1].begin_ns * 1e-9, run_count_ - 1};
}

std::vector<LogWarning> TraceAuditor::SaturationWarnings() const {
  std::vector<LogWarning> lines;
  const double peak = std::max({peak_[0], peak_[1], peak_[2]});
  const std::optional<double> full_scale = SaturationFullScale(peak, options_);
  if (!full_scale) return lines;
  const size_t c = static_cast<size_t>(
      std::find(full_scales_rad_s_.begin(), full_scales_rad_s_.end(), *full_scale) -
      full_scales_rad_s_.begin());
  SHUTTERLAB_CHECK(c < saturation_.size()) << "full scale not among the candidates";
  const Saturation& at = saturation_[c];
  for (int a = 0; a < 3; ++a) {
    if (at.count[a] == 0) continue;
    lines.push_back(LogWarning{
        "saturated",
        "axis " + std::string(kAxisNames[a]) + ", " + std::to_string(at.count[a]) +
            " sample(s) within " + FormatNumber("%g", options_.saturation_margin * 100) +
            " % of the +-" + FormatNumber("%.0f", *full_scale * kDegPerRad) + " deg/s full scale" +
            (options_.full_scale_rad_s ? "" : " (where the peak lands)") + ", peak " +
            FormatNumber("%.0f", peak_[a] * kDegPerRad) + " deg/s, from " +
            SecondsText(at.first_ns[a]) + " to " + SecondsText(at.last_ns[a]) +
            ": the rotation there is under-reported",
        at.first_ns[a] * 1e-9, at.count[a]});
  }
  return lines;
}

std::vector<LogWarning> TraceAuditor::Finish() {
  std::vector<LogWarning> warnings;
  if (samples_ < 2) return warnings;
  CloseBlock(/*at_end=*/true);
  if (auto gaps = GapWarning()) warnings.push_back(std::move(*gaps));
  if (duplicates_ > 0) {
    warnings.push_back({"duplicate_time",
                        std::to_string(duplicates_) + " sample(s) share the time of the one before",
                        first_duplicate_ns_ * 1e-9, duplicates_});
  }
  if (auto rate = RateChangeWarning()) warnings.push_back(std::move(*rate));
  for (LogWarning& w : SaturationWarnings()) warnings.push_back(std::move(w));
  return warnings;
}

TraceSampling TraceSampling::Of(const GyroTrace& trace) {
  TraceSampling sampling;
  sampling.samples = trace.size();
  if (trace.empty()) return sampling;
  sampling.t_begin_ns = trace.t_begin_ns();
  sampling.t_end_ns = trace.t_end_ns();
  sampling.median_interval_ns = trace.sampling().median_interval_ns;
  sampling.nominal_interval_ns = trace.sampling().nominal_interval_ns;
  sampling.gaps = trace.sampling().gap_indices.size();
  sampling.duplicate_timestamps = trace.sampling().duplicate_timestamps;
  return sampling;
}

TraceSampling TraceAuditor::Sampling() const {
  TraceSampling sampling;
  sampling.samples = samples_;
  if (samples_ == 0) return sampling;
  sampling.t_begin_ns = t_begin_ns_;
  sampling.t_end_ns = t_last_ns_;
  sampling.duplicate_timestamps = duplicates_;
  if (samples_ < 2) return sampling;
  sampling.median_interval_ns = intervals_.Median();
  sampling.nominal_interval_ns =
      NominalIntervalNs(sampling.median_interval_ns, samples_, t_last_ns_ - t_begin_ns_);
  sampling.gaps = intervals_.CountAbove(
      SamplingReport::kGapFactor *
      static_cast<double>(NominalIntervalNs(sampling.median_interval_ns, samples_ - duplicates_,
                                            t_last_ns_ - t_begin_ns_)));
  return sampling;
}

std::optional<double> SaturationFullScale(double peak_rad_s, const TraceAuditOptions& options) {
  if (options.full_scale_rad_s) return options.full_scale_rad_s;
  for (double full_scale_dps : kCommonGyroFullScalesDps) {
    const double full_scale = full_scale_dps * kRadPerDeg;
    // A calibrated rate can exceed the raw range a little (scale factors above 1).
    if (peak_rad_s >= (1.0 - options.saturation_margin) * full_scale &&
        peak_rad_s <= (1.0 + 2.5 * options.saturation_margin) * full_scale)
      return full_scale;
  }
  return std::nullopt;
}

std::optional<double> SaturationFullScale(const GyroTrace& trace,
                                          const TraceAuditOptions& options) {
  double peak = 0.0;
  for (const GyroSample& s : trace.samples())
    peak = std::max(peak, s.omega_rad_s.cwiseAbs().maxCoeff());
  return SaturationFullScale(peak, options);
}

std::vector<LogWarning> AuditTrace(const GyroTrace& trace, const TraceAuditOptions& options) {
  TraceAuditor auditor(options);
  auditor.Add(trace.samples());
  return auditor.Finish();
}

}  // namespace shutterlab
