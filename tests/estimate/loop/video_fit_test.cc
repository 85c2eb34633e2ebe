// The video pair model: VideoPairPredictor against the renderer's own match of rolling
// shutter frames (its brute-force twin), the per-pair translation (epipolar) model, and the loop on
// video pairs: axis permutations, time and readout, translation.

#include "estimate/loop/effect_fit.h"
#include "estimate/loop/effect_model.h"
#include "model/effect_io.h"
#include "model/effects.h"
#include "model/truth_model.h"
#include "render/rs_warp.h"
#include "sim/so3.h"
#include "tests/estimate/loop/effect_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

// The predictor and the renderer differ only in where integration starts and in interpolating
// between rows (rotated vectors vs slerp of poses): ~1e-8 px.
constexpr double kTwinTolPx = 1e-7;
constexpr double kClipStartS = 12.6, kFps = 30.0;

double FrameTime(int k) { return kClipStartS + k / kFps; }

// Pairs k-1 -> k (k = 1..pairs) with points on a grid, matched by the RENDERER's geometry under
// `truth` (frames in the world of frame 0, as render --video), plus Gaussian noise (sigma per
// component). Points whose match leaves the earlier frame are dropped, as measure would.
std::vector<FramePoints> RenderedPairs(const TrueModel& truth, const GyroTrace& gyro, int pairs,
                                       int step_px, double sigma_px, uint64_t seed = 1) {
  const CameraMotion motion(gyro, truth);
  const int64_t anchor = SecondsToNs(FrameTime(0));
  const PinholeCamera& cam = truth.rig.camera;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma_px);
  std::vector<FramePoints> out;
  for (int k = 1; k <= pairs; ++k) {
    const FrameGeometry later(cam, truth.rig.altitude_m,
                              motion.Frame(SecondsToNs(FrameTime(k)), anchor), {4000, 3000});
    const FrameGeometry earlier(cam, truth.rig.altitude_m,
                                motion.Frame(SecondsToNs(FrameTime(k - 1)), anchor), {4000, 3000});
    FramePoints f;
    f.frame = k;
    f.t_first_row_ns = SecondsToNs(FrameTime(k));
    f.earlier = EarlierFrame{k - 1, SecondsToNs(FrameTime(k - 1))};
    for (int v = step_px / 2; v < cam.height; v += step_px) {
      for (int u = step_px / 2; u < cam.width; u += step_px) {
        const std::optional<Eigen::Vector2d> q = VideoMatch(later, earlier, u, v);
        if (!q) continue;
        MeasuredPoint p;
        p.u = u;
        p.v = v;
        p.dx = q->x() - u + noise(rng);
        p.dy = q->y() - v + noise(rng);
        f.points.push_back(p);
      }
    }
    out.push_back(std::move(f));
  }
  return out;
}

// The true models the twin test checks: each effect of docs/FORMATS.md's table that a rotation-only
// video model holds (velocity is the pair translation's).
std::vector<std::pair<std::string, TrueModel>> TrueModels() {
  std::vector<std::pair<std::string, TrueModel>> out;
  const std::vector<std::string> injections = {"time_offset=4ms",
                                               "readout_time=36ms",
                                               "gyro_to_camera=0,-1,0,-1,0,0,0,0,-1",
                                               "gyro_scale=1.05,0.95,1.04",
                                               "gyro_bias=0.01rad/s,-0.02rad/s,0.005rad/s",
                                               "lens_distortion=-0.1,0.02",
                                               "readout_direction=bottom_to_top",
                                               "clock_rate=300ppm"};
  TrueModel declared;
  declared.rig = test::VideoRig();
  out.emplace_back("declared", declared);
  for (const std::string& injection : injections) {
    TrueModel model = declared;
    ApplyInjection(injection, &model);
    out.emplace_back(injection, model);
  }
  // A 120 degree fisheye, as declared and with its lens effect.
  TrueModel fisheye;
  fisheye.rig = test::FisheyeRig(640, 480);
  out.emplace_back("fisheye", fisheye);
  ApplyInjection("lens_distortion=0.09,0.02,-0.04,0.015", &fisheye);
  out.emplace_back("fisheye lens_distortion=0.09,0.02,-0.04,0.015", fisheye);
  return out;
}

TEST(VideoPairPredictor, EqualsTheRenderersMatchForEveryEffect) {
  const GyroTrace gyro = test::FlightTrace(20.0, 3);
  for (const auto& [name, truth] : TrueModels()) {
    const std::vector<FramePoints> pairs = RenderedPairs(truth, gyro, 3, 40, 0.0);
    const VideoPairPredictor predictor(gyro, pairs, false, 1.0);
    std::vector<Eigen::Vector2d> predicted;
    predictor.Predict(truth, &predicted);
    size_t i = 0, compared = 0;
    double worst = 0.0;
    for (const FramePoints& f : pairs) {
      for (const MeasuredPoint& p : f.points) {
        ASSERT_TRUE(predicted[i].allFinite()) << name << " point " << i;
        worst = std::max(worst, (predicted[i] - Eigen::Vector2d(p.dx, p.dy)).norm());
        ++i;
        ++compared;
      }
    }
    EXPECT_GT(compared, 300u) << name;
    EXPECT_LT(worst, kTwinTolPx) << name;
  }
}

TEST(VideoPairPredictor, RefusesMixedFrames) {
  const GyroTrace gyro = test::FlightTrace(20.0, 3);
  TrueModel truth;
  truth.rig = test::VideoRig();
  std::vector<FramePoints> frames = RenderedPairs(truth, gyro, 2, 80, 0.0);
  frames[1].earlier.reset();
  EXPECT_THROW(MakePredictor(gyro, frames, false, 1.0), std::invalid_argument);
  EXPECT_THROW(MakePredictor(gyro, {frames[1]}, true, 1.0), std::invalid_argument);
}

TEST(VideoPairPredictor, PairTranslationFollowsAMovingCamera) {
  // A camera moving over flat ground: the rotation-only prediction misses by the parallax, while
  // each match lies on its epipolar line (per-row poses, the translation direction fitted).
  const GyroTrace gyro = test::FlightTrace(20.0, 3);
  TrueModel truth;
  truth.rig = test::VideoRig();
  truth.rig.velocity_mps = {3.0, -2.0, 4.0};
  TrueModel declared;
  declared.rig = test::VideoRig();
  const std::vector<FramePoints> pairs = RenderedPairs(truth, gyro, 3, 32, 0.0);
  std::vector<Eigen::Vector2d> rotation, translation;
  VideoPairPredictor(gyro, pairs, false, 1.0).Predict(declared, &rotation);
  const VideoPairPredictor epipolar(gyro, pairs, true, 1.0);
  epipolar.Predict(declared, &translation);
  double rotation_ss = 0.0, translation_worst = 0.0;
  size_t i = 0;
  for (const FramePoints& f : pairs) {
    for (const MeasuredPoint& p : f.points) {
      const Eigen::Vector2d measured(p.dx, p.dy);
      rotation_ss += (measured - rotation[i]).squaredNorm();
      ASSERT_TRUE(translation[i].allFinite());
      translation_worst = std::max(translation_worst, (measured - translation[i]).norm());
      // Only the distance across the line is a residual: the second component is always 0.
      EXPECT_EQ((measured - translation[i]).y(), 0.0);
      ++i;
    }
  }
  EXPECT_GT(std::sqrt(rotation_ss / i), 0.3);
  EXPECT_LT(translation_worst, 1e-4);
  // The direction, in the earlier frame's row-0 camera axes: nearly the world velocity (the
  // frames look nearly straight down, a few degrees off by the flight's attitude).
  ASSERT_EQ(epipolar.translation_dirs().size(), pairs.size());
  for (const Eigen::Vector3d& dir : epipolar.translation_dirs()) {
    EXPECT_GT(std::abs(dir.dot(truth.rig.velocity_mps.normalized())), 0.99) << dir.transpose();
  }
}

LoopResult Loop(const TrueModel& declared, const GyroTrace& gyro,
                const std::vector<FramePoints>& pairs, bool translation, double noise_px) {
  LoopOptions options;
  options.pair_translation = translation;
  for (const EffectSpec& spec : AllEffects()) {
    if (spec.effect != Effect::kVelocity) options.candidates.push_back(spec.effect);
  }
  return CloseTheLoop(declared.rig, gyro, pairs, noise_px, options);
}

constexpr double kVideoNoisePx = 0.03;  // per component
constexpr double kNoiseRmsPx = kVideoNoisePx * 1.41421356;

TEST(CloseTheLoopVideo, FindsAWronglyLabelledGyro) {
  // The sensor's axes are a quarter turn about z and a flip from what camera.json says: far
  // outside a local fit's reach; the loop starts from the best of the 24 axis rotations.
  const GyroTrace gyro = test::FlightTrace(20.0, 3);
  TrueModel truth, declared;
  truth.rig = declared.rig = test::VideoRig();
  ApplyInjection("gyro_to_camera=0,1,0,1,0,0,0,0,-1", &truth);
  const std::vector<FramePoints> pairs = RenderedPairs(truth, gyro, 8, 32, kVideoNoisePx);
  const LoopResult loop = Loop(declared, gyro, pairs, false, kNoiseRmsPx);
  ASSERT_FALSE(loop.effects.empty());
  EXPECT_EQ(Spec(loop.effects.front().effect).name, "gyro_to_camera");
  const double angle_rad =
      LogSO3(Eigen::Quaterniond(loop.model.rig.cam_from_gyro * truth.rig.cam_from_gyro.transpose()))
          .norm();
  EXPECT_LT(angle_rad, 0.1 * M_PI / 180) << loop.model.rig.cam_from_gyro;
  EXPECT_FALSE(loop.unexplained);
}

TEST(CloseTheLoopVideo, RecoversTimeOffsetNotAClockRateOverAShortClip) {
  if (test::kAsan) GTEST_SKIP() << "reduced set under ASan";
  // Over half a second a clock rate is a time offset in all but a few parts in 1e4: the simpler
  // effect must be named.
  const GyroTrace gyro = test::FlightTrace(20.0, 3);
  TrueModel truth, declared;
  truth.rig = declared.rig = test::VideoRig();
  truth.rig.time_offset_s = 0.004;
  const std::vector<FramePoints> pairs = RenderedPairs(truth, gyro, 15, 32, kVideoNoisePx);
  for (bool translation : {false, true}) {
    const LoopResult loop = Loop(declared, gyro, pairs, translation, kNoiseRmsPx);
    ASSERT_EQ(loop.effects.size(), 1u) << translation;
    EXPECT_EQ(Spec(loop.effects[0].effect).name, "time_offset") << translation;
    EXPECT_NEAR(loop.model.rig.time_offset_s, 0.004, 0.05e-3) << translation;
    EXPECT_EQ(loop.residual_components, translation ? 1 : 2);
  }
}

TEST(CloseTheLoopVideo, TranslationExplainsAMovingCameraThatRotationCannot) {
  const GyroTrace gyro = test::FlightTrace(20.0, 3);
  TrueModel truth, declared;
  truth.rig = declared.rig = test::VideoRig();
  truth.rig.velocity_mps = {2.0, 1.0, 3.0};
  const std::vector<FramePoints> pairs = RenderedPairs(truth, gyro, 8, 32, kVideoNoisePx);
  const LoopResult rotation = Loop(declared, gyro, pairs, false, kNoiseRmsPx);
  const LoopResult translation = Loop(declared, gyro, pairs, true, kNoiseRmsPx);
  EXPECT_TRUE(rotation.unexplained) << rotation.after.rms_px;
  EXPECT_FALSE(translation.unexplained);
  EXPECT_TRUE(translation.effects.empty()) << Spec(translation.effects.front().effect).name;
  EXPECT_EQ(translation.pair_translation_dirs.size(), pairs.size());
  // Across the line the noise alone is left: one component of sigma.
  EXPECT_LT(translation.after.rms_px, 1.3 * kVideoNoisePx);
}

TEST(CloseTheLoopVideo, RecoversPerAxisGyroScale) {
  const GyroTrace gyro = test::FlightTrace(20.0, 3);
  TrueModel truth, declared;
  truth.rig = declared.rig = test::VideoRig();
  ApplyInjection("gyro_scale=1.05,0.95,1.04", &truth);
  const std::vector<FramePoints> pairs = RenderedPairs(truth, gyro, 15, 32, kVideoNoisePx);
  const LoopResult loop = Loop(declared, gyro, pairs, false, kNoiseRmsPx);
  ASSERT_EQ(loop.effects.size(), 1u);
  EXPECT_EQ(Spec(loop.effects[0].effect).name, "gyro_scale");
  EXPECT_LT((loop.model.gyro_scale - Eigen::Vector3d(1.05, 0.95, 1.04)).cwiseAbs().maxCoeff(), 2e-3)
      << loop.model.gyro_scale.transpose();
}

TEST(FitEffects, FitsTheGivenEffectsWithoutSelection) {
  const GyroTrace gyro = test::FlightTrace(20.0, 3);
  TrueModel truth, declared;
  truth.rig = declared.rig = test::VideoRig();
  truth.rig.shutter.readout_s = 0.036;
  const std::vector<FramePoints> pairs = RenderedPairs(truth, gyro, 8, 32, kVideoNoisePx);
  LoopOptions options;
  const LoopResult fit = FitEffects(declared.rig, gyro, pairs, kNoiseRmsPx,
                                    {Effect::kReadoutTime, Effect::kTimeOffset}, options);
  ASSERT_EQ(fit.effects.size(), 2u);
  EXPECT_EQ(Spec(fit.effects[0].effect).name, "readout_time");
  EXPECT_NEAR(fit.model.rig.shutter.readout_s, 0.036, 0.2e-3);
  EXPECT_NEAR(fit.model.rig.time_offset_s, 0.0, 0.1e-3);
  // The time offset is in the fit although the data do not need it, with its standard error.
  EXPECT_GT(std::get<double>(fit.effects[1].stderr_value), 0.0);
  EXPECT_EQ(fit.effects[0].parameters.size(), 1);
  EXPECT_EQ(fit.effects[1].covariance.rows(), 1);
  EXPECT_LT(fit.after.rms_px, fit.before.rms_px);
}

}  // namespace
}  // namespace shutterlab
