#pragma once
// A camera that re-rendered its own image and wrote down how (GoPro IORI: each frame's image
// orientation relative to the body, image_orientation.csv): the claim tested against the images,
// and applied where it holds.
//
// GoPro documents neither IORI's axes nor its sense, so every reading is tried: the frame's
// rotation between the image's virtual camera and the physical one is S = A Q^s A^T, Q the written
// quaternion, s = +1 or -1, A one of the 24 signed axis permutations (effect_model.h
// AxisRotations). The images say how they turned between two frames: the rotation consensus
// (estimate/loop/point_screen.h) gives each pair the image's rotation theta_img = theta_gyro +
// dw dt, theta_gyro = Log(R_e^T R_l) the declared gyro's. A reading predicts
// theta_S = Log(S_e^T R_e^T R_l S_l). Over the pairs whose consensus is determined and whose two
// frames have IORI, the reading with the least sum |theta_img - theta_S|^2 is taken; it explains
// share = 1 - that sum / sum |theta_img - theta_gyro|^2 of how the image departs from the gyro.
// The share is no test: a camera carried on a walk translates, and the rotation consensus takes
// the parallax of a near scene for rotation (on the GoPro MAX clip the best reading, the one
// CORI's own axes give, explains 27 %). The test (JudgeImageOrientation) is point_screen.h's
// check 3 run again with the reading applied: the claim holds when the image then follows the
// gyro turned by S (gain within [kMinGain, 1 / kMinGain]) and the gain is nearer 1 than the
// gyro's alone. Where the camera so turned moves too little for check 3 (fewer than 3 pairs with
// enough predicted motion), the rotations decide: share >= kMinImageOrientationShare (0.5) and
// the median |theta_img| / |theta_S| within [kMinGain, 1 / kMinGain]. It is then applied
// (FramePoints::cam_from_image). The images are then the stabiliser's rendering, not the sensor's
// rows: validate names no effect of the sensor on them (ReRenderedByStabiliser,
// validation_result.h).

#include "estimate/loop/frame_points.h"
#include "estimate/loop/point_screen.h"
#include "model/truth_model.h"
#include "sim/gyro_trace.h"

#include <Eigen/Geometry>

#include <map>
#include <string>
#include <vector>

namespace shutterlab {

inline constexpr double kMinImageOrientationShare = 0.5;

struct ImageOrientationCheck {
  bool present = false;  // the dataset has IORI
  int pairs_tested = 0;
  double share = 0.0;  // of the image's departure from the gyro the best reading explains
  double gain = 0.0;   // median |theta_img| / |theta_S| over the tested pairs with it
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();  // A of the best reading
  bool inverse = false;                                // s = -1
  // JudgeImageOrientation: the image's gain against the gyro alone and against the gyro turned
  // by the reading (point_screen.h check 3; NaN: not determined), over applied_pairs pairs.
  double raw_gain = 0.0, applied_gain = 0.0;
  int applied_pairs = 0;
  bool holds = false;
  std::string verdict;  // for a person
};

// Finds the best reading on the pairs and their rotation consensus (one FrameConsensus per pair);
// holds stays false until JudgeImageOrientation.
ImageOrientationCheck TestImageOrientation(const TrueModel& declared, const GyroTrace& gyro,
                                           const std::vector<FramePoints>& pairs,
                                           const std::vector<FrameConsensus>& consensus,
                                           const std::map<int64_t, Eigen::Quaterniond>& iori);

// The claim's test from check 3 without (raw) and with (applied) the best reading applied: sets
// holds, the gains and the verdict.
void JudgeImageOrientation(const GyroFollowCheck& raw, const GyroFollowCheck& applied,
                           ImageOrientationCheck* check);

// The reading's S of one written quaternion.
Eigen::Matrix3d CamFromImage(const ImageOrientationCheck& reading, const Eigen::Quaterniond& q);

// Sets every pair's cam_from_image (both frames) from the reading; pairs whose frames lack IORI
// are removed, their indices into the given pairs returned (ascending).
std::vector<size_t> ApplyImageOrientation(const ImageOrientationCheck& reading,
                                          const std::map<int64_t, Eigen::Quaterniond>& iori,
                                          std::vector<FramePoints>* pairs);

}  // namespace shutterlab
