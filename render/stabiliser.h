#pragma once
// A stabiliser that re-renders a video (render --video --stabiliser): known-answer footage for the
// test of whether the image follows the gyro, per camera axis (estimate/loop/point_screen.h).
//
// Each frame k is turned by one rotation S_k (its cam_from_image, FramePoints' convention): row v
// of the output is seen from world_from_cam(t_v) S_k, so every row keeps its own readout time and
// the frame keeps the sensor's rolling shutter (a stabiliser that renders row by row, as an EIS
// with rolling-shutter correction does; the loop's model with cam_from_image is exact for it).
// R_k is the camera's orientation at frame k's middle row; the modes:
//  - whole: the orientation is smoothed on all three axes. phi_k = Log(R_0^T R_k), its Gaussian
//    average over the frames' times (sigma = window_s) phi-bar_k, S_k = R_k^T R_0 Exp(phi-bar_k);
//    a clip that turns more than 170 degrees from its first frame is refused (the average would
//    cross Log's wrap at 180).
//  - roll (horizon levelling): only the roll about the optical axis (camera z) is smoothed. r_k is
//    the accumulated z part of Log(R_(k-1)^T R_k), r-bar_k its Gaussian average, S_k = Rz(r-bar_k -
//    r_k): the image keeps the slow roll and loses the fast one.
//  - roll-lock: the roll is held at the first frame's, S_k = Rz(-r_k): the image never rolls.
// The other axes follow the gyro in the two roll modes.

#include "model/truth_model.h"

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

enum class StabiliserMode { kOff, kWhole, kRoll, kRollLock };

// "off", "whole", "roll", "roll-lock".
const char* StabiliserModeName(StabiliserMode mode);
std::optional<StabiliserMode> ParseStabiliserMode(const std::string& name);

struct StabiliserOptions {
  StabiliserMode mode = StabiliserMode::kOff;
  double window_s = 0.5;  // the smoothing's sigma (whole, roll)
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

// Each frame's S_k (identity for kOff); motions: the frames' motions in one world (a video's),
// t_s: their times in seconds, increasing.
std::vector<Eigen::Matrix3d> StabiliserRotations(const StabiliserOptions& options,
                                                 const std::vector<FrameMotion>& motions,
                                                 const std::vector<double>& t_s);

// Turns every row's pose (and the reference's) by cam_from_image: world_from_cam(v) S.
void TurnFrame(const Eigen::Matrix3d& cam_from_image, FrameMotion* motion);

}  // namespace shutterlab
