// MeasureDisplacement against exact truth: rendered rolling-shutter pairs of the real aerial scenes
// (a multirotor-like gyro trace), known warps, masks, input types and the noise_px claim.

#include "estimate/loop/measure.h"

#include "io/image_io.h"
#include "model/truth_model.h"
#include "render/rs_warp.h"
#include "sim/synth/synth.h"
#include "tests/render/render_fixtures.h"
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

// The accuracy measure must reach: RMS of |field - truth| over measured pixels, px.
constexpr double kMaxRmsPx = 0.08;
// noise_px / RMS(point - truth): an estimate of a noise level from a few thousand points, allowing
// for the row model's own small error.
constexpr double kNoiseRatioMin = 0.7;
constexpr double kNoiseRatioMax = 1.4;

struct RenderedPair {
  cv::Mat ref, rs, truth;  // truth: CV_32FC2 d(p) = p_ref - p
  double d_px = 0.0;
};

// 1280x960, fx 1100, 30 ms readout, 50 m (half size under sanitizers: 4x fewer pixels).
RigModel AerialRig() {
  const double s = test::kAsan ? 0.5 : 1.0;
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

// The frame at t_s of `motion`, rendered over `scene`, with its truth.
RenderedPair RenderPair(const cv::Mat& scene, const TrueModel& truth, const CameraMotion& motion,
                        double t_s) {
  const FrameMotion fm = motion.Frame(SecondsToNs(t_s));
  const FrameGeometry geometry(truth.rig.camera, truth.rig.altitude_m, fm, scene.size());
  const FrameGeometry reference(truth.rig.camera, truth.rig.altitude_m, fm.Reference(),
                                scene.size());
  RenderedPair pair;
  RenderFrame(scene, geometry, Interpolation::kBilinear, &pair.rs);
  RenderFrame(scene, reference, Interpolation::kBilinear, &pair.ref);
  pair.truth = DisplacementField(geometry);
  pair.d_px = FrameDistortionPx(pair.truth);
  return pair;
}

// Frames of a synthetic multirotor flight over a real scene, rendered once per scene.
const std::vector<RenderedPair>& Pairs(const std::string& scene_name) {
  static std::map<std::string, std::vector<RenderedPair>> cache;
  auto it = cache.find(scene_name);
  if (it != cache.end()) return it->second;
  cv::Mat scene = ReadImage(scene_name);
  if (test::kAsan) cv::resize(scene, scene, {}, 0.5, 0.5, cv::INTER_AREA);
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
  // Capture times picked from this trace for D of about 2, 6, 10, 15 and 24 px (full size).
  const std::vector<double> times_s = test::kAsan ? std::vector<double>{10.1, 17.0}
                                                  : std::vector<double>{8.7, 7.9, 10.1, 17.0, 23.7};
  for (double t_s : times_s) pairs.push_back(RenderPair(scene, truth, motion, t_s));
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

// measure.h's claim: a perfect model leaves rms ~ noise_px over `points`.
void ExpectNoiseClaimHolds(const DisplacementMeasurement& m, const cv::Mat& truth) {
  ASSERT_GT(m.points.size(), 100u);
  const double ratio = m.noise_px / PointRmsAgainstTruth(m, truth);
  EXPECT_GT(ratio, kNoiseRatioMin);
  EXPECT_LT(ratio, kNoiseRatioMax);
}

void ExpectAccurateOnScene(const std::string& scene_name) {
  for (const RenderedPair& pair : Pairs(scene_name)) {
    const DisplacementMeasurement m = MeasureDisplacement(pair.ref, pair.rs);
    const FieldError e = ErrorAgainstTruth(m.field, pair.truth);
    const double point_rms = PointRmsAgainstTruth(m, pair.truth);
    std::printf(
        "%s D %.2f px (measured %.2f): field rms %.4f max %.3f px over %.1f%%; points %zu "
        "rms %.4f, noise_px %.4f\n",
        scene_name.c_str(), pair.d_px, m.d_px, e.rms_px, e.max_px, 100.0 * m.measured_fraction,
        m.points.size(), point_rms, m.noise_px);
    EXPECT_LE(e.rms_px, kMaxRmsPx);
    EXPECT_GT(m.measured_fraction, 0.85);
    EXPECT_NEAR(m.d_px, pair.d_px, 0.05 * pair.d_px + 0.1);
    ExpectNoiseClaimHolds(m, pair.truth);
  }
}

TEST(Measure, AccurateOnRenderedGroundTexture) { ExpectAccurateOnScene(test::GroundScenePath(1)); }

// A 120 degree fisheye (640x480, half under sanitizers; the GoPro MAX's coefficients): the field
// along a row is no longer a homography's, and the row model must still follow it. One frame, D
// about 4 px.
TEST(Measure, AccurateOnAFisheyeRender) {
  const cv::Mat scene = ReadImage(test::GroundScenePath(1));
  TrueModel truth;
  truth.rig = test::kAsan ? test::FisheyeRig(320, 240) : test::FisheyeRig(640, 480);
  truth.rig.altitude_m = 20.0;  // the scene's 4 cm pixels seen about as fine as the camera's
  SynthOptions synth;
  synth.profile = MotionProfile::kFlight;
  synth.rate_hz = 1000.0;
  synth.duration_s = 20.0;
  synth.seed = 11;
  synth.imu = ImuErrorModel::Ideal();
  const GyroTrace trace = SynthesizeTrace(synth);
  const CameraMotion motion(trace, truth);
  const RenderedPair pair = RenderPair(scene, truth, motion, 17.0);
  const DisplacementMeasurement m = MeasureDisplacement(pair.ref, pair.rs);
  const FieldError e = ErrorAgainstTruth(m.field, pair.truth);
  std::printf("fisheye D %.2f px (measured %.2f): field rms %.4f max %.3f px over %.1f%%\n",
              pair.d_px, m.d_px, e.rms_px, e.max_px, 100.0 * m.measured_fraction);
  EXPECT_GT(pair.d_px, 1.0) << "the frame should move";
  EXPECT_LE(e.rms_px, kMaxRmsPx);
  EXPECT_NEAR(m.d_px, pair.d_px, 0.05 * pair.d_px + 0.1);
  ExpectNoiseClaimHolds(m, pair.truth);
}
TEST(Measure, AccurateOnARealGrassAndRoofsPhoto) {
  SHUTTERLAB_REAL_DATA(photo, "images/siyi_zr10/IMG_0100.jpg");
  ExpectAccurateOnScene(photo);
}

TEST(Measure, AccurateOnARealTreeCanopyPhoto) {
  SHUTTERLAB_REAL_DATA(photo, "images/siyi_zr10/IMG_0150.jpg");
  ExpectAccurateOnScene(photo);
}

// A 480x360 crop of a rendered pair (and its truth): the cheap pair for the type and mask tests.
RenderedPair CroppedPair() {
  const RenderedPair& full = Pairs(test::GroundScenePath(1)).back();
  const cv::Rect crop(full.rs.cols / 2 - 240, full.rs.rows / 2 - 180, 480, 360);
  RenderedPair pair;
  pair.ref = full.ref(crop).clone();
  pair.rs = full.rs(crop).clone();
  pair.truth = full.truth(crop).clone();
  return pair;
}

TEST(Measure, IdenticalImagesGiveZeroField) {
  const cv::Mat texture = test::SmoothTexture({320, 240}, CV_8UC1);
  const DisplacementMeasurement m = MeasureDisplacement(texture, texture);
  EXPECT_GT(m.measured_fraction, 0.9);
  const FieldError e =
      ErrorAgainstTruth(m.field, cv::Mat(texture.size(), CV_32FC2, cv::Scalar(0, 0)));
  EXPECT_LT(e.max_px, 1e-3);
  EXPECT_LT(m.d_px, 1e-3);
  EXPECT_LT(m.noise_px, 1e-3);
}

// image(p) = ref(A p + t), so d(p) = (A - I) p + t exactly: linear in u and v, as the row model
// can represent. warpAffine quantises coordinates to 1/32 px, hence the tolerance.
TEST(Measure, RecoversKnownAffineWarp) {
  constexpr double kTolRmsPx = 0.03;
  const cv::Mat ref = test::SmoothTexture({400, 300}, CV_8UC1, 3, 1.5);
  const double angle = 0.4 * CV_PI / 180, scale = 1.003;
  const cv::Matx23d m(scale * std::cos(angle), -scale * std::sin(angle), 2.3,
                      scale * std::sin(angle), scale * std::cos(angle), -1.7);
  cv::Mat image;
  cv::warpAffine(ref, image, m, ref.size(), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                 cv::BORDER_REFLECT);
  cv::Mat truth(ref.size(), CV_32FC2);
  for (int v = 0; v < ref.rows; ++v) {
    for (int u = 0; u < ref.cols; ++u) {
      truth.at<cv::Vec2f>(v, u) =
          cv::Vec2f(static_cast<float>(m(0, 0) * u + m(0, 1) * v + m(0, 2) - u),
                    static_cast<float>(m(1, 0) * u + m(1, 1) * v + m(1, 2) - v));
    }
  }
  // Only the border (reflected, not warped) may be left unmeasured.
  const cv::Rect inner(8, 8, ref.cols - 16, ref.rows - 16);
  const DisplacementMeasurement measured = MeasureDisplacement(ref, image);
  const FieldError e = ErrorAgainstTruth(measured.field(inner), truth(inner));
  EXPECT_LT(e.rms_px, kTolRmsPx);
  EXPECT_GT(static_cast<double>(e.pixels) / inner.area(), 0.9);
  EXPECT_NEAR(measured.d_px, FrameDistortionPx(truth), 0.05);
}

TEST(Measure, TexturelessSaturatedAndBlackRegionsAreUnmeasured) {
  RenderedPair pair = CroppedPair();
  // The same rectangles in both images: flat grey (no texture), white (saturated), black (what
  // the renderer writes outside the scene).
  const cv::Rect flat(40, 40, 120, 100), white(260, 40, 120, 100), black(0, 250, 480, 110);
  for (cv::Mat* image : {&pair.ref, &pair.rs}) {
    (*image)(flat).setTo(cv::Scalar(120, 110, 100));
    (*image)(white).setTo(cv::Scalar(255, 255, 255));
    (*image)(black).setTo(cv::Scalar(0, 0, 0));
  }
  const DisplacementMeasurement m = MeasureDisplacement(pair.ref, pair.rs);
  // Well inside each rectangle (beyond the gaps that the row model may bridge): nothing.
  const int kInsetPx = 30;
  for (const cv::Rect& r : {flat, white, black}) {
    const cv::Rect inside(r.x + kInsetPx, r.y + kInsetPx, r.width - 2 * kInsetPx,
                          r.height - 2 * kInsetPx);
    EXPECT_EQ(cv::countNonZero(m.confidence(inside)), 0) << inside;
    std::vector<cv::Mat> dxdy;
    cv::split(m.field(inside), dxdy);
    EXPECT_EQ(cv::countNonZero(dxdy[0] == dxdy[0]), 0) << "finite field in " << inside;
  }
  // Saturated and black pixels are never filled, not even next to measured ones.
  for (const cv::Rect& r : {white, black}) {
    std::vector<cv::Mat> dxdy;
    cv::split(m.field(r), dxdy);
    EXPECT_EQ(cv::countNonZero(dxdy[0] == dxdy[0]), 0) << r;
  }
  for (const MeasuredPoint& p : m.points) {
    for (const cv::Rect& r : {flat, white, black}) {
      EXPECT_FALSE(r.contains(cv::Point(static_cast<int>(p.u), static_cast<int>(p.v))))
          << p.u << "," << p.v;
    }
  }
  // The rest is measured as well as ever.
  EXPECT_LT(ErrorAgainstTruth(m.field, pair.truth).rms_px, kMaxRmsPx);
}

TEST(Measure, GreyRgbSixteenBitAndFloatAgree) {
  constexpr double kAgreePx = 0.02;  // different grey conversions, same geometry
  const RenderedPair pair = CroppedPair();
  const DisplacementMeasurement rgb = MeasureDisplacement(pair.ref, pair.rs);
  cv::Mat ref_bgr, rs_bgr, ref_grey, rs_grey, ref16, rs16, ref32, rs32;
  cv::cvtColor(pair.ref, ref_bgr, cv::COLOR_RGB2BGR);
  cv::cvtColor(pair.rs, rs_bgr, cv::COLOR_RGB2BGR);
  cv::cvtColor(pair.ref, ref_grey, cv::COLOR_RGB2GRAY);
  cv::cvtColor(pair.rs, rs_grey, cv::COLOR_RGB2GRAY);
  pair.ref.convertTo(ref16, CV_16U, 257.0);
  pair.rs.convertTo(rs16, CV_16U, 257.0);
  pair.ref.convertTo(ref32, CV_32F, 1.0 / 255.0);
  pair.rs.convertTo(rs32, CV_32F, 1.0 / 255.0);
  const FieldError rgb_error = ErrorAgainstTruth(rgb.field, pair.truth);
  EXPECT_LT(rgb_error.rms_px, kMaxRmsPx);
  // Channel order and bit depth change nothing: the grey of the channels' mean is the same.
  for (const auto& [ref, rs] : {std::pair{ref_bgr, rs_bgr}, {ref16, rs16}, {ref32, rs32}}) {
    const DisplacementMeasurement m = MeasureDisplacement(ref, rs);
    EXPECT_LT(ErrorAgainstTruth(m.field, rgb.field).max_px, 1e-4);
    EXPECT_NEAR(m.noise_px, rgb.noise_px, 1e-6);
  }
  // A luminance grey image is a different picture of the same geometry.
  const DisplacementMeasurement grey = MeasureDisplacement(ref_grey, rs_grey);
  EXPECT_LT(ErrorAgainstTruth(grey.field, pair.truth).rms_px, kMaxRmsPx);
  EXPECT_LT(ErrorAgainstTruth(grey.field, rgb.field).rms_px, kAgreePx);
  EXPECT_NEAR(grey.measured_fraction, rgb.measured_fraction, 0.05);
}

// With sensor noise added to both images the raw points get much noisier; noise_px must follow.
// Without the dense field (video pairs) the points, their noise and the measured share are the
// same numbers, bit for bit; only the field and its confidence are left empty.
TEST(Measure, WithoutTheDenseFieldThePointsAreTheSame) {
  const RenderedPair pair = CroppedPair();
  const DisplacementMeasurement full = MeasureDisplacement(pair.ref, pair.rs);
  MeasureOptions options;
  options.dense_field = false;
  const DisplacementMeasurement points = MeasureDisplacement(pair.ref, pair.rs, options);
  EXPECT_TRUE(points.field.empty());
  EXPECT_TRUE(points.confidence.empty());
  EXPECT_EQ(points.noise_px, full.noise_px);
  EXPECT_EQ(points.measured_fraction, full.measured_fraction);
  ASSERT_EQ(points.points.size(), full.points.size());
  ASSERT_GT(full.points.size(), 100u);
  for (size_t i = 0; i < full.points.size(); ++i) {
    const MeasuredPoint &a = full.points[i], &b = points.points[i];
    EXPECT_TRUE(a.u == b.u && a.v == b.v && a.dx == b.dx && a.dy == b.dy && a.weight == b.weight)
        << "point " << i;
  }
}

TEST(Measure, NoiseEstimateFollowsImageNoise) {
  RenderedPair pair = CroppedPair();
  cv::RNG rng(5);
  for (cv::Mat* image : {&pair.ref, &pair.rs}) {
    cv::Mat noise(image->size(), CV_32FC3);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, 3.0);  // grey levels
    cv::Mat noisy;
    image->convertTo(noisy, CV_32FC3);
    noisy += noise;
    noisy.convertTo(*image, CV_8UC3);
  }
  const DisplacementMeasurement m = MeasureDisplacement(pair.ref, pair.rs);
  std::printf("noisy: noise_px %.4f, points rms %.4f, field rms %.4f\n", m.noise_px,
              PointRmsAgainstTruth(m, pair.truth), ErrorAgainstTruth(m.field, pair.truth).rms_px);
  ExpectNoiseClaimHolds(m, pair.truth);
  EXPECT_LT(ErrorAgainstTruth(m.field, pair.truth).rms_px, kMaxRmsPx);
}

TEST(Measure, RejectsMismatchedOrEmptyImages) {
  const cv::Mat a = test::SmoothTexture({64, 48}, CV_8UC1);
  const cv::Mat b = test::SmoothTexture({64, 40}, CV_8UC1);
  EXPECT_THROW(MeasureDisplacement(a, b), std::invalid_argument);
  EXPECT_THROW(MeasureDisplacement(a, cv::Mat()), std::invalid_argument);
  MeasureOptions options;
  options.grid_step_px = 0;
  EXPECT_THROW(MeasureDisplacement(a, a, options), std::invalid_argument);
}

}  // namespace
}  // namespace shutterlab
