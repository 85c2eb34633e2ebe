#pragma once
// The video branch of `validate` (estimate/validate.h describes it); used by validate.cc only.

#include "estimate/validate.h"
#include "render/frames_csv.h"
#include "sim/gyro_trace.h"

#include <chrono>
#include <ostream>
#include <string>
#include <vector>

namespace shutterlab {

// Validates a video dataset whose camera.json (result->declared), gyro log and frames.csv entries
// (all with an empty ref) have been read and checked; fills *result.
void ValidateVideoDataset(const std::string& dataset_dir, const GyroTrace& gyro,
                          const std::vector<FrameEntry>& entries, const ValidateOptions& options,
                          const ValidateProgress& progress, ValidationResult* result);

// Each frame's residual statistics (and, with keep_residuals, its points' residuals) from the
// loop's per-point residuals; frames[k] holds out[k]'s points. translation: the video
// pair-translation loop, or null.
void FillFrameResiduals(const std::vector<FramePoints>& frames, const LoopResult& loop,
                        const LoopResult* translation, bool keep_residuals,
                        std::vector<FrameValidation>* out);

// Wall-clock seconds since start, for the report's timings.
double SecondsSince(std::chrono::steady_clock::time_point start);

// The noise of all frames' points pooled (RMS over points), px, never below kMinNoisePx: identical
// images measure exactly 0, against which every residual would be infinitely significant.
inline constexpr double kMinNoisePx = 1e-3;
double PooledNoisePx(const std::vector<FrameValidation>& frames);

// The value with every number at 4 significant digits, for tables (the JSON keeps them all).
nlohmann::json Rounded(const nlohmann::json& value);

// A loop's lines for a person: before, each effect with its value +- standard error and the
// residual after it, after (against the noise), explained or not.
void WriteLoopSummary(const LoopResult& loop, std::ostream& out);

// The report JSON of a video validation: the preferred model's LoopToJson (FORMATS.md keys) with
// "model", then "rotation_only", "translation" (each LoopToJson), "pairs", "halves", "claims",
// "skipped", "timing_s".
nlohmann::json VideoValidationToJson(const ValidationResult& result);

// The tables and summary for a person.
std::string VideoValidationReport(const ValidationResult& result);

// The effects FORMATS.md lists that a video's rotation-only or pair-translation model can fit:
// all but velocity, which the pair translation replaces.
std::vector<std::string> VideoCandidates();

// False for the effects that the pair-translation model cannot tell from translation: over a scene
// of nearly one depth a rotation about an image-plane axis moves the image as a sideways move does
// (the epipole goes where the shift points), so a free translation per pair absorbs the gyro's
// scale, bias and mounting about those axes. Those are fitted with the rotation-only model only.
bool IdentifiableWithPairTranslation(const std::string& effect);

}  // namespace shutterlab
