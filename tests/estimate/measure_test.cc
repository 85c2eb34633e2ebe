// MeasureDisplacement against exact truth: rendered rolling-shutter pairs of the real aerial scenes
// (a multirotor-like gyro trace), known warps, masks, input types and the noise_px claim.

#include "estimate/measure.h"

#include "render/image_io.h"
#include "render/rs_warp.h"
#include "render/truth_model.h"
#include "sim/synth.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

#if defined(__SANITIZE_ADDRESS__)
constexpr bool kSanitized = true;
#else
constexpr bool kSanitized = false;
#endif

// The accuracy requirement: RMS of |field - truth| over measured pixels, px.
constexpr double kMaxRmsPx = 0.08;

struct RenderedPair {
  cv::Mat ref, rs, truth;  // truth: CV_32FC2 d(p) = p_ref - p
  double d_px = 0.0;
};

// 1280x960, fx 1100, 30 ms readout, 50 m (half size under sanitizers: 4x fewer pixels).
RigModel AerialRig() {
  const double s = kSanitized ? 0.5 : 1.0;
  RigModel rig;
  rig.camera.width = static_cast<int>(1280 * s);
  rig.camera.height = static_cast<int>(960 * s);
  rig.camera.fx = rig.camera.fy = 1100.0 * s;
  rig.camera.cx = (rig.camera.width - 1) / 2.0;
  rig.camera.cy = (rig.camera.height - 1) / 2.0;
  rig.shutter.readout_s = 0.030;
  rig.altitude_m = 50.0;
  return rig;
}

// Frames of a synthetic multirotor flight over a real scene, rendered once per scene.
const std::vector<RenderedPair>& Pairs(const std::string& scene_name) {
  static std::map<std::string, std::vector<RenderedPair>> cache;
  auto it = cache.find(scene_name);
  if (it != cache.end()) return it->second;
  cv::Mat scene = ReadImage(test::SourcePath("assets/scenes/" + scene_name));
  if (kSanitized) cv::resize(scene, scene, {}, 0.5, 0.5, cv::INTER_AREA);
  SynthOptions synth;
  synth.profile = MotionProfile::kFlight;
  synth.rate_hz = 1000.0;
  synth.duration_s = 40.0;
  synth.seed = 11;
  synth.imu = ImuErrorModel::Ideal();
  const GyroTrace trace = SynthesizeTrace(synth);
  TrueModel truth;
  truth.rig = AerialRig();
  const CameraMotion motion(trace, truth);
  std::vector<RenderedPair> pairs;
  const int frames = kSanitized ? 2 : 4;
  for (int i = 0; i < frames; ++i) {
    const FrameMotion fm = motion.Frame(SecondsToNs(8.0 + 2.9 * i));
    const FrameGeometry geometry(truth.rig.camera, truth.rig.altitude_m, fm, scene.size());
    const FrameGeometry reference(truth.rig.camera, truth.rig.altitude_m, fm.Reference(),
                                  scene.size());
    RenderedPair pair;
    RenderFrame(scene, geometry, Interpolation::kBilinear, &pair.rs);
    RenderFrame(scene, reference, Interpolation::kBilinear, &pair.ref);
    pair.truth = DisplacementField(geometry);
    pair.d_px = FrameDistortionPx(pair.truth);
    pairs.push_back(pair);
  }
  return cache[scene_name] = pairs;
}

struct FieldError {
  double rms_px = 0.0, max_px = 0.0;
  size_t pixels = 0;
};

FieldError ErrorAgainstTruth(const cv::Mat& field, const cv::Mat& truth) {
  FieldError e;
  double sum = 0.0;
  for (int v = 0; v < field.rows; ++v) {
    for (int u = 0; u < field.cols; ++u) {
      const cv::Vec2f m = field.at<cv::Vec2f>(v, u), t = truth.at<cv::Vec2f>(v, u);
      if (!std::isfinite(m[0]) || !std::isfinite(t[0])) continue;
      const double d = cv::norm(m - t);
      sum += d * d;
      e.max_px = std::max(e.max_px, d);
      ++e.pixels;
    }
  }
  e.rms_px = e.pixels ? std::sqrt(sum / e.pixels) : 0.0;
  return e;
}

double PointRmsAgainstTruth(const DisplacementMeasurement& m, const cv::Mat& truth) {
  double sum = 0.0;
  for (const MeasuredPoint& p : m.points) {
    const cv::Vec2f t = truth.at<cv::Vec2f>(static_cast<int>(p.v), static_cast<int>(p.u));
    sum += (p.dx - t[0]) * (p.dx - t[0]) + (p.dy - t[1]) * (p.dy - t[1]);
  }
  return std::sqrt(sum / m.points.size());
}

void ExpectAccurateOnScene(const std::string& scene_name) {
  for (const RenderedPair& pair : Pairs(scene_name)) {
    const DisplacementMeasurement m = MeasureDisplacement(pair.ref, pair.rs);
    const FieldError e = ErrorAgainstTruth(m.field, pair.truth);
    const double point_rms = PointRmsAgainstTruth(m, pair.truth);
    std::printf("%s D %.2f px (measured %.2f): field rms %.4f max %.3f px over %.1f%%; points %zu "
                "rms %.4f, noise_px %.4f\n",
                scene_name.c_str(), pair.d_px, m.d_px, e.rms_px, e.max_px,
                100.0 * m.measured_fraction, m.points.size(), point_rms, m.noise_px);
    EXPECT_LE(e.rms_px, kMaxRmsPx);
    EXPECT_GT(m.measured_fraction, 0.5);
  }
}

TEST(Measure, AccurateOnRenderedGrassAndRoofs) { ExpectAccurateOnScene("siyi_zr10_img0100.jpg"); }
TEST(Measure, AccurateOnRenderedTreeCanopy) { ExpectAccurateOnScene("siyi_zr10_img0150.jpg"); }

}  // namespace
}  // namespace shutterlab
