#include "sim/logs/gyro_candidates.h"

#include "sim/units.h"

#include <algorithm>
#include <cstdio>
#include <utility>

namespace shutterlab {
namespace internal {

namespace {

struct CleanedCandidate {
  GyroCandidate candidate;
  double rate_hz = 0.0;
  size_t dropped_time = 0;   // t <= 0 (PX4 and ArduPilot write 0 for 'not set')
  size_t dropped_value = 0;  // non-finite rate
  size_t dropped_spike = 0;  // isolated timestamp spike
  size_t out_of_order = 0;   // samples that had to be moved by the sort
  size_t dropped_outlier_end = 0;
};

int64_t MedianInterval(const std::vector<GyroSample>& s) {
  if (s.size() < 2) return 0;
  std::vector<int64_t> d(s.size() - 1);
  for (size_t i = 0; i + 1 < s.size(); ++i) d[i] = s[i + 1].t_ns - s[i].t_ns;
  return UpperMedian(std::move(d));
}

CleanedCandidate Clean(GyroCandidate in) {
  CleanedCandidate out;
  std::vector<GyroSample> kept;
  kept.reserve(in.samples.size());
  for (const GyroSample& s : in.samples) {
    if (s.t_ns <= 0) {
      ++out.dropped_time;
    } else if (!s.omega_rad_s.allFinite()) {
      ++out.dropped_value;
    } else {
      kept.push_back(s);
    }
  }
  // A corrupted timestamp shows as one sample outside the span of its two neighbours, which
  // themselves are in order (logs are written in time order per topic instance).
  std::vector<GyroSample> despiked;
  despiked.reserve(kept.size());
  const size_t n = kept.size();
  for (size_t i = 0; i < n; ++i) {
    const int64_t t = kept[i].t_ns;
    bool spike = false;
    if (i > 0 && i + 1 < n) {
      const int64_t a = kept[i - 1].t_ns, b = kept[i + 1].t_ns;
      spike = a <= b && (t < a || t > b);
    } else if (i == 0 && n >= 3) {
      spike = t > kept[1].t_ns && kept[1].t_ns <= kept[2].t_ns;
    } else if (i + 1 == n && n >= 3) {
      spike = t < kept[n - 2].t_ns && kept[n - 3].t_ns <= kept[n - 2].t_ns;
    }
    if (spike) {
      ++out.dropped_spike;
    } else {
      despiked.push_back(kept[i]);
    }
  }
  for (size_t i = 1; i < despiked.size(); ++i) {
    if (despiked[i].t_ns < despiked[i - 1].t_ns) ++out.out_of_order;
  }
  std::stable_sort(despiked.begin(), despiked.end(),
                   [](const GyroSample& a, const GyroSample& b) { return a.t_ns < b.t_ns; });
  // An end sample far beyond the rest (a corrupted time that sorted to an end) would stretch the
  // trace by minutes; gaps above this are not a logger pause.
  constexpr int64_t kMaxEndGapNs = 60'000'000'000;  // 60 s
  while (despiked.size() >= 3 &&
         despiked.back().t_ns - despiked[despiked.size() - 2].t_ns > kMaxEndGapNs) {
    despiked.pop_back();
    ++out.dropped_outlier_end;
  }
  while (despiked.size() >= 3 && despiked[1].t_ns - despiked[0].t_ns > kMaxEndGapNs) {
    despiked.erase(despiked.begin());
    ++out.dropped_outlier_end;
  }
  const int64_t median = MedianInterval(despiked);
  out.rate_hz = median > 0 ? 1e9 / static_cast<double>(median) : 0.0;
  out.candidate = std::move(in);
  out.candidate.samples = std::move(despiked);
  return out;
}

std::string Describe(const CleanedCandidate& c) {
  char rate[64];
  std::snprintf(rate, sizeof(rate), "%.1f Hz", c.rate_hz);
  return c.candidate.name + " (" + rate + ", " + std::to_string(c.candidate.samples.size()) +
         " samples)";
}

}  // namespace

bool ChooseGyroSource(std::vector<GyroCandidate> candidates, FlightLog* log) {
  std::vector<CleanedCandidate> usable;
  for (GyroCandidate& c : candidates) {
    CleanedCandidate cleaned = Clean(std::move(c));
    if (cleaned.candidate.samples.size() >= 2 && cleaned.rate_hz > 0.0) {
      usable.push_back(std::move(cleaned));
    }
  }
  if (usable.empty()) return false;
  std::stable_sort(
      usable.begin(), usable.end(),
      [](const CleanedCandidate& a, const CleanedCandidate& b) { return a.rate_hz > b.rate_hz; });
  // Rates of the same sensor differ by a few percent between topics (jitter, dropped messages);
  // within that band the rawer topic is the better source.
  constexpr double kSimilarRate = 0.9;
  const double best_rate = usable.front().rate_hz;
  size_t chosen = 0;
  for (size_t i = 1; i < usable.size(); ++i) {
    if (usable[i].rate_hz < kSimilarRate * best_rate) break;
    const auto& a = usable[i].candidate;
    const auto& b = usable[chosen].candidate;
    if (a.preference < b.preference ||
        (a.preference == b.preference && a.samples.size() > b.samples.size())) {
      chosen = i;
    }
  }
  std::rotate(usable.begin(), usable.begin() + chosen, usable.begin() + chosen + 1);
  log->gyro_sources_available.clear();
  for (const CleanedCandidate& c : usable) log->gyro_sources_available.push_back(Describe(c));

  CleanedCandidate& best = usable.front();
  const std::string& name = best.candidate.name;
  auto warn = [&](size_t count, const char* what) {
    if (count == 0) return;
    log->records_skipped += count;
    log->warnings.push_back(
        {"corrupt", name + ": " + std::to_string(count) + " " + what, std::nullopt, count});
  };
  warn(best.dropped_time, "samples with a zero timestamp dropped");
  warn(best.candidate.unreadable_time,
       "samples with an unreadable timestamp (beyond 292 years in nanoseconds) dropped");
  warn(best.dropped_value, "samples with a non-finite rate dropped");
  warn(best.dropped_spike, "samples with a timestamp out of line with their neighbours dropped");
  warn(best.dropped_outlier_end, "samples more than 60 s beyond the rest dropped");
  if (best.out_of_order > 0) {
    log->warnings.push_back({"time_backwards",
                             name + ": " + std::to_string(best.out_of_order) +
                                 " samples were out of time order and were sorted",
                             std::nullopt, best.out_of_order});
  }
  log->gyro_source = name;
  log->gyro = GyroTrace(std::move(best.candidate.samples));
  return true;
}

}  // namespace internal
}  // namespace shutterlab
