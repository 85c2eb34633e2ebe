#include "sim/still_detect.h"

#include "sim/check.h"
#include "sim/interval_histogram.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

// Stretches whose variance is within this factor of the least are equally quiet (a constant
// rotation is as quiet as stillness).
constexpr double kQuietVarianceFactor = 1.5;

// Prefix sums of the rates (offset by the trace mean, so that sums of squares keep their precision)
// and of their squares: any window's mean and variance in O(1). Only the last span + 1 sums are
// needed, kept in a ring (a trace held whole and a streamed one alike): the same sums, added in the
// same order, so every window's mean and variance is the same double either way.
class WindowStats {
 public:
  // Room for at least the last `prefixes` prefix sums (every window's span + 1), rounded up to a
  // power of two: a slot is then a mask of the index, where a modulo (a division, six to ten a
  // sample) was most of a 200 000-sample search's time. At most twice the memory: 2 s at 8 kHz
  // is 16 001 sums, a ring of 16 384 (0.9 MB).
  WindowStats(const Eigen::Vector3d& offset, size_t prefixes)
      : offset_(offset), slot_mask_(PowerOfTwoAtLeast(prefixes) - 1) {
    sum_.resize(slot_mask_ + 1);
    sq_.resize(slot_mask_ + 1);
    t_ns_.resize(slot_mask_ + 1);
    sum_[0].setZero();
    sq_[0].setZero();
  }
  // The next sample (index count()).
  void Add(const GyroSample& s) {
    const Eigen::Vector3d x = s.omega_rad_s - offset_;
    const size_t prev = Slot(end_), next = Slot(end_ + 1);
    sum_[next] = sum_[prev] + x;
    sq_[next] = sq_[prev] + x.cwiseAbs2();
    t_ns_[prev] = s.t_ns;
    ++end_;
  }
  size_t count() const { return end_; }  // samples added
  // Mean over samples [begin, end) (within the kept ones).
  Eigen::Vector3d Mean(size_t begin, size_t end) const {
    return (sum_[Slot(end)] - sum_[Slot(begin)]) / static_cast<double>(end - begin) + offset_;
  }
  // Sum over axes of the (population) variance over [begin, end).
  double Variance(size_t begin, size_t end) const {
    const double n = static_cast<double>(end - begin);
    const Eigen::Vector3d mean = (sum_[Slot(end)] - sum_[Slot(begin)]) / n;
    return std::max(0.0, ((sq_[Slot(end)] - sq_[Slot(begin)]) / n - mean.cwiseAbs2()).sum());
  }
  int64_t t_ns(size_t i) const { return t_ns_[Slot(i)]; }  // time of a kept sample

 private:
  static size_t PowerOfTwoAtLeast(size_t n) {
    size_t p = 1;
    while (p < n) p *= 2;
    return p;
  }
  size_t Slot(size_t i) const { return i & slot_mask_; }
  Eigen::Vector3d offset_;
  size_t slot_mask_;
  std::vector<Eigen::Vector3d> sum_, sq_;
  std::vector<int64_t> t_ns_;  // t_ns_[Slot(i)]: sample i
  size_t end_ = 0;
};

// What the detection needs to know of the whole trace before it looks at windows.
struct TraceSummary {
  size_t n = 0;
  Eigen::Vector3d mean_rad_s = Eigen::Vector3d::Zero();  // summed in sample order, then / n
  int64_t t_begin_ns = 0, t_end_ns = 0;
  int64_t interval_ns = 0;  // nominal (NominalIntervalNs): the windows' length in samples
  double DurationS() const { return (t_end_ns - t_begin_ns) * 1e-9; }
};

// The window N and the stretch (min_duration_s) in samples, checked against the trace.
struct StillSizes {
  size_t window = 0, stretch = 0;
};

StillSizes Sizes(const TraceSummary& trace, const StillDetectOptions& options) {
  SHUTTERLAB_CHECK(trace.n >= 2) << "still detection needs a trace of at least 2 samples";
  const double dt_s = trace.interval_ns * 1e-9;
  SHUTTERLAB_CHECK(dt_s > 0) << "still detection needs increasing timestamps";
  StillSizes sizes;
  sizes.window = std::max<size_t>(2, static_cast<size_t>(std::llround(options.window_s / dt_s)));
  sizes.stretch =
      std::max(sizes.window, static_cast<size_t>(std::llround(options.min_duration_s / dt_s)));
  SHUTTERLAB_CHECK(sizes.window <= trace.n)
      << "still window of " << options.window_s << " s (" << sizes.window
      << " samples) is longer than the trace (" << trace.n << " samples, " << trace.DurationS()
      << " s)";
  SHUTTERLAB_CHECK(sizes.stretch <= trace.n)
      << "the trace lasts " << trace.DurationS() << " s (" << trace.n
      << " samples), shorter than the " << options.min_duration_s << " s still segment asked for";
  return sizes;
}

bool IsQuiet(double stretch_variance, double least) {
  return stretch_variance <= kQuietVarianceFactor * least + kMinSpreadRadS * kMinSpreadRadS;
}

// The still test of step 3, from the windows inside the reference stretch: Add each window's mean
// and variance in order, then Finish.
class StillTest {
 public:
  explicit StillTest(const Eigen::Vector3d& m_ref) : m_ref_(m_ref) {}
  void Add(const Eigen::Vector3d& mean, double variance) {
    dm_sq_ += (mean - m_ref_).cwiseAbs2();
    v_sum_ += variance;
    v_sq_ += variance * variance;
    ++inside_;
  }
  // The limits; throws std::invalid_argument when the reference stretch (from ref_s after the
  // trace's start) itself moves.
  void Finish(const StillDetectOptions& options, double ref_s) {
    const double inside = static_cast<double>(inside_);
    const Eigen::Vector3d mean_spread = (dm_sq_ / inside).cwiseSqrt().cwiseMax(kMinSpreadRadS);
    const double v_mean = v_sum_ / inside;
    const double v_spread = std::max(std::sqrt(std::max(0.0, v_sq_ / inside - v_mean * v_mean)),
                                     kMinSpreadRadS * kMinSpreadRadS);
    mean_limit_ = options.k_sigma * mean_spread;
    v_limit_ = v_mean + options.k_sigma * v_spread;
    // A stretch that moves slowly is quiet within each window but its window means wander: for
    // noise whose correlation time is well below the window, their variance is about v / N (times
    // the correlation factor); motion makes it comparable to or larger than the in-window variance.
    const double wander = mean_spread.cwiseAbs2().sum();
    SHUTTERLAB_CHECK(wander <= kMaxWanderRatio * v_mean + 3 * kMinSpreadRadS * kMinSpreadRadS)
        << "no still segment found: the quietest " << options.min_duration_s << " s, from " << ref_s
        << " s, still moves (its " << options.window_s << " s means wander "
        << std::sqrt(wander / std::max(v_mean, 1e-300)) << " times the in-window noise); give "
        << "--bias A:B";
  }
  bool Still(const Eigen::Vector3d& mean, double variance) const {
    const Eigen::Vector3d dm = (mean - m_ref_).cwiseAbs();
    return (dm.array() <= mean_limit_.array()).all() && variance <= v_limit_;
  }

 private:
  Eigen::Vector3d m_ref_;
  Eigen::Vector3d dm_sq_ = Eigen::Vector3d::Zero();
  double v_sum_ = 0.0, v_sq_ = 0.0;
  size_t inside_ = 0;
  Eigen::Vector3d mean_limit_ = Eigen::Vector3d::Zero();
  double v_limit_ = 0.0;
};

// Steps 4 and 5: the runs of still windows, fed window by window in order (window j once samples
// up to j + N - 1 are known), and the best of them.
class RunFinder {
 public:
  RunFinder(const TraceSummary& trace, size_t window, const StillDetectOptions& options)
      : trace_(trace),
        window_(window),
        first_(options.first),
        min_ns_(SecondsToNs(options.min_duration_s)) {}
  // Window j (its first sample at t_j_ns, its last at t_last_ns) is still or not; false when the
  // search is over (options.first and a run long enough).
  bool Add(size_t j, bool still, int64_t t_j_ns, int64_t t_last_ns) {
    if (still && !in_run_) {
      in_run_ = true;
      begin_ = j;
      begin_ns_ = t_j_ns;
    } else if (!still && in_run_) {
      // The run's end sample j - 1 + N (the window before's last + 1) is this window's last.
      return Close(j - 1 + window_, t_last_ns);
    }
    return true;
  }
  // After the last window: a run still open ends one interval past the last sample.
  void Finish() {
    if (in_run_ && !done_) Close(trace_.n, trace_.t_end_ns + trace_.interval_ns);
  }
  StillSegment Result(const Eigen::Vector3d& m_ref, const StillDetectOptions& options) const {
    SHUTTERLAB_CHECK(best_ns_ >= min_ns_)
        << "no still segment of at least " << options.min_duration_s
        << " s found (longest: " << std::max<int64_t>(best_ns_, 0) * 1e-9 << " s"
        << (best_ns_ > 0
                ? " at " + std::to_string((best_begin_ns_ - trace_.t_begin_ns) * 1e-9) + " s"
                : std::string())
        << "); give --bias A:B";
    StillSegment out;
    out.first_sample = best_begin_;
    out.end_sample = best_end_;
    out.window_samples = window_;
    out.quiet_mean_rad_s = m_ref;
    out.segment.begin_s = (best_begin_ns_ - trace_.t_begin_ns) * 1e-9;
    out.segment.end_s = (best_end_ns_ - trace_.t_begin_ns) * 1e-9;
    return out;
  }

 private:
  // The run [begin_, end) closes; end_ns: the time of sample end (or one interval past the last).
  bool Close(size_t end, int64_t end_ns) {
    in_run_ = false;
    const int64_t duration_ns = end_ns - begin_ns_;
    if (duration_ns > best_ns_ || (first_ && duration_ns >= min_ns_)) {
      best_ns_ = duration_ns;
      best_begin_ = begin_;
      best_end_ = end;
      best_begin_ns_ = begin_ns_;
      best_end_ns_ = end_ns;
    }
    done_ = first_ && duration_ns >= min_ns_;
    return !done_;
  }

  const TraceSummary& trace_;
  size_t window_;
  bool first_;
  int64_t min_ns_;
  bool in_run_ = false, done_ = false;
  size_t begin_ = 0;
  int64_t begin_ns_ = 0;
  size_t best_begin_ = 0, best_end_ = 0;
  int64_t best_ns_ = -1, best_begin_ns_ = 0, best_end_ns_ = 0;
};

// Every sample of a fresh source, in order, to visit(sample); stops early when visit returns false.
template <typename Visit>
void ForEachSample(const std::function<std::unique_ptr<GyroSource>()>& open, Visit visit) {
  const std::unique_ptr<GyroSource> source = open();
  for (GyroChunk chunk = source->Next(); !chunk.empty(); chunk = source->Next()) {
    for (const GyroSample& s : chunk) {
      if (!visit(s)) return;
    }
  }
}

}  // namespace

void StillDetectOptions::Check() const {
  SHUTTERLAB_CHECK(std::isfinite(window_s) && window_s > 0)
      << "still window must be > 0 s, got " << window_s;
  SHUTTERLAB_CHECK(std::isfinite(k_sigma) && k_sigma > 0) << "k_sigma must be > 0, got " << k_sigma;
  SHUTTERLAB_CHECK(std::isfinite(min_duration_s) && min_duration_s >= window_s)
      << "min still duration " << min_duration_s << " s must be at least the window " << window_s
      << " s";
}

namespace {

// Steps 2 to 5 over a trace that sweep(prefixes, f) hands out from its start: every sample added
// in order to a WindowStats of that many prefixes, f(stats) called after each until it returns
// false. A trace held whole and a streamed one give the same doubles in the same order.
template <typename Sweep>
StillSegment Detect(const TraceSummary& trace, const StillDetectOptions& options, Sweep sweep) {
  const StillSizes sizes = Sizes(trace, options);
  const size_t window = sizes.window, stretch = sizes.stretch;
  // 2. Reference: the quietest stretch; of the equally quiet ones the one with the smallest mean
  // rate, since a still gyro reads only its bias.
  double least = std::numeric_limits<double>::infinity();
  sweep(stretch + 1, [&](const WindowStats& stats) {
    if (stats.count() < stretch) return true;
    const size_t j = stats.count() - stretch;
    least = std::min(least, stats.Variance(j, j + stretch));
    return true;
  });
  size_t ref = 0;
  int64_t ref_ns = trace.t_begin_ns;
  Eigen::Vector3d m_ref = Eigen::Vector3d::Zero();
  double ref_rate = std::numeric_limits<double>::infinity();
  sweep(stretch + 1, [&](const WindowStats& stats) {
    if (stats.count() < stretch) return true;
    const size_t j = stats.count() - stretch;
    if (!IsQuiet(stats.Variance(j, j + stretch), least)) return true;
    const Eigen::Vector3d mean = stats.Mean(j, j + stretch);
    if (mean.norm() < ref_rate) {
      ref_rate = mean.norm();
      ref = j;
      ref_ns = stats.t_ns(j);
      m_ref = mean;
    }
    return true;
  });
  // How much a still window's statistics wander, from the windows inside the reference stretch.
  StillTest test(m_ref);
  const size_t inside_end = ref + stretch - window + 1;  // windows [ref, inside_end)
  sweep(window + 1, [&](const WindowStats& stats) {
    if (stats.count() < window) return true;
    const size_t j = stats.count() - window;
    if (j >= ref) test.Add(stats.Mean(j, j + window), stats.Variance(j, j + window));
    return j + 1 < inside_end;
  });
  test.Finish(options, (ref_ns - trace.t_begin_ns) * 1e-9);
  // 3.-5. Runs of still windows.
  RunFinder runs(trace, window, options);
  sweep(window + 1, [&](const WindowStats& stats) {
    if (stats.count() < window) return true;
    const size_t j = stats.count() - window;
    return runs.Add(j, test.Still(stats.Mean(j, j + window), stats.Variance(j, j + window)),
                    stats.t_ns(j), stats.t_ns(j + window - 1));
  });
  runs.Finish();
  return runs.Result(m_ref, options);
}

}  // namespace

StillSegment DetectStillSegment(const GyroTrace& trace, const StillDetectOptions& options) {
  options.Check();
  TraceSummary summary;
  summary.n = trace.size();
  SHUTTERLAB_CHECK(summary.n >= 2) << "still detection needs a trace of at least 2 samples";
  for (const GyroSample& s : trace.samples()) summary.mean_rad_s += s.omega_rad_s;
  summary.mean_rad_s /= static_cast<double>(summary.n);
  summary.t_begin_ns = trace.t_begin_ns();
  summary.t_end_ns = trace.t_end_ns();
  summary.interval_ns = trace.sampling().nominal_interval_ns;
  return Detect(summary, options, [&](size_t prefixes, const auto& f) {
    WindowStats stats(summary.mean_rad_s, prefixes);
    for (const GyroSample& s : trace.samples()) {
      stats.Add(s);
      if (!f(stats)) return;
    }
  });
}

StillSegment DetectStillSegment(const std::function<std::unique_ptr<GyroSource>()>& open,
                                const StillDetectOptions& options) {
  options.Check();
  // The length, the mean (summed in sample order, as for a trace held whole) and the nominal
  // interval (IntervalHistogram's median, as GyroTrace::sampling).
  TraceSummary summary;
  IntervalHistogram intervals;
  ForEachSample(open, [&](const GyroSample& s) {
    if (summary.n == 0) {
      summary.t_begin_ns = s.t_ns;
    } else {
      intervals.Add(s.t_ns - summary.t_end_ns);
    }
    summary.t_end_ns = s.t_ns;
    summary.mean_rad_s += s.omega_rad_s;
    ++summary.n;
    return true;
  });
  SHUTTERLAB_CHECK(summary.n >= 2) << "still detection needs a trace of at least 2 samples";
  summary.mean_rad_s /= static_cast<double>(summary.n);
  summary.interval_ns =
      NominalIntervalNs(intervals.Median(), summary.n, summary.t_end_ns - summary.t_begin_ns);
  return Detect(summary, options, [&](size_t prefixes, const auto& f) {
    WindowStats stats(summary.mean_rad_s, prefixes);
    ForEachSample(open, [&](const GyroSample& s) {
      stats.Add(s);
      return f(stats);
    });
  });
}

}  // namespace shutterlab
