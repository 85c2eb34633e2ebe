#include "estimate/loop/effect_fit.h"

// How the loop decides:
//
// Residual r_i = measured - predicted at every point (2 components). noise_px is the RMS length of
// the measurement error, so each component has variance sigma^2 = noise_px^2 / 2.
//
// 0. Robustness. The fits minimise the Huber loss (delta = 3 noise_px,
// estimate/loop/least_squares.h):
//    a bad match pulls with a bounded force. The statistics below are taken over the points less
//    gross outliers: points more than 5 noise_px off (probability e^-25 for a Gaussian error),
//    at most the 5 % largest (beyond that share a large residual is the model's, not a few bad
//    matches'). Point weights (MeasuredPoint::weight) weight every sum.
// 1. "Above the noise?" is a chi-square test: m = sum w |r|^2 / (sum w noise_px^2), the mean square
//    residual over the noise's, against chi2_{1-alpha}(k) / k with k = 2 (sum w)^2 / sum w^2 / c.
//    c is the spatial correlation factor of the residual: the variance of a sum of neighbouring
//    residuals over the sum of their variances, c = 1 + sum_{i != j, |p_i - p_j| <= R} r_i.r_j /
//    sum_i |r_i|^2 (R = 4 point spacings), 1 for independent points and the factor by which
//    correlated noise (dense optical flow) inflates the spread of every sum of squares. Dividing
//    the degrees of freedom by c keeps the false-alarm rate at alpha (LoopOptions::significance,
//    1e-3) for correlated noise; the quantile is Wilson-Hilferty's. Measured on clean data
//    (bench/effect_fit_bench.cc, 12 frames x 1564 points, 200 sets each): 0 alarms with white
//    noise, 0 with noise correlated over 3x3 neighbouring points (c ~ 9).
// 2. Candidates: each effect not yet added is fitted jointly with the added ones (robust LM;
//    time_offset and clock_rate start from the best of a scan of +-0.25 s of shift in 4 ms steps,
//    since the cost is not convex over shifts longer than the motion's ~0.1 s time scale; for
//    clock_rate, the line through each frame's best shift). Each is
//    scored by BIC in its Gaussian form with the variance of the best candidate of the round (an
//    F-test's denominator, so it does not depend on noise_px being exact):
//      dBIC = (RSS_j - RSS_current) / (s^2 c) + (p_j - p_current) ln(n / c),
//    RSS = sum w |r|^2 over the round's points (outliers of the best candidate left out),
//    s^2 = RSS_best / (m sum w - p_best - nuisance), m the residual components per point (2; 1
//    with pair_translation, whose per-pair directions are the nuisance parameters), c from the
//    best candidate's residual, n = m (sum w)^2 / sum w^2 (readout_direction counts as one
//    parameter). The candidate with the lowest dBIC is added when dBIC < -bic_margin (10) and it
//    explains >= min_explained_share (30 %) of the residual's excess over the noise
//    (RSS - noise_sq sum w, noise_sq = noise_px^2 m / 2).
//    clock_rate (rate and offset) nests time_offset: it is chosen over time_offset only when its
//    rate is 3 standard errors from zero.
// 3. Ambiguity: other candidates within ambiguity_margin (10) of the chosen one's dBIC that explain
//    as much are named in ambiguous_with (not clock_rate beside time_offset: it holds the offset).
// 4. Backward step (stepwise selection): after an addition, each earlier effect is refitted away;
//    the one whose removal costs least is dropped if that is less than bic_margin (a readout error
//    first absorbed by a gyro scale is replaced, not kept beside the readout). A dropped effect is
//    not tried again. Repeat until the residual passes test 1 or its trimmed RMS is within
//    material_ratio (1.15) of noise_px (rule 5), no candidate qualifies, or max_effects.
// 5. unexplained = test 1 still rejects AND the trimmed RMS is above material_ratio (1.15) x
//    noise_px (noise_px is itself an estimate). So a candidate that removes a sliver of a residual
//    that stays far above noise is not added (rule 2), and a residual left far above noise is
//    always flagged: a wrong effect never stands as a confident answer.
//
// Standard errors (LoopOptions::covariance; every estimator is kept per effect for the record):
//  - model: (J^T W J)^-1 s^2 c with s^2 the model's own residual variance (not noise_px) and c its
//    residual's spatial correlation factor (rule 1). It holds for errors that are independent
//    beyond a few point spacings; measurement errors coherent over a whole frame or pair (a flow
//    bias along row bands, a pair's own timing, a car that the screening missed) are not.
//  - cluster sandwich (Liang & Zeger 1986): A^-1 (sum_g s_g s_g^T) A^-1 G / (G - 1), s_g the
//    score of frame (pair) g.
//  - cluster jackknife (the default): leave one frame or pair out, each refit one Gauss-Newton
//    step from the full fit, V = (G - 1) / G sum (d_g - mean d)(d_g - mean d)^T. It is scaled by
//    t_{0.975}(G - 1) / 1.96, so that +-1.96 reported standard errors is the t interval of a
//    variance estimated from G clusters (G = 7: x1.25; G = 19: x1.07), and never put below the
//    white-noise standard error ((J^T W J)^-1 s^2, c = 1: no data are more informative than
//    independent points). With fewer than 3 clusters it is the model's.
//  Calibration (tests/estimate/loop/coverage_test.cc), the truth within 2 reported standard errors:
//  60 seeded clips with an injected offset and readout whose pairs carry pair-coherent errors: the
//  jackknife 95 % and 95 % (median |error| / SE 0.66 and 0.62; a calibrated SE gives 95 % and
//  0.67), the model's 97-100 % at 0.52-0.56; 50 rendered and measured 240x180 clips (the flow's
//  own errors): the jackknife 92 % and 92 % (0.86, 0.90), the model's 100 % and 90 % at
//  0.43-0.49.

#include "estimate/loop/effect_model.h"
#include "estimate/loop/least_squares.h"
#include "sim/check.h"
#include "sim/so3.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <numeric>
#include <unordered_map>

namespace shutterlab {

void LoopOptions::Check() const {
  SHUTTERLAB_CHECK(max_effects >= 0 && max_effects <= 9)
      << "max_effects must be in [0, 9], got " << max_effects;
  SHUTTERLAB_CHECK(significance > 0 && significance < 0.5)
      << "significance must be in (0, 0.5), got " << significance;
  SHUTTERLAB_CHECK(bic_margin >= 0) << "bic_margin must be >= 0";
  SHUTTERLAB_CHECK(min_explained_share >= 0 && min_explained_share <= 1)
      << "min_explained_share must be in [0, 1]";
  SHUTTERLAB_CHECK(ambiguity_margin >= 0) << "ambiguity_margin must be >= 0";
  SHUTTERLAB_CHECK(material_ratio >= 1) << "material_ratio must be >= 1";
}

const char* CovarianceKindName(CovarianceKind kind) {
  switch (kind) {
    case CovarianceKind::kModel:
      return "model";
    case CovarianceKind::kClusterSandwich:
      return "cluster sandwich";
    case CovarianceKind::kClusterJackknife:
      return "cluster jackknife";
  }
  return "?";
}

ResidualStats ResidualStatsOf(const std::vector<double>& squared_norms) {
  ResidualStats stats;
  double sum = 0.0;
  for (double s : squared_norms) {
    sum += s;
    stats.max_px = std::max(stats.max_px, std::sqrt(s));
  }
  stats.points = squared_norms.size();
  stats.rms_px = stats.points > 0 ? std::sqrt(sum / stats.points) : 0.0;
  return stats;
}

std::vector<Eigen::Vector2d> PredictDisplacements(const TrueModel& model, const GyroTrace& gyro,
                                                  const FramePoints& frame) {
  const std::vector<FramePoints> frames = {frame};
  const std::unique_ptr<PointPredictor> predictor =
      MakePredictor(gyro, frames, /*pair_translation=*/false, /*robust_delta_px=*/1.0);
  std::vector<Eigen::Vector2d> out;
  predictor->Predict(model, &out);
  return out;
}

namespace {

// Upper-tail standard normal quantile z with P(Z > z) = alpha, by bisection on erfc.
double NormalUpperQuantile(double alpha) {
  double lo = -10.0, hi = 10.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (0.5 * std::erfc(mid / std::sqrt(2.0)) > alpha) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  return 0.5 * (lo + hi);
}

// chi2_{1-alpha}(k) / k by Wilson-Hilferty (accurate to ~1 % for k >= 10).
double ChiSquareQuantileOverDof(double alpha, double k) {
  const double a = 2.0 / (9.0 * k);
  const double base = 1.0 - a + NormalUpperQuantile(alpha) * std::sqrt(a);
  return base * base * base;
}

// Everything a fit needs about the data.
// A fitted clock rate counts only when it is this many standard errors from zero (see the loop).
constexpr double kRateSignificance = 3.0;

struct Context {
  TrueModel declared;
  const PointPredictor* predictor = nullptr;
  std::vector<Eigen::Vector2d> measured;
  std::vector<Eigen::Vector2d> px;
  std::vector<std::pair<size_t, size_t>> frame_ranges;  // [begin, end) per frame
  std::vector<double> frame_t_s;                        // t_first_row per frame, camera clock
  Eigen::VectorXd weights;  // per point; 0 for points the declared model cannot predict
  double noise_px = 0.0;
  // Residual components per point that carry information (PointPredictor), and the expected
  // weighted |r|^2 of a point under the noise alone: noise_px^2 * components / 2.
  int components = 2;
  double noise_sq = 0.0;
  int nuisance = 0;  // parameters the predictor solves itself
  double huber_delta = 0.0;
  CovarianceKind covariance = CovarianceKind::kClusterJackknife;
  double span_s = 0.0;
  // The starts' scans (FitHypothesis) judge a model on a sample of the points: at most
  // kScanPointsPerFrame of each frame, spread over it (every k-th of its usable points). A scan
  // only picks the start that the fit on every point then refines; 125 shifts on every point of a
  // long clip cost more than the fit itself.
  std::shared_ptr<const PointPredictor> scan_predictor;
  std::vector<size_t> scan_index;                            // into the full set, per sample
  std::vector<std::pair<size_t, size_t>> scan_frame_ranges;  // [begin, end) in the sample
};

struct Hypothesis {
  std::vector<Effect> effects;  // in the order added
  Eigen::VectorXd x;            // continuous parameters, concatenated in that order
};

int ParameterCount(const std::vector<Effect>& effects) {
  int n = 0;
  for (Effect e : effects) n += Spec(e).parameter_count;
  return n;
}

// For the information criterion: a discrete choice is one decision.
int CriterionParameters(const std::vector<Effect>& effects) {
  int n = 0;
  for (Effect e : effects) n += std::max(1, Spec(e).parameter_count);
  return n;
}

TrueModel ModelOf(const Context& ctx, const std::vector<Effect>& effects,
                  const Eigen::VectorXd& x) {
  TrueModel model = ctx.declared;
  int offset = 0;
  for (Effect e : effects) {
    Spec(e).apply_delta(x.data() + offset, &model);
    offset += Spec(e).parameter_count;
  }
  return model;
}

// The declared lens is the user's calibration and is taken as it is (a wide lens may fold just
// beyond the corners); only a fitted change must keep the image in one piece.
bool Plausible(const Context& ctx, const TrueModel& model) {
  return model.rig.shutter.readout_s >= 0 && (model.gyro_scale.array() > 0).all() &&
         std::abs(model.clock_rate_ppm) < 1e5 && model.gyro_bias_rad_s.allFinite() &&
         model.rig.velocity_mps.allFinite() &&
         (model.rig.camera.distortion == ctx.declared.rig.camera.distortion ||
          model.rig.camera.DistortionMonotonicOverImage());
}

void Residuals(const Context& ctx, const TrueModel& model, Eigen::VectorXd* r,
               std::vector<uint8_t>* valid) {
  const size_t n = ctx.measured.size();
  r->setZero(2 * n);
  valid->assign(n, 0);
  if (!Plausible(ctx, model)) return;
  std::vector<Eigen::Vector2d> predicted;
  ctx.predictor->Predict(model, &predicted);
  for (size_t i = 0; i < n; ++i) {
    if (!predicted[i].allFinite()) continue;
    r->segment<2>(2 * i) = ctx.measured[i] - predicted[i];
    (*valid)[i] = 1;
  }
}

// c = 1 + sum_{i != j near} r_i.r_j / sum |r_i|^2 over the kept points' weighted residuals.
double CorrelationFactor(const Context& ctx, const Eigen::VectorXd& r,
                         const std::vector<uint8_t>& keep) {
  double self = 0.0, cross = 0.0;
  std::vector<size_t> idx;
  std::vector<Eigen::Vector2d> z;
  for (const auto& [begin, end] : ctx.frame_ranges) {
    idx.clear();
    z.clear();
    double u0 = 1e300, u1 = -1e300, v0 = 1e300, v1 = -1e300;
    for (size_t i = begin; i < end; ++i) {
      if (!keep[i]) continue;
      z.push_back(std::sqrt(ctx.weights[i]) * r.segment<2>(2 * i));
      idx.push_back(i);
      u0 = std::min(u0, ctx.px[i].x());
      u1 = std::max(u1, ctx.px[i].x());
      v0 = std::min(v0, ctx.px[i].y());
      v1 = std::max(v1, ctx.px[i].y());
    }
    if (idx.size() < 2) continue;
    const double spacing =
        std::max(1.0, std::sqrt((u1 - u0 + 1) * (v1 - v0 + 1) / static_cast<double>(idx.size())));
    const double radius = 4.0 * spacing;
    std::unordered_map<int64_t, std::vector<size_t>> cells;
    // Unsigned shift: shifting a negative cell index is undefined behaviour.
    auto key = [](int64_t cu, int64_t cv) {
      return static_cast<int64_t>((static_cast<uint64_t>(cu) << 32) ^
                                  (static_cast<uint64_t>(cv) & 0xffffffffu));
    };
    for (size_t k = 0; k < idx.size(); ++k) {
      const Eigen::Vector2d& p = ctx.px[idx[k]];
      cells[key(static_cast<int64_t>(std::floor(p.x() / radius)),
                static_cast<int64_t>(std::floor(p.y() / radius)))]
          .push_back(k);
    }
    for (size_t k = 0; k < idx.size(); ++k) {
      self += z[k].squaredNorm();
      const Eigen::Vector2d& p = ctx.px[idx[k]];
      const int64_t cu = static_cast<int64_t>(std::floor(p.x() / radius));
      const int64_t cv = static_cast<int64_t>(std::floor(p.y() / radius));
      for (int64_t du = -1; du <= 1; ++du) {
        for (int64_t dv = -1; dv <= 1; ++dv) {
          const auto it = cells.find(key(cu + du, cv + dv));
          if (it == cells.end()) continue;
          for (size_t m : it->second) {
            if (m <= k) continue;
            if ((ctx.px[idx[m]] - p).squaredNorm() > radius * radius) continue;
            cross += 2.0 * z[k].dot(z[m]);
          }
        }
      }
    }
  }
  if (!(self > 0)) return 1.0;
  return std::max(1.0, 1.0 + cross / self);
}

// The points a residual is judged on: every weighted point with a prediction, less gross
// outliers: points more than kOutlierNoise * noise_px off (probability e^-25 for a Gaussian
// measurement), at most kMaxOutlierShare of the points (the largest ones). Beyond that share a
// large residual is the model's, not a few bad matches', and is kept.
constexpr double kOutlierNoise = 5.0;
constexpr double kMaxOutlierShare = 0.05;
// A candidate that leaves more than this share of the judged points without a prediction (a clock
// rate that pushes frames off the gyro log, say) is not considered.
constexpr double kMaxLostShare = 0.01;
// An information matrix scaled to unit diagonal (a correlation matrix) whose smallest eigenvalue is
// below this leaves a parameter combination undetermined: two parameters correlated beyond
// 1 - 1e-9 (numeric Jacobians carry ~1e-8 relative error).
constexpr double kMinInformationRatio = 1e-9;
// A parameter whose unit-scaled loading on such a combination exceeds this takes part in it.
constexpr double kMinUndeterminedLoading = 1e-4;

std::vector<uint8_t> KeepMask(const Context& ctx, const Eigen::VectorXd& r,
                              const std::vector<uint8_t>& valid) {
  const size_t n = valid.size();
  std::vector<uint8_t> keep(n, 0);
  std::vector<std::pair<double, size_t>> large;
  size_t candidates = 0;
  for (size_t i = 0; i < n; ++i) {
    if (!valid[i] || ctx.weights[i] <= 0) continue;
    ++candidates;
    keep[i] = 1;
    const double s = r.segment<2>(2 * i).norm();
    if (s > kOutlierNoise * ctx.noise_px) large.emplace_back(s, i);
  }
  const size_t max_drop = static_cast<size_t>(kMaxOutlierShare * candidates);
  std::sort(large.begin(), large.end(), std::greater<>());
  for (size_t k = 0; k < std::min(max_drop, large.size()); ++k) keep[large[k].second] = 0;
  return keep;
}

// Weighted sum of squares over the mask; a masked point without prediction counts as an outlier at
// the trimming level (it was fitted elsewhere and lost its prediction).
double MaskedRss(const Context& ctx, const Eigen::VectorXd& r, const std::vector<uint8_t>& valid,
                 const std::vector<uint8_t>& keep) {
  const double lost = std::pow(kOutlierNoise * ctx.noise_px, 2);
  double rss = 0.0;
  for (size_t i = 0; i < keep.size(); ++i) {
    if (!keep[i]) continue;
    rss += ctx.weights[i] * (valid[i] ? r.segment<2>(2 * i).squaredNorm() : lost);
  }
  return rss;
}

struct MaskSums {
  double w = 0.0, w2 = 0.0;
};
MaskSums SumWeights(const Context& ctx, const std::vector<uint8_t>& keep) {
  MaskSums sums;
  for (size_t i = 0; i < keep.size(); ++i) {
    if (!keep[i]) continue;
    sums.w += ctx.weights[i];
    sums.w2 += ctx.weights[i] * ctx.weights[i];
  }
  return sums;
}

struct LevelTest {
  double ratio = 0.0;      // mean square residual / noise_px^2 (trimmed)
  double threshold = 0.0;  // chi2 quantile / dof
  double c = 1.0;
  double rms_px = 0.0;  // trimmed RMS
  bool above = false;
};

LevelTest TestLevel(const Context& ctx, const Eigen::VectorXd& r, const std::vector<uint8_t>& valid,
                    double significance) {
  LevelTest t;
  const std::vector<uint8_t> keep = KeepMask(ctx, r, valid);
  const MaskSums sums = SumWeights(ctx, keep);
  if (!(sums.w > 0)) return t;
  const double rss = MaskedRss(ctx, r, valid, keep);
  t.rms_px = std::sqrt(rss / sums.w);
  t.ratio = rss / (sums.w * ctx.noise_sq);
  t.c = CorrelationFactor(ctx, r, keep);
  const double k = std::max(1.0, ctx.components * sums.w * sums.w / sums.w2 / t.c);
  t.threshold = ChiSquareQuantileOverDof(significance, k);
  t.above = t.ratio > t.threshold;
  return t;
}

// Over the points the fit uses (weight > 0: not left out by the screening, predicted by the
// declared model).
ResidualStats Stats(const Context& ctx, const Eigen::VectorXd& r,
                    const std::vector<uint8_t>& valid) {
  std::vector<double> squared_norms;
  for (size_t i = 0; i < valid.size(); ++i) {
    if (valid[i] && ctx.weights[i] > 0) squared_norms.push_back(r.segment<2>(2 * i).squaredNorm());
  }
  return ResidualStatsOf(squared_norms);
}

// The search goes on only while the residual is materially above the noise as well: noise_px is
// an estimate, and a residual within material_ratio of it is as much the measurement's own
// systematic error (on rendered video pairs the true model leaves 1.04-1.13x noise_px) as any
// effect's; candidates fitted to it pick up the measurement, not the rig. The same test says
// "unexplained" after the loop.
bool Material(const Context& ctx, const LoopOptions& options, const LevelTest& t) {
  return t.above && t.rms_px > options.material_ratio * std::sqrt(ctx.noise_sq);
}

struct Fit {
  Hypothesis hypothesis;
  TrueModel model;
  RobustSolution solution;
  double rss = 0.0;  // 2 * robust cost
  ResidualStats stats;
};

RobustProblem MakeProblem(const Context& ctx, const std::vector<Effect>& effects) {
  RobustProblem problem;
  problem.residuals = [&ctx, effects](const Eigen::VectorXd& x, Eigen::VectorXd* r,
                                      std::vector<uint8_t>* valid) {
    Residuals(ctx, ModelOf(ctx, effects, x), r, valid);
  };
  problem.weights = ctx.weights;
  problem.steps.resize(ParameterCount(effects));
  int k = 0;
  for (Effect e : effects) {
    for (int i = 0; i < Spec(e).parameter_count; ++i)
      problem.steps[k++] = Spec(e).step(i, ctx.span_s);
  }
  problem.huber_delta = ctx.huber_delta;
  // Far above any point's real cost: the solver does not fit by pushing points off the trace, and
  // rejects implausible models (negative readout or scale), which predict nothing.
  problem.invalid_cost = HuberRho(1e3 * ctx.huber_delta, ctx.huber_delta);
  return problem;
}

// The robust cost of a model per frame over the scans' sample (Context::scan_predictor), as
// FitHypothesis's problem counts it; every frame infinite for an implausible model.
std::vector<double> ScanCosts(const Context& ctx, const TrueModel& model) {
  const size_t frames = ctx.scan_frame_ranges.size();
  std::vector<double> costs(frames, std::numeric_limits<double>::infinity());
  if (!Plausible(ctx, model)) return costs;
  std::vector<Eigen::Vector2d> predicted;
  ctx.scan_predictor->Predict(model, &predicted);
  const double invalid_cost = HuberRho(1e3 * ctx.huber_delta, ctx.huber_delta);
  for (size_t f = 0; f < frames; ++f) {
    double cost = 0.0;
    for (size_t j = ctx.scan_frame_ranges[f].first; j < ctx.scan_frame_ranges[f].second; ++j) {
      const size_t i = ctx.scan_index[j];
      const double w = ctx.weights[i];
      if (w <= 0) continue;
      cost += w * (predicted[j].allFinite()
                       ? HuberRho((ctx.measured[i] - predicted[j]).norm(), ctx.huber_delta)
                       : invalid_cost);
    }
    costs[f] = cost;
  }
  return costs;
}

// Fits hypothesis.effects from hypothesis.x. When the last effect is time_offset or clock_rate,
// its start is the best of a coarse scan (the cost is not convex over tens of ms of shift).
Fit FitHypothesis(const Context& ctx, Hypothesis hypothesis) {
  const RobustProblem problem = MakeProblem(ctx, hypothesis.effects);
  const Eigen::Index p = problem.steps.size();
  if (!hypothesis.effects.empty() && p > 0) {
    const Effect last = hypothesis.effects.back();
    if (last == Effect::kTimeOffset || last == Effect::kClockRate) {
      // Shifts of the offset within +-kScanS in steps of kScanStepS: finer than the ~0.1 s over
      // which a multirotor's rotation rate changes, so one start lies in the true minimum's basin.
      // Each frame's cost is kept per shift: time_offset starts at the shift best for all frames;
      // clock_rate (offset + rate * t) at the line through each frame's best shift against its
      // time, so a rate that shifts the frames differently needs no second scan.
      constexpr double kScanS = 0.25, kScanStepS = 0.004;
      const int steps = static_cast<int>(std::lround(kScanS / kScanStepS));
      const size_t frame_count = ctx.frame_ranges.size();
      std::vector<double> frame_best_cost(frame_count, std::numeric_limits<double>::infinity());
      std::vector<double> frame_best_shift(frame_count, 0.0);
      double best_cost = std::numeric_limits<double>::infinity(), best_shift = 0.0;
      for (int k = -steps; k <= steps; ++k) {
        const double shift = k * kScanStepS;
        Eigen::VectorXd x = hypothesis.x;
        x[p - 1] += shift;
        const std::vector<double> frame_costs = ScanCosts(ctx, ModelOf(ctx, hypothesis.effects, x));
        double cost = 0.0;
        for (size_t f = 0; f < frame_count; ++f) {
          const double frame_cost = frame_costs[f];
          cost += frame_cost;
          if (frame_cost < frame_best_cost[f]) {
            frame_best_cost[f] = frame_cost;
            frame_best_shift[f] = shift;
          }
        }
        if (cost < best_cost) {
          best_cost = cost;
          best_shift = shift;
        }
      }
      hypothesis.x[p - 1] += best_shift;
      if (last == Effect::kClockRate && frame_count >= 2) {
        // Theil-Sen line shift = a + b t through the frames' best shifts (the median of the
        // pairwise slopes, then of the intercepts): a frame whose own best shift is an alias of
        // its motion does not tilt it.
        std::vector<double> slopes, intercepts;
        for (size_t f = 0; f < frame_count; ++f) {
          for (size_t g = f + 1; g < frame_count; ++g) {
            const double dt = ctx.frame_t_s[g] - ctx.frame_t_s[f];
            if (dt != 0.0) slopes.push_back((frame_best_shift[g] - frame_best_shift[f]) / dt);
          }
        }
        const double rate = slopes.empty() ? 0.0 : UpperMedian(slopes);
        for (size_t f = 0; f < frame_count; ++f) {
          intercepts.push_back(frame_best_shift[f] - rate * ctx.frame_t_s[f]);
        }
        hypothesis.x[p - 1] += UpperMedian(intercepts) - best_shift;
        hypothesis.x[p - 2] += rate * 1e6;
      }
    }
  }
  if (!hypothesis.effects.empty() && hypothesis.effects.back() == Effect::kGyroToCamera) {
    // A wrongly mounted or differently labelled sensor is off by a quarter or half turn, far
    // outside the basin of a fit started at the declared mounting: start at the best of the 24
    // axis permutations with signs (the rotations among them) and the declared mounting itself.
    // R_CG = Exp(x) R_declared (EffectSpec::apply_delta), so x = Log(S R_declared^T) reaches S.
    const Eigen::Matrix3d declared = ctx.declared.rig.cam_from_gyro;
    const auto total_cost = [&](const Eigen::VectorXd& x) {
      const std::vector<double> costs = ScanCosts(ctx, ModelOf(ctx, hypothesis.effects, x));
      return std::accumulate(costs.begin(), costs.end(), 0.0);
    };
    Eigen::VectorXd best_x = hypothesis.x;
    double best_cost = total_cost(best_x);
    for (const Eigen::Matrix3d& axes : AxisRotations()) {
      Eigen::VectorXd x = hypothesis.x;
      x.tail<3>() = LogSO3(Eigen::Quaterniond(axes * declared.transpose()));
      const double cost = total_cost(x);
      if (cost < best_cost) {
        best_cost = cost;
        best_x = x;
      }
    }
    hypothesis.x = best_x;
  }
  Fit fit;
  fit.solution = SolveRobust(problem, hypothesis.x);
  hypothesis.x = fit.solution.x;
  fit.model = ModelOf(ctx, hypothesis.effects, hypothesis.x);
  fit.hypothesis = std::move(hypothesis);
  fit.rss = 2.0 * fit.solution.cost;
  fit.stats = Stats(ctx, fit.solution.residuals, fit.solution.valid);
  return fit;
}

// The inverse of a symmetric information matrix over the parameter combinations it determines (an
// eigenvalue of the matrix scaled to unit diagonal, so that units do not matter, above
// kMinInformationRatio); *undetermined (optional) marks the parameters that take part in a
// combination it does not. False when the matrix has a non-positive diagonal or is not finite.
bool DeterminedInverse(const Eigen::MatrixXd& a, Eigen::MatrixXd* inverse,
                       std::vector<bool>* undetermined) {
  const Eigen::Index p = a.rows();
  const Eigen::VectorXd diagonal = a.diagonal();
  if (!a.allFinite() || !(diagonal.array() > 0).all()) return false;
  const Eigen::VectorXd unit = diagonal.cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd scaled = unit.asDiagonal() * a * unit.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(scaled);
  if (eig.info() != Eigen::Success) return false;
  Eigen::VectorXd inverse_eigenvalues = Eigen::VectorXd::Zero(p);
  if (undetermined != nullptr) undetermined->assign(p, false);
  for (Eigen::Index j = 0; j < p; ++j) {
    if (eig.eigenvalues()[j] > kMinInformationRatio) {
      inverse_eigenvalues[j] = 1.0 / eig.eigenvalues()[j];
      continue;
    }
    for (Eigen::Index i = 0; undetermined != nullptr && i < p; ++i) {
      if (std::abs(eig.eigenvectors()(i, j)) > kMinUndeterminedLoading) (*undetermined)[i] = true;
    }
  }
  *inverse =
      unit.asDiagonal() *
      (eig.eigenvectors() * inverse_eigenvalues.asDiagonal() * eig.eigenvectors().transpose()) *
      unit.asDiagonal();
  return true;
}

// Each frame's (cluster's) share of the information matrix and of the score at the fit:
// A_g = sum_i w_i J_i^T J_i, s_g = sum_i w_i J_i^T r_i over the frame's judged points (IRLS
// weights); frames with no such point are left out.
struct ClusterTerms {
  std::vector<Eigen::MatrixXd> information;
  std::vector<Eigen::VectorXd> score;
};
ClusterTerms Clusters(const Context& ctx, const RobustSolution& sol,
                      const std::vector<uint8_t>& keep) {
  const Eigen::Index p = sol.x.size();
  ClusterTerms terms;
  for (const auto& [begin, end] : ctx.frame_ranges) {
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(p, p);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(p);
    bool any = false;
    for (size_t i = begin; i < end; ++i) {
      if (!keep[i] || sol.irls_weights[i] <= 0) continue;
      const auto j = sol.jacobian.middleRows(2 * i, 2);
      a.noalias() += sol.irls_weights[i] * j.transpose() * j;
      g.noalias() += sol.irls_weights[i] * j.transpose() * sol.residuals.segment<2>(2 * i);
      any = true;
    }
    if (!any) continue;
    terms.information.push_back(std::move(a));
    terms.score.push_back(std::move(g));
  }
  return terms;
}

// The three covariances of the fitted parameters (see the top of this file); NaN rows and columns
// for the parameters the data do not determine, all NaN when nothing is.
struct Covariances {
  Eigen::MatrixXd model, sandwich, jackknife;
  Eigen::MatrixXd white;  // (J^T W J)^-1 s^2: the model's without the correlation factor
  int clusters = 0;
};
// Cluster covariances need at least this many frames or pairs with points.
constexpr int kMinClusters = 3;

Covariances AllCovariances(const Context& ctx, const Fit& fit) {
  const Eigen::Index p = fit.solution.x.size();
  Covariances out;
  if (p == 0) return out;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  out.model = out.sandwich = out.jackknife = out.white = Eigen::MatrixXd::Constant(p, p, nan);
  const RobustSolution& sol = fit.solution;
  Eigen::MatrixXd a_inv;
  std::vector<bool> undetermined;
  if (!DeterminedInverse(sol.normal, &a_inv, &undetermined)) return out;
  const std::vector<uint8_t> keep = KeepMask(ctx, sol.residuals, sol.valid);
  const MaskSums sums = SumWeights(ctx, keep);
  const double dof = std::max(1.0, ctx.components * sums.w - static_cast<double>(p) - ctx.nuisance);
  const double s2 = MaskedRss(ctx, sol.residuals, sol.valid, keep) / dof;
  out.white = a_inv * s2;
  out.model = out.white * CorrelationFactor(ctx, sol.residuals, keep);
  // Cluster-robust sandwich (Liang & Zeger 1986, with the G / (G - 1) small-sample factor): the
  // scatter of the frames' scores s_g. It sees errors coherent over a whole frame (a measurement
  // bias along row bands, a per-frame timing error), which the neighbourhood factor c cannot.
  const ClusterTerms clusters = Clusters(ctx, sol, keep);
  const int g_count = static_cast<int>(clusters.score.size());
  out.clusters = g_count;
  if (g_count >= 2) {
    Eigen::MatrixXd meat = Eigen::MatrixXd::Zero(p, p);
    for (const Eigen::VectorXd& g : clusters.score) meat.noalias() += g * g.transpose();
    out.sandwich = a_inv * meat * a_inv * (g_count / (g_count - 1.0));
    // Leave-one-frame-out jackknife, each refit taken as one Gauss-Newton step from the full fit:
    // without frame g the score is -s_g and the information A - A_g, so the refit moves by
    // d_g = -(A - A_g)^-1 s_g; V = (G - 1) / G sum (d_g - mean d)(d_g - mean d)^T. A frame
    // without which a combination is not determined gives no refit; fewer than two refits, no
    // jackknife.
    std::vector<Eigen::VectorXd> moves;
    for (int g = 0; g < g_count; ++g) {
      Eigen::MatrixXd without_inv;
      std::vector<bool> lost;
      if (!DeterminedInverse(sol.normal - clusters.information[g], &without_inv, &lost)) continue;
      if (lost != undetermined) continue;
      moves.push_back(-without_inv * clusters.score[g]);
    }
    if (moves.size() >= 2) {
      Eigen::VectorXd mean = Eigen::VectorXd::Zero(p);
      for (const Eigen::VectorXd& d : moves) mean += d;
      mean /= static_cast<double>(moves.size());
      Eigen::MatrixXd v = Eigen::MatrixXd::Zero(p, p);
      for (const Eigen::VectorXd& d : moves) v.noalias() += (d - mean) * (d - mean).transpose();
      const double m = static_cast<double>(moves.size());
      out.jackknife = v * ((m - 1.0) / m);
    }
  }
  for (Eigen::MatrixXd* c : {&out.model, &out.sandwich, &out.jackknife, &out.white}) {
    for (Eigen::Index i = 0; i < p; ++i) {
      if (!undetermined[i]) continue;
      c->row(i).setConstant(nan);
      c->col(i).setConstant(nan);
    }
  }
  return out;
}

// The two-sided 97.5 % quantile of Student's t with nu degrees of freedom: exact for 1 and 2, the
// Cornish-Fisher expansion beyond (within 0.2 % for nu >= 3).
double StudentT975(int nu) {
  if (nu <= 1) return 12.706;
  if (nu == 2) return 4.303;
  const double z = 1.959964, z3 = z * z * z, z5 = z3 * z * z, z7 = z5 * z * z, n = nu;
  return z + (z3 + z) / (4 * n) + (5 * z5 + 16 * z3 + 3 * z) / (96 * n * n) +
         (3 * z7 + 19 * z5 + 17 * z3 - 15 * z) / (384 * n * n * n);
}

// A covariance with each standard error raised to at least floor_sd's, keeping its correlations.
Eigen::MatrixXd WithFloor(const Eigen::MatrixXd& covariance, const Eigen::VectorXd& floor_sd) {
  const Eigen::VectorXd sd = covariance.diagonal().cwiseMax(1e-300).cwiseSqrt();
  const Eigen::VectorXd scale = sd.cwiseMax(floor_sd).cwiseQuotient(sd);
  return scale.asDiagonal() * covariance * scale.asDiagonal();
}

// The covariance the loop reports (LoopOptions::covariance, the top of this file) and the kind it
// came from (the model's where too few clusters make the others meaningless).
Eigen::MatrixXd Covariance(const Context& ctx, const Fit& fit, CovarianceKind* used = nullptr) {
  const Covariances all = AllCovariances(ctx, fit);
  CovarianceKind kind = ctx.covariance;
  if (kind != CovarianceKind::kModel && all.clusters < kMinClusters) kind = CovarianceKind::kModel;
  if (used != nullptr) *used = kind;
  switch (kind) {
    case CovarianceKind::kModel:
      return all.model;
    case CovarianceKind::kClusterSandwich:
      return all.sandwich;
    case CovarianceKind::kClusterJackknife: {
      const double t_scale = StudentT975(all.clusters - 1) / StudentT975(1000000);
      return WithFloor(all.jackknife * (t_scale * t_scale),
                       all.white.diagonal().cwiseMax(0.0).cwiseSqrt());
    }
  }
  return all.model;
}

// 3 noise_px on the residual's length: a Gaussian point passes with probability 1 - e^-9.
double HuberDelta(double noise_px) { return 3.0 * noise_px; }

Context MakeContext(const TrueModel& declared, const PointPredictor& predictor,
                    const std::vector<FramePoints>& frames, double noise_px) {
  Context ctx;
  ctx.declared = declared;
  ctx.predictor = &predictor;
  ctx.noise_px = noise_px;
  ctx.components = predictor.residual_components();
  ctx.noise_sq = noise_px * noise_px * ctx.components / 2.0;
  ctx.nuisance = predictor.nuisance_parameters();
  ctx.huber_delta = HuberDelta(noise_px);
  ctx.span_s = predictor.frames_span_s();
  ctx.weights.resize(predictor.point_count());
  for (const FramePoints& f : frames) {
    const size_t begin = ctx.measured.size();
    for (const MeasuredPoint& p : f.points) {
      ctx.weights[ctx.measured.size()] = std::isfinite(p.weight) ? std::max(0.0, p.weight) : 0.0;
      if (!std::isfinite(p.dx) || !std::isfinite(p.dy)) ctx.weights[ctx.measured.size()] = 0.0;
      ctx.measured.emplace_back(p.dx, p.dy);
      ctx.px.emplace_back(p.u, p.v);
    }
    ctx.frame_ranges.emplace_back(begin, ctx.measured.size());
    ctx.frame_t_s.push_back(f.t_first_row_ns * 1e-9);
  }
  return ctx;
}

// The fit's effects with their docs/FORMATS.md values, standard errors, parameters and covariance;
// the residual after each is the fit's own (the loop overwrites it with the residual when it was
// added).
std::vector<IdentifiedEffect> IdentifiedEffects(const Context& ctx, const Fit& fit) {
  const Covariances all = AllCovariances(ctx, fit);
  CovarianceKind used = ctx.covariance;
  const Eigen::MatrixXd cov = Covariance(ctx, fit, &used);
  const auto sd = [](const Eigen::MatrixXd& c, int offset, int n) -> Eigen::VectorXd {
    return c.size() ? Eigen::VectorXd(c.diagonal().segment(offset, n).cwiseSqrt())
                    : Eigen::VectorXd();
  };
  std::vector<IdentifiedEffect> effects;
  int offset = 0;
  for (Effect e : fit.hypothesis.effects) {
    const int n = Spec(e).parameter_count;
    IdentifiedEffect effect;
    effect.effect = e;
    effect.value = Spec(e).value(fit.model);
    effect.out_of_bounds = OutOfBounds(e, effect.value, &fit.model.rig);
    effect.covariance = cov.block(offset, offset, n, n);
    effect.stderr_value = EffectStderr(e, fit.model, effect.covariance);
    effect.parameters = fit.hypothesis.x.segment(offset, n);
    effect.parameter_stderr_model = sd(all.model, offset, n);
    effect.parameter_stderr_sandwich = sd(all.sandwich, offset, n);
    effect.parameter_stderr_jackknife = sd(all.jackknife, offset, n);
    effect.clusters = all.clusters;
    effect.stderr_from = used;
    effect.after = fit.stats;
    effects.push_back(std::move(effect));
    offset += n;
  }
  return effects;
}

// measured - predicted per point of a fit, NaN where it predicts nothing.
std::vector<Eigen::Vector2d> PointResiduals(const Fit& fit) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<Eigen::Vector2d> out(fit.solution.valid.size(), Eigen::Vector2d(nan, nan));
  for (size_t i = 0; i < out.size(); ++i) {
    if (fit.solution.valid[i]) out[i] = fit.solution.residuals.segment<2>(2 * i);
  }
  return out;
}

std::string Describe(const std::vector<Effect>& effects, const TrueModel& model) {
  std::string out;
  for (Effect e : effects) {
    out += (out.empty() ? "" : "; ") + Spec(e).name + " = " + EffectValueText(Spec(e).value(model));
  }
  return out;
}

// The scans' sample (Context::scan_predictor): at most kScanPointsPerFrame of each frame's points
// with weight, every k-th of them.
constexpr size_t kScanPointsPerFrame = 128;
void SampleForScans(const GyroTrace& gyro, const std::vector<FramePoints>& frames,
                    bool pair_translation, Context* ctx) {
  std::vector<FramePoints> sample;
  ctx->scan_index.clear();
  ctx->scan_frame_ranges.clear();
  size_t at = 0;
  for (const FramePoints& f : frames) {
    FramePoints kept = f;
    kept.points.clear();
    size_t usable = 0;
    for (size_t i = 0; i < f.points.size(); ++i) usable += ctx->weights[at + i] > 0;
    const size_t stride =
        std::max<size_t>(1, (usable + kScanPointsPerFrame - 1) / kScanPointsPerFrame);
    const size_t begin = ctx->scan_index.size();
    size_t seen = 0;
    for (size_t i = 0; i < f.points.size(); ++i) {
      if (!(ctx->weights[at + i] > 0) || seen++ % stride != 0) continue;
      kept.points.push_back(f.points[i]);
      ctx->scan_index.push_back(at + i);
    }
    ctx->scan_frame_ranges.emplace_back(begin, ctx->scan_index.size());
    sample.push_back(std::move(kept));
    at += f.points.size();
  }
  ctx->scan_predictor = MakePredictor(gyro, sample, pair_translation, ctx->huber_delta);
}

// The common start of CloseTheLoop and FitEffects: the inputs checked, the predictor and the
// context, and the declared model's fit (points it cannot predict take no part: they would have no
// residual); result gets noise_px, residual_components, before and residuals_before.
struct Start {
  std::unique_ptr<PointPredictor> predictor;  // ctx points into it
  Context ctx;
  Fit declared;
};
Start Begin(const TrueModel& declared, const GyroTrace& gyro,
            const std::vector<FramePoints>& frames, double noise_px, const LoopOptions& options,
            LoopResult* result) {
  options.Check();
  declared.Check();
  SHUTTERLAB_CHECK(std::isfinite(noise_px) && noise_px > 0)
      << "noise_px must be positive, got " << noise_px;
  SHUTTERLAB_CHECK(!frames.empty()) << "no frames to fit";
  Start start;
  start.predictor = MakePredictor(gyro, frames, options.pair_translation, HuberDelta(noise_px));
  start.ctx = MakeContext(declared, *start.predictor, frames, noise_px);
  Context& ctx = start.ctx;
  ctx.covariance = options.covariance;
  const Fit first = FitHypothesis(ctx, Hypothesis{});
  for (size_t i = 0; i < first.solution.valid.size(); ++i) {
    if (!first.solution.valid[i]) ctx.weights[i] = 0.0;
  }
  SHUTTERLAB_CHECK(ctx.weights.sum() > 0)
      << "no measured point that the declared model can predict";
  SampleForScans(gyro, frames, options.pair_translation, &ctx);
  start.declared = FitHypothesis(ctx, Hypothesis{});
  result->noise_px = noise_px;
  result->residual_components = ctx.components;
  result->covariance = options.covariance;
  result->before = start.declared.stats;
  result->residuals_before = PointResiduals(start.declared);
  return start;
}

// ---- The loop's rounds: a driver (CloseTheLoop) over the judged steps below, each reading and
// filling one Round record; LogRound writes the round's log lines from that record.

// How one fit's residual is judged (rules 1-2 at the top of this file), computed once per fit:
// its points less gross outliers, their weight sums, its sum of squares over them, its residual
// variance s^2, its correlation factor c and the effective number of observations n / c.
struct Judged {
  std::vector<uint8_t> keep;
  MaskSums sums;
  double rss = 0.0;
  double s2 = 0.0;
  double c = 1.0;
  double n_eff = 2.0;
};

Judged Judge(const Context& ctx, const Fit& fit) {
  const RobustSolution& sol = fit.solution;
  Judged judged;
  judged.keep = KeepMask(ctx, sol.residuals, sol.valid);
  judged.sums = SumWeights(ctx, judged.keep);
  judged.rss = MaskedRss(ctx, sol.residuals, sol.valid, judged.keep);
  judged.s2 =
      judged.rss / std::max(1.0, ctx.components * judged.sums.w -
                                     CriterionParameters(fit.hypothesis.effects) - ctx.nuisance);
  judged.c = CorrelationFactor(ctx, sol.residuals, judged.keep);
  judged.n_eff =
      std::max(2.0, ctx.components * judged.sums.w * judged.sums.w / judged.sums.w2 / judged.c);
  return judged;
}

// Another fit's weighted sum of squares on the points `judged` keeps: models compared with each
// other are judged on the same points.
double RssOn(const Context& ctx, const Judged& judged, const Fit& fit) {
  return MaskedRss(ctx, fit.solution.residuals, fit.solution.valid, judged.keep);
}

// One candidate of a round: the current effects plus `effect`, fitted jointly, and its scores.
struct Candidate {
  Effect effect = Effect::kTimeOffset;
  Fit fit;  // moved into the loop's current fit when chosen
  // The effect's fitted value and the fit's residual, for the log (the chosen fit moves away).
  EffectValue value;
  double rms_px = 0.0;
  size_t kept = 0;       // the round's judged points
  size_t lost = 0;       // of them, those this candidate predicts nothing for
  bool predicts = true;  // false: it loses too many points to be a candidate (dbic infinite)
  double dbic = 0.0;     // against the current model (rule 2)
  double share = 0.0;    // of the residual's excess over the noise it explains
};

// The clock-rate rule choosing time_offset over the clock_rate that BIC chose.
struct RateOverrule {
  double rate_ppm = 0.0, rate_sd_ppm = 0.0;
  bool rate_significant = false;  // true: time_offset alone already leaves the noise
};

// The backward step's refit of the current effects without one of the earlier ones.
struct Removal {
  Effect effect = Effect::kTimeOffset;
  double rms_px = 0.0;
  double dbic = 0.0;  // the change of BIC removing it: it is dropped when below bic_margin
};

struct Round {
  int number = 0;
  std::vector<Candidate> candidates;
  int chosen = -1;    // index into candidates
  bool stop = false;  // no candidate qualifies (rule 2): the loop ends
  std::vector<RateOverrule> rate_overrules;
  std::vector<Effect> ambiguous;  // with the chosen one (rule 3)
  std::vector<Removal> removals;
  std::optional<Effect> dropped;  // by the backward step
  LevelTest level;                // the residual's level test after the round
};

// Rule 2's candidates: each effect neither added nor dropped, fitted jointly with the current ones
// (the new one starts at zero; FitHypothesis scans its start where the cost is not convex).
std::vector<Candidate> FitCandidates(const Context& ctx, const Fit& current,
                                     const std::vector<Effect>& candidates,
                                     const std::vector<Effect>& removed) {
  auto contains = [](const std::vector<Effect>& effects, Effect e) {
    return std::find(effects.begin(), effects.end(), e) != effects.end();
  };
  std::vector<Candidate> out;
  for (Effect effect : candidates) {
    if (contains(current.hypothesis.effects, effect) || contains(removed, effect)) continue;
    Hypothesis h = current.hypothesis;
    h.effects.push_back(effect);
    const int n_new = Spec(effect).parameter_count;
    h.x.conservativeResize(h.x.size() + n_new);
    h.x.tail(n_new).setZero();
    Candidate candidate;
    candidate.effect = effect;
    candidate.fit = FitHypothesis(ctx, std::move(h));
    candidate.value = Spec(effect).value(candidate.fit.model);
    candidate.rms_px = candidate.fit.stats.rms_px;
    out.push_back(std::move(candidate));
  }
  return out;
}

// Rule 2's scores: each candidate's dBIC against the current model and its share of the excess
// over the noise, every model judged on the same points (those the round's best candidate does not
// call gross outliers). Chooses the lowest dBIC among the candidates that explain enough; stops the
// loop when that does not lower BIC by bic_margin.
void ScoreRound(const Context& ctx, const LoopOptions& options, const Fit& current, Round* round) {
  std::vector<Candidate>& candidates = round->candidates;
  const Fit* best_fit = &candidates[0].fit;
  for (const Candidate& candidate : candidates) {
    if (candidate.fit.rss < best_fit->rss) best_fit = &candidate.fit;
  }
  const Judged best = Judge(ctx, *best_fit);
  const int p_cur = CriterionParameters(current.hypothesis.effects);
  const double rss_cur = RssOn(ctx, best, current);
  const double noise_rss = ctx.noise_sq * best.sums.w;
  const double excess_cur = std::max(0.0, rss_cur - noise_rss);
  for (size_t j = 0; j < candidates.size(); ++j) {
    Candidate& candidate = candidates[j];
    const int p_j = CriterionParameters(candidate.fit.hypothesis.effects);
    const double rss_j = RssOn(ctx, best, candidate.fit);
    candidate.dbic = (rss_j - rss_cur) / (best.s2 * best.c) + (p_j - p_cur) * std::log(best.n_eff);
    candidate.share =
        excess_cur > 0 ? (excess_cur - std::max(0.0, rss_j - noise_rss)) / excess_cur : 0.0;
    for (size_t i = 0; i < best.keep.size(); ++i) {
      candidate.kept += best.keep[i];
      candidate.lost += best.keep[i] && !candidate.fit.solution.valid[i];
    }
    // A model that predicts nothing for many points would be scored on the rest (MaskedRss
    // charges a lost point only the trimming level): it is no explanation of the data.
    if (candidate.lost > kMaxLostShare * candidate.kept) {
      candidate.predicts = false;
      candidate.dbic = std::numeric_limits<double>::infinity();
      candidate.share = 0.0;
      continue;
    }
    if (candidate.share >= options.min_explained_share &&
        (round->chosen < 0 || candidate.dbic < candidates[round->chosen].dbic)) {
      round->chosen = static_cast<int>(j);
    }
  }
  round->stop = round->chosen < 0 || candidates[round->chosen].dbic >= -options.bic_margin;
}

// clock_rate nests time_offset (its rate fixed at 0). The simpler offset is the explanation when
// the rate's own (cluster-robust) standard error cannot tell it from 0, or when the offset alone
// already leaves the residual at the noise level (rule 5's material test): BIC alone favours the
// rate when frame-coherent measurement errors make a drift look real (a 0.5 s clip "drifts" by a
// few hundred ppm on the measurement's own systematic error).
void ApplyClockRateRule(const Context& ctx, const LoopOptions& options, Round* round) {
  std::vector<Candidate>& candidates = round->candidates;
  if (candidates[round->chosen].effect != Effect::kClockRate) return;
  for (size_t j = 0; j < candidates.size(); ++j) {
    const Candidate& offset = candidates[j];
    if (offset.effect != Effect::kTimeOffset || offset.share < options.min_explained_share ||
        offset.dbic >= -options.bic_margin) {
      continue;
    }
    const Fit& rate_fit = candidates[round->chosen].fit;
    const Eigen::Index rate_index = rate_fit.solution.x.size() - 2;
    const double rate_sd = std::sqrt(Covariance(ctx, rate_fit)(rate_index, rate_index));
    const double rate = rate_fit.solution.x[rate_index];
    if (!(std::abs(rate) > kRateSignificance * rate_sd)) {
      round->rate_overrules.push_back({rate, rate_sd, /*rate_significant=*/false});
      round->chosen = static_cast<int>(j);
    } else if (!Material(ctx, options,
                         TestLevel(ctx, offset.fit.solution.residuals, offset.fit.solution.valid,
                                   options.significance))) {
      round->rate_overrules.push_back({rate, rate_sd, /*rate_significant=*/true});
      round->chosen = static_cast<int>(j);
    }
  }
}

// Rule 3: the other candidates within ambiguity_margin of the chosen one's dBIC that explain
// enough as well.
std::vector<Effect> FindAmbiguous(const LoopOptions& options, const Round& round) {
  const Candidate& chosen = round.candidates[round.chosen];
  std::vector<Effect> ambiguous;
  for (size_t j = 0; j < round.candidates.size(); ++j) {
    if (static_cast<int>(j) == round.chosen) continue;
    const Candidate& other = round.candidates[j];
    // clock_rate holds time_offset (rate and offset): when the offset alone is chosen, the rate
    // fitted to ~0 beside it is the same explanation, not another one.
    if (chosen.effect == Effect::kTimeOffset && other.effect == Effect::kClockRate) continue;
    if (other.dbic - chosen.dbic < options.ambiguity_margin &&
        other.share >= options.min_explained_share) {
      ambiguous.push_back(other.effect);
    }
  }
  return ambiguous;
}

// Rule 4, the backward step (stepwise selection): an effect added earlier may be redundant now (a
// readout error first absorbed by a gyro scale, say). Refits without each earlier effect and drops
// the one whose removal costs least if that is less than bic_margin: *current becomes that refit.
// Returns the dropped effect's index in the effects before the step, or -1.
int TryDropOne(const Context& ctx, const LoopOptions& options, Fit* current, Round* round) {
  const std::vector<Effect> effects = current->hypothesis.effects;
  if (effects.size() < 2) return -1;
  const Judged now = Judge(ctx, *current);
  int drop = -1;
  double drop_dbic = options.bic_margin;
  Fit drop_fit;
  for (size_t k = 0; k + 1 < effects.size(); ++k) {
    Hypothesis h;
    int offset = 0;
    for (size_t m = 0; m < effects.size(); ++m) {
      const int n = Spec(effects[m]).parameter_count;
      if (m != k) {
        h.effects.push_back(effects[m]);
        h.x.conservativeResize(h.x.size() + n);
        h.x.tail(n) = current->hypothesis.x.segment(offset, n);
      }
      offset += n;
    }
    // Keep the just-added effect last (its start is the current value, no scan needed).
    Fit without = FitHypothesis(ctx, std::move(h));
    const double dbic_remove = (RssOn(ctx, now, without) - now.rss) / (now.s2 * now.c) -
                               std::max(1, Spec(effects[k]).parameter_count) * std::log(now.n_eff);
    round->removals.push_back({effects[k], without.stats.rms_px, dbic_remove});
    if (dbic_remove < drop_dbic) {
      drop_dbic = dbic_remove;
      drop = static_cast<int>(k);
      drop_fit = std::move(without);
    }
  }
  if (drop < 0) return -1;
  round->dropped = effects[drop];
  *current = std::move(drop_fit);
  return drop;
}

// The level test's line: "<what>: rms ... (trimmed), ...: above the noise / at the noise level".
std::string LevelLine(const std::string& what, const LevelTest& t, double significance) {
  return what + ": rms " + FormatNumber("%.4f", t.rms_px) + " px (trimmed), mean square " +
         FormatNumber("%.3f", t.ratio) + "x noise^2, threshold " +
         FormatNumber("%.3f", t.threshold) + " (alpha " + FormatNumber("%g", significance) +
         ", correlation factor " + FormatNumber("%.2f", t.c) +
         "): " + (t.above ? "above the noise" : "at the noise level");
}

// A round's log lines, in the order of its steps: the candidates, then either the stop or the
// clock-rate rule, the addition with its ambiguities, the backward step and the new level.
void LogRound(const Round& round, const LoopOptions& options, std::vector<std::string>* log) {
  const std::string at = "round " + std::to_string(round.number) + ": ";
  for (const Candidate& c : round.candidates) {
    const std::string& name = Spec(c.effect).name;
    const std::string fitted = name + " = " + EffectValueText(c.value);
    if (!c.predicts) {
      log->push_back(at + name + ": predicts " + std::to_string(c.kept - c.lost) + " of " +
                     std::to_string(c.kept) + " points; " + fitted + "; not a candidate");
      continue;
    }
    log->push_back(at + name + ": rms " + FormatNumber("%.4f", c.rms_px) + " px, dBIC " +
                   FormatNumber("%.1f", c.dbic) + ", explains " +
                   FormatNumber("%.1f", 100.0 * c.share) + " % of the excess; " + fitted);
  }
  if (round.stop) {
    log->push_back(at + "no candidate lowers BIC by " + FormatNumber("%g", options.bic_margin) +
                   " while explaining " + FormatNumber("%g", 100.0 * options.min_explained_share) +
                   " % of the excess; stop");
    return;
  }
  for (const RateOverrule& o : round.rate_overrules) {
    log->push_back(at + "clock_rate's rate is " + FormatNumber("%.3g", o.rate_ppm) + " +- " +
                   FormatNumber("%.3g", o.rate_sd_ppm) + " ppm" +
                   (o.rate_significant ? ", but time_offset alone leaves the noise: time_offset"
                                       : ", not significant: time_offset"));
  }
  const std::string& added = Spec(round.candidates[round.chosen].effect).name;
  std::string line = at + "added " + added;
  for (Effect a : round.ambiguous) line += " (ambiguous with " + Spec(a).name + ")";
  log->push_back(line);
  for (const Removal& r : round.removals) {
    log->push_back(at + "without " + Spec(r.effect).name + ": rms " +
                   FormatNumber("%.4f", r.rms_px) + " px, dBIC " + FormatNumber("%+.1f", r.dbic));
  }
  if (round.dropped)
    log->push_back(at + "dropped " + Spec(*round.dropped).name + " (redundant now)");
  log->push_back(LevelLine("with " + added, round.level, options.significance));
}

// The candidates tried: options.candidates, or every effect.
std::vector<Effect> CandidateEffects(const LoopOptions& options) {
  std::vector<Effect> candidates = options.candidates;
  if (candidates.empty()) {
    for (const EffectSpec& spec : AllEffects()) candidates.push_back(spec.effect);
  }
  return candidates;
}

// What the loop keeps per effect of its current fit: the residual once it was added (or once the
// backward step dropped an earlier one) and what it was ambiguous with then.
struct Added {
  ResidualStats after;
  std::vector<Effect> ambiguous_with;
};

// The loop's result from its final joint fit: values and standard errors, residuals, and the
// verdict of rule 5 on `level`, the final residual's level test.
void Conclude(const Context& ctx, const LoopOptions& options, const Fit& current,
              const std::vector<Added>& added, const LevelTest& level,
              const PointPredictor& predictor, LoopResult* result) {
  result->effects = IdentifiedEffects(ctx, current);
  for (size_t k = 0; k < result->effects.size(); ++k) {
    result->effects[k].ambiguous_with = added[k].ambiguous_with;
    result->effects[k].after = added[k].after;
  }
  result->after = current.stats;
  result->model = current.model;
  result->residuals_after = PointResiduals(current);
  if (options.pair_translation) {  // the directions of the final model, not of a trial step
    std::vector<Eigen::Vector2d> unused;
    predictor.Predict(current.model, &unused);
    result->pair_translation_dirs = predictor.translation_dirs();
  }
  result->unexplained = Material(ctx, options, level);
  result->log.push_back(std::string("unexplained: ") + (result->unexplained ? "yes" : "no"));
}

}  // namespace

LoopResult CloseTheLoop(const RigModel& declared, const GyroTrace& gyro,
                        const std::vector<FramePoints>& frames, double noise_px,
                        const LoopOptions& options) {
  TrueModel start;
  start.rig = declared;
  return CloseTheLoop(start, gyro, frames, noise_px, options);
}

LoopResult CloseTheLoop(const TrueModel& declared, const GyroTrace& gyro,
                        const std::vector<FramePoints>& frames, double noise_px,
                        const LoopOptions& options) {
  LoopResult result;
  Start start = Begin(declared, gyro, frames, noise_px, options, &result);
  const Context& ctx = start.ctx;
  Fit current = std::move(start.declared);
  const std::vector<Effect> candidates = CandidateEffects(options);
  LevelTest level =
      TestLevel(ctx, current.solution.residuals, current.solution.valid, options.significance);
  result.log.push_back(LevelLine("declared model", level, options.significance));
  result.above_noise_before = level.above;

  std::vector<Added> added;     // one per effect of current, in its order
  std::vector<Effect> removed;  // dropped by the backward step; not tried again
  for (int number = 1; Material(ctx, options, level) &&
                       static_cast<int>(current.hypothesis.effects.size()) < options.max_effects &&
                       number <= 2 * options.max_effects;
       ++number) {
    Round round;
    round.number = number;
    round.candidates = FitCandidates(ctx, current, candidates, removed);
    if (round.candidates.empty()) break;
    ScoreRound(ctx, options, current, &round);
    if (round.stop) {
      LogRound(round, options, &result.log);
      break;
    }
    ApplyClockRateRule(ctx, options, &round);
    round.ambiguous = FindAmbiguous(options, round);
    current = std::move(round.candidates[round.chosen].fit);
    added.push_back({current.stats, round.ambiguous});
    const int dropped = TryDropOne(ctx, options, &current, &round);
    if (dropped >= 0) {
      removed.push_back(*round.dropped);
      added.erase(added.begin() + dropped);
      added.back().after = current.stats;
    }
    level = round.level =
        TestLevel(ctx, current.solution.residuals, current.solution.valid, options.significance);
    LogRound(round, options, &result.log);
  }
  Conclude(ctx, options, current, added, level, *start.predictor, &result);
  return result;
}

LoopResult FitEffects(const RigModel& declared, const GyroTrace& gyro,
                      const std::vector<FramePoints>& frames, double noise_px,
                      const std::vector<Effect>& effects, const LoopOptions& options) {
  TrueModel start;
  start.rig = declared;
  return FitEffects(start, gyro, frames, noise_px, effects, options);
}

LoopResult FitEffects(const TrueModel& declared, const GyroTrace& gyro,
                      const std::vector<FramePoints>& frames, double noise_px,
                      const std::vector<Effect>& effects, const LoopOptions& options) {
  LoopResult result;
  Start start = Begin(declared, gyro, frames, noise_px, options, &result);
  const Context& ctx = start.ctx;
  Fit current = std::move(start.declared);
  // One effect at a time, as the loop adds them, so each gets the loop's start (scans, axes).
  for (Effect effect : effects) {
    Hypothesis h = current.hypothesis;
    h.effects.push_back(effect);
    const int n = Spec(effect).parameter_count;
    h.x.conservativeResize(h.x.size() + n);
    h.x.tail(n).setZero();
    current = FitHypothesis(ctx, std::move(h));
    result.log.push_back("fitted " + Describe(current.hypothesis.effects, current.model) +
                         ": rms " + FormatNumber("%.4f", current.stats.rms_px) + " px");
  }
  result.effects = IdentifiedEffects(ctx, current);
  const LevelTest level =
      TestLevel(ctx, current.solution.residuals, current.solution.valid, options.significance);
  result.after = current.stats;
  result.model = current.model;
  result.residuals_after = PointResiduals(current);
  result.unexplained = Material(ctx, options, level);
  return result;
}

std::vector<Effect> EffectsOf(const LoopResult& loop) {
  std::vector<Effect> effects;
  for (const IdentifiedEffect& e : loop.effects) effects.push_back(e.effect);
  return effects;
}

void WithholdUncalibratedStderr(FitModel model, LoopResult* loop) {
  for (IdentifiedEffect& e : loop->effects) {
    const EffectSpec& spec = Spec(e.effect);
    const std::vector<FitModel>& fails = spec.stderr_fails_in;
    if (spec.parameter_count == 0 || std::find(fails.begin(), fails.end(), model) == fails.end())
      continue;
    const int n = spec.parameter_count;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    // Everything a standard error could be drawn from (correct draws its uncertainty from the
    // covariance), not only the value's.
    e.covariance = Eigen::MatrixXd::Constant(n, n, nan);
    e.stderr_value = EffectStderr(e.effect, loop->model, e.covariance);
    for (Eigen::VectorXd* v :
         {&e.parameter_stderr_model, &e.parameter_stderr_sandwich, &e.parameter_stderr_jackknife}) {
      v->setConstant(nan);
    }
    e.stderr_withheld = std::string("the ") + FitModelName(model) + " model's standard error of " +
                        spec.name + " does not hold: docs/validation.md, Every effect, every model";
  }
}

}  // namespace shutterlab
