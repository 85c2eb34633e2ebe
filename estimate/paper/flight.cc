#include "estimate/paper/flight.h"

#include "estimate/paper/window_stats.h"
#include "sim/check.h"
#include "sim/so3.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace shutterlab {
namespace {

// Window starts per chunk: the chunk's ends, ranges and kernel buffers stay in L2.
constexpr size_t kChunkWindows = 8192;
// The vector criterion's cheap upper bound skips the exact pairwise test only when it clears the
// threshold by more than its own rounding (cosines near 1 carry ~1e-16 absolute error; the
// sqrt(1 - c^2) terms ~1e-13 at the smallest angles we meet).
constexpr double kCosBoundMargin = 1e-12;

// Orientations as structure of arrays (Hamilton w, x, y, z) so the per-window dot products stream.
struct Quaternions {
  std::vector<double> w, x, y, z;
  // |q_i . q_j| = cos(theta_ij / 2), theta_ij the rotation angle between the two orientations.
  double AbsDot(size_t i, size_t j) const {
    return std::abs(w[i] * w[j] + x[i] * x[j] + y[i] * y[j] + z[i] * z[j]);
  }
  // theta_ij from the relative rotation q_i^* q_j = (w, v): 2 atan2(|v|, |w|), accurate also for
  // tiny angles (acos of a dot product near 1 is not).
  double Angle(size_t i, size_t j) const {
    const double rw = w[i] * w[j] + x[i] * x[j] + y[i] * y[j] + z[i] * z[j];
    // v = w_i v_j - w_j v_i - v_i x v_j
    const double vx = w[i] * x[j] - w[j] * x[i] - (y[i] * z[j] - z[i] * y[j]);
    const double vy = w[i] * y[j] - w[j] * y[i] - (z[i] * x[j] - x[i] * z[j]);
    const double vz = w[i] * z[j] - w[j] * z[i] - (x[i] * y[j] - y[i] * x[j]);
    return 2.0 * std::atan2(std::sqrt(vx * vx + vy * vy + vz * vz), std::abs(rw));
  }
};

// The analysed samples' per-axis angles and orientations, integrated as a stream over a sliding
// buffer that holds samples [base, end) only, so that memory stays O(chunk + window) for any trace
// length (and a 10^8-sample log needs no 3 GB of angle arrays). Index g counts the samples after
// the bias segment (trace index first + g). The recurrences are exactly those of
// IntegratePerAxis (angle += (w_g - b) dt) and OrientationTrace (q_g = q_{g-1} Exp(0.5 (w_{g-1} +
// w_g) dt), bias-corrected rates), evaluated in the same order, so the values are bit-identical
// to theirs.
class AngleStream {
 public:
  AngleStream(const GyroTrace& trace, size_t first, const Eigen::Vector3d& bias_rad_s, bool with_q)
      : trace_(trace), first_(first), bias_(bias_rad_s), with_q_(with_q) {}

  // Makes samples [new_base, new_end) available; new_base and new_end never decrease.
  void Advance(size_t new_base, size_t new_end) {
    // Every sample must be stepped through once, in order, for the running sums.
    SHUTTERLAB_CHECK(new_base <= end_ || (end_ == 0 && new_base == 0)) << "stream skipped samples";
    const size_t keep_from = std::max(new_base, base_);
    const size_t keep = end_ > keep_from ? end_ - keep_from : 0;
    const size_t size = new_end - new_base;
    for (auto* v : Buffers()) {
      if (keep > 0 && keep_from > base_) {
        std::copy(v->begin() + (keep_from - base_), v->begin() + (keep_from - base_) + keep,
                  v->begin());
      }
      if (v->size() < size) v->resize(size);
    }
    base_ = new_base;
    for (size_t g = std::max(end_, new_base); g < new_end; ++g) Step(g);
    end_ = std::max(end_, new_end);
  }

  const double* angle(int a) const { return angle_buffer_[a].data(); }
  const Quaternions& q() const { return q_; }
  size_t base() const { return base_; }

 private:
  std::vector<std::vector<double>*> Buffers() {
    std::vector<std::vector<double>*> out = {&angle_buffer_[0], &angle_buffer_[1],
                                             &angle_buffer_[2]};
    if (with_q_) out.insert(out.end(), {&q_.w, &q_.x, &q_.y, &q_.z});
    return out;
  }

  void Step(size_t g) {
    const GyroSample& s = trace_[first_ + g];
    if (g > 0) {
      const GyroSample& previous = trace_[first_ + g - 1];
      const double dt_s = (s.t_ns - previous.t_ns) * 1e-9;
      for (int a = 0; a < 3; ++a) angle_[a] += (s.omega_rad_s[a] - bias_[a]) * dt_s;
      if (with_q_) {
        const Eigen::Vector3d wa = previous.omega_rad_s - bias_;
        const Eigen::Vector3d wb = s.omega_rad_s - bias_;
        current_ = (current_ * ExpSO3(0.5 * (wa + wb) * dt_s)).normalized();
      }
    }
    const size_t i = g - base_;
    for (int a = 0; a < 3; ++a) angle_buffer_[a][i] = angle_[a];
    if (with_q_) {
      q_.w[i] = current_.w();
      q_.x[i] = current_.x();
      q_.y[i] = current_.y();
      q_.z[i] = current_.z();
    }
  }

  const GyroTrace& trace_;
  const size_t first_;
  const Eigen::Vector3d bias_;
  const bool with_q_;
  size_t base_ = 0, end_ = 0;
  double angle_[3] = {0.0, 0.0, 0.0};
  Eigen::Quaterniond current_ = Eigen::Quaterniond::Identity();
  std::vector<double> angle_buffer_[3];
  Quaternions q_;
};

// The vector criterion for one window [begin, end) against several thresholds (cos_half[l] =
// cos(threshold_l / 2)); flags[l] set when some pair of orientations is further apart.
//
// Pruning by the triangle inequality on SO(3): with a_i the angle from an anchor sample,
//   max_i a_i  <=  max pairwise angle  <=  a_(1) + a_(2)  (the two largest a_i).
// The first sample as anchor gives the best lower bound for motion that keeps turning one way
// (a_(1) is the whole sweep); the middle sample gives the best upper bound (the sweep splits in
// halves). Only windows whose bounds straddle a threshold pay for the O(n^2) pairwise test,
// which compares |q_i . q_j| with cos(threshold / 2): four multiply-adds per pair.
void VectorFlags(const Quaternions& q, size_t begin, size_t end,
                 const std::vector<double>& cos_half, bool* flags) {
  const size_t mid = begin + (end - 1 - begin) / 2;
  double lower_cos = 1.0;  // cos(lower bound / 2): smallest |dot| with an anchor
  for (size_t i = begin + 1; i < end; ++i) lower_cos = std::min(lower_cos, q.AbsDot(begin, i));
  double d1 = 1.0, d2 = 1.0;  // the two smallest |dot| with the middle anchor
  for (size_t i = begin; i < end; ++i) {
    if (i == mid) continue;
    const double d = q.AbsDot(mid, i);
    if (d < d1) {
      d2 = d1;
      d1 = d;
    } else if (d < d2) {
      d2 = d;
    }
  }
  lower_cos = std::min(lower_cos, d1);
  // cos((a_(1) + a_(2)) / 2) = c1 c2 - s1 s2.
  const double upper_cos =
      d1 * d2 - std::sqrt(std::max(0.0, 1.0 - d1 * d1)) * std::sqrt(std::max(0.0, 1.0 - d2 * d2));
  for (size_t l = 0; l < cos_half.size(); ++l) {
    const double c = cos_half[l];
    if (lower_cos < c) {
      flags[l] = true;
    } else if (upper_cos >= c + kCosBoundMargin) {
      flags[l] = false;
    } else {
      bool any = false;
      for (size_t i = begin; i < end && !any; ++i) {
        for (size_t j = i + 1; j < end; ++j) {
          if (q.AbsDot(i, j) < c) {
            any = true;
            break;
          }
        }
      }
      flags[l] = any;
    }
  }
}

// The largest pairwise rotation angle in [begin, end), rad: exact, pruned with the middle anchor
// (a pair can beat the best so far only if a_i + a_j does). For --series only.
double MaxPairwiseAngle(const Quaternions& q, size_t begin, size_t end,
                        std::vector<double>* scratch) {
  const size_t mid = begin + (end - 1 - begin) / 2;
  std::vector<double>& a = *scratch;
  a.resize(end - begin);
  double best = 0.0, a_max = 0.0;
  for (size_t i = begin; i < end; ++i) {
    a[i - begin] = i == mid ? 0.0 : q.Angle(mid, i);
    a_max = std::max(a_max, a[i - begin]);
  }
  best = a_max;
  for (size_t i = begin; i < end; ++i) {
    if (a[i - begin] + a_max <= best) continue;
    for (size_t j = i + 1; j < end; ++j) {
      if (a[i - begin] + a[j - begin] > best) best = std::max(best, q.Angle(i, j));
    }
  }
  return best;
}

// What the pass over the windows needs: where the samples after the bias segment start, the
// windows per duration and the thresholds per limit.
struct FlightPlan {
  size_t first = 0;                // first sample after the bias segment
  size_t n = 0;                    // samples from there to the end
  std::vector<int64_t> window_ns;  // per duration
  std::vector<size_t> windows;     // window starts per duration
  size_t windows_max = 0;
  std::vector<bool> too_few_samples;            // per duration: not longer than 2 sample intervals
  int64_t sample_interval_ns = 0;               // median, of the analysed samples
  std::vector<double> threshold_rad, cos_half;  // per limit; cos_half: cos(threshold / 2)
};

// Median interval between the samples from `first` on (the trace's own median covers the bias
// segment too, which may be sampled differently).
int64_t MedianIntervalNs(const GyroTrace& trace, size_t first) {
  std::vector<int64_t> intervals;
  intervals.reserve(trace.size() - first);
  for (size_t k = first + 1; k < trace.size(); ++k)
    intervals.push_back(trace[k].t_ns - trace[k - 1].t_ns);
  return intervals.empty() ? 0 : UpperMedian(std::move(intervals));
}

// The bias removed from every sample: the options' known one, or estimated on their segment.
BiasEstimate FlightBias(const GyroTrace& trace, const FlightOptions& options) {
  BiasEstimate bias;
  if (options.known_bias_rad_s) {
    bias.bias_rad_s = *options.known_bias_rad_s;
    bias.first_after = 0;
  } else {
    bias = EstimateBias(trace, options.bias);
  }
  return bias;
}

// Windows per duration: starts k with t_k + W <= t_last (docs/FORMATS.md: the rest run past the
// end); thresholds per limit, with the noise allowance.
FlightPlan PlanFlight(const GyroTrace& trace, const FlightOptions& options, size_t first) {
  FlightPlan plan;
  plan.first = first;
  plan.n = trace.size() - first;
  if (plan.n < 2) {
    throw std::invalid_argument("only " + std::to_string(plan.n) +
                                " sample(s) after the bias segment (it ends at " +
                                FormatNumber("%g", options.bias.end_s) + " s; the trace lasts " +
                                FormatNumber("%.3f", trace.DurationS()) +
                                " s): give an earlier --bias A:B, --auto-bias, or a longer log");
  }
  const int64_t t0 = trace[first].t_ns;
  const int64_t t_last = trace.t_end_ns();
  const double span_s = (t_last - t0) * 1e-9;
  plan.sample_interval_ns = MedianIntervalNs(trace, first);
  const size_t windows_count = options.windows_s.size();
  plan.window_ns.resize(windows_count);
  plan.windows.resize(windows_count);
  plan.too_few_samples.resize(windows_count);
  for (size_t wi = 0; wi < windows_count; ++wi) {
    const double w = options.windows_s[wi];
    plan.window_ns[wi] = SecondsToNs(w);
    if (plan.window_ns[wi] <= kMinWindowSampleIntervals * plan.sample_interval_ns) {
      plan.too_few_samples[wi] = true;  // plan.windows[wi] stays 0: nothing to sweep
      continue;
    }
    if (t0 + plan.window_ns[wi] > t_last) {
      throw std::invalid_argument("window " + FormatNumber("%g", w) + " s is longer than the " +
                                  FormatNumber("%.3f", span_s) +
                                  " s of trace after the bias segment: give shorter --windows or "
                                  "an earlier --bias A:B");
    }
    plan.windows[wi] = trace.LowerBound(t_last - plan.window_ns[wi] + 1) - first;
    plan.windows_max = std::max(plan.windows_max, plan.windows[wi]);
  }
  const size_t limits = options.limits_m.size();
  SHUTTERLAB_CHECK(limits <= 64) << "at most 64 ground limits";
  plan.threshold_rad.resize(limits);
  plan.cos_half.resize(limits);
  for (size_t l = 0; l < limits; ++l) {
    plan.threshold_rad[l] = std::atan(options.limits_m[l] / options.altitude_m) +
                            options.noise_allowance_arcsec / kArcsecPerRad;
    plan.cos_half[l] = std::cos(0.5 * plan.threshold_rad[l]);
  }
  return plan;
}

// Each duration's windows starting in [k0, k1): their ends (local indices: the stream's buffer
// starts at sample k0) into chunk_end, their number into count; e is the running window end per
// duration (global index). Returns the end of the samples the chunk needs.
size_t ChunkWindowEnds(const GyroTrace& trace, const FlightPlan& plan, size_t k0, size_t k1,
                       std::vector<size_t>* e, std::vector<std::vector<uint32_t>>* chunk_end,
                       std::vector<size_t>* count) {
  const auto t = [&](size_t g) { return trace[plan.first + g].t_ns; };
  size_t region_end = k0 + 1;
  for (size_t wi = 0; wi < plan.windows.size(); ++wi) {
    const size_t k_stop = std::min(k1, plan.windows[wi]);
    size_t& end = (*e)[wi];
    for (size_t k = k0; k < k_stop; ++k) {
      const int64_t t_end = t(k) + plan.window_ns[wi];
      while (end < plan.n && t(end) < t_end) ++end;
      // Local index: the stream's buffer starts at sample k0.
      (*chunk_end)[wi][(*count)[wi]++] = static_cast<uint32_t>(end - k0);
    }
    if ((*count)[wi] > 0) region_end = std::max(region_end, end);
  }
  return region_end;
}

// The m windows' per-axis ranges (rad) against each limit: flagged on any axis and per axis, added
// to the duration's rows (rows[l]: limit l's row of this duration, `stride` rows apart).
void CountAxisFlags(const std::array<std::vector<double>, 3>& range, size_t m,
                    const std::vector<double>& threshold_rad, FlightRow* rows, size_t stride) {
  // Per-axis counts: limit-outer loops with local counters in doubles (exact below 2^53), a
  // form the compiler vectorises (compare, blend, add), unlike bool-to-integer sums.
  const double* rx = range[0].data();
  const double* ry = range[1].data();
  const double* rz = range[2].data();
  for (size_t l = 0; l < threshold_rad.size(); ++l) {
    const double th = threshold_rad[l];
    double any = 0, fx = 0, fy = 0, fz = 0;
    for (size_t i = 0; i < m; ++i) {
      const double x = rx[i], y = ry[i], z = rz[i];
      fx += x > th ? 1.0 : 0.0;
      fy += y > th ? 1.0 : 0.0;
      fz += z > th ? 1.0 : 0.0;
      any += (x > th || y > th || z > th) ? 1.0 : 0.0;
    }
    FlightRow& row = rows[l * stride];
    row.flagged += static_cast<size_t>(any);
    row.flagged_axis[0] += static_cast<size_t>(fx);
    row.flagged_axis[1] += static_cast<size_t>(fy);
    row.flagged_axis[2] += static_cast<size_t>(fz);
  }
}

// The m windows (window i: stream samples [i, ends[i])) by the vector criterion against each
// limit, and where it and the per-axis one disagree, added to the duration's rows as above.
void CountVectorFlags(const Quaternions& q, const uint32_t* ends, size_t m,
                      const std::array<std::vector<double>, 3>& range, const FlightPlan& plan,
                      FlightRow* rows, size_t stride) {
  bool vector_flag[64];
  for (size_t i = 0; i < m; ++i) {
    VectorFlags(q, i, ends[i], plan.cos_half, vector_flag);
    const double r_max = std::max(range[0][i], std::max(range[1][i], range[2][i]));
    for (size_t l = 0; l < plan.threshold_rad.size(); ++l) {
      FlightRow& row = rows[l * stride];
      const bool flagged = r_max > plan.threshold_rad[l];
      row.flagged_vector += vector_flag[l];
      row.flagged_vector_only += vector_flag[l] && !flagged;
      row.flagged_axis_only += flagged && !vector_flag[l];
    }
  }
}

// The first duration's m windows starting at k0 appended to the --series output.
void AppendSeries(const GyroTrace& trace, const FlightOptions& options, const FlightPlan& plan,
                  size_t k0, const Quaternions& q, const uint32_t* ends, size_t m,
                  const std::array<std::vector<double>, 3>& range, std::vector<double>* scratch,
                  FlightSeries* series) {
  for (size_t i = 0; i < m; ++i) {
    series->t_ns.push_back(trace[plan.first + k0 + i].t_ns);
    for (int a = 0; a < 3; ++a) series->range_arcsec[a].push_back(range[a][i] * kArcsecPerRad);
    if (options.vector_criterion && options.series_vector) {
      series->vector_arcsec.push_back(MaxPairwiseAngle(q, i, ends[i], scratch) * kArcsecPerRad);
    }
  }
}

// One pass over chunks of window starts; every duration's windows of the chunk are done together
// so the angles are integrated once. Counts into result->rows (limit-major), the series.
void SweepWindows(const GyroTrace& trace, const FlightOptions& options, const FlightPlan& plan,
                  FlightResult* result) {
  const size_t windows_count = plan.windows.size();
  AngleStream stream(trace, plan.first, result->bias.bias_rad_s, options.vector_criterion);
  SlidingRangeKernel kernel;
  std::vector<std::vector<uint32_t>> chunk_end(windows_count, std::vector<uint32_t>(kChunkWindows));
  std::vector<size_t> e(windows_count, 0);  // running window end per duration (global index)
  std::array<std::vector<double>, 3> range;
  for (auto& r : range) r.resize(kChunkWindows);
  std::vector<double> scratch;
  for (size_t k0 = 0; k0 < plan.windows_max; k0 += kChunkWindows) {
    const size_t k1 = std::min(plan.windows_max, k0 + kChunkWindows);
    std::vector<size_t> count(windows_count, 0);
    const size_t region_end = ChunkWindowEnds(trace, plan, k0, k1, &e, &chunk_end, &count);
    stream.Advance(k0, region_end);
    const Quaternions& q = stream.q();
    for (size_t wi = 0; wi < windows_count; ++wi) {
      const size_t m = count[wi];
      if (m == 0) continue;
      const uint32_t* ends = chunk_end[wi].data();
      kernel.Run3({stream.angle(0), stream.angle(1), stream.angle(2)}, ends, 0, m,
                  {range[0].data(), range[1].data(), range[2].data()});
      FlightRow* rows = &result->rows[wi];  // limit l's row: rows[l * windows_count]
      CountAxisFlags(range, m, plan.threshold_rad, rows, windows_count);
      if (options.vector_criterion) {
        CountVectorFlags(q, ends, m, range, plan, rows, windows_count);
      }
      if (options.series && wi == 0) {
        AppendSeries(trace, options, plan, k0, q, ends, m, range, &scratch, &result->series);
      }
    }
    if (options.progress) options.progress(static_cast<double>(k1) / plan.windows_max);
  }
}

// Each row's limit, window, threshold and shares of the windows.
void FinishRows(const FlightOptions& options, const FlightPlan& plan, FlightResult* result) {
  const size_t windows_count = plan.windows.size();
  for (size_t wi = 0; wi < windows_count; ++wi) {
    for (size_t l = 0; l < plan.threshold_rad.size(); ++l) {
      FlightRow& row = result->rows[l * windows_count + wi];
      row.limit_m = options.limits_m[l];
      row.window_s = options.windows_s[wi];
      row.threshold_arcsec = plan.threshold_rad[l] * kArcsecPerRad;
      row.windows = plan.windows[wi];
      if (plan.too_few_samples[wi]) {
        row.too_few_samples = true;
        const double nan = std::numeric_limits<double>::quiet_NaN();
        row.flagged_percent = row.flagged_percent_vector = nan;
        row.flagged_percent_axis = {nan, nan, nan};
        continue;
      }
      const double to_percent = 100.0 / static_cast<double>(plan.windows[wi]);
      row.flagged_percent = row.flagged * to_percent;
      for (int a = 0; a < 3; ++a) row.flagged_percent_axis[a] = row.flagged_axis[a] * to_percent;
      row.flagged_percent_vector = row.flagged_vector * to_percent;
    }
  }
}

}  // namespace

void FlightOptions::Check() const {
  SHUTTERLAB_CHECK(std::isfinite(altitude_m) && altitude_m > 0)
      << "altitude must be positive (got " << altitude_m << " m)";
  SHUTTERLAB_CHECK(!limits_m.empty()) << "give at least one ground limit";
  for (double limit : limits_m) {
    SHUTTERLAB_CHECK(std::isfinite(limit) && limit > 0)
        << "ground limit must be positive (got " << limit << " m)";
  }
  SHUTTERLAB_CHECK(!windows_s.empty()) << "give at least one window duration";
  for (double w : windows_s) {
    SHUTTERLAB_CHECK(std::isfinite(w) && w > 0 && w < 1e6)
        << "window duration must be positive (got " << w << " s)";
    SHUTTERLAB_CHECK(SecondsToNs(w) > 0) << "window duration " << w << " s is below 1 ns";
  }
  SHUTTERLAB_CHECK(std::isfinite(noise_allowance_arcsec) && noise_allowance_arcsec >= 0)
      << "noise allowance must be >= 0 (got " << noise_allowance_arcsec << " arcsec)";
  SHUTTERLAB_CHECK(bias.begin_s >= 0 && bias.end_s > bias.begin_s)
      << "bias segment " << bias.begin_s << ":" << bias.end_s << " must satisfy 0 <= A < B";
}

FlightResult Flight(const GyroTrace& trace, const FlightOptions& options) {
  options.Check();
  SHUTTERLAB_CHECK(!trace.empty()) << "empty gyro trace";
  FlightResult result;
  result.altitude_m = options.altitude_m;
  result.noise_allowance_arcsec = options.noise_allowance_arcsec;
  result.vector_criterion = options.vector_criterion;
  result.bias = FlightBias(trace, options);
  const FlightPlan plan = PlanFlight(trace, options, result.bias.first_after);
  result.samples = plan.n;
  result.sample_interval_s = plan.sample_interval_ns * 1e-9;
  result.rows.resize(options.limits_m.size() * options.windows_s.size());
  if (options.series) result.series.window_s = options.windows_s[0];
  SweepWindows(trace, options, plan, &result);
  result.windows_total = plan.windows[0];
  FinishRows(options, plan, &result);
  return result;
}

std::vector<LogWarning> FlightWarnings(const FlightResult& result) {
  std::string windows;
  size_t count = 0;
  for (const FlightRow& row : result.rows) {
    if (!row.too_few_samples) continue;
    const std::string window = FormatNumber("%g", row.window_s * 1e3) + " ms";
    if (windows.find(window) == std::string::npos)
      windows += (windows.empty() ? "" : ", ") + window;
    ++count;
  }
  if (count == 0) return {};
  const double dt_s = result.sample_interval_s;
  return {{"too_few_samples",
           "windows of " + windows + " not analysed: at " + FormatNumber("%.4g", 1.0 / dt_s) +
               " Hz a window must be longer than " +
               FormatNumber("%.4g", kMinWindowSampleIntervals * dt_s * 1e3) +
               " ms (2 sample intervals) to measure a range",
           std::nullopt, count}};
}

std::string FlightTable(const FlightResult& result) {
  std::ostringstream out;
  // A known bias (FlightOptions::known_bias_rad_s) leaves no segment: every sample is analysed.
  out << "flight: " << result.samples
      << (result.bias.samples > 0 ? " samples after the bias segment" : " samples (known bias)")
      << ", altitude " << result.altitude_m << " m, noise allowance "
      << result.noise_allowance_arcsec << "\"\n";
  out << "limit    window   threshold   windows      x %      y %      z %   per-axis %";
  if (result.vector_criterion) out << "   vector %";
  out << "\n";
  size_t too_few = 0;
  for (const FlightRow& row : result.rows) {
    char line[256];
    if (row.too_few_samples) {
      ++too_few;
      std::snprintf(line, sizeof(line), "%5.1f cm %5.1f ms %9.1f\"   too few samples\n",
                    row.limit_m * 100, row.window_s * 1000, row.threshold_arcsec);
      out << line;
      continue;
    }
    std::snprintf(line, sizeof(line), "%5.1f cm %5.1f ms %9.1f\" %10zu %8.2f %8.2f %8.2f %12.2f",
                  row.limit_m * 100, row.window_s * 1000, row.threshold_arcsec, row.windows,
                  row.flagged_percent_axis[0], row.flagged_percent_axis[1],
                  row.flagged_percent_axis[2], row.flagged_percent);
    out << line;
    if (result.vector_criterion) out << FormatNumber("%11.2f", row.flagged_percent_vector);
    out << "\n";
  }
  if (too_few > 0) {
    const double dt_s = result.sample_interval_s;
    out << "too few samples: at " << FormatNumber("%.4g", 1.0 / dt_s)
        << " Hz a window must be longer than "
        << FormatNumber("%.4g", kMinWindowSampleIntervals * dt_s * 1000.0)
        << " ms (2 sample intervals) to measure a range; those rows were not analysed\n";
  }
  if (result.vector_criterion && too_few < result.rows.size()) {
    size_t vector_more = 0, axis_more = 0, vector_only = 0, axis_only = 0;
    for (const FlightRow& row : result.rows) {
      vector_more += row.flagged_vector > row.flagged;
      axis_more += row.flagged > row.flagged_vector;
      vector_only += row.flagged_vector_only;
      axis_only += row.flagged_axis_only;
    }
    out << "criteria: ";
    if (vector_more > 0 && axis_more == 0) {
      out << "the vector angle flags more in " << vector_more << " of " << result.rows.size()
          << " rows: per-axis ranges are NOT on the safe side on this data";
    } else if (axis_more > 0 && vector_more == 0) {
      out << "per-axis flags more in " << axis_more << " of " << result.rows.size()
          << " rows: per-axis ranges are on the safe side on this data";
    } else if (axis_more == 0 && vector_more == 0) {
      out << "both criteria flag the same share in every row";
    } else {
      out << "mixed: vector flags more in " << vector_more << " rows, per-axis in " << axis_more;
    }
    out << " (windows flagged only by the vector angle: " << vector_only
        << ", only per axis: " << axis_only << ")\n";
  }
  return out.str();
}

std::vector<std::pair<double, double>> FlaggedIntervalsS(const FlightSeries& series,
                                                         double threshold_arcsec) {
  std::vector<std::pair<double, double>> intervals;
  for (size_t k = 0; k < series.t_ns.size(); ++k) {
    const bool flagged = series.range_arcsec[0][k] > threshold_arcsec ||
                         series.range_arcsec[1][k] > threshold_arcsec ||
                         series.range_arcsec[2][k] > threshold_arcsec;
    if (!flagged) continue;
    const double begin_s = series.t_ns[k] * 1e-9;
    const double end_s = begin_s + series.window_s;
    if (!intervals.empty() && begin_s <= intervals.back().second) {
      intervals.back().second = std::max(intervals.back().second, end_s);
    } else {
      intervals.emplace_back(begin_s, end_s);
    }
  }
  return intervals;
}

void WriteFlightSeriesCsv(const std::string& path, const FlightSeries& series) {
  std::string out = "t,range_x,range_y,range_z,vector\n";
  out.reserve(series.t_ns.size() * 80 + out.size());
  const bool vector = !series.vector_arcsec.empty();
  for (size_t k = 0; k < series.t_ns.size(); ++k) {
    AppendSecondsFromNs(series.t_ns[k], &out);
    for (int a = 0; a < 3; ++a) {
      out += ',';
      AppendDouble(series.range_arcsec[a][k], &out);
    }
    out += ',';
    if (vector) AppendDouble(series.vector_arcsec[k], &out);
    out += '\n';
  }
  WriteFileAtomically(path, out);
}

}  // namespace shutterlab
