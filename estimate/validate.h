#pragma once
// `validate` (issue 4): test the paper's threshold model and the declared full model against the
// displacement measured in a rig dataset, then close the loop on undeclared effects.
//
// For every frame of the dataset (FORMATS.md "Rig dataset"; truth/ and truth.json are never read):
//  - measured: MeasureDisplacement(ref, image): the points, their noise, D_meas (px), and
//    D_meas_m = D_meas_px * altitude_m / f, f = (fx + fy) / 2;
//  - full model: FORMATS.md's D of the declared model's d(p) (rotation, velocity, lens), evaluated
//    on a grid (kGridStepPx, first and last rows and columns included);
//  - paper's model: estimate/analyze.h Analyze() with a trigger at the frame's gyro time
//    t_first_row + time_offset_s (no bias estimate: gyro.csv is taken as calibrated), which gives
//    D_paper_m = altitude * tan(largest per-axis range in the readout), the per-axis ranges and the
//    dominant axis; D_vector_m = altitude * tan(largest rotation angle between row 0 and any row),
//    the vector criterion, for the per-axis vs vector question.
// Then CloseTheLoop over all frames' points, noise_px = the RMS of the frames' noise over points.
//
// Video datasets (FORMATS.md "Video datasets": every ref empty; issue 6) are validated pair by
// pair: frames in time order, each against the one before it (MeasureDisplacement(earlier, later)
// gives q - p). There is no global-shutter reference, so no D and no paper's model; the loop runs
// twice over the pairs' points:
//  - rotation only (FORMATS.md's video model; the baseline);
//  - with each pair's translation as an unknown direction (LoopOptions::pair_translation, the
//    epipolar constraint), which parallax from a moving camera needs. Its candidates leave out the
//    gyro's mounting, scale and bias (IdentifiableWithPairTranslation); it starts from the
//    rotation-only loop's values of those when that loop left the noise.
// Both are reported, with the share of the rotation-only residual that translation explains. Then:
//  - stability: the preferred model's effects refitted on the first and the second half of the
//    pairs (FitEffects), each effect's two values compared against their standard errors;
//  - the source's claims: when the dataset has an import.json (shutterlab import), each claim that
//    the loop can test (readout_s, gyro_to_camera, time_offset_s, direction) is fitted as an effect
//    beside the identified ones and compared with what the source said.
// Pairs whose declared readout the gyro log does not cover are left out and listed.
// Default candidates for video: every FORMATS.md effect but velocity (translation is the pair
// model's), unless options.loop.candidates names them.

#include "estimate/effect_fit.h"
#include "estimate/measure.h"

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

struct ValidateOptions {
  std::vector<double> limits_m{0.05, 0.10};  // acceptable smear on the ground, m
  MeasureOptions measure;
  LoopOptions loop;
  // Keep the per-point residuals before and after the loop (for plots).
  bool keep_residuals = true;
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

// One measured point's residual (measured - predicted), px, at rolling-shutter pixel (u, v).
struct PointResidual {
  float u = 0, v = 0;
  float before_dx = 0, before_dy = 0;  // against the declared model
  float after_dx = 0, after_dy = 0;    // against the declared model plus the identified effects
  // Video: against the model with pair translation (only the part across the epipolar line).
  float translation_dx = 0, translation_dy = 0;
};

struct FrameValidation {
  int64_t frame = 0;
  std::string image;      // frames.csv's image path (relative to the dataset)
  double t_gyro_s = 0.0;  // t_first_row + time_offset_s, gyro clock
  size_t points = 0;      // measured points
  double measured_fraction = 0.0;
  double noise_px = 0.0;  // this frame's measurement noise
  double d_meas_px = 0.0, d_meas_m = 0.0;
  double d_full_px = 0.0, d_full_m = 0.0;  // declared full model
  double d_paper_m = 0.0;                  // paper's per-axis threshold model
  double d_vector_m = 0.0;                 // the same with the rotation-vector angle
  double d_centre_px = 0.0;  // full model's D in the principal point's column only (nadir pixels)
  std::array<double, 3> range_arcsec{};                // per camera axis within the readout
  int dominant_axis = 0;                               // 0 x, 1 y, 2 z (camera axes)
  std::vector<bool> flag_meas, flag_full, flag_paper;  // one per limit: D_m > limit
  ResidualStats before, after;                         // this frame's points only
  std::vector<PointResidual> residuals;                // when ValidateOptions::keep_residuals
  // Video pairs: the earlier frame this one was measured against, the residual after the loop with
  // pair translation, and the pair's fitted translation direction (earlier frame's camera axes).
  std::optional<int64_t> previous;
  ResidualStats translation_after;
  Eigen::Vector3d translation_dir = Eigen::Vector3d::Zero();
};

// Video: one effect of a model fitted on each half of the pairs.
struct HalfAgreement {
  std::string effect;
  nlohmann::json first, first_stderr, second, second_stderr;  // FORMATS.md values
  // Mahalanobis distance of the two fits' parameters under the sum of their covariances
  // (gyro_to_camera: its parameters are rotation vectors about the same declared mounting, so
  // they are compared directly), and whether it is below the 99 % quantile of chi-square with the
  // effect's parameter count (readout_direction: the same direction). Not determined where a half
  // has no standard error (a parameter combination its data do not pin down).
  double distance = 0.0;
  bool agree = true;
  bool determined = true;
};
struct HalfCheck {
  std::string model;  // "rotation_only" or "translation"
  size_t first_pairs = 0, second_pairs = 0;
  std::vector<HalfAgreement> effects;
  ResidualStats first_after, second_after;
  TrueModel first_model, second_model;  // the declared model plus each half's fitted effects
};

// Video datasets from `shutterlab import`: one of the source's claims against the data.
struct ClaimCheck {
  std::string claim;       // import.json's name: readout_s, gyro_to_camera, time_offset_s, ...
  std::string effect;      // the effect fitted to test it
  std::string status;      // import.json's status ("source claim", "guess", ...)
  nlohmann::json claimed;  // the value the source states
  nlohmann::json found, found_stderr;  // fitted beside the identified effects
  double difference = 0.0;             // |found - claimed| / stderr (gyro_to_camera: angle, deg)
  std::string verdict;                 // for a person
};

// Paper's flags against the measured truth at one limit (a frame is "positive" when over it).
struct Confusion {
  double limit_m = 0.0;
  int true_positive = 0, false_positive = 0, false_negative = 0, true_negative = 0;
};

// D_paper / D_meas over the frames whose dominant axis is `axis` (0 x, 1 y, 2 z; 3: all frames).
struct RatioGroup {
  int axis = 3;
  int frames = 0;
  double paper_min = 0, paper_median = 0, paper_max = 0;  // D_paper_m / D_meas_m
  double vector_median = 0;                               // D_vector_m / D_meas_m
  double full_median = 0;                                 // D_full / D_meas
  double centre_median = 0;                               // D_centre_px / D_full_px
};

struct ValidationResult {
  std::string dataset;
  RigModel declared;
  std::vector<double> limits_m;
  std::vector<FrameValidation> frames;
  std::vector<Confusion> confusion_paper;  // one per limit
  std::vector<Confusion> confusion_full;   // the full model's flags, same layout
  std::vector<RatioGroup> ratios;          // per dominant axis that occurs, then all frames
  LoopResult loop;
  // Video datasets (see the top): `loop` is the rotation-only baseline.
  bool video = false;
  LoopResult translation_loop;
  // The rotation-only loop's gyro-side effects (gyro_to_camera, gyro_scale, gyro_bias) the
  // translation loop started from: those it cannot tell from translation, taken when the
  // rotation-only loop left the noise.
  std::vector<std::string> translation_inherits;
  std::string preferred = "rotation_only";  // or "translation": the model that explains the data
  // Share of the rotation-only residual's excess over the noise (mean square per component, over
  // the same trimmed points) that per-pair translation explains; 0 when the rotation-only loop
  // ends at the noise (unexplained false).
  double translation_explains = 0.0;
  double rotation_mean_sq_px2 = 0.0, translation_mean_sq_px2 = 0.0;  // px^2
  std::vector<HalfCheck> halves;
  std::vector<ClaimCheck> claims;
  std::vector<std::string> skipped;  // pairs left out, and why
  // Wall time per stage, s.
  double read_s = 0, measure_s = 0, predict_s = 0, loop_s = 0;
};

// progress(stage, done, total): stage is "measure" or "predict"; may be empty.
using ValidateProgress = std::function<void(const std::string& stage, size_t done, size_t total)>;

// Reads the dataset in `dataset_dir` and validates it. Everything is read and checked first; bad
// input throws IoError / std::invalid_argument with one line naming the file, line and problem
// (video datasets: see the top of this file).
ValidationResult ValidateDataset(const std::string& dataset_dir, const ValidateOptions& options,
                                 const ValidateProgress& progress = {});

// The report JSON: LoopToJson's FORMATS.md keys plus "dataset", "limits_m", "frames_detail",
// "confusion", "ratios", "timing_s" and "log".
nlohmann::json ValidationToJson(const ValidationResult& result);

// The table and summary for a person.
std::string ValidationReport(const ValidationResult& result);

// With --out DIR: per-frame residual pictures before/after (DIR/NNNN_residual.png), the per-row
// residual profile before/after of all frames (DIR/residual_rows.png, DIR/residual_rows.csv).
// Returns the paths written. Creates DIR when missing; each file whole or not at all.
std::vector<std::string> WriteValidationPlots(const std::string& dir,
                                              const ValidationResult& result);

// For the demo: renders a small rig dataset with ONE effect in the truth that camera.json does not
// declare (a multirotor-like ideal gyro, sim/motion.h; 30 ms readout, 50 m, f = 1100 px at 1280
// wide scaled to `width`), validates it and writes out_dir/dataset (the rig dataset and its truth),
// out_dir/report.json and out_dir/plots (WriteValidationPlots, validate.html).
struct InjectedDemoOptions {
  std::string scene_path;                       // nadir scene image
  std::string out_dir;                          // created if missing
  std::string injection = "time_offset=0.004";  // render --inject NAME=VALUE
  int frames = 6;
  int width = 640, height = 480;
  uint64_t seed = 3;  // the flight motion
  void Check() const;
};
ValidationResult RenderAndValidate(const InjectedDemoOptions& options,
                                   const ValidateProgress& progress = {});

}  // namespace shutterlab
