#pragma once
// The axis rotations that gyro_to_camera fits start from (the effects themselves are the table of
// model/effects.h), and a fast predictor of the displacement d(p) = p_ref - p of many measured
// points under any TrueModel.
//
// The predictor computes exactly what the renderer's truth computes (CameraMotion::Frame +
// FrameGeometry::RefPixel): the same row times (TrueModel::RowGyroOffsetS), the same orientation
// integration (OrientationTrace over the true camera-frame rates), the same ray / ground-plane /
// reprojection arithmetic. Only the start of the integration differs: the renderer integrates from
// the first gyro sample of the log, the predictor from the last sample at or before the frame's
// first row time, which is the same relative rotation R(t_0)^T R(t_v) up to rounding (~1e-15).
// That keeps one evaluation proportional to the points and the readout span, not the log length.

#include "estimate/loop/frame_points.h"
#include "model/camera.h"
#include "model/effects.h"
#include "model/truth_model.h"
#include "sim/gyro_trace.h"

#include <Eigen/Core>

#include <memory>
#include <string>
#include <vector>

namespace shutterlab {

// The 24 rotations among the signed permutation matrices (det +1): every way of labelling a
// sensor's axes with camera axes, signs included. gyro_to_camera fits start at the best of them.
const std::vector<Eigen::Matrix3d>& AxisRotations();

// What the loop fits: a prediction of every measured point of a set of frames under any TrueModel,
// frame after frame in the order given, points in their order; NaN where there is none.
class PointPredictor {
 public:
  virtual ~PointPredictor() = default;
  virtual void Predict(const TrueModel& model, std::vector<Eigen::Vector2d>* out) const = 0;
  virtual size_t point_count() const = 0;
  // Largest |t_first_row| of the frames, s (camera clock).
  virtual double frames_span_s() const = 0;
  // Components of (measured - predicted) per point that carry information: 2, or 1 where the
  // prediction is the measured point's foot on a line (the other component is fitted away).
  virtual int residual_components() const { return 2; }
  // Parameters solved inside Predict (not the loop's), for the degrees of freedom.
  virtual int nuisance_parameters() const { return 0; }
  // Translation directions solved inside the last Predict, one per frame (none by default).
  virtual const std::vector<Eigen::Vector3d>& translation_dirs() const {
    static const std::vector<Eigen::Vector3d> kNone;
    return kNone;
  }
};

// Reference datasets: d(p) = p_ref - p of every measured point.
// Rays (K^-1 p, undistorted) are cached while the intrinsics and distortion do not change, so an
// evaluation that only changes gyro-side or timing parameters re-integrates the frames' readout
// spans and re-projects, nothing else. Not thread-safe (the ray cache).
class DisplacementPredictor : public PointPredictor {
 public:
  DisplacementPredictor(const GyroTrace& gyro, const std::vector<FramePoints>& frames);

  // NaN where the ray misses the ground, the reference point is behind the camera, or a needed
  // instant lies outside the gyro trace.
  void Predict(const TrueModel& model, std::vector<Eigen::Vector2d>* out) const override;
  size_t point_count() const override { return points_; }
  double frames_span_s() const override { return frames_span_s_; }

 private:
  struct Frame {
    int64_t t_first_row_ns = 0;
    std::vector<double> rows;         // distinct v of the frame's points, ascending
    std::vector<int> row_of_point;    // index into rows, per point
    std::vector<Eigen::Vector2d> px;  // (u, v) per point
    size_t first = 0;                 // index of the frame's first point in the output
  };
  void RefreshRays(const PinholeCamera& camera) const;

  const GyroTrace& gyro_;
  std::vector<Frame> frames_;
  size_t points_ = 0;
  double frames_span_s_ = 0.0;
  mutable bool rays_valid_ = false;
  mutable PinholeCamera rays_camera_;
  mutable std::vector<Eigen::Vector3d> rays_;  // CamFromImg of every point, output order
};

// Video pairs (every frame has FramePoints::earlier): the match q of each point p of the later
// frame in the earlier one, both rolling shutter (docs/FORMATS.md "Video datasets"), as q - p.
//  A frame re-rendered by a stabiliser (FramePoints::cam_from_image S, per frame) looks through
//  R(t) S instead of R(t): q ~ K S_w^T R(t_w)^T R(t_v) S_v K^-1 p, and the same in the epipolar
//  constraint.
//  - Rotation only (the default): q ~ K R(t_w)^T R(t_v) K^-1 p with K^-1 / K undistorting /
//    distorting, t_v the point's row time, t_w the time of q's own row w = q.y: a fixed point,
//    iterated from w = v (the contraction is the image rate times the row time, far below 1).
//    render/rs_warp.h VideoMatch computes the same from the rendered scene (its brute-force twin).
//    declared velocity is not used: translation is pair_translation's.
//  - pair_translation: each pair's camera moves along an unknown direction V (world frame) during
//    the pair (per-row poses, as Gyroflow's rs-sync). The ray of p at t_v and of q at t_w then
//    lie in one plane with V: V . ((R_w x_q) x (R_v x_p)) = 0, x the undistorted rays, w the
//    MEASURED match's row. V is the eigenvector of the smallest eigenvalue of the weighted sum of
//    those cross products' outer products, weighted to pixel distances from the epipolar line and
//    made robust by Huber IRLS (robust_delta_px); measured - predicted is (d, 0), d the measured
//    match's signed distance across its epipolar line, px (1 component: the "prediction" is the
//    measured match shifted by d along x, not a point on the line; see PredictPair).
// Not thread-safe (ray caches).
class VideoPairPredictor : public PointPredictor {
 public:
  VideoPairPredictor(const GyroTrace& gyro, const std::vector<FramePoints>& frames,
                     bool pair_translation, double robust_delta_px);

  void Predict(const TrueModel& model, std::vector<Eigen::Vector2d>* out) const override;
  size_t point_count() const override { return points_; }
  double frames_span_s() const override { return frames_span_s_; }
  int residual_components() const override { return pair_translation_ ? 1 : 2; }
  int nuisance_parameters() const override {
    return pair_translation_ ? 2 * static_cast<int>(pairs_.size()) : 0;
  }
  // pair_translation: each pair's V (unit; its sign arbitrary, kept from one Predict to the next)
  // from the last Predict, in the earlier frame's row-0 camera axes.
  const std::vector<Eigen::Vector3d>& translation_dirs() const override {
    return translation_dirs_;
  }
  // The screening's epipolar consensus (estimate/loop/point_screen.h), pair_translation only: for
  // each pair, the translation direction that most matches agree with (MSAC over two-match samples:
  // V = a_i x a_j, each match's distance truncated at threshold_px[k]; kHypotheses samples seeded
  // by the pair's index), and every match's distance across its epipolar line under it, px (NaN
  // where there is none), in input order. Matches of weight 0 are neither sampled nor scored.
  std::vector<double> ConsensusDistances(const TrueModel& model,
                                         const std::vector<double>& threshold_px,
                                         int hypotheses) const;

 private:
  struct Pair {
    int64_t t_later_ns = 0, t_earlier_ns = 0;  // t_first_row of both frames, camera clock
    std::vector<double> rows;                  // distinct v of the points, ascending
    std::vector<int> row_of_point;
    std::vector<Eigen::Vector2d> px;        // p (later frame)
    std::vector<Eigen::Vector2d> measured;  // (dx, dy) = q - p as measured
    std::vector<Eigen::Vector2d> match;     // measured q = p + (dx, dy) (earlier frame)
    std::vector<double> weight;
    size_t first = 0;
    // FramePoints::cam_from_image of the later and the earlier frame (identity: not re-rendered).
    Eigen::Matrix3d later_cam_from_image = Eigen::Matrix3d::Identity();
    Eigen::Matrix3d earlier_cam_from_image = Eigen::Matrix3d::Identity();
  };
  void RefreshRays(const PinholeCamera& camera) const;
  // Predict for pair k (its points in *out, its direction in translation_dirs_).
  void PredictPair(const TrueModel& model, size_t k, std::vector<Eigen::Vector2d>* out) const;

  const GyroTrace& gyro_;
  std::vector<Pair> pairs_;
  bool pair_translation_ = false;
  double robust_delta_px_ = 0.0;
  size_t points_ = 0;
  double frames_span_s_ = 0.0;
  mutable bool rays_valid_ = false;
  mutable PinholeCamera rays_camera_;
  mutable std::vector<Eigen::Vector3d> rays_, match_rays_;  // K^-1 p, K^-1 q (z = 1)
  // pair_translation: each pair's V at the previous prediction, which orients the next one's
  // arbitrary sign, and with it the sign of every distance (PredictPair).
  mutable std::vector<Eigen::Vector3d> previous_dirs_;
  mutable std::vector<Eigen::Vector3d> translation_dirs_;
};

// The predictor for a set of frames: VideoPairPredictor when they are video pairs (all of them:
// mixing throws std::invalid_argument), DisplacementPredictor otherwise. robust_delta_px: Huber
// threshold of the pair translation's inner fit (only used with pair_translation).
std::unique_ptr<PointPredictor> MakePredictor(const GyroTrace& gyro,
                                              const std::vector<FramePoints>& frames,
                                              bool pair_translation, double robust_delta_px);

}  // namespace shutterlab
