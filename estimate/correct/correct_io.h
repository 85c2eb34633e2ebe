#pragma once
// `correct`'s results at the edge: correct.json (docs/FORMATS.md "Correction output") and the
// table a person reads.

#include "estimate/correct/correct_summary.h"

#include <nlohmann/json.hpp>

#include <string>

namespace shutterlab {

// {"format": "correction/1", "dataset", "out", "kind", "reference", "translation", "report",
//  "effects", "model", "gyro_noise", "map", "frames": [...], "skipped", "notes", "warnings"}.
nlohmann::json CorrectionToJson(const CorrectSummary& summary);

// Per frame D before and predicted after (px and m), with the truth's where measured, and a
// closing line.
std::string CorrectionTable(const CorrectSummary& summary);

}  // namespace shutterlab
