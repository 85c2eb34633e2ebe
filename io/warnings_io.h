#pragma once
// What a reader lost (sim/log_warning.h LogWarning) as JSON, docs/FORMATS.md "Warnings": one
// object per warning with kind, message, and t_s and count where they apply. Every JSON output
// that carries warnings (the commands' --json, import.json, the validate report) writes them here.

#include "sim/log_warning.h"

#include <nlohmann/json_fwd.hpp>

#include <vector>

namespace shutterlab {

nlohmann::json WarningsToJson(const std::vector<LogWarning>& warnings);

}  // namespace shutterlab
