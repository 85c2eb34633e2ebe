#include "sim/gyro_sync.h"

#include "sim/sensor_pair.h"
#include "sim/text_file.h"

#include <Eigen/Dense>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <complex>
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
constexpr int kIterations = 8;
constexpr double kDerivativeStepS = 0.005;  // keeps 30 Hz motion's derivative to 6 %

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

// |w| every step_s over the trace, less its mean (0 where there is no rate).
std::vector<double> Magnitudes(const GyroTrace& trace, double step_s) {
  const RateAt rate(trace);
  const size_t n = static_cast<size_t>(trace.DurationS() / step_s) + 1;
  std::vector<double> m(n, 0.0);
  std::vector<bool> valid(n, false);
  double sum = 0;
  size_t count = 0;
  for (size_t i = 0; i < n; ++i) {
    Eigen::Vector3d w;
    if (!rate(trace.t_begin_ns() + i * step_s * 1e9, &w)) continue;
    m[i] = w.norm();
    valid[i] = true;
    sum += m[i];
    ++count;
  }
  for (size_t i = 0; i < n; ++i) m[i] = valid[i] ? m[i] - sum / std::max<size_t>(count, 1) : 0.0;
  return m;
}

struct CoarseLag {
  double offset_s = 0, peak = 0, runner_up = 0;
};

// The lag of b against a (t_b = t_a + offset) where their magnitudes correlate best: every lag's
// sum by one FFT, normalised by the energies of that lag's overlap.
CoarseLag FindCoarseLag(const GyroTrace& a, const GyroTrace& b, double step_s, double min_overlap_s,
                        double max_offset_s) {
  const std::vector<double> ma = Magnitudes(a, step_s), mb = Magnitudes(b, step_s);
  const int na = static_cast<int>(ma.size()), nb = static_cast<int>(mb.size());
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
  for (int i = 1; i + 1 < static_cast<int>(c.size()); ++i) {
    if (std::abs(i - best) > distinct && c[i] >= c[i - 1] && c[i] >= c[i + 1])
      lag.runner_up = std::max(lag.runner_up, c[i]);
  }
  // The peak's sub-step place from a parabola through it and its neighbours.
  double frac = 0;
  if (best > 0 && best + 1 < static_cast<int>(c.size()) && c[best - 1] > -2 && c[best + 1] > -2) {
    const double denom = c[best - 1] - 2 * c[best] + c[best + 1];
    if (denom < 0) frac = 0.5 * (c[best - 1] - c[best + 1]) / denom;
  }
  lag.offset_s = base_s + (best - (na - 1) + frac) * step_s;
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

// One Gauss-Newton step for the first p of x = (offset, rate), with the bias difference
// eliminated (the residuals and the Jacobian's columns less their means); the derivatives are
// central differences over (h_offset_s, h_rate).
struct FineStep {
  Eigen::VectorXd step;
  Eigen::MatrixXd normal;
  double sigma2 = 0, rms = 0;
  size_t n = 0;
};
FineStep GaussNewtonStep(const FineProblem& problem, const Eigen::Vector2d& x, int p,
                         double h_offset_s, double h_rate) {
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
  for (size_t i = 0; i < r0.size(); ++i) {
    if (!used[i]) continue;
    const Eigen::Vector3d ri = r0[i] - mean_r;
    ss += ri.squaredNorm();
    for (int k = 0; k < p; ++k) {
      const Eigen::Vector3d dk = d[k][i] - mean_d[k];
      gradient[k] += dk.dot(ri);
      for (int l = 0; l < p; ++l) out.normal(k, l) += dk.dot(d[l][i] - mean_d[l]);
    }
  }
  out.sigma2 = ss / std::max<double>(3.0 * out.n - p - 3, 1.0);
  out.rms = std::sqrt(ss / (3.0 * out.n));
  out.step = out.normal.ldlt().solve(-gradient);
  return out;
}

}  // namespace

GyroSync SyncGyros(const GyroTrace& a, const GyroTrace& b, const GyroSyncOptions& options) {
  if (a.size() < 100 || b.size() < 100)
    throw std::invalid_argument("a trace of fewer than 100 samples: nothing to align");
  GyroSync sync;
  const double ia = IntervalS(a), ib = IntervalS(b);
  sync.faster_interval_s = std::min(ia, ib);
  sync.slower_interval_s = std::max(ia, ib);
  const double step_s = std::max(kCoarseStepS, sync.slower_interval_s);
  const double min_overlap_s = std::min(kMinOverlapS, 0.5 * std::min(a.DurationS(), b.DurationS()));
  const CoarseLag lag = FindCoarseLag(a, b, step_s, min_overlap_s, options.max_offset_s);
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
  // The mounting, with b on a's clock at the coarse offset.
  const SensorPair pair = FuseSensorPair(a, Shifted(b, lag.offset_s), SensorPairOptions{});
  sync.a_from_b = pair.a_from_b;
  sync.mounting_fitted = pair.mounting_fitted;
  sync.mounting_angle_deg = pair.mounting_angle_deg;
  // The overlap on a's clock, and its middle: the reference of the rate.
  const double begin_ns = std::max<double>(a.t_begin_ns(), b.t_begin_ns() - 1e9 * lag.offset_s);
  const double end_ns = std::min<double>(a.t_end_ns(), b.t_end_ns() - 1e9 * lag.offset_s);
  sync.overlap_s = (end_ns - begin_ns) * 1e-9;
  const bool fit_rate = sync.overlap_s >= options.min_rate_overlap_s;
  FineProblem problem{a, b, ia >= ib, 0.5 * (begin_ns + end_ns), sync.a_from_b};
  sync.reference_a_s = problem.t_mid_ns * 1e-9;
  // Gauss-Newton on (offset, rate). The derivatives are central differences over
  // kDerivativeStepS: over one sample interval the sensors' noise would swamp them (0.006 rad/s
  // over 1.25 ms is 7 rad/s^2, a brisk motion's own), and a Jacobian that holds the residual's
  // noise gives a biased step and a standard error far too small.
  const int p = fit_rate ? 2 : 1;
  Eigen::Vector2d x(lag.offset_s, 0.0);
  const double h_offset_s = std::max(kDerivativeStepS, 2 * sync.faster_interval_s);
  const double h_rate = h_offset_s / std::max(0.5 * sync.overlap_s, 1.0);
  FineStep last;
  for (int iteration = 0; iteration < kIterations; ++iteration) {
    // The mounting again at the offset found (the coarse offset's pairs bias it), once the offset
    // has settled, when the motion shows it.
    if (iteration == kIterations / 2 && sync.mounting_fitted) {
      problem.r_ab = problem.Mounting(x[0], x[1]);
      sync.a_from_b = problem.r_ab;
      sync.mounting_angle_deg = Eigen::AngleAxisd(problem.r_ab).angle() * 180.0 / M_PI;
    }
    last = GaussNewtonStep(problem, x, p, h_offset_s, h_rate);
    x.head(p) += last.step;
  }
  const Eigen::MatrixXd covariance = last.sigma2 * last.normal.inverse();
  sync.residual_rms_rad_s = last.rms;
  sync.offset_s = x[0];
  sync.offset_stderr_s = std::sqrt(covariance(0, 0));
  if (fit_rate) {
    sync.rate_ppm = 1e6 * x[1];
    sync.rate_stderr_ppm = 1e6 * std::sqrt(covariance(1, 1));
  }
  sync.residuals = last.n;
  return sync;
}

}  // namespace shutterlab
