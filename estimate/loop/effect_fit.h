#pragma once
// Closing the loop: the residual between measured displacements and the declared model,
// a statistical test of whether it is above the measurement noise, and the search over
// docs/FORMATS.md's candidate effects (fit each by nonlinear least squares, pick by an information
// criterion, add, repeat).
//
// (Interface fixed first so that validate can be written against it; see effect_fit.cc.)

#include "estimate/loop/frame_points.h"
#include "estimate/loop/measure.h"
#include "model/camera.h"
#include "model/effects.h"
#include "model/truth_model.h"
#include "sim/gyro_trace.h"

#include <Eigen/Core>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

struct ResidualStats {
  double rms_px = 0.0;  // root mean square of |measured - predicted| over all points, px
  double max_px = 0.0;
  size_t points = 0;
};
// The statistics of residuals given as squared lengths, px^2.
ResidualStats ResidualStatsOf(const std::vector<double>& squared_norms);

// How the standard errors of fitted effects are computed (effect_fit.cc, "Standard errors").
enum class CovarianceKind {
  kModel,             // (J^T W J)^-1 s^2 c: points independent but for their neighbours
  kClusterSandwich,   // cluster-robust sandwich, frames (video: pairs) as clusters
  kClusterJackknife,  // leave-one-frame-out jackknife (one Gauss-Newton step per refit)
};
const char* CovarianceKindName(CovarianceKind kind);

// One identified effect, docs/FORMATS.md names, values and units.
struct IdentifiedEffect {
  Effect effect = Effect::kTimeOffset;  // its name and unit: Spec(effect)
  EffectValue value;         // docs/FORMATS.md value (number, [3], 3x3, {k1, k2}, direction)
  EffectValue stderr_value;  // same shape as value (std::monostate for readout_direction)
  // Why no real device has the value (OutOfBounds, model/effects.h); "" when one can. Such a fit
  // explains the residual but is never named as a fix.
  std::string out_of_bounds;
  std::vector<Effect> ambiguous_with;  // effects that explain the data as well
  ResidualStats after;                 // residual once this effect is added
  // The fitted parameters (EffectSpec::parameter_count of them, deltas from the declared model as
  // EffectSpec::apply_delta takes them) and their covariance, as the standard errors come from.
  Eigen::VectorXd parameters;
  Eigen::MatrixXd covariance;  // LoopOptions::covariance's
  // Each parameter's standard error by every CovarianceKind (NaN where none), and the clusters
  // (frames or pairs with points) they were computed over: the report says which one it used, the
  // coverage test measures them all.
  Eigen::VectorXd parameter_stderr_model, parameter_stderr_sandwich, parameter_stderr_jackknife;
  int clusters = 0;
  // Where the standard error came from: LoopOptions::covariance, or the model's with fewer than 3
  // clusters.
  CovarianceKind stderr_from = CovarianceKind::kModel;
  // Why stderr_value is not reported (NaN: null in JSON), "" when it is: a model whose standard
  // error for the effect does not hold (EffectSpec::stderr_fails_in).
  std::string stderr_withheld;
};

struct LoopOptions {
  // Candidate effects tried; default: all of them (AllEffects).
  std::vector<Effect> candidates;
  int max_effects = 3;
  // False-alarm rate of the "residual above the measurement noise" test (a chi-square test of the
  // robust mean square residual against noise_px, degrees of freedom divided by the spatial
  // correlation factor estimated from the residual; see effect_fit.cc).
  double significance = 1e-3;
  // A candidate is added only when it lowers BIC by more than this (10: "very strong" evidence,
  // Kass & Raftery 1995) ...
  double bic_margin = 10.0;
  // ... and explains at least this share of the residual's excess over the noise (a candidate that
  // removes a sliver of a large unexplained residual is not what is there).
  double min_explained_share = 0.3;
  // Other candidates whose BIC is within this of the chosen one's are reported in ambiguous_with.
  double ambiguity_margin = 10.0;
  // The search goes on, and unexplained is set, only while the residual is significantly above
  // noise (the test above) AND its trimmed RMS is above material_ratio * noise_px: noise_px is
  // itself an estimate (on rendered reference datasets measure's noise_px was 1.0-1.4x the RMS that
  // the true model left, never below; on rendered video pairs the true model left 1.04-1.13x).
  double material_ratio = 1.15;
  // Video pairs only: each pair's camera translation is an unknown direction (Gyroflow rs-sync's
  // epipolar constraint with per-row poses). Only each match's distance from its epipolar line is
  // fitted then; the translation directions are solved inside every prediction (effect_model.h).
  bool pair_translation = false;
  // The standard errors the effects get, and that claims, halves and every "contradicted" use.
  CovarianceKind covariance = CovarianceKind::kClusterJackknife;
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

struct LoopResult {
  ResidualStats before, after;
  double noise_px = 0.0;
  std::vector<IdentifiedEffect> effects;  // in the order added
  bool unexplained = false;
  // The level test on the declared model's residual (the loop searches only when it is true).
  bool above_noise_before = false;
  TrueModel model;  // the declared model plus the identified effects
  // Measured minus predicted per point (input order, all frames), declared model and final model;
  // NaN where there is no prediction. With pair_translation only the part across the epipolar
  // line is a residual.
  std::vector<Eigen::Vector2d> residuals_before, residuals_after;
  // Residual components per point that carry information (2; 1 with pair_translation).
  int residual_components = 2;
  CovarianceKind covariance = CovarianceKind::kClusterJackknife;  // the effects' standard errors
  // With pair_translation: each frame's fitted translation direction (unit, in the earlier
  // frame's row-0 camera axes; sign arbitrary), input order.
  std::vector<Eigen::Vector3d> pair_translation_dirs;
  // For a person: each round's candidates with their fitted residual and criterion.
  std::vector<std::string> log;
};

// The standard errors of `loop`, fitted as `model`, that do not hold (EffectSpec::
// stderr_fails_in) withheld: NaN (the covariance and every parameter's too), and
// IdentifiedEffect::stderr_withheld says why. Run once the halves and claims have used them.
void WithholdUncalibratedStderr(FitModel model, LoopResult* loop);

// Predicted displacement at each point of `frame` under `model`, with the logged gyro trace: d(p) =
// p_ref - p (docs/FORMATS.md "The model"), or for a video pair the rotation-only match q - p; NaN
// where the ray misses the ground, the match leaves the frame or an instant leaves the trace.
std::vector<Eigen::Vector2d> PredictDisplacements(const TrueModel& model, const GyroTrace& gyro,
                                                  const FramePoints& frame);

// Runs the loop. declared: camera.json; noise_px: the measurement's noise (MeasureDisplacement).
LoopResult CloseTheLoop(const RigModel& declared, const GyroTrace& gyro,
                        const std::vector<FramePoints>& frames, double noise_px,
                        const LoopOptions& options = {});

// Fits a given list of effects (no selection), each started as the loop starts it, and reports
// them as the loop would: values, standard errors, residuals. For the stability check on subsets of
// the frames (the two halves of a clip).
LoopResult FitEffects(const RigModel& declared, const GyroTrace& gyro,
                      const std::vector<FramePoints>& frames, double noise_px,
                      const std::vector<Effect>& effects, const LoopOptions& options = {});

// The same from a model that already holds errors beyond camera.json (a gyro scale or bias found
// by another fit): the effects are fitted on top of `start`, and `before` is start's residual.
LoopResult CloseTheLoop(const TrueModel& start, const GyroTrace& gyro,
                        const std::vector<FramePoints>& frames, double noise_px,
                        const LoopOptions& options = {});
LoopResult FitEffects(const TrueModel& start, const GyroTrace& gyro,
                      const std::vector<FramePoints>& frames, double noise_px,
                      const std::vector<Effect>& effects, const LoopOptions& options = {});

// The loop's identified effects, in the order they were added.
std::vector<Effect> EffectsOf(const LoopResult& loop);

}  // namespace shutterlab
