#include "sim/trace_audit.h"

#include "sim/text_file.h"
#include "sim/units.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace shutterlab {
namespace {

constexpr const char* kAxisNames[3] = {"x", "y", "z"};
constexpr int64_t kRateBlockNs = 1'000'000'000;
constexpr size_t kMaxRateChangesListed = 4;

// The trace cut into 1 s blocks, each with its median sample interval: the local rate, against
// which a gap is judged (a log that changes rate is not full of gaps) and rate changes are found.
struct RateBlock {
  size_t begin = 0, end = 0;  // samples [begin, end); the block's intervals end at end
  int64_t median_interval_ns = 0;
};

std::vector<RateBlock> RateBlocks(const GyroTrace& trace) {
  std::vector<RateBlock> blocks;
  std::vector<int64_t> intervals;
  size_t begin = 0;
  for (size_t k = 1; k <= trace.size(); ++k) {
    const bool block_ends = k == trace.size() || trace[k].t_ns - trace[begin].t_ns >= kRateBlockNs;
    if (k < trace.size()) intervals.push_back(trace[k].t_ns - trace[k - 1].t_ns);
    if (!block_ends) continue;
    // A short block says little about the rate: it joins the previous one.
    if (intervals.size() < 8 && !blocks.empty()) {
      blocks.back().end = k;
    } else {
      blocks.push_back({begin, k, UpperMedian(intervals)});
    }
    intervals.clear();
    begin = k;
  }
  return blocks;
}

std::optional<LogWarning> GapWarning(const GyroTrace& trace, const std::vector<RateBlock>& blocks) {
  size_t gaps = 0;
  int64_t missing_ns = 0, longest_ns = 0;
  size_t longest_at = 0, first_at = 0;
  for (size_t b = 0; b < blocks.size(); ++b) {
    const RateBlock& block = blocks[b];
    for (size_t k = std::max<size_t>(block.begin, 1); k < block.end; ++k) {
      // The interval into a block's first sample joins two blocks: the slower rate judges it.
      const int64_t local_ns =
          k == block.begin && b > 0
              ? std::max(block.median_interval_ns, blocks[b - 1].median_interval_ns)
              : block.median_interval_ns;
      const int64_t gap_ns = trace[k].t_ns - trace[k - 1].t_ns;
      if (local_ns == 0 || gap_ns <= SamplingReport::kGapFactor * local_ns) continue;
      if (gaps++ == 0) first_at = k - 1;
      missing_ns += gap_ns - local_ns;
      if (gap_ns > longest_ns) {
        longest_ns = gap_ns;
        longest_at = k - 1;
      }
    }
  }
  if (gaps == 0) return std::nullopt;
  return LogWarning{
      "gap",
      std::to_string(gaps) + " interval(s) over " + FormatNumber("%g", SamplingReport::kGapFactor) +
          "x the median " + FormatNumber("%.3f", trace.sampling().median_interval_ns * 1e-6) +
          " ms, " + FormatNumber("%.3f", missing_ns * 1e-9) + " s missing in all; longest " +
          FormatNumber("%.3f", longest_ns * 1e-9) + " s at " + SecondsText(trace[longest_at].t_ns),
      trace[first_at].t_ns * 1e-9, gaps};
}

// Consecutive blocks whose rates differ by more than the factor: the rates and where they change.
std::optional<LogWarning> RateChangeWarning(const GyroTrace& trace,
                                            const std::vector<RateBlock>& blocks, double factor) {
  std::vector<RateBlock> runs;
  for (const RateBlock& b : blocks) {
    if (!runs.empty()) {
      const double ratio = static_cast<double>(b.median_interval_ns) /
                           std::max<int64_t>(1, runs.back().median_interval_ns);
      if (ratio < factor && ratio > 1.0 / factor) continue;
    }
    runs.push_back(b);
  }
  if (runs.size() < 2) return std::nullopt;
  std::string line = "sample rate changes " + std::to_string(runs.size() - 1) + " time(s):";
  for (size_t r = 0; r < runs.size() && r <= kMaxRateChangesListed; ++r) {
    const double rate_hz = runs[r].median_interval_ns > 0 ? 1e9 / runs[r].median_interval_ns : 0;
    line += (r ? ", then " : " ") + FormatNumber("%.4g", rate_hz) + " Hz" +
            (r ? " from " + SecondsText(trace[runs[r].begin].t_ns) : "");
  }
  if (runs.size() > kMaxRateChangesListed + 1) line += ", ...";
  return LogWarning{"rate_change", line, trace[runs[1].begin].t_ns * 1e-9, runs.size() - 1};
}

std::vector<LogWarning> SaturationWarnings(const GyroTrace& trace,
                                           const TraceAuditOptions& options) {
  std::vector<LogWarning> lines;
  const std::optional<double> full_scale = SaturationFullScale(trace, options);
  if (!full_scale) return lines;
  const double limit = (1.0 - options.saturation_margin) * *full_scale;
  for (int a = 0; a < 3; ++a) {
    size_t count = 0;
    int64_t first_ns = 0, last_ns = 0;
    double peak = 0.0;
    for (const GyroSample& s : trace.samples()) {
      const double v = std::abs(s.omega_rad_s[a]);
      peak = std::max(peak, v);
      if (v < limit) continue;
      if (count++ == 0) first_ns = s.t_ns;
      last_ns = s.t_ns;
    }
    if (count == 0) continue;
    lines.push_back(LogWarning{
        "saturated",
        "axis " + std::string(kAxisNames[a]) + ", " + std::to_string(count) + " sample(s) within " +
            FormatNumber("%g", options.saturation_margin * 100) + " % of the +-" +
            FormatNumber("%.0f", *full_scale * kDegPerRad) + " deg/s full scale" +
            (options.full_scale_rad_s ? "" : " (where the peak lands)") + ", peak " +
            FormatNumber("%.0f", peak * kDegPerRad) + " deg/s, from " + SecondsText(first_ns) +
            " to " + SecondsText(last_ns) + ": the rotation there is under-reported",
        first_ns * 1e-9, count});
  }
  return lines;
}

}  // namespace

std::optional<double> SaturationFullScale(const GyroTrace& trace,
                                          const TraceAuditOptions& options) {
  if (options.full_scale_rad_s) return options.full_scale_rad_s;
  double peak = 0.0;
  for (const GyroSample& s : trace.samples())
    peak = std::max(peak, s.omega_rad_s.cwiseAbs().maxCoeff());
  for (double full_scale_dps : kCommonGyroFullScalesDps) {
    const double full_scale = full_scale_dps * kRadPerDeg;
    // A calibrated rate can exceed the raw range a little (scale factors above 1).
    if (peak >= (1.0 - options.saturation_margin) * full_scale &&
        peak <= (1.0 + 2.5 * options.saturation_margin) * full_scale)
      return full_scale;
  }
  return std::nullopt;
}

std::vector<LogWarning> AuditTrace(const GyroTrace& trace, const TraceAuditOptions& options) {
  std::vector<LogWarning> warnings;
  if (trace.size() < 2) return warnings;
  const std::vector<RateBlock> blocks = RateBlocks(trace);
  if (auto gaps = GapWarning(trace, blocks)) warnings.push_back(std::move(*gaps));
  if (const size_t duplicates = trace.sampling().duplicate_timestamps; duplicates > 0) {
    size_t first = 1;
    while (trace[first].t_ns != trace[first - 1].t_ns) ++first;
    warnings.push_back({"duplicate_time",
                        std::to_string(duplicates) + " sample(s) share the time of the one before",
                        trace[first].t_ns * 1e-9, duplicates});
  }
  if (auto rate = RateChangeWarning(trace, blocks, options.rate_change_factor))
    warnings.push_back(std::move(*rate));
  for (LogWarning& w : SaturationWarnings(trace, options)) warnings.push_back(std::move(w));
  return warnings;
}

}  // namespace shutterlab
