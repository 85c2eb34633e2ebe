#pragma once
// What `validate` finds (estimate/loop/validate.h describes how): per frame, per limit, the loop's
// effects, and for video datasets both models, the halves and the source's claims.

#include "estimate/loop/effect_fit.h"
#include "estimate/loop/image_orientation.h"
#include "estimate/loop/measure.h"
#include "estimate/loop/point_screen.h"
#include "io/lens_profile.h"
#include "model/effects.h"
#include "sim/log_warning.h"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

// Ratios D_model / D_meas are left out for frames measured below this D: a ratio of two numbers
// near the noise says nothing about a model.
inline constexpr double kMinRatioDPx = 1.0;

struct ValidateOptions {
  std::vector<double> limits_m{0.05, 0.10};  // acceptable smear on the ground, m
  // A Gyroflow lens profile (io/lens_profile.h) whose lens, scaled to the dataset's image size,
  // and readout (where it states one) replace camera.json's before anything is predicted.
  std::string lens_profile_path;
  MeasureOptions measure;  // its mask is the dataset's (camera.json) and mask_path's together
  LoopOptions loop;
  ScreenOptions screen;  // points left out before the loop (estimate/loop/point_screen.h)
  // validate --mask: a mask image (io/rig_dataset.h ReadMask, non-zero = use) beside
  // camera.json's own; a pixel is measured only where both allow it. Empty: none.
  std::string mask_path;
  // Keep the per-point residuals before and after the loop (for plots).
  bool keep_residuals = true;
  // Video: at most this many of a pair's measured points go to the loops, spread evenly over its
  // grid, and at most max_video_points over all pairs (a long clip's pairs get fewer each, never
  // fewer than 100). A pair's points share its errors (the standard errors see pairs, not points),
  // so beyond a few hundred they add cost, not information: a 360-pair clip of 854x480 measures
  // about 900 a pair, and keeps 111.
  size_t max_points_per_pair = 400;
  size_t max_video_points = 40000;
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
  // Why the rotation-only (still: the) loop and the pair-translation loop left it out, if they did.
  PointStatus status = PointStatus::kKept, translation_status = PointStatus::kKept;
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
  ResidualStats before, after;                         // this frame's points that the loop used
  // Points the screening left out (estimate/loop/point_screen.h): in a camera-fixed region, and
  // rejected by the frame's consensus (video: the rotation-only one; off_epipolar: the
  // pair-translation one).
  size_t camera_fixed = 0, moving = 0, off_epipolar = 0;
  std::vector<PointResidual> residuals;  // when ValidateOptions::keep_residuals
  // Video pairs: the earlier frame this one was measured against, the residual after the loop with
  // pair translation, and the pair's fitted translation direction (earlier frame's camera axes).
  std::optional<int64_t> previous;
  ResidualStats translation_after;
  Eigen::Vector3d translation_dir = Eigen::Vector3d::Zero();
};

// Video: one effect of a model fitted on each half of the pairs.
struct HalfAgreement {
  Effect effect = Effect::kTimeOffset;
  EffectValue first, first_stderr, second, second_stderr;  // docs/FORMATS.md values
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
  std::string claim;                    // import.json's name: readout_s, gyro_to_camera, ...
  Effect effect = Effect::kTimeOffset;  // the effect fitted to test it
  std::string status;                   // import.json's status ("source claim", "guess", ...)
  EffectValue claimed;                  // the value the source states (the effect's shape)
  // Fitted beside the identified effects (gyro_to_camera: the best of the 24 axis mappings, with
  // no standard error: std::monostate; readout_direction: the better reading, the same).
  EffectValue found, found_stderr;
  double difference = 0.0;  // |found - claimed| / stderr (gyro_to_camera: angle, deg)
  std::string verdict;      // for a person
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
  RigModel declared;                           // camera.json, with the lens profile's when given
  std::optional<LensProfileUse> lens_profile;  // what ValidateOptions::lens_profile_path gave
  std::vector<LogWarning> warnings;            // what the audit of gyro.csv found (RigDataset)
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
  // The points left out before the loop, the camera-fixed region, the consensus per frame, and
  // (video) whether the image follows the gyro at all.
  PointScreen screen;
  // Video of a stabilised camera that wrote its per-frame rotation (image_orientation.csv): the
  // claim tested, and applied where it holds (estimate/loop/image_orientation.h).
  ImageOrientationCheck image_orientation;
  // Video whose image does not follow the gyro about some camera axes but does about the others
  // (a stabiliser on those axes: GyroFollowCheck::OnSomeAxes): the first screening's check, with
  // its per-axis numbers. The pairs then carry the image's own rotation about those axes
  // (FollowImageAbout) and `screen` is theirs.
  std::optional<GyroFollowCheck> axes_not_following;
  cv::Mat mask;                  // CV_8U 0 / 255 the measurement used (empty: none)
  std::string mask_description;  // where it came from, for a person
  // Wall time per stage, s.
  double read_s = 0, measure_s = 0, predict_s = 0, loop_s = 0;
};

// Whether the images are a stabiliser's rendering rather than the sensor's rows (video): they do
// not follow the gyro, or follow it only turned by the stabiliser's own rotation (IORI). No
// effect of the sensor is named on them, and no claim about it settled.
inline bool ReRenderedByStabiliser(const ValidationResult& result) {
  const GyroFollowCheck& follow = result.screen.gyro_follow;
  return (follow.determined && !follow.follows) || result.image_orientation.holds;
}

// progress(stage, done, total): stage is "measure" or "predict"; may be empty.
using ValidateProgress = std::function<void(const std::string& stage, size_t done, size_t total)>;

}  // namespace shutterlab
