#include "sim/logs/gyro_candidates.h"

#include "sim/check.h"

#include <algorithm>
#include <cstdio>
#include <utility>

namespace shutterlab {
namespace internal {

namespace {

// An end sample far beyond the rest (a corrupted time that sorted to an end) would stretch the
// trace by minutes; gaps above this are not a logger pause.
constexpr int64_t kMaxEndGapNs = 60'000'000'000;  // 60 s

// Pass 2 inserts a late sample into the samples it holds back; beyond this depth (only a summary
// without limits gets there) it holds them all and sorts once at the end instead.
constexpr size_t kMaxInsertDepth = size_t{1} << 16;

// Rates of the same sensor differ by a few percent between topics (jitter, dropped messages);
// within that band the rawer topic is the better source.
constexpr double kSimilarRate = 0.9;

std::string Describe(const CandidateSummary& c) {
  char rate[64];
  std::snprintf(rate, sizeof(rate), "%.1f Hz", c.rate_hz());
  return c.name() + " (" + rate + ", " + std::to_string(c.samples()) + " samples)";
}

// Inserts x into held (in key order), after the entries with the same time: they came first.
template <typename T, typename TimeOf>
void InsertInTimeOrder(std::deque<T>* held, T x, TimeOf time_of) {
  if (held->empty() || time_of(held->back()) <= time_of(x)) {
    held->push_back(std::move(x));
    return;
  }
  auto at = std::upper_bound(held->begin(), held->end(), time_of(x),
                             [&](int64_t t, const T& h) { return t < time_of(h); });
  held->insert(at, std::move(x));
}

}  // namespace

int CleaningFront::Add(const std::optional<int64_t>& t_ns, const Eigen::Vector3d& rate,
                       GyroSample out[2]) {
  if (!t_ns) {
    ++unreadable_time;
    return 0;
  }
  if (*t_ns <= 0) {
    ++dropped_time;
    return 0;
  }
  if (!rate.allFinite()) {
    ++dropped_value;
    return 0;
  }
  // A corrupted timestamp shows as one sample outside the span of its two neighbours, which
  // themselves are in order (logs are written in time order per topic instance). A sample is
  // decided once the next one is known.
  const size_t i = kept_++;
  if (i < 3) {
    window_[i] = {*t_ns, rate};
  } else {
    window_[0] = window_[1];
    window_[1] = window_[2];
    window_[2] = {*t_ns, rate};
  }
  if (i < 2) return 0;
  const int64_t a = window_[0].t_ns, t = window_[1].t_ns, b = window_[2].t_ns;
  int n = 0;
  if (i == 2) {  // the first: beyond its successor, which is in line with the next
    if (a > t && t <= b) {
      ++dropped_spike;
    } else {
      out[n++] = window_[0];
    }
  }
  if (a <= b && (t < a || t > b)) {
    ++dropped_spike;
  } else {
    out[n++] = window_[1];
  }
  return n;
}

int CleaningFront::Finish(GyroSample out[2]) {
  if (kept_ < 3) {
    for (size_t i = 0; i < kept_; ++i) out[i] = window_[i];
    return static_cast<int>(kept_);
  }
  // The last: before its predecessor, which is in line with the one before it.
  if (window_[2].t_ns < window_[1].t_ns && window_[0].t_ns <= window_[1].t_ns) {
    ++dropped_spike;
    return 0;
  }
  out[0] = window_[2];
  return 1;
}

CandidateSummary::CandidateSummary(std::string name, int preference, CandidateLimits limits)
    : name_(std::move(name)), preference_(preference), limits_(limits) {}

bool CandidateSummary::TooMany(size_t held, size_t limit) {
  if (held <= limit) return false;
  exact_ = false;
  held_ = {};
  interval_counts_ = {};
  leading_far_gaps_ = {};
  trailing_far_gaps_ = {};
  return true;
}

void CandidateSummary::AddKept(int64_t t_ns) {
  const size_t seq = kept_++;
  if (last_kept_t_ns_ && t_ns < *last_kept_t_ns_) ++out_of_order_;
  last_kept_t_ns_ = t_ns;
  if (!exact_) return;
  if (limits_.reorder_samples == SIZE_MAX) {  // no limit: every time held, sorted at the end
    held_.emplace_back(t_ns, seq);
    return;
  }
  // Held back reorder_samples deep, the smallest time is final unless a later one is smaller
  // still: then the disorder is deeper than the limit.
  if (last_sorted_t_ns_ && t_ns < *last_sorted_t_ns_) {
    TooMany(SIZE_MAX, 0);
    return;
  }
  InsertInTimeOrder(&held_, std::make_pair(t_ns, seq),
                    [](const std::pair<int64_t, size_t>& h) { return h.first; });
  while (held_.size() > limits_.reorder_samples) {
    // Taken off first: TakeSorted empties held_ when the intervals exceed their limit.
    const std::pair<int64_t, size_t> first = held_.front();
    held_.pop_front();
    TakeSorted(first.first, first.second);
    if (!exact_) return;
  }
}

void CandidateSummary::TakeSorted(int64_t t_ns, size_t seq) {
  const size_t position = sorted_++;
  if (seq > position) reorder_depth_ = std::max(reorder_depth_, seq - position);
  if (last_sorted_t_ns_) {
    const int64_t interval = t_ns - *last_sorted_t_ns_;
    ++interval_counts_[interval];
    if (interval > kMaxEndGapNs) {
      trailing_far_gaps_.push_back(interval);
      if (leading_run_open_) leading_far_gaps_.push_back(interval);
    } else {
      trailing_far_gaps_.clear();
      leading_run_open_ = false;
    }
    if (TooMany(interval_counts_.size(), limits_.intervals) ||
        TooMany(trailing_far_gaps_.size(), limits_.intervals) ||
        TooMany(leading_far_gaps_.size(), limits_.intervals))
      return;
  }
  last_sorted_t_ns_ = t_ns;
}

void CandidateSummary::Finish() {
  GyroSample rest[2];
  const int n = front_.Finish(rest);
  for (int i = 0; i < n; ++i) AddKept(rest[i].t_ns);
  if (!exact_) return;
  if (limits_.reorder_samples == SIZE_MAX) std::sort(held_.begin(), held_.end());
  for (const auto& [t_ns, seq] : held_) {
    TakeSorted(t_ns, seq);
    if (!exact_) return;
  }
  held_ = {};
  // The end drops: the last samples while more than 60 s beyond their predecessor, then the first
  // ones while more than 60 s before their successor, as long as 3 samples are left.
  const size_t total = sorted_;
  const size_t back = total >= 3 ? std::min(trailing_far_gaps_.size(), total - 2) : 0;
  const size_t left = total - back;
  const size_t front = left >= 3 ? std::min(leading_far_gaps_.size(), left - 2) : 0;
  for (size_t i = 0; i < back; ++i)
    --interval_counts_[trailing_far_gaps_[trailing_far_gaps_.size() - 1 - i]];
  for (size_t i = 0; i < front; ++i) --interval_counts_[leading_far_gaps_[i]];
  kept_begin_ = front;
  kept_end_ = total - back;
  // The median interval (the upper one of an even count) of what is left.
  rate_hz_ = 0.0;
  if (samples() >= 2) {
    std::vector<std::pair<int64_t, size_t>> counts(interval_counts_.begin(),
                                                   interval_counts_.end());
    std::sort(counts.begin(), counts.end());
    size_t rank = (samples() - 1) / 2;
    for (const auto& [interval, count] : counts) {
      if (rank < count) {
        if (interval > 0) rate_hz_ = 1e9 / static_cast<double>(interval);
        break;
      }
      rank -= count;
    }
  }
  interval_counts_ = {};
  leading_far_gaps_ = {};
  trailing_far_gaps_ = {};
}

void CandidateSummary::Warn(FlightLog* log) const {
  auto warn = [&](size_t count, const char* what) {
    if (count == 0) return;
    log->records_skipped += count;
    log->warnings.push_back(
        {"corrupt", name_ + ": " + std::to_string(count) + " " + what, std::nullopt, count});
  };
  warn(front_.dropped_time, "samples with a zero timestamp dropped");
  warn(front_.unreadable_time,
       "samples with an unreadable timestamp (beyond 292 years in nanoseconds) dropped");
  warn(front_.dropped_value, "samples with a non-finite rate dropped");
  warn(front_.dropped_spike, "samples with a timestamp out of line with their neighbours dropped");
  warn(sorted_ - samples(), "samples more than 60 s beyond the rest dropped");
  if (out_of_order_ > 0) {
    log->warnings.push_back({"time_backwards",
                             name_ + ": " + std::to_string(out_of_order_) +
                                 " samples were out of time order and were sorted",
                             std::nullopt, out_of_order_});
  }
}

std::optional<size_t> ChooseGyroSummary(const std::vector<CandidateSummary>& summaries,
                                        FlightLog* log) {
  std::vector<size_t> usable;
  for (size_t i = 0; i < summaries.size(); ++i) {
    SHUTTERLAB_CHECK(summaries[i].exact()) << summaries[i].name() << ": summary not exact";
    if (summaries[i].usable()) usable.push_back(i);
  }
  if (usable.empty()) return std::nullopt;
  std::stable_sort(usable.begin(), usable.end(), [&](size_t a, size_t b) {
    return summaries[a].rate_hz() > summaries[b].rate_hz();
  });
  const double best_rate = summaries[usable.front()].rate_hz();
  size_t chosen = 0;
  for (size_t i = 1; i < usable.size(); ++i) {
    const CandidateSummary& a = summaries[usable[i]];
    const CandidateSummary& b = summaries[usable[chosen]];
    if (a.rate_hz() < kSimilarRate * best_rate) break;
    if (a.preference() < b.preference() ||
        (a.preference() == b.preference() && a.samples() > b.samples())) {
      chosen = i;
    }
  }
  std::rotate(usable.begin(), usable.begin() + chosen, usable.begin() + chosen + 1);
  log->gyro_sources_available.clear();
  for (size_t i : usable) log->gyro_sources_available.push_back(Describe(summaries[i]));
  const CandidateSummary& best = summaries[usable.front()];
  best.Warn(log);
  log->gyro_source = best.name();
  return usable.front();
}

LogWarning ReadInMemoryWarning(const std::vector<CandidateSummary>& bounded) {
  std::string names;
  for (const CandidateSummary& s : bounded) {
    if (s.exact()) continue;
    names += (names.empty() ? "" : ", ") + s.name();
  }
  return {"memory",
          "gyro stream(s) " + names +
              ": samples out of time order too far back, or too many distinct intervals, to "
              "clean in bounded memory: their times were held in memory whole"};
}

CandidateCleaner::CandidateCleaner(const CandidateSummary& chosen)
    : depth_(chosen.reorder_depth_),
      sort_at_end_(chosen.reorder_depth_ > kMaxInsertDepth),
      kept_total_(chosen.kept_),
      keep_begin_(chosen.kept_begin_),
      keep_end_(chosen.kept_end_) {
  SHUTTERLAB_CHECK(chosen.exact()) << chosen.name() << ": summary not exact";
}

void CandidateCleaner::Release(const Held& held, std::vector<GyroSample>* out) {
  const size_t position = sorted_++;
  if (last_sorted_t_ns_ && held.sample.t_ns < *last_sorted_t_ns_) consistent_ = false;
  last_sorted_t_ns_ = held.sample.t_ns;
  if (position >= keep_begin_ && position < keep_end_) out->push_back(held.sample);
}

void CandidateCleaner::Hold(const GyroSample& sample, std::vector<GyroSample>* out) {
  Held held{sample, kept_++};
  if (depth_ == 0 && !sort_at_end_) {  // a stream in order: final at once, as through the queue
    Release(held, out);
    return;
  }
  if (sort_at_end_) {
    held_.push_back(held);
    return;
  }
  InsertInTimeOrder(&held_, held, [](const Held& h) { return h.sample.t_ns; });
  while (held_.size() > depth_) {
    Release(held_.front(), out);
    held_.pop_front();
  }
}

bool CandidateCleaner::Finish(std::vector<GyroSample>* out) {
  GyroSample rest[2];
  const int n = front_.Finish(rest);
  for (int i = 0; i < n; ++i) Hold(rest[i], out);
  if (sort_at_end_) {
    std::stable_sort(held_.begin(), held_.end(),
                     [](const Held& a, const Held& b) { return a.sample.t_ns < b.sample.t_ns; });
  }
  for (const Held& held : held_) Release(held, out);
  held_ = {};
  return consistent_ && kept_ == kept_total_;
}

bool ChooseGyroSource(std::vector<GyroCandidate> candidates, FlightLog* log) {
  std::vector<CandidateSummary> summaries;
  summaries.reserve(candidates.size());
  for (const GyroCandidate& c : candidates) {
    CandidateSummary& summary =
        summaries.emplace_back(c.name, c.preference, CandidateLimits::Unbounded());
    for (const GyroSample& s : c.samples) summary.Add(s.t_ns, s.omega_rad_s);
    for (size_t i = 0; i < c.unreadable_time; ++i) summary.Add(std::nullopt, {0, 0, 0});
    summary.Finish();
  }
  const std::optional<size_t> chosen = ChooseGyroSummary(summaries, log);
  if (!chosen) return false;
  CandidateCleaner cleaner(summaries[*chosen]);
  std::vector<GyroSample> cleaned;
  cleaned.reserve(summaries[*chosen].samples());
  for (const GyroSample& s : candidates[*chosen].samples)
    cleaner.Add(s.t_ns, s.omega_rad_s, &cleaned);
  SHUTTERLAB_CHECK(cleaner.Finish(&cleaned)) << "the cleaning's two passes disagree";
  log->gyro = GyroTrace(std::move(cleaned));
  return true;
}

}  // namespace internal
}  // namespace shutterlab
