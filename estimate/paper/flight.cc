#include "estimate/paper/flight.h"

#include "estimate/paper/window_stats.h"
#include "sim/check.h"
#include "sim/interval_histogram.h"
#include "sim/so3.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace shutterlab {
namespace {

// Window starts per chunk: the chunk's ends, ranges and kernel buffers stay in L2.
constexpr size_t kChunkWindows = 2048;
// The vector criterion's cheap upper bound skips the exact pairwise test only when it clears the
// threshold by more than its own rounding (cosines near 1 carry ~1e-16 absolute error; the
// sqrt(1 - c^2) terms ~1e-13 at the smallest angles we meet).
constexpr double kCosBoundMargin = 1e-12;

// Orientations as structure of arrays (Hamilton w, x, y, z) so the per-window dot products stream;
// a view of AngleBuffer's arrays from a window chunk's first sample.
struct Quaternions {
  const double *w, *x, *y, *z;
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

// A growable array that is not zero-filled (a sliding buffer writes every element it grows by).
template <typename T>
class Column {
 public:
  // Room for n more elements at the end; returns where they start.
  T* Grow(size_t n) {
    if (size_ + n > capacity_) {
      capacity_ = std::max(2 * capacity_, size_ + n);
      std::unique_ptr<T[]> larger(new T[capacity_]);
      std::copy(data_.get(), data_.get() + size_, larger.get());
      data_ = std::move(larger);
    }
    size_ += n;
    return data_.get() + size_ - n;
  }
  void DropFront(size_t n) {
    std::copy(data_.get() + n, data_.get() + size_, data_.get());
    size_ -= n;
  }
  const T* data() const { return data_.get(); }
  const T* end() const { return data_.get() + size_; }
  size_t size() const { return size_; }

 private:
  std::unique_ptr<T[]> data_;
  size_t size_ = 0, capacity_ = 0;
};

// The analysed samples (those after the bias segment) with their per-axis angles and orientations,
// integrated as they arrive, in a sliding buffer that holds the global indices [base, end) only, so
// that memory stays O(chunk + window) for any trace length (a 10^8-sample log needs no 3 GB of
// angle arrays). The recurrences are exactly those of IntegratePerAxis (angle += (w_g - b) dt) and
// OrientationTrace (q_g = q_{g-1} Exp(0.5 (w_{g-1} + w_g) dt), bias-corrected rates), evaluated in
// the same order, so the values are bit-identical to theirs.
class AngleBuffer {
 public:
  AngleBuffer(const Eigen::Vector3d& bias_rad_s, bool with_q)
      : bias_(bias_rad_s), with_q_(with_q) {}

  // Appends samples [s, s + n), integrating them.
  void Push(const GyroSample* s, size_t n) {
    if (n == 0) return;
    int64_t* t = t_.Grow(n);
    double* angle[3] = {angles_[0].Grow(n), angles_[1].Grow(n), angles_[2].Grow(n)};
    if (with_q_) {
      PushWithOrientations(s, n, t, angle);
    } else {
      // The per-axis recurrence alone, its state in registers: the common case, a tight loop.
      size_t i = 0;
      int64_t previous_t_ns = previous_.t_ns;
      if (end_ == 0) {  // the first sample: angle 0
        t[0] = previous_t_ns = s[0].t_ns;
        for (int a = 0; a < 3; ++a) angle[a][0] = angle_[a];
        i = 1;
      }
      double ax = angle_[0], ay = angle_[1], az = angle_[2];
      const double bx = bias_[0], by = bias_[1], bz = bias_[2];
      for (; i < n; ++i) {
        const double dt_s = (s[i].t_ns - previous_t_ns) * 1e-9;
        ax += (s[i].omega_rad_s[0] - bx) * dt_s;
        ay += (s[i].omega_rad_s[1] - by) * dt_s;
        az += (s[i].omega_rad_s[2] - bz) * dt_s;
        previous_t_ns = s[i].t_ns;
        t[i] = s[i].t_ns;
        angle[0][i] = ax;
        angle[1][i] = ay;
        angle[2][i] = az;
      }
      angle_[0] = ax;
      angle_[1] = ay;
      angle_[2] = az;
      previous_ = s[n - 1];
    }
    end_ += n;
  }
  // Samples before global index g are no longer needed. Their room is given back once they are
  // half of the buffer, so that each sample moves at most once or twice in all.
  void DropBefore(size_t g) {
    const size_t drop = g - base_;
    if (drop == 0 || 2 * drop < t_.size()) return;
    t_.DropFront(drop);
    for (auto& v : angles_) v.DropFront(drop);
    if (with_q_) {
      for (auto& v : q_) v.DropFront(drop);
    }
    base_ = g;
  }
  size_t end() const { return end_; }  // samples pushed in all
  int64_t t(size_t g) const { return t_.data()[g - base_]; }
  const int64_t* times(size_t g) const { return t_.data() + (g - base_); }  // from sample g on
  // Index of the first sample from g on with time >= t_ns (end() when none).
  size_t LowerBound(size_t g, int64_t t_ns) const {
    return base_ + (std::lower_bound(t_.data() + (g - base_), t_.end(), t_ns) - t_.data());
  }
  const double* angle(int a, size_t g) const { return angles_[a].data() + (g - base_); }
  Quaternions q(size_t g) const {
    const size_t i = g - base_;
    return {q_[0].data() + i, q_[1].data() + i, q_[2].data() + i, q_[3].data() + i};
  }

 private:
  // Push with the orientations too (the vector criterion): both recurrences per sample.
  void PushWithOrientations(const GyroSample* s, size_t n, int64_t* t, double* const* angle) {
    double* q[4] = {q_[0].Grow(n), q_[1].Grow(n), q_[2].Grow(n), q_[3].Grow(n)};
    for (size_t i = 0; i < n; ++i) {
      if (end_ + i > 0) {
        const double dt_s = (s[i].t_ns - previous_.t_ns) * 1e-9;
        for (int a = 0; a < 3; ++a) angle_[a] += (s[i].omega_rad_s[a] - bias_[a]) * dt_s;
        const Eigen::Vector3d wa = previous_.omega_rad_s - bias_;
        const Eigen::Vector3d wb = s[i].omega_rad_s - bias_;
        current_ = (current_ * ExpSO3(0.5 * (wa + wb) * dt_s)).normalized();
      }
      previous_ = s[i];
      t[i] = s[i].t_ns;
      for (int a = 0; a < 3; ++a) angle[a][i] = angle_[a];
      q[0][i] = current_.w();
      q[1][i] = current_.x();
      q[2][i] = current_.y();
      q[3][i] = current_.z();
    }
  }

  const Eigen::Vector3d bias_;
  const bool with_q_;
  size_t base_ = 0, end_ = 0;
  GyroSample previous_{};
  double angle_[3] = {0.0, 0.0, 0.0};
  Eigen::Quaterniond current_ = Eigen::Quaterniond::Identity();
  Column<int64_t> t_;
  Column<double> angles_[3];
  Column<double> q_[4];
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

// The thresholds per limit, with the noise allowance; cos_half: cos(threshold / 2).
struct FlightThresholds {
  std::vector<double> threshold_rad, cos_half;
};

FlightThresholds Thresholds(const FlightOptions& options) {
  const size_t limits = options.limits_m.size();
  SHUTTERLAB_CHECK(limits <= 64) << "at most 64 ground limits";
  FlightThresholds out;
  for (size_t l = 0; l < limits; ++l) {
    out.threshold_rad.push_back(std::atan(options.limits_m[l] / options.altitude_m) +
                                options.noise_allowance_arcsec / kArcsecPerRad);
    out.cos_half.push_back(std::cos(0.5 * out.threshold_rad.back()));
  }
  return out;
}

// The m windows' per-axis ranges (rad) against each limit: flagged on any axis and per axis, added
// to the duration's rows (rows[l]: limit l's row of this duration, `stride` rows apart).
void CountAxisFlags(const std::array<std::vector<double>, 3>& range, size_t m,
                    const std::vector<double>& threshold_rad, FlightRow* rows, size_t stride) {
  const double* rx = range[0].data();
  const double* ry = range[1].data();
  const double* rz = range[2].data();
  for (size_t l = 0; l < threshold_rad.size(); ++l) {
    const double th = threshold_rad[l];
    int64_t any = 0, fx = 0, fy = 0, fz = 0;
    size_t i = 0;
#if defined(__SSE2__)
    // Two windows at a time: a comparison gives all ones (-1) per lane where a range is over.
    const __m128d th2 = _mm_set1_pd(th);
    __m128i any2 = _mm_setzero_si128(), fx2 = any2, fy2 = any2, fz2 = any2;
    for (; i + 2 <= m; i += 2) {
      const __m128d over_x = _mm_cmpgt_pd(_mm_loadu_pd(rx + i), th2);
      const __m128d over_y = _mm_cmpgt_pd(_mm_loadu_pd(ry + i), th2);
      const __m128d over_z = _mm_cmpgt_pd(_mm_loadu_pd(rz + i), th2);
      fx2 = _mm_sub_epi64(fx2, _mm_castpd_si128(over_x));
      fy2 = _mm_sub_epi64(fy2, _mm_castpd_si128(over_y));
      fz2 = _mm_sub_epi64(fz2, _mm_castpd_si128(over_z));
      any2 = _mm_sub_epi64(any2, _mm_castpd_si128(_mm_or_pd(over_x, _mm_or_pd(over_y, over_z))));
    }
    const auto lanes = [](__m128i v) {
      int64_t lane[2];
      _mm_storeu_si128(reinterpret_cast<__m128i*>(lane), v);
      return lane[0] + lane[1];
    };
    any = lanes(any2);
    fx = lanes(fx2);
    fy = lanes(fy2);
    fz = lanes(fz2);
#endif
    for (; i < m; ++i) {
      const double x = rx[i], y = ry[i], z = rz[i];
      fx += x > th;
      fy += y > th;
      fz += z > th;
      any += x > th || y > th || z > th;
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
                      const std::array<std::vector<double>, 3>& range, const FlightThresholds& plan,
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

namespace {

// A rate or a duration as a person reads it, without an exponent: 4 significant digits, whole
// numbers from 10,000 up.
std::string PlainNumber(double value) {
  return FormatNumber(std::fabs(value) < 1e4 ? "%.4g" : "%.0f", value);
}

// Why windows were refused and what would do: flight's --window of the shortest 1-2-5 step (...,
// 0.5, 1, 2, 5, 10, 20, 50 ms ...) longer than two sample intervals (50 ms for a 50 Hz log), or a
// log fast enough for the shortest window refused (above 200 Hz for 10 ms). The warning `analyze`
// gives for a readout refused says the same: flight measures that log at the longer window.
std::string TooFewSamplesReason(const FlightResult& result) {
  const double shortest_ms = kMinWindowSampleIntervals * result.sample_interval_s * 1e3;
  // From a decade below, so that log10's rounding cannot skip the step wanted.
  double decade_ms = std::pow(10.0, std::floor(std::log10(shortest_ms)) - 1.0);
  double step_ms = decade_ms;
  for (int decades = 0; step_ms <= shortest_ms && decades < 4; ++decades, decade_ms *= 10.0) {
    for (const double factor : {1.0, 2.0, 5.0}) {
      step_ms = factor * decade_ms;
      if (step_ms > shortest_ms) break;
    }
  }
  double refused_ms = std::numeric_limits<double>::infinity();
  for (const FlightRow& row : result.rows)
    if (row.too_few_samples) refused_ms = std::min(refused_ms, row.window_s * 1e3);
  const std::string step =
      step_ms >= 1000.0 ? PlainNumber(step_ms / 1e3) + "s" : PlainNumber(step_ms) + "ms";
  return "at " + PlainNumber(1.0 / result.sample_interval_s) + " Hz a window must be longer than " +
         PlainNumber(shortest_ms) +
         " ms (2 sample intervals) to measure a range: give flight --window " + step +
         " or longer, or log above " + PlainNumber(kMinWindowSampleIntervals / refused_ms * 1e3) +
         " Hz for " + PlainNumber(refused_ms) + " ms windows";
}

std::vector<LogWarning> TooFewSamplesWarnings(const FlightResult& result) {
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
  return {{"too_few_samples",
           "windows of " + windows + " not analysed: " + TooFewSamplesReason(result), std::nullopt,
           count}};
}

}  // namespace

struct FlightStream::Impl {
  explicit Impl(const FlightOptions& given)
      : options(given),
        thresholds(Thresholds(given)),
        segment_begin_ns(SecondsToNs(given.bias.begin_s)),
        segment_end_ns(SecondsToNs(given.bias.end_s)) {
    for (double w : options.windows_s) {
      window_ns.push_back(SecondsToNs(w));
      window_max_ns = std::max(window_max_ns, window_ns.back());
    }
    const size_t durations = window_ns.size();
    chunk_end.assign(durations, std::vector<uint32_t>(kChunkWindows));
    e.assign(durations, 0);
    ranges.resize(durations);
    sets.resize(durations);
    for (size_t wi = 0; wi < durations; ++wi) {
      for (int a = 0; a < 3; ++a) {
        ranges[wi][a].resize(kChunkWindows);
        sets[wi].out[a] = ranges[wi][a].data();
      }
    }
    rows.resize(options.limits_m.size() * durations);
    if (options.series) series.window_s = options.windows_s[0];
    if (options.summary) {
      summary.emplace();
      summary->window_s = options.windows_s[0];
      summary->flagged.assign(options.limits_m.size(),
                              IntervalUnion(options.summary_max_intervals));
    }
  }

  void Add(const GyroSample* samples, size_t count) {
    if (count == 0) return;
    if (total == 0) {
      t0_ns = samples[0].t_ns;
      if (options.known_bias_rad_s) {
        bias.bias_rad_s = *options.known_bias_rad_s;
        bias.first_after = 0;
        StartAnalysis();
      }
    }
    total += count;
    t_last_ns = samples[count - 1].t_ns;
    size_t i = 0;
    while (!buffer && i < count) {
      if (TakeForBias(samples[i])) break;  // the segment is over: this sample is analysed
      ++i;
    }
    if (!buffer || i == count) return;
    // A chunk of window starts at a time, so that the samples are integrated, swept and dropped
    // while they are in the cache.
    for (; i < count; i += kChunkWindows)
      AddAnalysed(samples + i, std::min(kChunkWindows, count - i));
  }

  // Samples after the bias segment: integrated, and every chunk of windows they complete swept.
  void AddAnalysed(const GyroSample* s, size_t n) {
    if (buffer->end() == 0) t_first_analysed_ns = s[0].t_ns;
    // The intervals, handed to the histogram as runs of equal ones.
    int64_t previous_ns = buffer->end() == 0 ? s[0].t_ns : t_last_analysed_ns, run_ns = 0;
    size_t run = 0;
    for (size_t k = buffer->end() == 0 ? 1 : 0; k < n; ++k) {
      const int64_t dt = s[k].t_ns - previous_ns;
      if (dt != run_ns) {
        intervals.AddRun(run_ns, run);
        run_ns = dt;
        run = 0;
      }
      ++run;
      previous_ns = s[k].t_ns;
    }
    intervals.AddRun(run_ns, run);
    t_last_analysed_ns = s[n - 1].t_ns;
    buffer->Push(s, n);
    SweepCompleteChunks();
  }

  // Before the analysis: a sample of the bias segment (or before it) is kept or counted; true when
  // the segment is over with this sample, which then starts the analysis.
  bool TakeForBias(const GyroSample& s) {
    if (bias_failed) return false;
    if (s.t_ns < t0_ns + segment_end_ns) {
      if (s.t_ns >= t0_ns + segment_begin_ns) {
        segment.push_back(s);
      } else {
        ++before_segment;
      }
      return false;
    }
    if (segment.size() < kMinBiasSamples) {  // said at Finish, with the trace's length
      bias_failed = true;
      return false;
    }
    bias = SegmentBias();
    segment = {};
    StartAnalysis();
    return true;
  }

  BiasEstimate SegmentBias() const {
    return BiasOverSegment(segment.data(), segment.data() + segment.size(), options.bias,
                           before_segment + segment.size(), (t_last_ns - t0_ns) * 1e-9);
  }

  void StartAnalysis() {
    buffer = std::make_unique<AngleBuffer>(bias.bias_rad_s, options.vector_criterion);
  }

  // Every chunk of window starts whose windows, the longest included, lie inside the samples so
  // far: the windows of every duration starting in it are then complete.
  void SweepCompleteChunks() {
    const std::vector<size_t> all(window_ns.size(), std::numeric_limits<size_t>::max());
    while (next_k0 + kChunkWindows <= buffer->end() &&
           buffer->t(next_k0 + kChunkWindows - 1) + window_max_ns <= t_last_analysed_ns) {
      SweepChunk(next_k0, next_k0 + kChunkWindows, all);
      next_k0 += kChunkWindows;
      buffer->DropBefore(next_k0);
    }
  }

  // The windows starting in [k0, k1) of every duration (at most windows[wi] of duration wi): their
  // ends, per-axis ranges and flags, counted into rows (limit-major) and the series.
  void SweepChunk(size_t k0, size_t k1, const std::vector<size_t>& windows) {
    const size_t durations = window_ns.size();
    const size_t n = buffer->end();
    // Every duration's window ends, then their ranges in one kernel pass (the block extrema of
    // the samples are shared), then the counts.
    const int64_t* t = buffer->times(k0);  // local indices from here on: sample k0 is 0
    for (size_t wi = 0; wi < durations; ++wi) {
      const size_t m = std::min(k1, std::max(k0, windows[wi])) - k0;
      const int64_t window = window_ns[wi];
      uint32_t* ends = chunk_end[wi].data();
      size_t end = e[wi] - k0;  // window k0 - 1 ended there, at or after k0
      // The search of WindowEndsByDuration, kept apart from it: that one is the tests' reference.
      const size_t samples_end = n - k0;
      for (size_t i = 0; i < m; ++i) {
        const int64_t t_end = t[i] + window;
        // At a steady rate each window ends one sample after the one before. Testing that guess
        // is cheaper than the search, whose loop tests twice a window and mispredicts its exit:
        // t[end] < t_end says the end moves at all (not at a repeated time, nor where windows
        // before a pause share one end), t[guess] >= t_end that it moves by one; guess <
        // samples_end only bounds the reads (a swept window ends before the last sample).
        const size_t guess = end + 1;
        if (guess < samples_end && t[end] < t_end && t[guess] >= t_end) {
          end = guess;
        } else {
          while (end < samples_end && t[end] < t_end) ++end;
        }
        ends[i] = static_cast<uint32_t>(end);
      }
      e[wi] = end + k0;
      sets[wi].ends = ends;
      sets[wi].count = m;
    }
    kernel.Run3Sets({buffer->angle(0, k0), buffer->angle(1, k0), buffer->angle(2, k0)}, 0, sets);
    for (size_t wi = 0; wi < durations; ++wi) {
      const size_t m = sets[wi].count;
      if (m == 0) continue;
      const uint32_t* ends = chunk_end[wi].data();
      const std::array<std::vector<double>, 3>& range = ranges[wi];
      FlightRow* duration_rows = &rows[wi];  // limit l's row: duration_rows[l * durations]
      CountAxisFlags(range, m, thresholds.threshold_rad, duration_rows, durations);
      const Quaternions q = options.vector_criterion ? buffer->q(k0) : Quaternions{};
      if (options.vector_criterion) {
        CountVectorFlags(q, ends, m, range, thresholds, duration_rows, durations);
      }
      if (options.series && wi == 0) {
        for (size_t i = 0; i < m; ++i) {
          series.t_ns.push_back(buffer->t(k0 + i));
          for (int a = 0; a < 3; ++a) series.range_arcsec[a].push_back(range[a][i] * kArcsecPerRad);
          if (options.vector_criterion && options.series_vector) {
            series.vector_arcsec.push_back(MaxPairwiseAngle(q, i, ends[i], &scratch) *
                                           kArcsecPerRad);
          }
        }
      }
      if (summary && wi == 0) Summarise(k0, m, range);
    }
  }

  // The windows starting at k0 .. k0 + m - 1 into the summary: the same values FlaggedIntervalsS
  // and a histogram read from the series.
  void Summarise(size_t k0, size_t m, const std::array<std::vector<double>, 3>& range) {
    for (size_t i = 0; i < m; ++i) {
      const double r[3] = {range[0][i] * kArcsecPerRad, range[1][i] * kArcsecPerRad,
                           range[2][i] * kArcsecPerRad};
      for (int a = 0; a < 3; ++a) summary->range_arcsec[a].Add(r[a]);
      const double largest = std::max({r[0], r[1], r[2]});
      for (size_t l = 0; l < summary->flagged.size(); ++l) {
        if (largest <= thresholds.threshold_rad[l] * kArcsecPerRad) continue;
        const double begin_s = buffer->t(k0 + i) * 1e-9;
        summary->flagged[l].Add(begin_s, begin_s + summary->window_s);
      }
    }
  }

  FlightResult Finish();

  const FlightOptions options;
  const FlightThresholds thresholds;
  std::vector<int64_t> window_ns;  // per duration
  int64_t window_max_ns = 0;
  // Every sample.
  size_t total = 0;
  int64_t t0_ns = 0, t_last_ns = 0;
  // The bias segment (after the first sample) and its samples until it is over, and the samples
  // before it.
  const int64_t segment_begin_ns, segment_end_ns;
  std::vector<GyroSample> segment;
  size_t before_segment = 0;
  bool bias_failed = false;
  BiasEstimate bias;
  // The analysed samples (null until the bias is known) and their intervals.
  std::unique_ptr<AngleBuffer> buffer;
  int64_t t_first_analysed_ns = 0, t_last_analysed_ns = 0;
  IntervalHistogram intervals;
  // The sweep over chunks of window starts.
  size_t next_k0 = 0;
  std::vector<size_t> e;  // running window end per duration (global index)
  std::vector<std::vector<uint32_t>> chunk_end;
  std::vector<std::array<std::vector<double>, 3>> ranges;  // per duration, per axis
  std::vector<SlidingRangeKernel::WindowSet> sets;         // per duration: its ends and ranges
  std::vector<double> scratch;
  SlidingRangeKernel kernel;
  std::vector<FlightRow> rows;
  FlightSeries series;
  std::optional<FlightWindowSummary> summary;
};

FlightResult FlightStream::Impl::Finish() {
  SHUTTERLAB_CHECK(total > 0) << "empty gyro trace";
  const double trace_s = (t_last_ns - t0_ns) * 1e-9;
  if (!buffer) SegmentBias();  // throws when the segment holds too few samples
  const size_t n = buffer ? buffer->end() : 0;
  if (n < 2) {
    throw std::invalid_argument("only " + std::to_string(n) +
                                " sample(s) after the bias segment (it ends at " +
                                FormatNumber("%g", options.bias.end_s) + " s; the trace lasts " +
                                FormatNumber("%.3f", trace_s) +
                                " s): give an earlier --bias A:B, --auto-bias, or a longer log");
  }
  const int64_t interval_ns = intervals.Median();
  const size_t durations = window_ns.size();
  std::vector<size_t> windows(durations, 0);
  std::vector<bool> too_few(durations, false);
  size_t windows_max = 0;
  for (size_t wi = 0; wi < durations; ++wi) {
    if (window_ns[wi] <= kMinWindowSampleIntervals * interval_ns) {
      too_few[wi] = true;  // windows[wi] stays 0: its rows are not analysed
      continue;
    }
    if (t_first_analysed_ns + window_ns[wi] > t_last_analysed_ns) {
      throw std::invalid_argument(
          "window " + FormatNumber("%g", options.windows_s[wi]) + " s is longer than the " +
          FormatNumber("%.3f", (t_last_analysed_ns - t_first_analysed_ns) * 1e-9) +
          " s of trace after the bias segment: give a shorter --window or an earlier --bias A:B");
    }
    windows[wi] = buffer->LowerBound(next_k0, t_last_analysed_ns - window_ns[wi] + 1);
    windows_max = std::max(windows_max, windows[wi]);
  }
  for (size_t k0 = next_k0; k0 < windows_max; k0 += kChunkWindows)
    SweepChunk(k0, std::min(windows_max, k0 + kChunkWindows), windows);

  FlightResult result;
  result.altitude_m = options.altitude_m;
  result.noise_allowance_arcsec = options.noise_allowance_arcsec;
  result.vector_criterion = options.vector_criterion;
  result.bias = bias;
  result.samples = n;
  result.sample_interval_s = interval_ns * 1e-9;
  result.windows_total = windows[0];
  result.rows = std::move(rows);
  if (options.series && !too_few[0]) result.series = std::move(series);
  result.series.window_s = options.series ? options.windows_s[0] : 0.0;
  if (summary && !too_few[0]) {
    summary->windows = windows[0];
    result.summary = std::move(summary);
  } else if (summary) {
    result.summary.emplace();  // not analysed: nothing to draw
    result.summary->window_s = options.windows_s[0];
    result.summary->flagged.resize(options.limits_m.size());
  }
  for (size_t wi = 0; wi < durations; ++wi) {
    for (size_t l = 0; l < thresholds.threshold_rad.size(); ++l) {
      FlightRow& row = result.rows[l * durations + wi];
      if (too_few[wi]) row = FlightRow{};  // swept as it came, but not an answer
      row.limit_m = options.limits_m[l];
      row.window_s = options.windows_s[wi];
      row.threshold_arcsec = thresholds.threshold_rad[l] * kArcsecPerRad;
      row.windows = windows[wi];
      if (too_few[wi]) {
        row.too_few_samples = true;
        const double nan = std::numeric_limits<double>::quiet_NaN();
        row.flagged_percent = row.flagged_percent_vector = nan;
        row.flagged_percent_axis = {nan, nan, nan};
        continue;
      }
      const double to_percent = 100.0 / static_cast<double>(windows[wi]);
      row.flagged_percent = row.flagged * to_percent;
      for (int a = 0; a < 3; ++a) row.flagged_percent_axis[a] = row.flagged_axis[a] * to_percent;
      row.flagged_percent_vector = row.flagged_vector * to_percent;
    }
  }
  result.warnings = TooFewSamplesWarnings(result);
  return result;
}

FlightStream::FlightStream(const FlightOptions& options) {
  options.Check();
  impl_ = std::make_unique<Impl>(options);
}

FlightStream::~FlightStream() = default;

void FlightStream::Add(const GyroSample* samples, size_t count) { impl_->Add(samples, count); }

FlightResult FlightStream::Finish() { return impl_->Finish(); }

FlightResult Flight(const GyroTrace& trace, const FlightOptions& options) {
  FlightStream stream(options);
  // Slices, so that progress can be told on a long trace.
  constexpr size_t kSlice = 1 << 20;
  for (size_t i = 0; i < trace.size(); i += kSlice) {
    stream.Add(trace.samples().data() + i, std::min(kSlice, trace.size() - i));
    if (options.progress) options.progress(static_cast<double>(i) / trace.size());
  }
  return stream.Finish();
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
    out << "too few samples, those rows were not analysed: " << TooFewSamplesReason(result) << "\n";
  }
  if (result.vector_criterion && too_few < result.rows.size()) {
    const size_t analysed = result.rows.size() - too_few;  // refused rows are no comparison
    size_t vector_more = 0, axis_more = 0, vector_only = 0, axis_only = 0;
    for (const FlightRow& row : result.rows) {
      vector_more += row.flagged_vector > row.flagged;
      axis_more += row.flagged > row.flagged_vector;
      vector_only += row.flagged_vector_only;
      axis_only += row.flagged_axis_only;
    }
    out << "criteria: ";
    if (vector_more > 0 && axis_more == 0) {
      out << "the vector angle flags more in " << vector_more << " of " << analysed
          << " rows: per-axis ranges are NOT on the safe side on this data";
    } else if (axis_more > 0 && vector_more == 0) {
      out << "per-axis flags more in " << axis_more << " of " << analysed
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
