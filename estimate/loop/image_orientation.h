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
// The claim holds when share >= kMinShare (0.5) and the image then turns as the model says
// (median |theta_img| / |theta_S| within [kMinGain, 1 / kMinGain], point_screen.h's 0.7); it is
// then applied (FramePoints::cam_from_image), and the validation runs on the re-imaged model.

#include "estimate/loop/frame_points.h"
#include "estimate/loop/point_screen.h"
#include "render/truth_model.h"
#include "sim/gyro_trace.h"

#include <Eigen/Geometry>

#include <map>
#include <string>
#include <vector>

namespace shutterlab {

struct ImageOrientationCheck {
  bool present = false;  // the dataset has IORI
  int pairs_tested = 0;
  double share = 0.0;  // of the image's departure from the gyro the best reading explains
  double gain = 0.0;   // median |theta_img| / |theta_S| over the tested pairs with it
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();  // A of the best reading
  bool inverse = false;                                // s = -1
  bool holds = false;
  std::string verdict;  // for a person
};

inline constexpr double kMinImageOrientationShare = 0.5;

// Tests the readings on the pairs and their rotation consensus (one FrameConsensus per pair).
ImageOrientationCheck TestImageOrientation(const TrueModel& declared, const GyroTrace& gyro,
                                           const std::vector<FramePoints>& pairs,
                                           const std::vector<FrameConsensus>& consensus,
                                           const std::map<int64_t, Eigen::Quaterniond>& iori);

// The reading's S of one written quaternion.
Eigen::Matrix3d CamFromImage(const ImageOrientationCheck& reading, const Eigen::Quaterniond& q);

// Sets every pair's cam_from_image (both frames) from the reading; pairs whose frames lack IORI
// are removed, their indices into the given pairs returned (ascending).
std::vector<size_t> ApplyImageOrientation(const ImageOrientationCheck& reading,
                                          const std::map<int64_t, Eigen::Quaterniond>& iori,
                                          std::vector<FramePoints>* pairs);

}  // namespace shutterlab
