#include "sim/gyro_sync.h"

#include "sim/check.h"
#include "sim/sensor_pair.h"
#include "sim/text_file.h"

#include <Eigen/Dense>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <stdexcept>
#include <string>
#include <unsupported/Eigen/FFT>
#include <vector>

namespace shutterlab {
namespace {

constexpr double kCoarseStepS = 0.01;  // 100 Hz: the rates' envelope, for the coarse lag
constexpr double kMinOverlapS = 10.0;  // at every lag searched (or half the shorter trace)
constexpr double kMinPeakCorrelation = 0.5;
constexpr double kMaxRunnerUpShare = 0.95;  // a steady swing scores 0.99 and more
constexpr double kDistinctLagS = 0.5;       // a local maximum this far from the peak is another lag
// The least RMS change of a trace's rate magnitude (its 10 ms means, rad/s) that can be aligned: a
// constant rate's is rounding alone (about 1e-19), whose correlations mean nothing; a still MEMS
// gyro's noise is 1e-3 and more, which the peak's own test refuses.
constexpr double kMinMagnitudeChangeRadS = 1e-6;
constexpr int kIterations = 8;
constexpr double kDerivativeStepS = 0.005;  // keeps 30 Hz motion's derivative to 6 %
constexpr double kSmoothingS = 0.02;        // the fine fit's triangle: 140 Hz kept to 5 %

double IntervalS(const GyroTrace& trace) { return trace.sampling().nominal_interval_ns * 1e-9; }

// The rate of a trace at any time inside it, linearly between its samples; none across a gap.
// Queries that go forward in time are answered in constant time (a cursor).
class RateAt {
 public:
  explicit RateAt(const GyroTrace& trace)
      : trace_(trace), gap_ns_(3.0 * trace.sampling().nominal_interval_ns) {}
  bool operator()(double t_ns, Eigen::Vector3d* w) const {
    const std::vector<GyroSample>& s = trace_.samples();
    if (s.size() < 2 || t_ns < s.front().t_ns || t_ns > s.back().t_ns) return false;
    if (cursor_ >= s.size() - 1 || s[cursor_].t_ns > t_ns) cursor_ = 0;
    if (s[cursor_ + 1].t_ns < t_ns) {
      cursor_ = std::max<size_t>(trace_.LowerBound(static_cast<int64_t>(std::ceil(t_ns))), 1) - 1;
    }
    const GyroSample &p = s[cursor_], &q = s[std::min(cursor_ + 1, s.size() - 1)];
    const double span = static_cast<double>(q.t_ns - p.t_ns);
    if (span > gap_ns_) return false;
    const double f = span > 0 ? (t_ns - p.t_ns) / span : 0.0;
    *w = (1 - f) * p.omega_rad_s + f * q.omega_rad_s;
    return true;
  }

 private:
  const GyroTrace& trace_;
  double gap_ns_;
  mutable size_t cursor_ = 0;
};

// |mean w| over each step_s of the trace (bins from its first sample), less their mean; 0 for a
// bin without samples. The mean, not a sample every step_s: a multirotor's vibration (100 to
// 300 Hz) sampled at 100 Hz would alias into the envelope, and the coarse peak then fell more
// than a step from the truth (10 ms on a synthetic flight against itself at half the rate).
std::vector<double> Magnitudes(const GyroTrace& trace, double step_s) {
  const size_t n = static_cast<size_t>(trace.DurationS() / step_s) + 1;
  std::vector<Eigen::Vector3d> sum(n, Eigen::Vector3d::Zero());
  std::vector<int> count(n, 0);
  for (const GyroSample& s : trace.samples()) {
    const size_t bin =
        std::min(n - 1, static_cast<size_t>((s.t_ns - trace.t_begin_ns()) * 1e-9 / step_s));
    sum[bin] += s.omega_rad_s;
    ++count[bin];
  }
  std::vector<double> m(n, 0.0);
  double total = 0;
  size_t valid = 0;
  for (size_t i = 0; i < n; ++i) {
    if (count[i] == 0) continue;
    m[i] = (sum[i] / count[i]).norm();
    total += m[i];
    ++valid;
  }
  for (size_t i = 0; i < n; ++i) {
    if (count[i] > 0) m[i] -= total / static_cast<double>(valid);
  }
  return m;
}

struct CoarseLag {
  double offset_s = 0, peak = 0, runner_up = 0;
};

// The lag of b against a (t_b = t_a + offset) where their magnitudes correlate best: every lag's
// sum by one FFT, normalised by the energies of that lag's overlap.
CoarseLag FindCoarseLag(const GyroTrace& a, const GyroTrace& b, double step_s, double min_overlap_s,
                        const GyroSyncOptions& options) {
  const double max_offset_s = options.max_offset_s;
  const std::vector<double> ma = Magnitudes(a, step_s), mb = Magnitudes(b, step_s);
  const int na = static_cast<int>(ma.size()), nb = static_cast<int>(mb.size());
  for (const auto& [name, m] : {std::pair{&options.a_name, &ma}, {&options.b_name, &mb}}) {
    double sum_sq = 0;
    for (const double v : *m) sum_sq += v * v;
    const double rms_change = std::sqrt(sum_sq / static_cast<double>(m->size()));
    if (!(rms_change >= kMinMagnitudeChangeRadS)) {
      throw std::invalid_argument(
          "the motion is too weak to align the traces: the rate magnitude of " + *name +
          " never changes (" + FormatNumber("%.1e", rms_change) +
          " rad/s RMS over its 10 ms means): record some turns about every axis in both");
    }
  }
  size_t n = 1;
  while (n < ma.size() + mb.size()) n *= 2;
  std::vector<double> pa(n, 0.0), pb(n, 0.0);
  std::copy(ma.begin(), ma.end(), pa.begin());
  std::copy(mb.begin(), mb.end(), pb.begin());
  Eigen::FFT<double> fft;
  std::vector<std::complex<double>> fa, fb;
  fft.fwd(fa, pa);
  fft.fwd(fb, pb);
  for (size_t i = 0; i < fa.size(); ++i) fa[i] = std::conj(fa[i]) * fb[i];
  std::vector<double> r;
  fft.inv(r, fa);                                        // r[k mod n] = sum_i ma[i] mb[i + k]
  std::vector<double> ea(na + 1, 0.0), eb(nb + 1, 0.0);  // prefix sums of the squares
  for (int i = 0; i < na; ++i) ea[i + 1] = ea[i] + ma[i] * ma[i];
  for (int j = 0; j < nb; ++j) eb[j + 1] = eb[j] + mb[j] * mb[j];
  const double base_s = (b.t_begin_ns() - a.t_begin_ns()) * 1e-9;
  const int min_overlap = static_cast<int>(min_overlap_s / step_s);
  std::vector<double> c(na + nb - 1, -2.0);  // index k + na - 1; -2: not searched
  for (int k = -(na - 1); k <= nb - 1; ++k) {
    const int i0 = std::max(0, -k), i1 = std::min(na, nb - k);  // a's overlap [i0, i1)
    if (i1 - i0 < min_overlap) continue;
    if (max_offset_s > 0 && std::abs(base_s + k * step_s) > max_offset_s) continue;
    const double energy = (ea[i1] - ea[i0]) * (eb[i1 + k] - eb[i0 + k]);
    if (!(energy > 0)) continue;
    c[k + na - 1] = r[(k + static_cast<int>(n)) % static_cast<int>(n)] / std::sqrt(energy);
  }
  const int best = static_cast<int>(std::max_element(c.begin(), c.end()) - c.begin());
  if (c[best] <= -2.0) {
    throw std::invalid_argument("the traces overlap by less than " +
                                FormatNumber("%.1f", min_overlap_s) +
                                " s at every offset searched");
  }
  CoarseLag lag;
  lag.peak = c[best];
  const int distinct = static_cast<int>(kDistinctLagS / step_s);
  bool other_lag_searched = false;
  for (int i = 0; i < static_cast<int>(c.size()); ++i) {
    if (std::abs(i - best) <= distinct || c[i] <= -2.0) continue;
    other_lag_searched = true;
    if (i > 0 && i + 1 < static_cast<int>(c.size()) && c[i] >= c[i - 1] && c[i] >= c[i + 1])
      lag.runner_up = std::max(lag.runner_up, c[i]);
  }
  // The peak's sub-step place from a parabola through it and its neighbours.
  double frac = 0;
  if (best > 0 && best + 1 < static_cast<int>(c.size()) && c[best - 1] > -2 && c[best + 1] > -2) {
    const double denom = c[best - 1] - 2 * c[best] + c[best + 1];
    if (denom < 0) frac = 0.5 * (c[best - 1] - c[best + 1]) / denom;
  }
  lag.offset_s = base_s + (best - (na - 1) + frac) * step_s;
  // Without another lag to compare, a runner-up below the peak proves nothing (a swing a period
  // long aligns anywhere): too short to tell, unless the caller's bound itself leaves no offset
  // farther than kDistinctLagS from the peak.
  const bool bound_leaves_no_other =
      max_offset_s > 0 && std::max(std::abs(lag.offset_s - max_offset_s),
                                   std::abs(lag.offset_s + max_offset_s)) <= kDistinctLagS;
  if (!other_lag_searched && !bound_leaves_no_other) {
    throw std::invalid_argument(
        "the traces are too short to tell their offset from one " +
        FormatNumber("%.1f", kDistinctLagS) + " s away (each offset searched overlaps them by " +
        FormatNumber("%.2f", min_overlap_s) + " s or more): record a few seconds of turns in both" +
        (options.bound_option.empty()
             ? std::string()
             : ", or, where the clocks are known to differ by under " +
                   FormatNumber("%.2f", kDistinctLagS / 2) + " s, say so (" + options.bound_option +
                   " " + FormatNumber("%.2f", kDistinctLagS / 2) + "s)"));
  }
  return lag;
}

// b with its times moved by -offset_s: on a's clock.
GyroTrace Shifted(const GyroTrace& b, double offset_s) {
  std::vector<GyroSample> samples = b.samples();
  const int64_t shift = SecondsToNs(offset_s);
  for (GyroSample& s : samples) s.t_ns -= shift;
  return GyroTrace(std::move(samples));
}

// The fine fit's pairs (w_a, w_b) at the slower stream's samples, the other interpolated, for
// offset(t_a) = offset + rate (t_a - t_mid); (*ok)[i] is 0 where sample i has no partner.
struct FineProblem {
  const GyroTrace& a;
  const GyroTrace& b;
  bool a_slower;
  double t_mid_ns;
  Eigen::Matrix3d r_ab = Eigen::Matrix3d::Identity();

  void Partners(double offset_s, double rate, std::vector<Eigen::Vector3d>* wa,
                std::vector<Eigen::Vector3d>* wb, std::vector<char>* ok) const {
    const GyroTrace& slow = a_slower ? a : b;
    const RateAt fast(a_slower ? b : a);
    wa->assign(slow.size(), Eigen::Vector3d::Zero());
    wb->assign(slow.size(), Eigen::Vector3d::Zero());
    ok->assign(slow.size(), 0);
    for (size_t i = 0; i < slow.size(); ++i) {
      const double t = static_cast<double>(slow[i].t_ns);
      if (a_slower) {  // b at t_b = t + offset(t)
        (*wa)[i] = slow[i].omega_rad_s;
        (*ok)[i] = fast(t + 1e9 * offset_s + rate * (t - t_mid_ns), &(*wb)[i]);
      } else {  // a at t_a with t_a + offset(t_a) = t
        (*wb)[i] = slow[i].omega_rad_s;
        (*ok)[i] = fast((t - 1e9 * offset_s + rate * t_mid_ns) / (1 + rate), &(*wa)[i]);
      }
    }
  }
  std::vector<Eigen::Vector3d> Residuals(double offset_s, double rate,
                                         std::vector<char>* ok) const {
    std::vector<Eigen::Vector3d> wa, wb;
    Partners(offset_s, rate, &wa, &wb, ok);
    for (size_t i = 0; i < wa.size(); ++i) wa[i] -= r_ab * wb[i];
    return wa;
  }
  // The mounting from the pairs at (offset, rate): Kabsch on the centred rates.
  Eigen::Matrix3d Mounting(double offset_s, double rate) const {
    std::vector<Eigen::Vector3d> wa, wb;
    std::vector<char> ok;
    Partners(offset_s, rate, &wa, &wb, &ok);
    Eigen::Vector3d mean_a = Eigen::Vector3d::Zero(), mean_b = Eigen::Vector3d::Zero();
    double n = 0;
    for (size_t i = 0; i < wa.size(); ++i) {
      if (!ok[i]) continue;
      mean_a += wa[i], mean_b += wb[i], n += 1;
    }
    mean_a /= n, mean_b /= n;
    Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
    for (size_t i = 0; i < wa.size(); ++i) {
      if (ok[i]) h += (wb[i] - mean_b) * (wa[i] - mean_a).transpose();
    }
    return KabschRotation(h);
  }
};

// The offset where the rates agree best within half_width_s of coarse_s, on a grid of grid_s: at
// each, the mounting fitted there (when fit_mounting; problem.r_ab otherwise) and the mean square
// of the residual per paired sample, the bias difference eliminated. A vibration (a multirotor's,
// 100 to 300 Hz) makes the residual a comb of minima one period apart, and Gauss-Newton started
// at the coarse lag, up to a coarse step off, with the mounting fitted there, can settle in a
// neighbouring one: 6.6 ms off on a recorder's emulated flight against its own trace, and 3.6 ms
// against the same flight at half the rate on axes turned 115 deg, before this search.
double GridLag(FineProblem problem, bool fit_mounting, double coarse_s, double half_width_s,
               double grid_s) {
  double best_s = coarse_s, best_cost = std::numeric_limits<double>::infinity();
  const int steps = static_cast<int>(std::ceil(half_width_s / grid_s));
  std::vector<char> ok;
  for (int k = -steps; k <= steps; ++k) {
    const double offset_s = coarse_s + k * grid_s;
    if (fit_mounting) problem.r_ab = problem.Mounting(offset_s, 0.0);
    const std::vector<Eigen::Vector3d> r = problem.Residuals(offset_s, 0.0, &ok);
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    double n = 0, sum_sq = 0;
    for (size_t i = 0; i < r.size(); ++i) {
      if (ok[i]) mean += r[i], n += 1, sum_sq += r[i].squaredNorm();
    }
    if (n < 50) continue;
    const double cost = (sum_sq - mean.squaredNorm() / n) / n;
    if (cost < best_cost) best_cost = cost, best_s = offset_s;
  }
  return best_s;
}

// RMS per axis of the residual about its mean at x: on the streams as read (not smoothed), both
// sensors' noise and what the model misses.
double RawResidualRms(const FineProblem& problem, const Eigen::Vector2d& x) {
  std::vector<char> ok;
  const std::vector<Eigen::Vector3d> r = problem.Residuals(x[0], x[1], &ok);
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  double n = 0, sum_sq = 0;
  for (size_t i = 0; i < r.size(); ++i) {
    if (ok[i]) mean += r[i], n += 1, sum_sq += r[i].squaredNorm();
  }
  return n > 0 ? std::sqrt((sum_sq - mean.squaredNorm() / n) / (3 * n)) : 0.0;
}

// One Gauss-Newton step for the first p of x = (offset, rate), with the bias difference
// eliminated (the residuals and the Jacobian's columns less their means); the derivatives are
// central differences over (h_offset_s, h_rate).
struct FineStep {
  Eigen::VectorXd step;
  Eigen::MatrixXd normal;
  double sigma2 = 0;
  size_t n = 0;
  // The scores' covariance (Newey-West, below): the normal matrix's sandwich filling.
  Eigen::MatrixXd score_covariance;
};

// Newey-West's estimate of the covariance of the sum of the scores s_i (one per sample, in time
// order), with Bartlett weights up to lag floor(4 (n / 100)^(2/9)), or min_lags where more (the
// smoothing's width in samples: the fine fit's residuals are correlated over it): sigma^2 N when
// the residuals are independent, larger when they are not. Against a clip's frames they are not
// (the rotation of a pair of frames is a smooth function of the motion, and so is the part of it
// the model misses): the independent-residual error was 0.19 ms where the offset was 0.85 ms off.
Eigen::MatrixXd NeweyWest(const std::vector<Eigen::VectorXd>& scores, size_t min_lags) {
  const size_t n = scores.size();
  const Eigen::Index p = n > 0 ? scores.front().size() : 0;
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(p, p);
  for (const Eigen::VectorXd& s : scores) out += s * s.transpose();
  const size_t lags =
      std::max(min_lags, static_cast<size_t>(std::floor(4.0 * std::pow(n / 100.0, 2.0 / 9.0))));
  for (size_t l = 1; l <= lags && l < n; ++l) {
    const double w = 1.0 - static_cast<double>(l) / (lags + 1);
    Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(p, p);
    for (size_t i = 0; i + l < n; ++i) sum += scores[i] * scores[i + l].transpose();
    out += w * (sum + sum.transpose());
  }
  return out;
}
FineStep GaussNewtonStep(const FineProblem& problem, const Eigen::Vector2d& x, int p,
                         double h_offset_s, double h_rate, size_t min_lags) {
  // The residuals at x and at a step each way of each unknown, on the samples that have a
  // partner at all of them.
  std::vector<char> used, ok;
  const std::vector<Eigen::Vector3d> r0 = problem.Residuals(x[0], x[1], &used);
  std::vector<std::vector<Eigen::Vector3d>> d(p);
  for (int k = 0; k < p; ++k) {
    const double h = k == 0 ? h_offset_s : h_rate;
    Eigen::Vector2d up = x, down = x;
    up[k] += h, down[k] -= h;
    const std::vector<Eigen::Vector3d> ru = problem.Residuals(up[0], up[1], &ok);
    for (size_t i = 0; i < used.size(); ++i) used[i] = used[i] && ok[i];
    const std::vector<Eigen::Vector3d> rd = problem.Residuals(down[0], down[1], &ok);
    for (size_t i = 0; i < used.size(); ++i) used[i] = used[i] && ok[i];
    d[k].resize(r0.size());
    for (size_t i = 0; i < r0.size(); ++i) d[k][i] = (ru[i] - rd[i]) / (2 * h);
  }
  FineStep out;
  Eigen::Vector3d mean_r = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> mean_d(p, Eigen::Vector3d::Zero());
  for (size_t i = 0; i < r0.size(); ++i) {
    if (!used[i]) continue;
    ++out.n;
    mean_r += r0[i];
    for (int k = 0; k < p; ++k) mean_d[k] += d[k][i];
  }
  if (out.n < 50) throw std::invalid_argument("fewer than 50 samples overlap at the offset found");
  mean_r /= out.n;
  for (int k = 0; k < p; ++k) mean_d[k] /= out.n;
  out.normal = Eigen::MatrixXd::Zero(p, p);
  Eigen::VectorXd gradient = Eigen::VectorXd::Zero(p);
  double ss = 0;
  std::vector<Eigen::VectorXd> scores;
  scores.reserve(out.n);
  for (size_t i = 0; i < r0.size(); ++i) {
    if (!used[i]) continue;
    const Eigen::Vector3d ri = r0[i] - mean_r;
    ss += ri.squaredNorm();
    Eigen::VectorXd score(p);
    for (int k = 0; k < p; ++k) {
      const Eigen::Vector3d dk = d[k][i] - mean_d[k];
      score[k] = dk.dot(ri);
      gradient[k] += score[k];
      for (int l = 0; l < p; ++l) out.normal(k, l) += dk.dot(d[l][i] - mean_d[l]);
    }
    scores.push_back(std::move(score));
  }
  out.score_covariance = NeweyWest(scores, min_lags);
  out.sigma2 = ss / std::max<double>(3.0 * out.n - p - 3, 1.0);
  out.step = out.normal.ldlt().solve(-gradient);
  return out;
}

}  // namespace

GyroTrace BoxAverage(const GyroTrace& trace, double window_s) {
  SHUTTERLAB_CHECK(window_s > 0) << "the averaging window must be positive";
  const std::vector<GyroSample>& s = trace.samples();
  std::vector<Eigen::Vector3d> prefix(s.size() + 1, Eigen::Vector3d::Zero());
  for (size_t i = 0; i < s.size(); ++i) prefix[i + 1] = prefix[i] + s[i].omega_rad_s;
  const int64_t half_ns = SecondsToNs(0.5 * window_s);
  std::vector<GyroSample> out;
  out.reserve(s.size());
  size_t lo = 0, hi = 0;  // the window is [lo, hi)
  for (size_t i = 0; i < s.size(); ++i) {
    while (s[lo].t_ns < s[i].t_ns - half_ns) ++lo;
    while (hi < s.size() && s[hi].t_ns <= s[i].t_ns + half_ns) ++hi;
    out.push_back({s[i].t_ns, (prefix[hi] - prefix[lo]) / static_cast<double>(hi - lo)});
  }
  return GyroTrace(std::move(out));
}

double ClockAFromB(const GyroSync& sync, double t_b_s) {
  // t_b = t_a + offset + rate (t_a - reference), rate = rate_ppm 1e-6.
  const double rate = sync.rate_ppm.value_or(0.0) * 1e-6;
  return (t_b_s - sync.offset_s + rate * sync.reference_a_s) / (1.0 + rate);
}

GyroTrace OnClockA(const GyroTrace& b, const GyroSync& sync) {
  std::vector<GyroSample> samples = b.samples();
  for (GyroSample& s : samples) s.t_ns = SecondsToNs(ClockAFromB(sync, s.t_ns * 1e-9));
  return GyroTrace(std::move(samples));
}

namespace {

// A source's samples with their times put on another clock.
class ClockMappedSource : public GyroSource {
 public:
  ClockMappedSource(std::unique_ptr<GyroSource> inner, const GyroSync& sync)
      : inner_(std::move(inner)), sync_(sync) {}
  GyroChunk Next() override {
    const GyroChunk chunk = inner_->Next();
    mapped_.assign(chunk.begin(), chunk.end());
    for (GyroSample& s : mapped_) s.t_ns = SecondsToNs(ClockAFromB(sync_, s.t_ns * 1e-9));
    return {mapped_.data(), mapped_.size()};
  }
  double Fraction() const override { return inner_->Fraction(); }
  std::vector<LogWarning> Warnings() const override { return inner_->Warnings(); }

 private:
  std::unique_ptr<GyroSource> inner_;
  GyroSync sync_;
  std::vector<GyroSample> mapped_;
};

}  // namespace

std::unique_ptr<GyroSource> OnClockA(std::unique_ptr<GyroSource> b, const GyroSync& sync) {
  return std::make_unique<ClockMappedSource>(std::move(b), sync);
}

GyroSync SyncGyros(const GyroTrace& a, const GyroTrace& b, const GyroSyncOptions& options) {
  if (a.size() < 100 || b.size() < 100)
    throw std::invalid_argument("a trace of fewer than 100 samples: nothing to align");
  GyroSync sync;
  const double ia = IntervalS(a), ib = IntervalS(b);
  sync.faster_interval_s = std::min(ia, ib);
  sync.slower_interval_s = std::max(ia, ib);
  const double step_s = std::max(kCoarseStepS, sync.slower_interval_s);
  const double min_overlap_s = std::min(kMinOverlapS, 0.5 * std::min(a.DurationS(), b.DurationS()));
  const CoarseLag lag = FindCoarseLag(a, b, step_s, min_overlap_s, options);
  sync.peak_correlation = lag.peak;
  sync.runner_up_correlation = lag.runner_up;
  if (lag.peak < kMinPeakCorrelation || lag.runner_up >= kMaxRunnerUpShare * lag.peak) {
    throw std::invalid_argument(
        "the motion is too weak or too repetitive to align the traces: their rates' magnitudes "
        "correlate " +
        FormatNumber("%.2f", lag.peak) + " at the best offset (" +
        FormatNumber("%.3f", lag.offset_s) + " s) and " + FormatNumber("%.2f", lag.runner_up) +
        " at the next (need at least " + FormatNumber("%.2f", kMinPeakCorrelation) +
        ", and the next below " + FormatNumber("%.0f", 100 * kMaxRunnerUpShare) +
        " % of it): record some turns about every axis in both");
  }
  // Both streams smoothed alike (a triangle kSmoothingS wide: two boxes of half that), for the
  // mounting and the fine fit. The fine fit's derivatives over kDerivativeStepS hold for the
  // motion below about 30 Hz, and a vibration above (a multirotor's motors at 100 to 300 Hz) would
  // turn them around and walk Gauss-Newton away from the offset (9 ms on a synthetic flight
  // against itself at half the rate). The mounting's test weighs the motion against what the
  // streams do not share, and two gyros filtered differently (a recorder's 184 Hz DLPF against a
  // flight controller's raw samples) differ by their noise above the slower filter, which refused
  // a mounting the smoothed motion shows plainly. A symmetric window moves no time.
  const double half_s = 0.5 * kSmoothingS;
  const GyroTrace a_smooth = BoxAverage(BoxAverage(a, half_s), half_s);
  const GyroTrace b_smooth = BoxAverage(BoxAverage(b, half_s), half_s);
  // The mounting, with b on a's clock at the coarse offset, each sample of the slower stream
  // paired (FuseSensorPair pairs each of its first trace's samples with the other's nearest: from
  // the faster one, half or more would find none, and the mounting's test then failed on a rich
  // motion).
  const SensorPair pair =
      ia >= ib ? FuseSensorPair(a_smooth, Shifted(b_smooth, lag.offset_s), SensorPairOptions{})
               : FuseSensorPair(Shifted(b_smooth, lag.offset_s), a_smooth, SensorPairOptions{});
  sync.a_from_b = ia >= ib ? pair.a_from_b : Eigen::Matrix3d(pair.a_from_b.transpose());
  sync.mounting_fitted = pair.mounting_fitted;
  sync.mounting_angle_deg = pair.mounting_angle_deg;
  // The overlap on a's clock, and its middle: the reference of the rate.
  const double begin_ns = std::max<double>(a.t_begin_ns(), b.t_begin_ns() - 1e9 * lag.offset_s);
  const double end_ns = std::min<double>(a.t_end_ns(), b.t_end_ns() - 1e9 * lag.offset_s);
  sync.overlap_s = (end_ns - begin_ns) * 1e-9;
  const bool fit_rate = sync.overlap_s >= options.min_rate_overlap_s;
  FineProblem problem{a_smooth, b_smooth, ia >= ib, 0.5 * (begin_ns + end_ns), sync.a_from_b};
  sync.reference_a_s = problem.t_mid_ns * 1e-9;
  // Gauss-Newton on (offset, rate). The derivatives are central differences over
  // kDerivativeStepS: over one sample interval the sensors' noise would swamp them (0.006 rad/s
  // over 1.25 ms is 7 rad/s^2, a brisk motion's own), and a Jacobian that holds the residual's
  // noise gives a biased step and a standard error far too small.
  const int p = fit_rate ? 2 : 1;
  // Into the right minimum first (GridLag): within a coarse step, on a grid of half the faster
  // stream's interval (0.1 to 1 ms); the mounting again there.
  const double grid_s = std::clamp(0.5 * sync.faster_interval_s, 1e-4, 1e-3);
  Eigen::Vector2d x(GridLag(problem, sync.mounting_fitted, lag.offset_s, step_s, grid_s), 0.0);
  if (sync.mounting_fitted) problem.r_ab = problem.Mounting(x[0], 0.0);
  const double h_offset_s = std::max(kDerivativeStepS, 2 * sync.faster_interval_s);
  const double h_rate = h_offset_s / std::max(0.5 * sync.overlap_s, 1.0);
  const size_t smoothing_samples =
      static_cast<size_t>(std::ceil(kSmoothingS / sync.slower_interval_s));
  FineStep last;
  for (int iteration = 0; iteration < kIterations; ++iteration) {
    // The mounting again at the offset found (the coarse offset's pairs bias it), once the offset
    // has settled, when the motion shows it.
    if (iteration == kIterations / 2 && sync.mounting_fitted) {
      problem.r_ab = problem.Mounting(x[0], x[1]);
      sync.a_from_b = problem.r_ab;
      sync.mounting_angle_deg = Eigen::AngleAxisd(problem.r_ab).angle() * 180.0 / M_PI;
    }
    last = GaussNewtonStep(problem, x, p, h_offset_s, h_rate, smoothing_samples);
    x.head(p) += last.step;
  }
  // The standard errors: the larger of the independent residuals' and the sandwich's (robust to
  // residuals correlated in time: NeweyWest).
  const Eigen::MatrixXd inverse = last.normal.inverse();
  const Eigen::MatrixXd independent = last.sigma2 * inverse;
  const Eigen::MatrixXd sandwich = inverse * last.score_covariance * inverse;
  const auto stderr_of = [&](int k) {
    return std::sqrt(std::max(independent(k, k), sandwich(k, k)));
  };
  sync.residual_rms_rad_s =
      RawResidualRms(FineProblem{a, b, problem.a_slower, problem.t_mid_ns, problem.r_ab}, x);
  sync.offset_s = x[0];
  sync.offset_stderr_s = stderr_of(0);
  if (fit_rate) {
    sync.rate_ppm = 1e6 * x[1];
    sync.rate_stderr_ppm = 1e6 * stderr_of(1);
  }
  sync.residuals = last.n;
  return sync;
}

}  // namespace shutterlab
