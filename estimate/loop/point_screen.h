#pragma once
// Points that no fit may use, found before the loop, and whether the image follows the gyro at all.
//
// Real footage holds what the scene model cannot: parts of the frame that move with the camera (a
// car's dashboard, landing gear, propellers, burned-in on-screen text), things that move on their
// own (cars, people), and cameras that re-render their own image (a stabiliser). A robust loss
// only bounds their pull; here they are found and left out (weight 0), before any effect is fitted.
//
//  1. Camera-fixed regions (DetectCameraFixed). On a grid of cells (the measured points' spacing),
//     a point "stays" when its measured displacement is at most kStillRatio (0.35) of what the
//     declared model predicts there, and the prediction is "testable" when it is at least
//     max(kMinTestablePx, kMinTestableNoise (5) x the frame's noise) long (the scene must be
//     predicted to move for a pixel to be caught standing still; a camera-fixed point then stays
//     with probability 1 - e^-3 or more, its noise being at most a fifth of the prediction). A cell
//     moves with the camera when it was testable in at least kMinTestableFrames frames and stayed
//     in at least kFixedShare of them; isolated cells (no fixed neighbour among the 8) are dropped.
//     The points are the frames' corner tracks (FramePoints::tracks, estimate/loop/corner_tracks.h)
//     where the frames have any, else the measured points: dense flow drags a dark, flat region
//     along with the scene beside it, a track is kept only where texture pins it. A cell with no
//     testable point is unmeasured, not scene: unmeasured cells 4-connected to a connected part
//     of at least kMinRegionSeedCells fixed cells join the region (cells_joined), so the flat
//     lower part of a dashboard goes with its textured edge; the scene's cells bound it.
//     A scene point stays only where the camera's own motion cancels its parallax, which wanders
//     from frame to frame; a dashboard stays in every frame. When more than kMaxRegionShare of the
//     testable cells stay, it is no region but the whole image not following the gyro (check 3):
//     nothing is left out for it.
//  2. Consensus (RotationConsensus; for video pairs also the epipolar consensus of
//     VideoPairPredictor::ConsensusDistances). Per frame (or pair), one camera motion must explain
//     a point: the declared model plus a constant angular-rate correction dw over the frame, under
//     the rolling-shutter model itself (each point rotated by dw times its own time between the two
//     views, t_v - t_0 for a still frame, t_v - t_w for a video pair). The correction absorbs what
//     the loop will fit later (a clock offset, a readout, a gyro scale, bias or mounting all act on
//     a frame as a rate correction, to first order), so a point is judged against the frame's own
//     best motion, not against the declared one. MSAC (Torr & Zisserman 2000): kHypotheses random
//     two-point samples (seeded per frame: the same points give the same answer), each scored by
//     the sum of squared residuals truncated at kInlierSigmas (4.5) sigma of the frame's noise
//     (sigma = noise_px / sqrt(2) per component); the best is refitted on its inliers. A point is
//     left out when its residual exceeds kInlierSigmas x max(sigma, sigma-hat), sigma-hat the
//     residuals' own scale from their median (|e| of a 2-D Gaussian: median 1.177 sigma). A
//     Gaussian point is left out with probability e^-10; a model that is wrong everywhere by a
//     little (a lens still to be fitted) widens the threshold with it, a car that moves by pixels
//     stays far outside it. With pair translation (video), the epipolar consensus judges the
//     distance across each match's epipolar line (one component, median 0.674 sigma) by the same
//     rule, the pair's translation direction taking the place of dw.
//  3. Whether the image follows the gyro (CheckImageFollowsGyro, video). The rotation consensus
//     gives each pair the image's own rate, w_gyro + dw (w_gyro the declared gyro's mean rate over
//     the pair, camera axes). A stabiliser (the camera's own or an editor's) removes most of the
//     rotation the gyro saw: the image turns far less. gain = the median over testable pairs
//     (those whose predicted motion is at least kMinGyroTestPx and 5 noise long) of
//     |w_gyro + dw| / |w_gyro|; a mounting turns both alike, so the gain does not depend on it.
//     Below kMinGain (0.7) the image does not follow the gyro: no rolling-shutter effect fitted on
//     it is the sensor's, and the cells that stayed (check 1) are the stabiliser's doing, not a
//     region (they are kept). Measured: the phone clip 1.07 (15 pairs; 10-90 % of the pairs
//     0.88-1.13), the Karma drone's gimbal camera 0.85 (13 pairs), the GoPro MAX with HyperSmooth
//     0.56 (111 pairs; 10-90 %: 0.41-0.81).
//     Per camera axis (AxisFollow): a stabiliser may re-render one axis only (horizon levelling
//     re-renders the roll about the optical axis, z); the whole image's gain cannot see it. Over
//     every pair with a determined consensus (a slow one weighs little), the image's rate is fitted
//     as a linear map of the gyro's, w_img = M w_gyro (least squares, 9 numbers): row a of M says
//     how much of the gyro's rotation, about any axis, shows in the image's rotation about camera
//     axis a. A wrong axis mapping turns the rows (|M_a| stays 1: the loop fits gyro_to_camera); a
//     stabiliser on axis a shrinks row a. The same on the fast part of the rates (each less its
//     running mean over kSlowPairs pairs): a stabiliser that smooths removes the fast part and
//     keeps the slow. Axis a does not follow when |M_a| (or its fast part's) lies kFollowSigmas (3)
//     standard errors below kMinGain, the standard error at most kMaxFollowStderr; it clearly
//     follows when both, and M_aa, lie as far above (M_aa: the declared mapping holds about it; a
//     wrong mapping's large correction biases the consensus about every axis). No axis that
//     follows: the whole image does not. When some axes clearly follow and others do not,
//     FollowImageAbout gives each pair the image's own rotation about those that do not (its
//     cam_from_image), and the loop runs on the gyro about the axes that follow.

#include "estimate/loop/frame_points.h"
#include "model/truth_model.h"
#include "sim/gyro_trace.h"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace shutterlab {

// Why a measured point is left out of the fits (kKept: it is not).
enum class PointStatus : uint8_t {
  kKept = 0,
  kCameraFixed,  // in a region that moves with the camera (check 1)
  kMoving,       // no single camera motion of its frame explains it (rotation consensus)
  kOffEpipolar,  // off its pair's epipolar geometry (video, translation consensus only)
};
const char* PointStatusName(PointStatus status);

struct ScreenOptions {
  bool camera_fixed = true;  // check 1
  bool consensus = true;     // check 2
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

inline constexpr double kStillRatio = 0.35;
inline constexpr double kMinTestablePx = 1.0;
inline constexpr double kMinTestableNoise = 5.0;
inline constexpr int kMinTestableFrames = 2;
inline constexpr double kFixedShare = 0.6;
inline constexpr double kMaxRegionShare = 0.5;
inline constexpr size_t kMinRegionSeedCells = 4;
inline constexpr int kHypotheses = 200;
inline constexpr double kInlierSigmas = 4.5;
inline constexpr double kMinGain = 0.7;

// Check 1's cells: cell (c, r) covers columns [c step, (c + 1) step) and the same rows.
struct CameraFixedRegion {
  int step_px = 16, cols = 0, rows = 0;
  std::vector<uint8_t> fixed;        // per cell, row-major: 1 = moves with the camera
  std::vector<int> testable, still;  // per cell: testable frames, and of them those it stayed in
  size_t cells_fixed = 0, cells_testable = 0;
  size_t cells_joined = 0;   // of cells_fixed, those with no testable measurement (joined)
  bool whole_image = false;  // too much stayed: the image does not follow the gyro (no region)
  bool Contains(double u, double v) const;
};

// Check 2's result for one frame or pair.
struct FrameConsensus {
  size_t candidates = 0;  // points tested (weight > 0, predicted, not camera-fixed)
  size_t rejected = 0;    // of them, left out
  double threshold_px = 0.0;
  Eigen::Vector3d delta_omega_rad_s = Eigen::Vector3d::Zero();  // rotation consensus only
  bool determined = false;  // enough points to judge (otherwise every point is kept)
};

inline constexpr int kSlowPairs = 5;
inline constexpr double kMaxFollowStderr = 0.1;
inline constexpr double kFollowSigmas = 3.0;

// Check 3 about one camera axis.
struct AxisFollow {
  double gain = 0.0;      // M_aa: the image's rate about a per gyro rate about a
  double row_norm = 0.0;  // |M_a|: the share of the gyro's rotation that shows about a
  double row_norm_stderr = std::numeric_limits<double>::quiet_NaN();
  double fast_row_norm = 0.0;  // the same on the fast part
  double fast_row_norm_stderr = std::numeric_limits<double>::quiet_NaN();
  bool determined = false, fast_determined = false;
  bool follows = true;  // false only when determined and clearly below kMinGain
  // Determined and clearly at or above it, M_aa and the fast part too.
  bool clearly_follows = false;
};

// Check 3.
struct GyroFollowCheck {
  int pairs_tested = 0;  // pairs whose predicted motion is testable
  double gain = 1.0;     // median |w_gyro + dw| / |w_gyro| over them
  // Per tested pair: the later frame, the gyro's and the image's rate over the pair, rad/s.
  std::vector<int64_t> frames;
  std::vector<double> gyro_rate_rad_s, image_rate_rad_s;
  bool determined = false;
  bool follows = true;
  std::string verdict;  // for a person
  // Per camera axis x, y, z (AxisFollow), and the per-pair rates in camera axes they come from
  // (every pair with a determined consensus, not only the tested ones).
  std::array<AxisFollow, 3> axes;
  std::vector<Eigen::Vector3d> gyro_rate_cam_rad_s, image_rate_cam_rad_s;
  // Some axes determined to follow and others determined not to: a stabiliser on those.
  bool OnSomeAxes() const;
  std::vector<int> AxesNotFollowing() const;
};

// Everything the screening found, per point in the frames' order.
struct PointScreen {
  std::vector<PointStatus> rotation_status;     // for the rotation-only loop (still: the loop)
  std::vector<PointStatus> translation_status;  // video: for the pair-translation loop
  CameraFixedRegion region;
  std::vector<FrameConsensus> rotation, translation;  // per frame / pair
  GyroFollowCheck gyro_follow;                        // video only
  // Shares of the points with weight > 0 that each check left out.
  double camera_fixed_share = 0.0, moving_share = 0.0, off_epipolar_share = 0.0;
};

// Check 1 on the frames' points and the declared model's prediction of every point (frame after
// frame, NaN where none); frame_noise_px: each frame's measurement noise.
CameraFixedRegion DetectCameraFixed(const std::vector<FramePoints>& frames,
                                    const std::vector<Eigen::Vector2d>& predicted,
                                    const std::vector<double>& frame_noise_px, int width,
                                    int height, int step_px);

// Check 2's rotation consensus on the points whose *status is kKept (those it leaves out become
// kMoving): one FrameConsensus per frame.
std::vector<FrameConsensus> RotationConsensus(const TrueModel& declared,
                                              const std::vector<FramePoints>& frames,
                                              const std::vector<Eigen::Vector2d>& predicted,
                                              const std::vector<double>& frame_noise_px,
                                              std::vector<PointStatus>* status);

// Check 3 from the rotation consensus of video pairs.
GyroFollowCheck CheckImageFollowsGyro(const TrueModel& declared, const GyroTrace& gyro,
                                      const std::vector<FramePoints>& pairs,
                                      const std::vector<Eigen::Vector2d>& predicted,
                                      const std::vector<double>& frame_noise_px,
                                      const std::vector<FrameConsensus>& consensus);

// All three checks (3 and the epipolar consensus for video pairs only). step_px: the measured
// points' grid spacing; each frame's noise is taken as at least kMinNoisePx (measure.h).
PointScreen ScreenPoints(const TrueModel& declared, const GyroTrace& gyro,
                         const std::vector<FramePoints>& frames,
                         const std::vector<double>& frame_noise_px, int step_px,
                         const ScreenOptions& options);

// The frames with the points `status` leaves out at weight 0.
std::vector<FramePoints> WithoutScreened(const std::vector<FramePoints>& frames,
                                         const std::vector<PointStatus>& status);

// Gives each pair the image's own rotation about the camera axes that do not follow the gyro
// (check.AxesNotFollowing()): the later frame's cam_from_image turns by dw_a dt about each such
// axis a (dw: the pair's rotation consensus, dt: the time between the frames' middle rows) from
// the earlier's, which carries the turns accumulated along the pairs before it. Pairs whose
// consensus is not determined are removed, their indices into the given pairs returned (ascending).
std::vector<size_t> FollowImageAbout(const TrueModel& declared, const GyroFollowCheck& check,
                                     const std::vector<FrameConsensus>& consensus,
                                     std::vector<FramePoints>* pairs);

}  // namespace shutterlab
