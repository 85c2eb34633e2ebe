#pragma once
// Synthetic measurements for the effect-fitting tests and bench: the video tests' rig, a
// multirotor-like gyro trace, grid points with the exact displacement of a TrueModel plus Gaussian
// noise. The rigs they start from (MappingRig, NadirRig) are tests/render/render_fixtures.h's.

#include "estimate/loop/effect_fit.h"
#include "model/camera.h"
#include "model/truth_model.h"
#include "sim/gyro_trace.h"
#include "sim/synth/synth.h"
#include "tests/render/render_fixtures.h"

#include <Eigen/Core>

#include <cmath>
#include <cstdint>
#include <random>
#include <stdexcept>
#include <vector>

namespace shutterlab::test {

// The video tests' rig: the mapping rig's (tests/render/render_fixtures.h MappingRig) field of
// view at 640x480 (f = 550 px), 30 ms readout, 50 m.
inline RigModel VideoRig() { return NadirRig(640, 480, 550.0); }

// A multirotor-like logged trace (sim/synth/motion.h flight profile, ideal sensor: the fit only
// sees the logged rates, and the truth is defined on them), 1 kHz.
inline GyroTrace FlightTrace(double duration_s, uint64_t seed) {
  SynthOptions options;
  options.profile = MotionProfile::kFlight;
  options.rate_hz = 1000.0;
  options.duration_s = duration_s;
  options.seed = seed;
  options.imu = ImuErrorModel::Ideal();
  return SynthesizeTrace(options);
}

// Frames with points on a grid of step_px (offset step_px / 2), t_first_row at t_first_s.
inline std::vector<FramePoints> GridFrames(const RigModel& rig,
                                           const std::vector<double>& t_first_s, int step_px) {
  std::vector<FramePoints> frames;
  for (size_t k = 0; k < t_first_s.size(); ++k) {
    FramePoints f;
    f.frame = static_cast<int64_t>(k);
    f.t_first_row_ns = SecondsToNs(t_first_s[k]);
    for (int v = step_px / 2; v < rig.camera.height; v += step_px) {
      for (int u = step_px / 2; u < rig.camera.width; u += step_px) {
        MeasuredPoint p;
        p.u = u;
        p.v = v;
        f.points.push_back(p);
      }
    }
    frames.push_back(std::move(f));
  }
  return frames;
}

inline std::vector<double> EverySecond(int frames, double first_s = 8.0, double spacing_s = 1.0) {
  std::vector<double> t;
  for (int k = 0; k < frames; ++k) t.push_back(first_s + k * spacing_s);
  return t;
}

// Sets every point's measurement to the truth's displacement plus Gaussian noise of sigma_px per
// component (fixed seed). Throws std::runtime_error where the truth is undefined.
inline void MeasureExactly(const TrueModel& truth, const GyroTrace& gyro,
                           std::vector<FramePoints>* frames, uint64_t seed, double sigma_px) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma_px);
  for (FramePoints& f : *frames) {
    const std::vector<Eigen::Vector2d> d = PredictDisplacements(truth, gyro, f);
    for (size_t i = 0; i < f.points.size(); ++i) {
      if (!d[i].allFinite()) throw std::runtime_error("truth undefined at a test point");
      f.points[i].dx = d[i].x() + noise(rng);
      f.points[i].dy = d[i].y() + noise(rng);
    }
  }
}

// Video pairs k-1 -> k (k = 1..pairs, frames at first_s + k / 30 s) with points on a grid of
// step_px, measured as `truth` moves them plus Gaussian noise of noise_px rms length (points whose
// match leaves the frame dropped). cam_from_image (optional, one per frame 0..pairs): how a
// stabiliser re-rendered each frame in the truth; the points are not told (identity).
inline std::vector<FramePoints> MeasuredVideoPairs(
    const TrueModel& truth, const GyroTrace& gyro, int pairs, int step_px, double noise_px,
    uint64_t seed, double first_s = 12.6, const std::vector<Eigen::Matrix3d>& cam_from_image = {}) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_px / std::sqrt(2.0));
  std::vector<FramePoints> out;
  for (int k = 1; k <= pairs; ++k) {
    FramePoints f;
    f.frame = k;
    f.t_first_row_ns = SecondsToNs(first_s + k / 30.0);
    f.earlier = EarlierFrame{k - 1, SecondsToNs(first_s + (k - 1) / 30.0)};
    if (!cam_from_image.empty()) {
      f.cam_from_image = cam_from_image[k];
      f.earlier->cam_from_image = cam_from_image[k - 1];
    }
    for (int v = step_px / 2; v < truth.rig.camera.height; v += step_px) {
      for (int u = step_px / 2; u < truth.rig.camera.width; u += step_px) {
        f.points.push_back({1.0 * u, 1.0 * v});
      }
    }
    const std::vector<Eigen::Vector2d> d = PredictDisplacements(truth, gyro, f);
    std::vector<MeasuredPoint> kept;
    for (size_t i = 0; i < d.size(); ++i) {
      if (!d[i].allFinite()) continue;
      MeasuredPoint p = f.points[i];
      p.dx = d[i].x() + noise(rng);
      p.dy = d[i].y() + noise(rng);
      kept.push_back(p);
    }
    f.points = kept;
    f.cam_from_image.setIdentity();
    f.earlier->cam_from_image.setIdentity();
    out.push_back(std::move(f));
  }
  return out;
}

}  // namespace shutterlab::test
