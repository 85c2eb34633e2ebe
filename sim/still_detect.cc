#include "sim/still_detect.h"

#include "sim/check.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace shutterlab {
namespace {

// Prefix sums of the rates (offset by the trace mean, so that sums of squares keep their precision)
// and of their squares: any window's mean and variance in O(1).
class WindowStats {
 public:
  explicit WindowStats(const GyroTrace& trace) : sum_(trace.size() + 1), sq_(trace.size() + 1) {
    for (const GyroSample& s : trace.samples()) offset_ += s.omega_rad_s;
    offset_ /= static_cast<double>(trace.size());
    sum_[0].setZero();
    sq_[0].setZero();
    for (size_t i = 0; i < trace.size(); ++i) {
      const Eigen::Vector3d x = trace[i].omega_rad_s - offset_;
      sum_[i + 1] = sum_[i] + x;
      sq_[i + 1] = sq_[i] + x.cwiseAbs2();
    }
  }
  // Mean over samples [begin, end).
  Eigen::Vector3d Mean(size_t begin, size_t end) const {
    return (sum_[end] - sum_[begin]) / static_cast<double>(end - begin) + offset_;
  }
  // Sum over axes of the (population) variance over [begin, end).
  double Variance(size_t begin, size_t end) const {
    const double n = static_cast<double>(end - begin);
    const Eigen::Vector3d mean = (sum_[end] - sum_[begin]) / n;
    return std::max(0.0, ((sq_[end] - sq_[begin]) / n - mean.cwiseAbs2()).sum());
  }

 private:
  Eigen::Vector3d offset_ = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> sum_;
  std::vector<Eigen::Vector3d> sq_;
};

}  // namespace

void StillDetectOptions::Check() const {
  SHUTTERLAB_CHECK(std::isfinite(window_s) && window_s > 0)
      << "still window must be > 0 s, got " << window_s;
  SHUTTERLAB_CHECK(std::isfinite(k_sigma) && k_sigma > 0) << "k_sigma must be > 0, got " << k_sigma;
  SHUTTERLAB_CHECK(std::isfinite(min_duration_s) && min_duration_s >= window_s)
      << "min still duration " << min_duration_s << " s must be at least the window " << window_s
      << " s";
}

StillSegment DetectStillSegment(const GyroTrace& trace, const StillDetectOptions& options) {
  options.Check();
  SHUTTERLAB_CHECK(trace.size() >= 2) << "still detection needs a trace of at least 2 samples";
  const double dt_s = trace.sampling().median_interval_ns * 1e-9;
  SHUTTERLAB_CHECK(dt_s > 0) << "still detection needs increasing timestamps";
  const size_t n = trace.size();
  const size_t window =
      std::max<size_t>(2, static_cast<size_t>(std::llround(options.window_s / dt_s)));
  const size_t stretch =
      std::max(window, static_cast<size_t>(std::llround(options.min_duration_s / dt_s)));
  SHUTTERLAB_CHECK(window <= n) << "still window of " << options.window_s << " s (" << window
                                << " samples) is longer than the trace (" << n << " samples, "
                                << trace.DurationS() << " s)";
  SHUTTERLAB_CHECK(stretch <= n) << "the trace lasts " << trace.DurationS() << " s (" << n
                                 << " samples), shorter than the " << options.min_duration_s
                                 << " s still segment asked for";
  const WindowStats stats(trace);

  // 2. Reference: the quietest stretch. Stretches whose variance is within kQuietVarianceFactor of
  // the least are equally quiet (a constant rotation is as quiet as stillness); of those the one
  // with the smallest mean rate wins, since a still gyro reads only its bias.
  constexpr double kQuietVarianceFactor = 1.5;
  std::vector<double> stretch_variance(n - stretch + 1);
  double least = std::numeric_limits<double>::infinity();
  for (size_t j = 0; j + stretch <= n; ++j) {
    stretch_variance[j] = stats.Variance(j, j + stretch);
    least = std::min(least, stretch_variance[j]);
  }
  size_t ref = 0;
  double ref_rate = std::numeric_limits<double>::infinity();
  for (size_t j = 0; j + stretch <= n; ++j) {
    if (stretch_variance[j] > kQuietVarianceFactor * least + kMinSpreadRadS * kMinSpreadRadS)
      continue;
    const double rate = stats.Mean(j, j + stretch).norm();
    if (rate < ref_rate) {
      ref_rate = rate;
      ref = j;
    }
  }
  const Eigen::Vector3d m_ref = stats.Mean(ref, ref + stretch);
  Eigen::Vector3d dm_sq = Eigen::Vector3d::Zero();
  double v_sum = 0.0, v_sq = 0.0;
  const size_t inside = stretch - window + 1;
  for (size_t j = ref; j < ref + inside; ++j) {
    dm_sq += (stats.Mean(j, j + window) - m_ref).cwiseAbs2();
    const double v = stats.Variance(j, j + window);
    v_sum += v;
    v_sq += v * v;
  }
  const Eigen::Vector3d mean_spread =
      (dm_sq / static_cast<double>(inside)).cwiseSqrt().cwiseMax(kMinSpreadRadS);
  const double v_mean = v_sum / inside;
  const double v_spread = std::max(std::sqrt(std::max(0.0, v_sq / inside - v_mean * v_mean)),
                                   kMinSpreadRadS * kMinSpreadRadS);
  const Eigen::Vector3d mean_limit = options.k_sigma * mean_spread;
  const double v_limit = v_mean + options.k_sigma * v_spread;
  // A stretch that moves slowly is quiet within each window but its window means wander: for noise
  // whose correlation time is well below the window, their variance is about v / N (times the
  // correlation factor); motion makes it comparable to or larger than the in-window variance.
  const double wander = mean_spread.cwiseAbs2().sum();
  SHUTTERLAB_CHECK(wander <= kMaxWanderRatio * v_mean + 3 * kMinSpreadRadS * kMinSpreadRadS)
      << "no still segment found: the quietest " << options.min_duration_s << " s, from "
      << (trace[ref].t_ns - trace.t_begin_ns()) * 1e-9 << " s, still moves (its "
      << options.window_s << " s means wander " << std::sqrt(wander / std::max(v_mean, 1e-300))
      << " times the in-window noise); give --bias A:B";

  // 3.-5. Runs of still windows.
  auto still = [&](size_t j) {
    const Eigen::Vector3d dm = (stats.Mean(j, j + window) - m_ref).cwiseAbs();
    return (dm.array() <= mean_limit.array()).all() && stats.Variance(j, j + window) <= v_limit;
  };
  const int64_t interval_ns = trace.sampling().median_interval_ns;
  auto end_time_ns = [&](size_t end_sample) {
    return end_sample < n ? trace[end_sample].t_ns : trace.t_end_ns() + interval_ns;
  };
  const int64_t min_ns = SecondsToNs(options.min_duration_s);
  size_t best_begin = 0, best_end = 0;  // samples [begin, end)
  int64_t best_ns = -1;
  size_t j = 0;
  while (j + window <= n) {
    if (!still(j)) {
      ++j;
      continue;
    }
    const size_t a = j;
    while (j + window <= n && still(j)) ++j;
    const size_t begin = a, end = j - 1 + window;
    const int64_t duration_ns = end_time_ns(end) - trace[begin].t_ns;
    if (duration_ns > best_ns) {
      best_ns = duration_ns;
      best_begin = begin;
      best_end = end;
    }
    if (options.first && duration_ns >= min_ns) {
      best_begin = begin;
      best_end = end;
      best_ns = duration_ns;
      break;
    }
  }
  const int64_t t0 = trace.t_begin_ns();
  SHUTTERLAB_CHECK(best_ns >= min_ns)
      << "no still segment of at least " << options.min_duration_s
      << " s found (longest: " << std::max<int64_t>(best_ns, 0) * 1e-9 << " s"
      << (best_ns > 0 ? " at " + std::to_string((trace[best_begin].t_ns - t0) * 1e-9) + " s"
                      : std::string())
      << "); give --bias A:B";
  StillSegment out;
  out.first_sample = best_begin;
  out.end_sample = best_end;
  out.window_samples = window;
  out.quiet_mean_rad_s = m_ref;
  out.segment.begin_s = (trace[best_begin].t_ns - t0) * 1e-9;
  out.segment.end_s = (end_time_ns(best_end) - t0) * 1e-9;
  return out;
}

}  // namespace shutterlab
