#pragma once
// `validate`: test the paper's threshold model and the declared full model against the
// displacement measured in a rig dataset, then close the loop on undeclared effects.
//
// For every frame of the dataset (docs/FORMATS.md "Rig dataset"; truth/ and truth.json are never
// read):
//  - measured: MeasureDisplacement(ref, image): the points, their noise, D_meas (px), and
//    D_meas_m = D_meas_px * altitude_m / f, f = (fx + fy) / 2;
//  - full model: docs/FORMATS.md's D of the declared model's d(p) (rotation, velocity, lens),
//  evaluated
//    on a grid (kGridStepPx, first and last rows and columns included);
//  - paper's model: estimate/paper/analyze.h Analyze() with a trigger at the frame's gyro time
//    t_first_row + time_offset_s (no bias estimate: gyro.csv is taken as calibrated), which gives
//    D_paper_m = altitude * tan(largest per-axis range in the readout), the per-axis ranges and the
//    dominant axis; D_vector_m = altitude * tan(largest rotation angle between row 0 and any row),
//    the vector criterion, for the per-axis vs vector question.
// Then CloseTheLoop over all frames' points, noise_px = the RMS of the frames' noise over points.
//
// Video datasets (docs/FORMATS.md "Video datasets": every ref empty) are validated pair by
// pair: frames in time order, each against the one before it (MeasureDisplacement(earlier, later)
// gives q - p). There is no global-shutter reference, so no D and no paper's model; the loop runs
// twice over the pairs' points:
//  - rotation only (docs/FORMATS.md's video model; the baseline);
//  - with each pair's translation as an unknown direction (LoopOptions::pair_translation, the
//    epipolar constraint), which parallax from a moving camera needs. Its candidates leave out the
//    gyro's mounting, scale and bias (EffectSpec::identifiable_with_pair_translation); it starts
//    from the rotation-only loop's values of those when that loop left the noise.
// Both are reported, with the share of the rotation-only residual that translation explains. Then:
//  - stability: the preferred model's effects refitted on the first and the second half of the
//    pairs (FitEffects), each effect's two values compared against their standard errors;
//  - the source's claims: when the dataset has an import.json (shutterlab import), each claim that
//    the loop can test (readout_s, gyro_to_camera, time_offset_s, direction) is fitted as an effect
//    beside the identified ones and compared with what the source said.
// Pairs whose declared readout the gyro log does not cover are left out and listed.
// Default candidates for video: every docs/FORMATS.md effect but velocity (translation is the pair
// model's), unless options.loop.candidates names them.

#include "estimate/loop/validation_result.h"

#include <string>

namespace shutterlab {

// Reads the dataset in `dataset_dir` and validates it. Everything is read and checked first; bad
// input throws IoError / std::invalid_argument with one line naming the file, line and problem
// (video datasets: see the top of this file).
ValidationResult ValidateDataset(const std::string& dataset_dir, const ValidateOptions& options,
                                 const ValidateProgress& progress = {});

}  // namespace shutterlab
