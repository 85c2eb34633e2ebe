#pragma once
// The effects of docs/FORMATS.md's table ("Effect names, values and units"): what camera.json does
// not declare, what `render --inject` puts into a truth and what the validation loop fits.
//
// Everything that differs from one effect to the next is one row of one table (effects.cc), so a
// new effect is one new row, and a misspelt one is a compile error, not a run-time throw. Names are
// text only at the edges: the command line, JSON and reports.

#include "render/truth_model.h"

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <string_view>
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

// One effect. The fitted parameters (parameter_count of them, each a delta from the model's current
// value) are: time_offset 1 (s), readout_time 1 (s), gyro_to_camera 3 (rotation vector, rad,
// applied on the camera side: R_CG = Exp(x) * R_CG_declared), gyro_scale 3, gyro_bias 3 (rad/s),
// velocity 3 (m/s), lens_distortion 2 (k1, k2), clock_rate 2 (ppm, and the time offset that goes
// with it, s), readout_direction 0 (a discrete flip).
struct EffectSpec {
  Effect effect = Effect::kTimeOffset;
  std::string name;  // docs/FORMATS.md's name: "time_offset", ...
  std::string unit;  // of the value: "s", "rad/s", "m/s", "ppm", "" when dimensionless
  int parameter_count = 0;
  // Central-difference (and so LM) step of parameter i, in its own unit. frames_span_s: the
  // largest |camera time| of the frames (a clock-rate step moves the latest frame by ~10 us).
  double (*step)(int i, double frames_span_s) = nullptr;
  // Adds parameter_count deltas to *model (readout_direction: flips the direction, delta unused).
  void (*apply_delta)(const double* delta, TrueModel* model) = nullptr;
  // Sets the absolute value of `--inject NAME=VALUE` (VALUE as ApplyInjection parsed it) and
  // returns it as truth.json records it. Throws std::invalid_argument for a bad value.
  nlohmann::json (*inject)(const nlohmann::json& value, TrueModel* model) = nullptr;
  // The docs/FORMATS.md value read from a model (time_offset: the true time_offset_s, ...).
  nlohmann::json (*value)(const TrueModel& model) = nullptr;
  // Standard errors in the value's shape from the parameters' covariance and standard deviations
  // sd (its diagonal's roots, NaN where negative). See EffectStderr.
  nlohmann::json (*stderr_value)(const TrueModel& model, const Eigen::MatrixXd& covariance,
                                 const Eigen::VectorXd& sd) = nullptr;
  // False where the pair-translation model of video cannot tell the effect from translation: over a
  // scene of nearly one depth a rotation about an image-plane axis moves the image as a sideways
  // move does (the epipole goes where the shift points), so a free translation per pair absorbs
  // the gyro's scale, bias and mounting about those axes. Those are fitted rotation-only.
  bool identifiable_with_pair_translation = true;
  // The import.json claim ("what") that a fit of this effect tests; "" when none does.
  std::string claim;
};

// Every effect, in docs/FORMATS.md's order.
const std::vector<EffectSpec>& AllEffects();
const EffectSpec& Spec(Effect effect);

// The effect of a docs/FORMATS.md name; nullopt for any other text.
std::optional<Effect> ParseEffect(std::string_view name);
// The same where a name is required: throws std::invalid_argument
// "<where>: unknown effect 'NAME' (known: time_offset, readout_time, ...)".
Effect RequireEffect(std::string_view name, const std::string& where);

// Applies one `NAME=VALUE` effect to the true model and returns the value as truth.json records it
// (docs/FORMATS.md units). VALUE is JSON ("[1.01,1,1]", "{\"k1\":-0.1}") or comma-separated numbers
// ("1.01,1,1"; gyro_to_camera: 9 numbers, row-major; lens_distortion: k1[,k2[,p1,p2[,k3]]]) or, for
// readout_direction, a bare word. Throws std::invalid_argument for an unknown name or a bad value.
nlohmann::json ApplyInjection(const std::string& name_equals_value, TrueModel* model);

// Standard errors in the shape of the effect's value, from the covariance of its parameters
// (gyro_to_camera: per matrix entry, first order in the rotation vector). Null for
// readout_direction; NaN (null in JSON) for an undetermined parameter.
nlohmann::json EffectStderr(Effect effect, const TrueModel& model,
                            const Eigen::MatrixXd& covariance);

}  // namespace shutterlab
