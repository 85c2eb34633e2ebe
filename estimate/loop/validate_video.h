#pragma once
// The video branch of `validate` (estimate/loop/validate.h describes it); called by
// ValidateDataset.

#include "estimate/loop/validation_result.h"
#include "io/frames_csv.h"
#include "io/rig_dataset.h"
#include "model/effects.h"
#include "sim/gyro_trace.h"

#include <string>
#include <vector>

namespace shutterlab {

// Trimming of the "how much does translation explain" comparison: the largest residuals of either
// model (moving objects, bad matches) are left out, this share of each.
inline constexpr double kCompareTrimShare = 0.05;

// Validates a video dataset (ReadRigDataset, video true); result->declared is its camera.json.
// Fills *result.
void ValidateVideoDataset(const RigDataset& dataset, const ValidateOptions& options,
                          const ValidateProgress& progress, ValidationResult* result);

// The effects docs/FORMATS.md lists that a video's rotation-only or pair-translation model can fit:
// all but velocity, which the pair translation replaces. Those that the pair translation cannot
// tell from translation are fitted rotation-only (EffectSpec::identifiable_with_pair_translation).
std::vector<Effect> VideoCandidates();

}  // namespace shutterlab
