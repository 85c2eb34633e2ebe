#pragma once
// `analyze --photos --json`: the per-photo predictions (estimate/paper/photo_analysis.h) as
// docs/FORMATS.md's `photos` JSON, at the edge.

#include "estimate/paper/photo_analysis.h"
#include "io/photo_set.h"

#include <nlohmann/json.hpp>

namespace shutterlab {

// {"source", "model", "limits_m", "placement" (with a log), "photos": [...], "summary"}: one entry
// a photo with what was read (make, model, size, capture time, attitude, speed), what was chosen
// and where from (focal_px/focal_source, readout_s/readout_origin/readout_source,
// altitude_m/altitude_source), the predictions and flags, and what is missing.
nlohmann::json PhotoAnalysisToJson(const PhotoSet& set, const PhotoAnalysis& analysis);

}  // namespace shutterlab
