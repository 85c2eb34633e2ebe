#include "estimate/loop/validate_video.h"

#include "estimate/loop/claims_io.h"
#include "estimate/loop/effect_model.h"
#include "estimate/loop/frame_residuals.h"
#include "io/image_io.h"
#include "sim/check.h"
#include "sim/so3.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <opencv2/core/utility.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>
#include <sstream>

namespace shutterlab {
namespace {

// A pair whose flow matches less than this share of the pixels is left out: the images barely
// overlap or the flow failed, and the few points that pass are outliers that would dominate the
// residual (seen on a 5 fps clip: 2 of about 1,100 grid points, 75 px off).
constexpr double kMinPairMeasuredShare = 0.05;

namespace fs = std::filesystem;

// 99 % quantiles of chi-square with 1, 2, 3 degrees of freedom: two fits of an effect on disjoint
// halves agree when their difference, in the metric of the sum of their covariances, is below.
constexpr double kChi2Quantile99[4] = {0.0, 6.635, 9.210, 11.345};
// A source's scalar claim holds when the fitted value is within this many standard errors of it.
constexpr double kClaimSigmas = 3.0;
// Translation is the preferred model when the rotation-only residual stays above the noise and
// translation removes at least this share of its excess.
constexpr double kPreferTranslationShare = 0.5;

// The two halves' fits of one effect against each other.
HalfAgreement CompareHalves(const IdentifiedEffect& a, const IdentifiedEffect& b) {
  HalfAgreement out;
  out.effect = a.effect;
  out.first = a.value;
  out.first_stderr = a.stderr_value;
  out.second = b.value;
  out.second_stderr = b.stderr_value;
  const Eigen::Index n = a.parameters.size();
  if (n == 0) {  // readout_direction: a discrete choice
    out.agree = a.value == b.value;
    out.distance = out.agree ? 0.0 : std::numeric_limits<double>::infinity();
    return out;
  }
  // Both halves start from the same declared model, so their parameters (deltas from it; for
  // gyro_to_camera a rotation vector on the same side of the same R_CG) compare directly.
  const Eigen::VectorXd d = a.parameters - b.parameters;
  const Eigen::MatrixXd c = a.covariance + b.covariance;
  if (!d.allFinite() || !c.allFinite()) {
    out.determined = out.agree = false;
    out.distance = std::numeric_limits<double>::quiet_NaN();
    return out;
  }
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(c);
  double d2 = std::numeric_limits<double>::infinity();
  if (lu.isInvertible()) d2 = d.dot(lu.solve(d));
  out.distance = std::sqrt(std::max(0.0, d2));
  out.agree = d2 < kChi2Quantile99[std::min<Eigen::Index>(n, 3)];
  return out;
}

// The signed permutation nearest to a rotation: each row's largest entry, rounded to +-1.
Eigen::Matrix3d NearestAxes(const Eigen::Matrix3d& r) {
  Eigen::Matrix3d out = Eigen::Matrix3d::Zero();
  for (int row = 0; row < 3; ++row) {
    Eigen::Index col;
    r.row(row).cwiseAbs().maxCoeff(&col);
    out(row, col) = r(row, col) < 0 ? -1.0 : 1.0;
  }
  return out;
}

double AngleDeg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return AngularDistance(Eigen::Quaterniond(a), Eigen::Quaterniond(b)) * 180.0 / M_PI;
}

std::string MatrixText(const Eigen::Matrix3d& m) {
  std::string out = "[";
  for (int r = 0; r < 3; ++r) {
    out += r ? ", [" : "[";
    for (int c = 0; c < 3; ++c) out += (c ? "," : "") + FormatNumber("%g", m(r, c));
    out += "]";
  }
  return out + "]";
}

// Mean squares per residual component of two sets of per-point residuals over the same points:
// weighted points where both predict, less the kCompareTrimShare largest of either (moving objects,
// bad matches), px^2.
struct TrimmedComparison {
  double a = 0.0, b = 0.0;
  size_t points = 0;
};
TrimmedComparison CompareTrimmed(const std::vector<FramePoints>& pairs,
                                 const std::vector<Eigen::Vector2d>& a, int a_components,
                                 const std::vector<Eigen::Vector2d>& b, int b_components) {
  std::vector<double> sq_a, sq_b;
  size_t at = 0;
  for (const FramePoints& f : pairs) {
    for (const MeasuredPoint& p : f.points) {
      if (p.weight > 0 && a[at].allFinite() && b[at].allFinite()) {
        sq_a.push_back(a[at].squaredNorm() / a_components);
        sq_b.push_back(b[at].squaredNorm() / b_components);
      }
      ++at;
    }
  }
  TrimmedComparison out;
  if (sq_a.empty()) return out;
  const auto cut = [](std::vector<double> v) {
    const size_t k =
        std::min(v.size() - 1, static_cast<size_t>((1.0 - kCompareTrimShare) * v.size()));
    std::nth_element(v.begin(), v.begin() + k, v.end());
    return v[k];
  };
  const double cut_a = cut(sq_a), cut_b = cut(sq_b);
  for (size_t i = 0; i < sq_a.size(); ++i) {
    if (sq_a[i] > cut_a || sq_b[i] > cut_b) continue;
    out.a += sq_a[i];
    out.b += sq_b[i];
    ++out.points;
  }
  if (out.points > 0) {
    out.a /= out.points;
    out.b /= out.points;
  }
  return out;
}

// Share of a's excess over the noise (mean square per component) that b removes, in [0, 1]; when a
// is within the noise, what b removes is measured against the noise itself (a below-noise residual
// has no excess, and moving it by a sliver of the noise decides nothing).
double ExplainedShare(const TrimmedComparison& c, double noise_px) {
  const double noise_mean_sq_px2 = noise_px * noise_px / 2.0;
  const double excess = c.a - noise_mean_sq_px2;
  if (excess > noise_mean_sq_px2)
    return std::clamp((c.a - std::max(noise_mean_sq_px2, c.b)) / excess, 0.0, 1.0);
  return std::clamp((c.a - c.b) / noise_mean_sq_px2, 0.0, 1.0);
}

// The loop's rule for candidates (effect_fit.cc): one that loses more than this share of the points
// is not considered; the same for the axis mappings a gyro_to_camera claim is tested against.
constexpr double kMaxMappingLostShare = 0.01;

// Below this share of the residual's excess that the best value removes, the data do not pin a
// claim down: it is reported as not determined rather than held or contradicted.
constexpr double kMinClaimShare = 0.1;

// What the claims are tested against: the data, and both models with where their loops started.
struct ClaimInputs {
  const GyroTrace& gyro;
  // The pairs as each model's loop used them (the points the screening left out at weight 0).
  const std::vector<FramePoints>& pairs;  // the preferred model's
  const std::vector<FramePoints>& rotation_pairs;
  double noise_px;
  const TrueModel& preferred_start;
  const LoopResult& preferred;
  const LoopOptions& preferred_options;
  const TrueModel& rotation_start;
  const LoopResult& rotation;
  const LoopOptions& rotation_options;
};

// Fits shared between claims (the model's own effects are every claim's "without"), by
// (by_rotation, effects): each is fitted once.
using ClaimFits = std::map<std::pair<bool, std::vector<Effect>>, LoopResult>;

// The claimed gyro axes against the best other of the 24 mappings, rotation-only mean squares per
// component over the points both predict, px^2.
struct AxesComparison {
  double claimed_mean_sq_px2 = 0.0;
  double other_mean_sq_px2 = std::numeric_limits<double>::infinity();
  Eigen::Matrix3d other;
};

// The measured flow less the rotation-only model's prediction with the rotation loop's model and
// the given mounting, per point of the pairs.
std::vector<Eigen::Vector2d> MappingResiduals(const ClaimInputs& in, PointPredictor* predictor,
                                              const Eigen::Matrix3d& cam_from_gyro) {
  TrueModel model = in.rotation.model;
  model.rig.cam_from_gyro = cam_from_gyro;
  std::vector<Eigen::Vector2d> predicted;
  predictor->Predict(model, &predicted);
  std::vector<Eigen::Vector2d> r(predicted.size());
  size_t at = 0;
  for (const FramePoints& f : in.rotation_pairs) {
    for (const MeasuredPoint& p : f.points) {
      r[at] = Eigen::Vector2d(p.dx, p.dy) - predicted[at];
      ++at;
    }
  }
  return r;
}

// The claimed axes against the best other mapping of the 24, each pair of them over the points
// both predict (CompareTrimmed: mean square per component, the largest of either left out). A
// mapping that sends more than kMaxMappingLostShare of the claimed one's points out of the frame,
// where the measurement found them inside, is out.
AxesComparison CompareAxisMappings(const ClaimInputs& in, const Eigen::Matrix3d& claimed) {
  const std::unique_ptr<PointPredictor> predictor =
      MakePredictor(in.gyro, in.rotation_pairs, /*pair_translation=*/false, 1.0);
  const std::vector<Eigen::Vector2d> r_claimed = MappingResiduals(in, predictor.get(), claimed);
  std::vector<double> weights;
  for (const FramePoints& f : in.rotation_pairs) {
    for (const MeasuredPoint& p : f.points) weights.push_back(p.weight);
  }
  size_t claimed_points = 0;
  for (size_t i = 0; i < r_claimed.size(); ++i) {
    claimed_points += weights[i] > 0 && r_claimed[i].allFinite();
  }
  AxesComparison out;
  out.claimed_mean_sq_px2 = CompareTrimmed(in.rotation_pairs, r_claimed, 2, r_claimed, 2).a;
  out.other = claimed;
  const Eigen::Matrix3d claimed_axes = NearestAxes(claimed);
  for (const Eigen::Matrix3d& axes : AxisRotations()) {  // signed permutations already
    if (axes == claimed_axes) continue;
    const std::vector<Eigen::Vector2d> r = MappingResiduals(in, predictor.get(), axes);
    size_t lost = 0;
    for (size_t i = 0; i < r.size(); ++i) {
      lost += weights[i] > 0 && r_claimed[i].allFinite() && !r[i].allFinite();
    }
    if (lost > kMaxMappingLostShare * static_cast<double>(claimed_points)) continue;
    const TrimmedComparison c = CompareTrimmed(in.rotation_pairs, r_claimed, 2, r, 2);
    if (c.points == 0 || !(c.a > 0)) continue;
    if (!std::isfinite(out.other_mean_sq_px2) ||
        c.b / c.a < out.other_mean_sq_px2 / out.claimed_mean_sq_px2) {
      out.claimed_mean_sq_px2 = c.a;
      out.other_mean_sq_px2 = c.b;
      out.other = axes;
    }
  }
  return out;
}

// gyro_to_camera: the rotation-only residual of each of the 24 axis mappings against the claimed
// one's.
void CheckAxesClaim(const ClaimInputs& in, ClaimCheck* check) {
  const Eigen::Matrix3d claimed = std::get<Eigen::Matrix3d>(check->claimed);
  const AxesComparison axes = CompareAxisMappings(in, claimed);
  const bool claimed_best = axes.claimed_mean_sq_px2 <= axes.other_mean_sq_px2;
  check->found = claimed_best ? NearestAxes(claimed) : axes.other;
  check->difference = claimed_best ? 0.0 : AngleDeg(axes.other, claimed);
  // How much of the worse one's excess over the noise the better one removes.
  const double margin = ExplainedShare(
      claimed_best ? TrimmedComparison{axes.other_mean_sq_px2, axes.claimed_mean_sq_px2, 1}
                   : TrimmedComparison{axes.claimed_mean_sq_px2, axes.other_mean_sq_px2, 1},
      in.noise_px);
  const std::string numbers =
      "rotation-only rms per component " +
      FormatNumber("%.3f", std::sqrt(axes.claimed_mean_sq_px2)) + " px with the claimed axes, " +
      FormatNumber("%.3f", std::sqrt(axes.other_mean_sq_px2)) +
      " px with the best other of the 24 mappings " + MatrixText(axes.other) + " (" +
      FormatNumber("%.0f", 100 * margin) + " % of the worse one's excess)";
  if (margin < kMinClaimShare) {
    check->verdict = "not determined: " + numbers;
  } else {
    check->verdict = (claimed_best ? "claim holds: " : "claim contradicted: ") + numbers;
  }
}

// direction, a discrete claim: the model read as declared (c.a, without) and flipped (c.b, with).
void CheckDirectionClaim(const TrimmedComparison& c, const RigModel& declared, double noise_px,
                         ClaimCheck* check) {
  const ReadoutDirection other = declared.shutter.direction == ReadoutDirection::kTopToBottom
                                     ? ReadoutDirection::kBottomToTop
                                     : ReadoutDirection::kTopToBottom;
  const std::string declared_word = ReadoutDirectionName(declared.shutter.direction);
  const std::string other_word = ReadoutDirectionName(other);
  const bool flip_better = c.b < c.a;
  check->found = flip_better ? other : declared.shutter.direction;
  // How much of the worse reading's excess over the noise the better one removes.
  const double margin =
      ExplainedShare(flip_better ? c : TrimmedComparison{c.b, c.a, c.points}, noise_px);
  const std::string numbers =
      "rms per component " + FormatNumber("%.4f", std::sqrt(c.a)) + " px read " + declared_word +
      ", " + FormatNumber("%.4f", std::sqrt(c.b)) + " px read " + other_word + " (" +
      FormatNumber("%.0f", 100 * margin) + " % of the worse reading's excess)";
  if (margin < kMinClaimShare) {
    check->verdict = "not determined: " + numbers;
  } else {
    check->verdict =
        (check->found == check->claimed ? "claim holds: " : "claim contradicted: ") + numbers;
  }
}

// A scalar claim (readout_s, time_offset_s): the effect as fitted in `with` against the claim in
// standard errors; `share` is how much of the residual fitting it removes, `removes` that in words.
// False when `with` has no number for the effect (the claim is then not reported).
bool CheckScalarClaim(const LoopResult& with, double share, const std::string& removes,
                      ClaimCheck* check) {
  const IdentifiedEffect* effect = nullptr;
  for (const IdentifiedEffect& e : with.effects) {
    if (e.effect == check->effect) effect = &e;
  }
  const double* claimed_value = std::get_if<double>(&check->claimed);
  const double* found_value = effect ? std::get_if<double>(&effect->value) : nullptr;
  if (claimed_value == nullptr || found_value == nullptr) return false;
  check->found = effect->value;
  check->found_stderr = effect->stderr_value;
  const double claimed = *claimed_value, found = *found_value;
  const double* se_value = std::get_if<double>(&effect->stderr_value);
  const double se = se_value ? *se_value : std::numeric_limits<double>::quiet_NaN();
  check->difference = std::abs(found - claimed) / se;
  const std::string numbers =
      FormatNumber("%.3f", found * 1e3) + " +- " + FormatNumber("%.3f", se * 1e3) + " ms against " +
      FormatNumber("%.3f", claimed * 1e3) + " ms (" + FormatNumber("%.1f", check->difference) +
      " standard errors); " + removes;
  if (!std::isfinite(se)) {
    check->verdict = "not determined (no standard error): " + numbers;
  } else if (check->difference <= kClaimSigmas) {
    check->verdict = "claim holds: " + numbers;
  } else if (share < kMinClaimShare) {
    check->verdict = "not determined: " + numbers;
  } else {
    check->verdict = "claim contradicted: " + numbers;
  }
  return true;
}

// A fitted claim (scalars, direction): tested by the preferred model, or by the rotation-only one
// where the pair translation cannot tell the effect
// (EffectSpec::identifiable_with_pair_translation), with the effect fitted beside the model's
// identified ones and without it. False when the claim is not reported.
bool CheckFittedClaim(const ClaimInputs& in, ClaimFits* fits, ClaimCheck* check) {
  const Effect tested = check->effect;
  const bool by_rotation =
      in.preferred_options.pair_translation && !Spec(tested).identifiable_with_pair_translation;
  const LoopOptions& loop_options = by_rotation ? in.rotation_options : in.preferred_options;
  std::vector<Effect> base;
  for (Effect e : EffectsOf(by_rotation ? in.rotation : in.preferred)) {
    if (e != tested) base.push_back(e);
  }
  std::vector<Effect> with_effect = base;
  with_effect.push_back(tested);
  const TrueModel& start = by_rotation ? in.rotation_start : in.preferred_start;
  const std::vector<FramePoints>& pairs = by_rotation ? in.rotation_pairs : in.pairs;
  const auto fit = [&](const std::vector<Effect>& effects) -> const LoopResult& {
    const auto key = std::make_pair(by_rotation, effects);
    auto it = fits->find(key);
    if (it == fits->end()) {
      it = fits->emplace(key, FitEffects(start, in.gyro, pairs, in.noise_px, effects, loop_options))
               .first;
    }
    return it->second;
  };
  const LoopResult& without = fit(base);
  const LoopResult& with = fit(with_effect);
  const TrimmedComparison c =
      CompareTrimmed(pairs, without.residuals_after, without.residual_components,
                     with.residuals_after, with.residual_components);
  if (tested == Effect::kReadoutDirection) {
    CheckDirectionClaim(c, in.rotation_start.rig, in.noise_px, check);
    return true;
  }
  const double share = ExplainedShare(c, in.noise_px);
  const std::string removes = "fitting it removes " + FormatNumber("%.0f", 100 * share) +
                              " % of the residual's excess over the noise";
  return CheckScalarClaim(with, share, removes, check);
}

// A claim is tested by the preferred model, or by the rotation-only one where the pair translation
// cannot tell the effect (EffectSpec::identifiable_with_pair_translation). Scalars (readout_s,
// time_offset_s): the effect fitted beside the model's identified ones, against the claim in
// standard errors, and how much of the residual fitting it removes. direction: both readings.
// gyro_to_camera: the rotation- only residual of each of the 24 axis mappings against the claimed
// one's. Each model's fits start where its loop started (preferred_start, rotation_start).
std::vector<ClaimCheck> CheckClaims(const std::vector<SourceClaim>& claims, const ClaimInputs& in) {
  std::vector<ClaimCheck> checks;
  ClaimFits fits;
  for (const SourceClaim& claim : claims) {
    ClaimCheck check;
    check.claim = claim.what;
    check.effect = claim.effect;
    check.status = claim.status;
    check.claimed = claim.value;
    if (claim.effect == Effect::kGyroToCamera) {
      CheckAxesClaim(in, &check);
    } else if (!CheckFittedClaim(in, &fits, &check)) {
      continue;
    }
    checks.push_back(std::move(check));
  }
  return checks;
}

// What every step of a video dataset's validation reads.
struct VideoInputs {
  fs::path dir;
  std::string frames_path;  // for messages
  const GyroTrace& gyro;
  const std::vector<FrameEntry>& entries;
  const ValidateOptions& options;
  const ValidateProgress& progress;
};

// Frames in time order, as indices into the entries (frames.csv line numbers kept for messages:
// entry i is line i + 2); two frames at the same time, or fewer than two, are an error.
std::vector<size_t> FramesInTimeOrder(const VideoInputs& in) {
  const std::vector<FrameEntry>& entries = in.entries;
  std::vector<size_t> order(entries.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return entries[a].t_first_row_ns < entries[b].t_first_row_ns;
  });
  for (size_t k = 1; k < order.size(); ++k) {
    if (entries[order[k]].t_first_row_ns == entries[order[k - 1]].t_first_row_ns) {
      throw IoError(IoMessage(in.frames_path, static_cast<long>(order[k]) + 2,
                              "frame " + std::to_string(entries[order[k]].frame) +
                                  " has the same t_first_row as frame " +
                                  std::to_string(entries[order[k - 1]].frame)));
    }
  }
  if (order.size() < 2) {
    throw IoError(IoMessage(in.frames_path, 0, "a video dataset needs at least two frames"));
  }
  return order;
}

// Whether a frame's declared readout lies inside the gyro log.
bool ReadoutInsideGyro(const RigModel& rig, const GyroTrace& gyro, const FrameEntry& e) {
  const int64_t t0 = e.t_first_row_ns + SecondsToNs(rig.time_offset_s);
  return t0 >= gyro.t_begin_ns() && t0 + SecondsToNs(rig.shutter.readout_s) <= gyro.t_end_ns();
}

// A frame's image, of the size camera.json declares (`line`: its frames.csv line).
cv::Mat ReadFrameImage(const VideoInputs& in, const RigModel& rig, const FrameEntry& entry,
                       long line) {
  cv::Mat image = ReadImage((in.dir / entry.image).string());
  if (image.cols != rig.camera.width || image.rows != rig.camera.height) {
    throw IoError(IoMessage(in.frames_path, line,
                            "image '" + entry.image + "' is " + std::to_string(image.cols) + "x" +
                                std::to_string(image.rows) + ", camera.json declares " +
                                std::to_string(rig.camera.width) + "x" +
                                std::to_string(rig.camera.height)));
  }
  return image;
}

// At most `max` of the points, spread evenly over them (every k-th in grid order, k fractional).
void ThinEvenly(size_t max, std::vector<MeasuredPoint>* points) {
  if (points->size() <= max) return;
  std::vector<MeasuredPoint> kept;
  kept.reserve(max);
  const double stride = static_cast<double>(points->size()) / max;
  for (size_t i = 0; i < max; ++i) kept.push_back((*points)[static_cast<size_t>(i * stride)]);
  *points = std::move(kept);
}

// One pair's measurement, or why it has none (skip non-empty).
struct PairMeasurement {
  DisplacementMeasurement measured;
  std::string skip;
};

// Frame `entry` against the earlier one (previous): the flow from the later frame's pixel p to
// the earlier frame is q - p (the earlier frame is the "reference").
PairMeasurement MeasureOnePair(const VideoInputs& in, const RigModel& rig,
                               const FrameEntry& earlier, const cv::Mat& previous,
                               const FrameEntry& entry, const cv::Mat& image, size_t max_points) {
  PairMeasurement out;
  if (!ReadoutInsideGyro(rig, in.gyro, earlier) || !ReadoutInsideGyro(rig, in.gyro, entry)) {
    out.skip = "a readout lies outside the gyro log";
    return out;
  }
  MeasureOptions measure = in.options.measure;
  measure.frame_distortion = false;  // D of a flow between two frames means nothing
  measure.dense_field = false;       // only the points are used
  measure.corner_tracks = in.options.screen.camera_fixed;
  out.measured = MeasureDisplacement(previous, image, measure);
  if (out.measured.points.empty()) {
    out.skip = "no point could be measured";
  } else if (out.measured.measured_fraction < kMinPairMeasuredShare) {
    out.skip = "the flow matched only " +
               FormatNumber("%.1f", 100 * out.measured.measured_fraction) +
               " % of the pixels (too little overlap to measure)";
  }
  ThinEvenly(max_points, &out.measured.points);
  return out;
}

// A measured pair into the result (its row in result->frames, its points in *pairs), or its
// reason into result->skipped.
void AddPair(const FrameEntry& earlier, const FrameEntry& entry, PairMeasurement m,
             std::vector<FramePoints>* pairs, ValidationResult* result) {
  if (!m.skip.empty()) {
    result->skipped.push_back("pair " + std::to_string(earlier.frame) + " -> " +
                              std::to_string(entry.frame) + ": " + m.skip);
    return;
  }
  FrameValidation f;
  f.frame = entry.frame;
  f.previous = earlier.frame;
  f.image = entry.image;
  f.t_gyro_s = entry.t_first_row_ns * 1e-9 + result->declared.time_offset_s;
  f.points = m.measured.points.size();
  f.measured_fraction = m.measured.measured_fraction;
  f.noise_px = m.measured.noise_px;
  result->frames.push_back(std::move(f));
  FramePoints points;
  points.frame = entry.frame;
  points.t_first_row_ns = entry.t_first_row_ns;
  points.points = std::move(m.measured.points);
  points.tracks = std::move(m.measured.tracks);
  points.earlier = EarlierFrame{earlier.frame, earlier.t_first_row_ns};
  pairs->push_back(std::move(points));
}

// Every pair of consecutive frames (in time order): frame k against frame k-1. None measured is
// an error. Frames are read and pairs measured a chunk at a time, the chunk's pairs in parallel
// (each measurement on one thread: a few pairs at once use the cores better than one flow split
// over them), keeping only the chunk's images in memory; the result is the same whatever the
// thread count.
std::vector<FramePoints> MeasurePairs(const VideoInputs& in, const std::vector<size_t>& order,
                                      ValidationResult* result) {
  std::vector<FramePoints> pairs;
  const size_t pair_total = order.size() - 1;
  const size_t chunk = std::max<size_t>(2, 2 * static_cast<size_t>(cv::getNumThreads()));
  const RigModel& rig = result->declared;
  // ValidateOptions::max_points_per_pair and max_video_points.
  constexpr size_t kMinPointsPerPair = 100;
  const size_t max_points = std::min(
      in.options.max_points_per_pair,
      std::max(kMinPointsPerPair, in.options.max_video_points / std::max<size_t>(1, pair_total)));
  cv::Mat previous;  // the last image of the previous chunk
  for (size_t first = 0; first < order.size(); first += chunk) {
    const size_t last = std::min(order.size(), first + chunk);  // frames [first, last)
    std::vector<cv::Mat> images(last - first);
    std::vector<PairMeasurement> measured(last - first);
    std::vector<std::exception_ptr> errors(last - first);
    auto start = std::chrono::steady_clock::now();
    cv::parallel_for_(cv::Range(0, static_cast<int>(images.size())), [&](const cv::Range& r) {
      for (int i = r.start; i < r.end; ++i) {
        try {
          const size_t k = first + i;
          images[i] =
              ReadFrameImage(in, rig, in.entries[order[k]], static_cast<long>(order[k]) + 2);
        } catch (...) {
          errors[i] = std::current_exception();
        }
      }
    });
    for (const std::exception_ptr& e : errors) {
      if (e) std::rethrow_exception(e);
    }
    result->read_s += SecondsSince(start);
    start = std::chrono::steady_clock::now();
    cv::parallel_for_(cv::Range(0, static_cast<int>(images.size())), [&](const cv::Range& r) {
      for (int i = r.start; i < r.end; ++i) {
        const size_t k = first + i;
        if (k == 0) continue;
        const cv::Mat& earlier_image = i > 0 ? images[i - 1] : previous;
        try {
          measured[i] = MeasureOnePair(in, rig, in.entries[order[k - 1]], earlier_image,
                                       in.entries[order[k]], images[i], max_points);
        } catch (...) {
          errors[i] = std::current_exception();
        }
      }
    });
    result->measure_s += SecondsSince(start);
    for (size_t i = 0; i < images.size(); ++i) {
      if (errors[i]) std::rethrow_exception(errors[i]);
      const size_t k = first + i;
      if (k == 0) continue;
      AddPair(in.entries[order[k - 1]], in.entries[order[k]], std::move(measured[i]), &pairs,
              result);
      if (in.progress) in.progress("measure", k, pair_total);
    }
    previous = images.back();
  }
  if (pairs.empty()) {
    throw IoError(IoMessage(in.frames_path, 0,
                            "no pair of consecutive frames could be measured inside the gyro log"));
  }
  return pairs;
}

// The two models' options and where their loops start.
struct VideoModels {
  LoopOptions rotation_options, translation_options;
  TrueModel rotation_start, translation_start;
};

// Rotation only's candidates are the options' (VideoCandidates when none); the pair-translation
// model's are those of them that it can tell from translation.
VideoModels PrepareModels(const ValidateOptions& options, const RigModel& rig) {
  VideoModels models;
  models.rotation_options = options.loop;
  if (models.rotation_options.candidates.empty()) {
    models.rotation_options.candidates = VideoCandidates();
  }
  models.rotation_options.pair_translation = false;
  models.translation_options = models.rotation_options;
  models.translation_options.pair_translation = true;
  models.translation_options.candidates.clear();
  for (Effect e : models.rotation_options.candidates) {
    if (Spec(e).identifiable_with_pair_translation) {
      models.translation_options.candidates.push_back(e);
    }
  }
  models.rotation_start.rig = rig;
  return models;
}

// The loop twice: rotation only (the baseline, result->loop), then with each pair's translation
// (result->translation_loop); models->translation_start is set between them.
void RunBothLoops(const VideoInputs& in, const std::vector<FramePoints>& rotation_pairs,
                  const std::vector<FramePoints>& translation_pairs, double noise_px,
                  VideoModels* models, ValidationResult* result) {
  if (in.progress) in.progress("loop", 0, 2);
  result->loop = CloseTheLoop(models->rotation_start, in.gyro, rotation_pairs, noise_px,
                              models->rotation_options);
  if (in.progress) in.progress("loop", 1, 2);
  // The pair-translation model cannot tell the gyro's own calibration (mounting, scale, bias): it
  // takes the rotation-only loop's when that one left the noise (its fit is then trustworthy),
  // camera.json's otherwise (parallax may have bent it).
  models->translation_start = models->rotation_start;
  if (!result->loop.unexplained) {
    for (const IdentifiedEffect& e : result->loop.effects) {
      const EffectSpec& spec = Spec(e.effect);
      if (spec.identifiable_with_pair_translation) continue;
      result->translation_inherits.push_back(spec.name);
      spec.apply_delta(e.parameters.data(), &models->translation_start);
    }
  }
  result->translation_loop = CloseTheLoop(models->translation_start, in.gyro, translation_pairs,
                                          noise_px, models->translation_options);
  if (in.progress) in.progress("loop", 2, 2);
}

// The two models over the same trimmed points (those both loops used), per residual component, and
// which is preferred (result->preferred).
void PreferModel(const std::vector<FramePoints>& pairs, double noise_px, ValidationResult* result) {
  const LoopResult& rot = result->loop;
  const LoopResult& trans = result->translation_loop;
  const TrimmedComparison compared =
      CompareTrimmed(pairs, rot.residuals_after, rot.residual_components, trans.residuals_after,
                     trans.residual_components);
  result->rotation_mean_sq_px2 = compared.a;
  result->translation_mean_sq_px2 = compared.b;
  // Nothing for translation to explain when rotation alone leaves the noise.
  result->translation_explains = rot.unexplained ? ExplainedShare(compared, noise_px) : 0.0;
  // A stabiliser's rendering turns the image on its own: what the pair translations absorb of it
  // is no motion of the camera.
  result->preferred = rot.unexplained && result->translation_explains >= kPreferTranslationShare &&
                              !ReRenderedByStabiliser(*result)
                          ? "translation"
                          : "rotation_only";
}

// Stability: the preferred model's effects fitted on each half of the pairs, appended to
// result->halves (when it has effects and there are at least four pairs).
void CheckHalves(const ClaimInputs& in, ValidationResult* result) {
  const LoopResult& preferred = in.preferred;
  const std::vector<FramePoints>& pairs = in.pairs;
  if (preferred.effects.empty() || pairs.size() < 4) return;
  const size_t half = pairs.size() / 2;
  const std::vector<FramePoints> first(pairs.begin(), pairs.begin() + half);
  const std::vector<FramePoints> second(pairs.begin() + half, pairs.end());
  const std::vector<Effect> effects = EffectsOf(preferred);
  HalfCheck check;
  check.model = result->preferred;
  check.first_pairs = first.size();
  check.second_pairs = second.size();
  const LoopResult a =
      FitEffects(in.preferred_start, in.gyro, first, in.noise_px, effects, in.preferred_options);
  const LoopResult b =
      FitEffects(in.preferred_start, in.gyro, second, in.noise_px, effects, in.preferred_options);
  check.first_after = a.after;
  check.second_after = b.after;
  check.first_model = a.model;
  check.second_model = b.model;
  for (size_t e = 0; e < a.effects.size() && e < b.effects.size(); ++e) {
    check.effects.push_back(CompareHalves(a.effects[e], b.effects[e]));
  }
  result->halves.push_back(std::move(check));
}

// The screening (estimate/loop/point_screen.h) of the pairs into result->screen; with the
// stabiliser's own rotation (image_orientation.csv), its best reading found, the pairs screened
// again with it applied and the claim judged on the two (JudgeImageOrientation); where it holds,
// the applied pairs and their screening replace the raw ones (pairs without IORI left out).
void ScreenVideo(const RigDataset& dataset, const TrueModel& declared,
                 const ValidateOptions& options, std::vector<FramePoints>* pairs,
                 ValidationResult* result) {
  // The screening of `on`: the pairs less those at the indices in `removed` (ascending).
  const auto screen = [&](const std::vector<FramePoints>& on, const std::vector<size_t>& removed) {
    std::vector<double> noise_px;
    for (size_t i = 0; i < result->frames.size(); ++i) {
      if (!std::binary_search(removed.begin(), removed.end(), i)) {
        noise_px.push_back(result->frames[i].noise_px);
      }
    }
    return ScreenPoints(declared, dataset.gyro, on, noise_px, options.measure.grid_step_px,
                        options.screen);
  };
  // The pairs at the indices in `removed` (ascending) left out of the frames, said why.
  const auto drop = [&](const std::vector<size_t>& removed, const std::string& why) {
    for (auto it = removed.rbegin(); it != removed.rend(); ++it) {
      const FrameValidation& f = result->frames[*it];
      result->skipped.push_back("pair " + std::to_string(f.previous.value_or(-1)) + " -> " +
                                std::to_string(f.frame) + ": " + why);
      result->frames.erase(result->frames.begin() + static_cast<long>(*it));
    }
  };
  result->screen = screen(*pairs, {});
  // A stabiliser on some axes only: the image's own rotation about those, the gyro's about the
  // others (point_screen.h FollowImageAbout), and the pairs screened again so.
  if (dataset.image_orientation.empty() && result->screen.gyro_follow.OnSomeAxes()) {
    result->axes_not_following = result->screen.gyro_follow;
    const std::vector<size_t> removed =
        FollowImageAbout(declared, result->screen.gyro_follow, result->screen.rotation, pairs);
    result->screen = screen(*pairs, removed);
    drop(removed,
         "its rotation consensus is not determined (needed for the axes that do not "
         "follow the gyro)");
    return;
  }
  if (dataset.image_orientation.empty() || !options.screen.consensus) return;
  ImageOrientationCheck& check = result->image_orientation;
  check = TestImageOrientation(declared, dataset.gyro, *pairs, result->screen.rotation,
                               dataset.image_orientation);
  if (check.pairs_tested < 3) return;  // its verdict says why
  std::vector<FramePoints> applied = *pairs;
  const std::vector<size_t> removed =
      ApplyImageOrientation(check, dataset.image_orientation, &applied);
  PointScreen applied_screen = screen(applied, removed);
  JudgeImageOrientation(result->screen.gyro_follow, applied_screen.gyro_follow, &check);
  if (!check.holds) return;
  *pairs = std::move(applied);
  result->screen = std::move(applied_screen);
  drop(removed, "a frame without the stabiliser's rotation (IORI)");
}

}  // namespace

std::vector<Effect> VideoCandidates() {
  std::vector<Effect> effects;
  for (const EffectSpec& spec : AllEffects()) {
    if (spec.effect != Effect::kVelocity) effects.push_back(spec.effect);
  }
  return effects;
}

void ValidateVideoDataset(const RigDataset& dataset, const ValidateOptions& options,
                          const ValidateProgress& progress, ValidationResult* result) {
  auto start = std::chrono::steady_clock::now();
  const fs::path& dir = dataset.dir;
  const GyroTrace& gyro = dataset.gyro;
  const VideoInputs in{dir, dataset.frames_path, gyro, dataset.frames, options, progress};
  result->video = true;
  const std::vector<size_t> order = FramesInTimeOrder(in);
  const std::vector<SourceClaim> claims = ReadSourceClaims((dir / "import.json").string());
  result->read_s += SecondsSince(start);

  std::vector<FramePoints> pairs = MeasurePairs(in, order, result);

  start = std::chrono::steady_clock::now();
  const double noise_px = PooledNoisePx(result->frames);
  VideoModels models = PrepareModels(options, result->declared);
  ScreenVideo(dataset, models.rotation_start, options, &pairs, result);
  // A stabiliser's rendering shows no effect of the sensor (the top-level effects stay empty
  // whatever a loop fits): the loops fit the declared model alone, for its residual.
  if (ReRenderedByStabiliser(*result)) {
    models.rotation_options.max_effects = models.translation_options.max_effects = 0;
  }
  const std::vector<FramePoints> rotation_pairs =
      WithoutScreened(pairs, result->screen.rotation_status);
  const std::vector<FramePoints> translation_pairs =
      WithoutScreened(pairs, result->screen.translation_status);
  RunBothLoops(in, rotation_pairs, translation_pairs, noise_px, &models, result);
  const LoopResult& rot = result->loop;
  const LoopResult& trans = result->translation_loop;
  FillFrameResiduals(pairs, rot, &trans, result->screen, options.keep_residuals, &result->frames);
  PreferModel(WithoutScreened(translation_pairs, result->screen.rotation_status), noise_px, result);
  const bool translation = result->preferred == "translation";
  const ClaimInputs claim_inputs{gyro,
                                 translation ? translation_pairs : rotation_pairs,
                                 rotation_pairs,
                                 noise_px,
                                 translation ? models.translation_start : models.rotation_start,
                                 translation ? trans : rot,
                                 translation ? models.translation_options : models.rotation_options,
                                 models.rotation_start,
                                 rot,
                                 models.rotation_options};
  // A stabiliser's rendering settles none of the source's claims and shows no effect of the
  // sensor on either half, whatever a fit says: no fit is tried for them.
  const GyroFollowCheck& follow = result->screen.gyro_follow;
  if (ReRenderedByStabiliser(*result)) {
    for (const SourceClaim& claim : claims) {
      ClaimCheck check;
      check.claim = claim.what;
      check.effect = claim.effect;
      check.status = claim.status;
      check.claimed = claim.value;
      check.difference = std::numeric_limits<double>::quiet_NaN();
      check.verdict =
          result->image_orientation.holds
              ? "not determined: a stabiliser re-rendered the image (it follows the gyro only "
                "turned by the stabiliser's own rotation, IORI): a fit on it describes the "
                "stabiliser's output, not the sensor"
              : "not determined: the image does not follow the gyro (it turns " +
                    FormatNumber("%.2f", follow.gain) + "x as fast): a stabiliser re-rendered it";
      result->claims.push_back(std::move(check));
    }
  } else {
    CheckHalves(claim_inputs, result);
    // The source's claims, when the dataset came from `shutterlab import`.
    result->claims = CheckClaims(claims, claim_inputs);
  }
  WithholdUncalibratedStderr(FitModel::kPairTranslation, &result->translation_loop);
  WithholdUncalibratedStderr(FitModel::kRotationOnly, &result->loop);
  result->loop_s = SecondsSince(start);
}

}  // namespace shutterlab
