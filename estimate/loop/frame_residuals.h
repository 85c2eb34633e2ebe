#pragma once
// Per-frame residual statistics and the pooled measurement noise, shared by the still and the
// video branches of `validate`.

#include "estimate/loop/frame_points.h"
#include "estimate/loop/validation_result.h"

#include <vector>

namespace shutterlab {

// The noise of all frames' points pooled (RMS over points), px, never below kMinNoisePx
// (measure.h).
double PooledNoisePx(const std::vector<FrameValidation>& frames);

// Each frame's residual statistics over the points each loop used (and, with keep_residuals, every
// point's residuals and why a loop left it out) from the loops' per-point residuals; frames[k]
// holds out[k]'s points. translation: the video pair-translation loop, or null. screen: the
// screening's statuses, one per point of the frames (PointScreen).
void FillFrameResiduals(const std::vector<FramePoints>& frames, const LoopResult& loop,
                        const LoopResult* translation, const PointScreen& screen,
                        bool keep_residuals, std::vector<FrameValidation>* out);

}  // namespace shutterlab
