#pragma once
// What `validate` found, for a person and for files: the report JSON (docs/FORMATS.md "Validation
// report"), the tables, and the residual plots and page.

#include "estimate/loop/validation_result.h"

#include <nlohmann/json.hpp>

#include <ostream>
#include <string>
#include <vector>

namespace shutterlab {

// The report JSON: LoopToJson's docs/FORMATS.md keys plus "dataset", "limits_m", "frames_detail",
// "confusion", "ratios", "timing_s" and "log".
nlohmann::json ValidationToJson(const ValidationResult& result);

// The table and summary for a person.
std::string ValidationReport(const ValidationResult& result);

// With --out DIR: per-frame residual pictures before/after (DIR/NNNN_residual.png), the per-row
// residual profile before/after of all frames (DIR/residual_rows.png, DIR/residual_rows.csv).
// Returns the paths written. Creates DIR when missing; each file whole or not at all.
std::vector<std::string> WriteValidationPlots(const std::string& dir,
                                              const ValidationResult& result);

// The report JSON of a video validation: the preferred model's LoopToJson (docs/FORMATS.md keys)
// with "model", then "rotation_only", "translation" (each LoopToJson), "pairs", "halves", "claims",
// "skipped", "timing_s". ValidationToJson calls it for video datasets.
nlohmann::json VideoValidationToJson(const ValidationResult& result);

// The lens profile's notes (ValidationResult::lens_profile), one indented line each; "" without.
std::string LensProfileLines(const ValidationResult& result);

// The tables and summary of a video validation; ValidationReport calls it for video datasets.
std::string VideoValidationReport(const ValidationResult& result);

// What the screening left out before the loop (estimate/loop/point_screen.h), the mask, and (video)
// whether the image follows the gyro: the report's "screening" JSON and its lines for a person.
nlohmann::json ScreeningToJson(const ValidationResult& result);
void WriteScreeningSummary(const ValidationResult& result, std::ostream& out);

// A loop's lines for a person: before, each effect with its value +- standard error and the
// residual after it, after (against the noise), explained or not.
void WriteLoopSummary(const LoopResult& loop, std::ostream& out);

}  // namespace shutterlab
