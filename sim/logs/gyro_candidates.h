#pragma once
// Choosing the gyro trace of a flight log among the streams it holds: every reader that finds
// several (ULog topics and instances, DataFlash GYR / ISBD / IMU) cleans and ranks them here, so
// that all do it the same way.
//
// The cleaning of a stream (in log order): samples with t <= 0 (PX4 and ArduPilot write 0 for
// 'not set'), an unreadable time or a non-finite rate are dropped; so is an isolated timestamp
// spike, a sample outside the span of both its neighbours in log order (the first and last sample:
// beyond their one neighbour, which is in line with the next); what is left is stable-sorted by
// time; an end sample more than 60 s beyond its neighbour is dropped (the last ones first, then
// the first ones, while 3 samples are left). The chosen stream has the highest median interval's
// rate, preferring lower `preference` (then more samples) among those within 10% of the best rate.
//
// Two ways to use it, with one result:
//  - whole: collect every candidate's samples (GyroCandidate) and call ChooseGyroSource;
//  - streamed, in bounded memory (a reader that passes over its bytes twice):
//      pass 1: one CandidateSummary per stream, fed every sample (Add) in log order, then Finish;
//              ChooseGyroSummary picks one and fills the log's gyro_source, sources and warnings;
//              when a summary is not exact(), the disorder or the intervals of that file need more
//              memory than the limits allow: redo pass 1 with CandidateLimits::Unbounded() (and say
//              so: ReadInMemoryWarning);
//      pass 2: a CandidateCleaner made from the chosen summary, fed that stream's samples again in
//              the same order (Add, then Finish), appends exactly the cleaned samples
//              ChooseGyroSource gives, in order, holding only the few samples the sort must hold
//              back.

#include "sim/gyro_trace.h"
#include "sim/log_warning.h"
#include "sim/logs/flight_log.h"

#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace shutterlab {
namespace internal {

// One gyro stream found in a log, before the best one is chosen (the whole way).
struct GyroCandidate {
  std::string name;                 // e.g. "sensor_gyro_fifo.x,y,z" or "GYR/1"
  int preference = 0;               // lower is better among candidates of similar rate
  std::vector<GyroSample> samples;  // in log order; cleaned by ChooseGyroSource
  // Messages whose time could not be read (beyond int64 nanoseconds, or not an integer field):
  // left out of samples, counted here so that the warning says what they were.
  size_t unreadable_time = 0;
};

// Adds a sample read from a message with time t_ns (nullopt: unreadable, counted).
inline void AddCandidateSample(const std::optional<int64_t>& t_ns, const Eigen::Vector3d& rate,
                               GyroCandidate* candidate) {
  if (!t_ns) {
    ++candidate->unreadable_time;
    return;
  }
  candidate->samples.push_back({*t_ns, rate});
}

// Cleans every candidate, picks one (see the top of this file), fills log->gyro, gyro_source,
// gyro_sources_available, and adds warnings and records_skipped for what was dropped. Returns
// false when no candidate has 2 samples and a positive median interval.
bool ChooseGyroSource(std::vector<GyroCandidate> candidates, FlightLog* log);

// How much a CandidateSummary may hold; beyond it the summary is not exact().
struct CandidateLimits {
  // How far (in samples) one may have to move forward when sorted: pass 1 holds this many times
  // back (16 bytes each) before it takes the smallest as final.
  size_t reorder_samples = size_t{1} << 16;
  // Distinct intervals between sorted samples kept for the median (and gaps over 60 s at an end).
  size_t intervals = size_t{1} << 16;
  // No limit: pass 1 then holds every time of a stream (the whole way's memory, never inexact).
  static CandidateLimits Unbounded() { return {SIZE_MAX, SIZE_MAX}; }
};

// What drops the cleaning makes in log order (shared by both passes: the same rules, the same
// counts). Internal to CandidateSummary and CandidateCleaner.
class CleaningFront {
 public:
  // Takes the next sample; writes the samples now known to stay (0, 1 or 2, in log order) to out.
  int Add(const std::optional<int64_t>& t_ns, const Eigen::Vector3d& rate, GyroSample out[2]);
  // After the last Add: the samples still held (0..2).
  int Finish(GyroSample out[2]);
  size_t unreadable_time = 0, dropped_time = 0, dropped_value = 0, dropped_spike = 0;

 private:
  // The last kept samples: window_[0] oldest; kept_ counts every kept sample so far.
  GyroSample window_[3];
  size_t kept_ = 0;
};

// Pass 1: everything about one stream that the choice and the cleaning need, in bounded memory.
class CandidateSummary {
 public:
  CandidateSummary(std::string name, int preference, CandidateLimits limits = {});
  // The next sample in log order (t_ns nullopt: its time did not read).
  void Add(const std::optional<int64_t>& t_ns, const Eigen::Vector3d& rate) {
    GyroSample kept[2];
    const int n = front_.Add(t_ns, rate, kept);
    for (int i = 0; i < n; ++i) AddKept(kept[i].t_ns);
  }
  // After the last Add (once).
  void Finish();
  // False when the limits were too small for this stream: its rate, counts and cleaning are then
  // unknown (redo pass 1 with CandidateLimits::Unbounded()).
  bool exact() const { return exact_; }

  const std::string& name() const { return name_; }
  int preference() const { return preference_; }
  size_t samples() const { return kept_end_ - kept_begin_; }  // after cleaning
  double rate_hz() const { return rate_hz_; }
  // At least 2 samples and a positive median interval: a stream the choice may take.
  bool usable() const { return samples() >= 2 && rate_hz_ > 0.0; }
  // The warnings (and records_skipped) for what the cleaning dropped and sorted.
  void Warn(FlightLog* log) const;

 private:
  friend class CandidateCleaner;
  // A sample that passed the drops, its time and position among those (its sort key).
  void AddKept(int64_t t_ns);
  // The next time in sorted order (sorted_ of them came before); seq its position in log order.
  void TakeSorted(int64_t t_ns, size_t seq);
  bool TooMany(size_t held, size_t limit);

  std::string name_;
  int preference_;
  CandidateLimits limits_;
  CleaningFront front_;
  bool exact_ = true;
  size_t kept_ = 0;  // samples past the drops (the sort's input)
  std::optional<int64_t> last_kept_t_ns_;
  size_t out_of_order_ = 0;  // samples earlier than the one before them (moved by the sort)
  // The sort: the times not yet known to be final, in order, with their log positions.
  std::deque<std::pair<int64_t, size_t>> held_;
  std::optional<int64_t> last_sorted_t_ns_;
  size_t sorted_ = 0;
  size_t reorder_depth_ = 0;  // how far back a sample had to move: pass 2's buffer
  // Intervals between sorted samples (the median's), and the runs of over-60 s gaps at the ends.
  std::unordered_map<int64_t, size_t> interval_counts_;
  std::vector<int64_t> leading_far_gaps_, trailing_far_gaps_;
  bool leading_run_open_ = true;
  size_t kept_begin_ = 0, kept_end_ = 0;  // sorted positions [begin, end) left after the end drops
  double rate_hz_ = 0.0;
};

// Chooses among finished, exact summaries as ChooseGyroSource does; fills log->gyro_source,
// gyro_sources_available, and adds the chosen one's warnings and records_skipped. Returns the
// chosen summary's index, or nullopt when none is usable.
std::optional<size_t> ChooseGyroSummary(const std::vector<CandidateSummary>& summaries,
                                        FlightLog* log);

// Said when a file's gyro streams needed pass 1 without limits (their memory grows with the log).
LogWarning ReadInMemoryWarning(const std::vector<CandidateSummary>& bounded);

// Pass 2: the chosen stream's cleaned samples, from its samples fed again in log order.
class CandidateCleaner {
 public:
  explicit CandidateCleaner(const CandidateSummary& chosen);
  // The next sample in log order; appends the samples now final to out (in time order).
  void Add(const std::optional<int64_t>& t_ns, const Eigen::Vector3d& rate,
           std::vector<GyroSample>* out) {
    GyroSample kept[2];
    const int n = front_.Add(t_ns, rate, kept);
    for (int i = 0; i < n; ++i) Hold(kept[i], out);
  }
  // After the last Add: the rest. False when the samples fed were not those pass 1 saw (the file
  // changed in between): the output is then not the cleaned stream.
  bool Finish(std::vector<GyroSample>* out);

 private:
  struct Held {
    GyroSample sample;
    size_t seq;
  };
  void Hold(const GyroSample& sample, std::vector<GyroSample>* out);
  void Release(const Held& held, std::vector<GyroSample>* out);

  CleaningFront front_;
  size_t depth_;                  // samples held back before the smallest is final
  bool sort_at_end_;              // a disorder too deep to insert into: all held, sorted at the end
  size_t kept_total_;             // samples past the drops, as pass 1 counted them
  size_t keep_begin_, keep_end_;  // sorted positions kept
  size_t kept_ = 0, sorted_ = 0;
  bool consistent_ = true;
  std::optional<int64_t> last_sorted_t_ns_;
  std::deque<Held> held_;  // in time order (sort_at_end_: in log order)
};

}  // namespace internal
}  // namespace shutterlab
