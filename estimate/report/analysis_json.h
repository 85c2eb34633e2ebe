#pragma once
// The paper's analyses as docs/FORMATS.md's JSON (`flight`, `analyze`): the results stay typed in
// estimate/paper; their JSON is written here, at the edge.

#include "estimate/paper/analyze.h"
#include "estimate/paper/flight.h"
#include "sim/log_warning.h"

#include <nlohmann/json.hpp>

#include <vector>

namespace shutterlab {

// docs/FORMATS.md `flight` JSON (plus per-axis percentages, window counts and the bias).
nlohmann::json FlightToJson(const FlightResult& result);

// docs/FORMATS.md "Warnings": [{"kind", "message", "t_s", "count"}], t_s and count only where
// they apply.
nlohmann::json WarningsToJson(const std::vector<LogWarning>& warnings);

// docs/FORMATS.md `analyze` JSON (plus bias, verdict and per-image detail).
nlohmann::json AnalyzeToJson(const AnalyzeResult& result);

}  // namespace shutterlab
