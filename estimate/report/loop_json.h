#pragma once
// The loop's results as docs/FORMATS.md's JSON (`validate`, `measure --json`): the results stay
// typed in estimate/loop; their JSON is written here, at the edge.

#include "estimate/loop/effect_fit.h"
#include "estimate/loop/measure.h"

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

// docs/FORMATS.md "Validation report" keys (format, frames, before, effects, after, noise_px,
// unexplained) for a loop result, and its log; beyond them each effect's fitted "parameters" and
// their "covariance", and "fitted_model" (model/effect_io.h TrueModelToJson): what `correct`
// corrects with.
nlohmann::json LoopToJson(const LoopResult& result, size_t frame_count);

// What `correct --report` takes from a validation report.
struct ReportedEffect {
  Effect effect = Effect::kTimeOffset;
  EffectValue value;  // docs/FORMATS.md value
  // EffectSpec's parameters (deltas from the declared model) and their covariance; empty in a
  // report that does not carry them.
  Eigen::VectorXd parameters;
  Eigen::MatrixXd covariance;
};
struct ReportedModel {
  std::vector<ReportedEffect> effects;  // in the report's order
  // The declared model plus every effect, as the loop fitted it ("fitted_model"); absent from
  // reports of other tools or older versions.
  std::optional<TrueModel> fitted;
  double noise_px = 0.0;
  bool unexplained = false;
  ResidualStats after;
};
// Reads a validation report (docs/FORMATS.md validation/1); throws IoError("PATH: problem").
ReportedModel ReadValidationReport(const std::string& path);

// `shutterlab measure --json`: {"format": "measure/1", "width", "height", "D_px", ["D_m"],
// "noise_px", "measured_fraction", "points", ["truth": {"rms_px", "max_px", "pixels"}]}.
nlohmann::json MeasureToJson(const MeasureReport& report);

// The value with every number at 4 significant digits, for tables (the JSON keeps them all).
nlohmann::json Rounded(const nlohmann::json& value);

}  // namespace shutterlab
