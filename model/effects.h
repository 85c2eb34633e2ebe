#pragma once
// The effects of docs/FORMATS.md's table ("Effect names, values and units"): what camera.json does
// not declare, what `render --inject` puts into a truth and what the validation loop fits.
//
// Everything that differs from one effect to the next is one row of one table (effects.cc), so a
// new effect is one new row, and a misspelt one is a compile error, not a run-time throw. Names and
// values are text only at the edges: the command line, JSON and reports (model/effect_io.h).

#include "model/lens_distortion.h"
#include "model/truth_model.h"
#include "sim/readout_direction.h"

#include <Eigen/Core>

#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace shutterlab {

// In docs/FORMATS.md's order (AllEffects() lists them in it).
enum class Effect {
  kTimeOffset,
  kReadoutTime,
  kGyroToCamera,
  kGyroScale,
  kGyroBias,
  kVelocity,
  kLensDistortion,
  kReadoutDirection,
  kClockRate,
};

// One effect's value (or standard error) in docs/FORMATS.md's shape and units (EffectSpec::unit):
//  double: time_offset, readout_time (s), clock_rate (ppm);
//  Eigen::Vector3d: gyro_scale, gyro_bias (rad/s), velocity (m/s);
//  Eigen::Matrix3d: gyro_to_camera, R_CG (its standard error: per entry);
//  LensDistortion: lens_distortion, in the declared camera's model (model/lens_distortion.h);
//    the fit holds k1 and k2 of either model; Brown-Conrady's p1, p2 and k3 are non-zero only
//    where `--inject` set them, a fisheye's k3 and k4 are the declared ones (standard error NaN);
//  ReadoutDirection: readout_direction (a row order, IsRowReadout);
//  std::monostate: none (readout_direction's standard error).
// A standard error that the data do not determine is NaN. JSON and text: model/effect_io.h.
using EffectValue = std::variant<std::monostate, double, Eigen::Vector3d, Eigen::Matrix3d,
                                 LensDistortion, ReadoutDirection>;

// Which of EffectValue's alternatives an effect's value holds.
enum class EffectShape { kNumber, kVector3, kMatrix3, kLens, kDirection };

// The models validate fits and reports: the stills' loop, a clip's rotation-only model and its
// pair-translation model.
enum class FitModel { kStill, kRotationOnly, kPairTranslation };
// "still", "rotation-only", "pair-translation".
const char* FitModelName(FitModel model);

// True when value holds the alternative of shape.
bool HasShape(const EffectValue& value, EffectShape shape);
// What a value of the shape is, for messages: "a number", "3 numbers", "a 3x3 matrix", ...
const char* EffectShapeWords(EffectShape shape);

// An effect with its value: one `render --inject`, one entry of truth.json's "injected".
struct Injection {
  Effect effect = Effect::kTimeOffset;
  EffectValue value;
};

// The range of an effect's value (each axis of a vector) that a real device can have, in the
// effect's own unit (docs/FORMATS.md), and how a value outside is said: times `scale` in `unit`,
// with why no device has it.
struct PhysicalBounds {
  double lo = 0.0, hi = 0.0;
  double scale = 1.0;
  const char* unit = "";
  const char* why = "";
};

// One effect. The fitted parameters (parameter_count of them, each a delta from the model's current
// value) are: time_offset 1 (s), readout_time 1 (s), gyro_to_camera 3 (rotation vector, rad,
// applied on the camera side: R_CG = Exp(x) * R_CG_declared), gyro_scale 3, gyro_bias 3 (rad/s),
// velocity 3 (m/s), lens_distortion 2 (k1, k2), clock_rate 2 (ppm, and the time offset that goes
// with it, s), readout_direction 0 (a discrete flip).
struct EffectSpec {
  Effect effect = Effect::kTimeOffset;
  std::string name;  // docs/FORMATS.md's name: "time_offset", ...
  std::string unit;  // of the value: "s", "rad/s", "m/s", "ppm", "" when dimensionless
  EffectShape shape = EffectShape::kNumber;  // of value and stderr (readout_direction: no stderr)
  int parameter_count = 0;
  // Central-difference (and so LM) step of parameter i, in its own unit. frames_span_s: the
  // largest |camera time| of the frames (a clock-rate step moves the latest frame by ~10 us).
  double (*step)(int i, double frames_span_s) = nullptr;
  // Adds parameter_count deltas to *model (readout_direction: flips the direction, delta unused).
  void (*apply_delta)(const double* delta, TrueModel* model) = nullptr;
  // Sets the absolute value (of `shape`: ApplyInjection checks it) and returns it as truth.json
  // records it. Throws std::invalid_argument for a value out of range.
  EffectValue (*inject)(const EffectValue& value, TrueModel* model) = nullptr;
  // The docs/FORMATS.md value read from a model (time_offset: the true time_offset_s, ...;
  // lens_distortion: Brown-Conrady's k1 and k2 only, a fisheye's k1..k4).
  EffectValue (*value)(const TrueModel& model) = nullptr;
  // Standard errors in the value's shape from the parameters' covariance and standard deviations
  // sd (its diagonal's roots, NaN where negative). See EffectStderr.
  EffectValue (*stderr_value)(const TrueModel& model, const Eigen::MatrixXd& covariance,
                              const Eigen::VectorXd& sd) = nullptr;
  // False where the pair-translation model of video cannot tell the effect from translation: over a
  // scene of nearly one depth a rotation about an image-plane axis moves the image as a sideways
  // move does (the epipole goes where the shift points), so a free translation per pair absorbs
  // the gyro's scale, bias and mounting about those axes. Those are fitted rotation-only.
  bool identifiable_with_pair_translation = true;
  // The models whose standard error for the effect does not hold: over 350 rendered datasets
  // (scripts/coverage_study.py, docs/validation.md "Every effect, every model") its truth fell
  // outside 2 standard errors far more often than 10 % (by up to 29 of them). validate reports
  // those models' value of the effect without one, and says why.
  std::vector<FitModel> stderr_fails_in;
  // The import.json claim ("what") that a fit of this effect tests; "" when none does.
  std::string claim;
  // What a real device can have (docs/FORMATS.md "Physical bounds"); nullopt: every value of the
  // shape is plausible (a mounting, a lens, a readout direction). A fitted value outside is never
  // named as a fix (OutOfBounds).
  std::optional<PhysicalBounds> bounds;
};

// Every effect, in docs/FORMATS.md's order.
const std::vector<EffectSpec>& AllEffects();
const EffectSpec& Spec(Effect effect);

// The effect of a docs/FORMATS.md name; nullopt for any other text.
std::optional<Effect> ParseEffect(std::string_view name);
// The same where a name is required: throws std::invalid_argument
// "<where>: unknown effect 'NAME' (known: time_offset, readout_time, ...)".
Effect RequireEffect(std::string_view name, const std::string& where);

// Sets one effect's absolute value in the true model and returns the value as truth.json records it
// (docs/FORMATS.md units). Throws std::invalid_argument for a value of another shape than the
// effect's, or out of range (a readout that is not positive, a matrix that is not a rotation, a
// model that fails TrueModel::Check), and then leaves *model unchanged. From `NAME=VALUE` text:
// model/effect_io.h.
EffectValue ApplyInjection(const Injection& injection, TrueModel* model);

// "time_offset, readout_time, ...": the effects that have bounds.
std::string BoundedEffectNames();

// Why no real device has the value (Spec(effect).bounds, or camera.json's own for the effect
// where rig gives one: RigModel::bounds); "" when one can.
std::string OutOfBounds(Effect effect, const EffectValue& value, const RigModel* rig = nullptr);

// Standard errors in the shape of the effect's value, from the covariance of its parameters
// (gyro_to_camera: per matrix entry, first order in the rotation vector). std::monostate for
// readout_direction; NaN (null in JSON) for an undetermined parameter.
EffectValue EffectStderr(Effect effect, const TrueModel& model, const Eigen::MatrixXd& covariance);

// The value as its docs/FORMATS.md JSON text ("0.004", "[1.01,0.99,1.0]", "\"bottom_to_top\""),
// for logs and messages. Defined in model/effect_io.cc, beside the JSON it is.
std::string EffectValueText(const EffectValue& value);

}  // namespace shutterlab
