#pragma once
// The video branch of `validate` (estimate/validate.h describes it); called by ValidateDataset.

#include "estimate/loop/validation_result.h"
#include "render/frames_csv.h"
#include "sim/gyro_trace.h"

#include <string>
#include <vector>

namespace shutterlab {

// Trimming of the "how much does translation explain" comparison: the largest residuals of either
// model (moving objects, bad matches) are left out, this share of each.
inline constexpr double kCompareTrimShare = 0.05;

// Validates a video dataset whose camera.json (result->declared), gyro log and frames.csv entries
// (all with an empty ref) have been read and checked; fills *result.
void ValidateVideoDataset(const std::string& dataset_dir, const GyroTrace& gyro,
                          const std::vector<FrameEntry>& entries, const ValidateOptions& options,
                          const ValidateProgress& progress, ValidationResult* result);

// The effects FORMATS.md lists that a video's rotation-only or pair-translation model can fit:
// all but velocity, which the pair translation replaces.
std::vector<std::string> VideoCandidates();

// False for the effects that the pair-translation model cannot tell from translation: over a scene
// of nearly one depth a rotation about an image-plane axis moves the image as a sideways move does
// (the epipole goes where the shift points), so a free translation per pair absorbs the gyro's
// scale, bias and mounting about those axes. Those are fitted with the rotation-only model only.
bool IdentifiableWithPairTranslation(const std::string& effect);

}  // namespace shutterlab
