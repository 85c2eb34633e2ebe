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

// `shutterlab measure --json`: {"format": "measure/1", "width", "height", "D_px", ["D_m"],
// "noise_px", "measured_fraction", "points", ["truth": {"rms_px", "max_px", "pixels"}]}.
nlohmann::json MeasureToJson(const MeasureReport& report);

// The value with every number at 4 significant digits, for tables (the JSON keeps them all).
nlohmann::json Rounded(const nlohmann::json& value);

}  // namespace shutterlab
