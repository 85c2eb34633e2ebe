#include "render/rs_correct.h"

#include "model/effect_io.h"
#include "model/truth_model.h"
#include "render/rs_warp.h"
#include "tests/render/render_fixtures.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

using test::ConstantRateTrace;
using test::SmallRig;
using test::SmoothTexture;

// The fixed point is solved to kCorrectionSolveTolPx (1e-6 px) with a contraction far below 1:
// 1e-5 px leaves room for the rounding of a double round trip.
constexpr double kSolvedTolPx = 1e-5;
// The correction interpolates poses linearly between neighbouring rows, the renderer by slerp:
// they differ by up to theta^2 / 8 rad across the view, theta the row-to-row angle. The brute-force
// test turns at 3.5 rad/s with 0.22 ms rows (theta = 7.9e-4 rad): 7.8e-8 rad, 2.3e-5 px at 300 px.
constexpr double kRowInterpolationTolPx = 5e-5;

TrueModel TruthWith(const RigModel& rig, const std::vector<std::string>& injections = {}) {
  TrueModel model;
  model.rig = rig;
  for (const std::string& injection : injections) ApplyInjection(injection, &model);
  return model;
}

FrameMotion Motion(const TrueModel& model, const GyroTrace& trace, double t_first_row_s) {
  return CameraMotion(trace, model).Frame(SecondsToNs(t_first_row_s));
}

// Every effect of docs/FORMATS.md's table at once, on a fast-turning camera: a hard case.
const std::vector<std::string> kEveryEffect = {
    "gyro_scale=1.02,0.97,1.01",  "gyro_bias=0.01rad/s,-0.02rad/s,0.005rad/s",
    "velocity=3m/s,-2m/s,0.5m/s", "clock_rate=-150ppm",
    "lens_distortion=-0.2,0.05",  "readout_direction=bottom_to_top",
    "time_offset=-3ms",           "readout_time=25ms"};

TEST(CorrectionGeometry, NoMotionMapsEveryPixelToItself) {
  const RigModel rig = SmallRig(96, 72);
  const TrueModel truth = TruthWith(rig, {"lens_distortion=-0.2,0.05"});
  const FrameMotion motion = Motion(truth, ConstantRateTrace(Eigen::Vector3d::Zero()), 0.5);
  const CorrectionGeometry geometry(truth.rig.camera, motion, 0.0, rig.altitude_m);
  const CorrectionMap map(geometry, {});
  const cv::Mat image = SmoothTexture(cv::Size(96, 72), CV_8UC3, 9, 1.0);
  cv::Mat out;
  PackedMask mask;
  CorrectFrame(image, map, Interpolation::kBilinear, &out, &mask);
  EXPECT_EQ(cv::norm(out, image, cv::NORM_INF), 0.0);
  EXPECT_EQ(CountSetPixels(mask), 96u * 72u);
}

// The renderer's exact truth sends a rolling-shutter pixel q to p_ref (FrameGeometry::RefPixel);
// the correction's source of p_ref must be q again, whatever the effects and the lens.
void ExpectInvertsTheRenderersTruth(const RigModel& rig, const GyroTrace& trace,
                                    const std::vector<std::vector<std::string>>& cases) {
  for (const auto& injections : cases) {
    const TrueModel truth = TruthWith(rig, injections);
    const FrameMotion motion = Motion(truth, trace, 0.5);
    const FrameGeometry render(truth.rig.camera, truth.rig.altitude_m, motion, cv::Size(400, 300));
    const CorrectionGeometry geometry(truth.rig.camera, motion, 0.0, truth.rig.altitude_m);
    double largest_px = 0.0;
    for (int v = 0; v < rig.camera.height; v += 7) {
      for (int u = 0; u < rig.camera.width; u += 9) {
        const Eigen::Vector2d p_ref = *render.RefPixel(u, v);
        const std::optional<Eigen::Vector2d> q = geometry.SourcePixel(p_ref.x(), p_ref.y());
        ASSERT_TRUE(q) << injections.size() << " effects at (" << u << ", " << v << ")";
        EXPECT_NEAR(q->x(), u, kSolvedTolPx);
        EXPECT_NEAR(q->y(), v, kSolvedTolPx);
        const Eigen::Vector2d forward = *geometry.OutputPixel(u, v);
        EXPECT_NEAR((forward - p_ref).norm(), 0.0, kSolvedTolPx);
        largest_px = std::max(largest_px, (p_ref - Eigen::Vector2d(u, v)).norm());
      }
    }
    EXPECT_GT(largest_px, 0.5) << "the case must move pixels to test anything";
  }
}

TEST(CorrectionGeometry, InvertsTheRenderersTruthForEveryEffect) {
  std::vector<std::vector<std::string>> cases = {{}, kEveryEffect};
  for (const char* one : {"velocity=6m/s,-4m/s,1m/s", "lens_distortion=-0.3,0.1",
                          "clock_rate=300ppm", "readout_direction=bottom_to_top"}) {
    cases.push_back({one});
  }
  ExpectInvertsTheRenderersTruth(SmallRig(120, 90),
                                 ConstantRateTrace(Eigen::Vector3d(0.9, -1.2, 1.6)), cases);
}

TEST(CorrectionGeometry, InvertsTheRenderersTruthThroughAFisheye) {
  // A 120-degree fisheye (the GoPro MAX's coefficients); the lens effect adds to its k1, k2.
  ExpectInvertsTheRenderersTruth(
      test::FisheyeRig(120, 90, 60.0), ConstantRateTrace(Eigen::Vector3d(0.9, -1.2, 1.6)),
      {{}, {"lens_distortion=-0.02,0.01", "velocity=6m/s,-4m/s,1m/s", "time_offset=-3ms"}});
}

TEST(CorrectionGeometry, RotationOnlyThroughALensWiderThan180Degrees) {
  // A 220-degree fisheye (rotation only, as for video): rays beyond 90 degrees off the axis point
  // behind the image plane and must still be corrected, each rolling-shutter pixel's output
  // mapping back to it; outside the lens's image circle nothing has a source.
  const RigModel rig = test::FisheyeRig(160, 120, 110.0);
  const TrueModel truth = TruthWith(rig);
  const FrameMotion motion = Motion(truth, ConstantRateTrace(Eigen::Vector3d(1.2, -1.6, 2.0)), 0.5);
  const CorrectionGeometry geometry(rig.camera, motion, 0.0, std::nullopt);
  int behind = 0, compared = 0;
  for (int v = 0; v < rig.camera.height; v += 5) {
    for (int u = 0; u < rig.camera.width; u += 5) {
      const Eigen::Vector3d ray = rig.camera.CamFromImg(Eigen::Vector2d(u, v));
      const std::optional<Eigen::Vector2d> p = geometry.OutputPixel(u, v);
      if (!ray.allFinite()) {
        EXPECT_FALSE(p && p->allFinite())
            << "outside the image circle at (" << u << ", " << v << ")";
        continue;
      }
      ASSERT_TRUE(p) << "(" << u << ", " << v << ")";
      const std::optional<Eigen::Vector2d> q = geometry.SourcePixel(p->x(), p->y());
      ASSERT_TRUE(q) << "(" << u << ", " << v << ")";
      EXPECT_NEAR((*q - Eigen::Vector2d(u, v)).norm(), 0.0, kSolvedTolPx)
          << "(" << u << ", " << v << ")";
      behind += ray.z() <= 0 ? 1 : 0;
      ++compared;
    }
  }
  EXPECT_GT(behind, 20) << "the test must reach beyond 90 degrees";
  EXPECT_GT(compared, 500);
}

// The brute-force twin of the fixed point: scan every row w for a sign change of
// project(X, pose(w)).y - w with the renderer's own pose interpolation (FrameMotion), then bisect.
std::optional<Eigen::Vector2d> BruteForceSource(const PinholeCamera& camera,
                                                const FrameMotion& motion, double depth_m, double u,
                                                double v) {
  const Eigen::Vector3d ray = camera.CamFromImg(Eigen::Vector2d(u, v));  // reference pose: I, 0
  const Eigen::Vector3d point = ray * (depth_m / ray.z());
  const auto project = [&](double w) {
    return *camera.ImgFromCam(motion.WorldFromCamAtRow(w).transpose() *
                              (point - motion.CamCenterAtRow(w)));
  };
  const auto gap = [&](double w) { return project(w).y() - w; };
  for (int w = 0; w + 1 < camera.height; ++w) {
    double lo = w, hi = w + 1;
    if ((gap(lo) > 0) == (gap(hi) > 0)) continue;
    for (int it = 0; it < 60; ++it) {
      const double mid = 0.5 * (lo + hi);
      ((gap(mid) > 0) == (gap(lo) > 0) ? lo : hi) = mid;
    }
    return project(0.5 * (lo + hi));
  }
  return std::nullopt;
}

TEST(CorrectionGeometry, FixedPointMatchesABruteForceRowSearch) {
  const RigModel rig = SmallRig(120, 90);
  const TrueModel truth =
      TruthWith(rig, {"velocity=5m/s,-3m/s,0.5m/s", "lens_distortion=-0.25,0.06"});
  const FrameMotion motion = Motion(truth, ConstantRateTrace(Eigen::Vector3d(1.5, -2.0, 2.5)), 0.5);
  const CorrectionGeometry geometry(truth.rig.camera, motion, 0.0, rig.altitude_m);
  int compared = 0;
  for (int v = 3; v < rig.camera.height; v += 11) {
    for (int u = 2; u < rig.camera.width; u += 13) {
      const std::optional<Eigen::Vector2d> brute =
          BruteForceSource(truth.rig.camera, motion, rig.altitude_m, u + 0.25, v + 0.5);
      if (!brute) continue;  // the source leaves the frame: nothing to compare
      const Eigen::Vector2d fast = *geometry.SourcePixel(u + 0.25, v + 0.5);
      EXPECT_NEAR((fast - *brute).norm(), 0.0, kRowInterpolationTolPx)
          << "at (" << u << ", " << v << ")";
      ++compared;
    }
  }
  EXPECT_GT(compared, 40);
}

// Every pixel's interpolated source against its exact solution: the largest difference, px.
double WorstMapError(const CorrectionMap& map, const CorrectionGeometry& geometry) {
  const PinholeCamera& camera = geometry.camera();
  std::vector<float> xs(camera.width), ys(camera.width);
  double worst = 0.0;
  for (int v = 0; v < camera.height; ++v) {
    map.SourceRow(v, 0, camera.width, xs.data(), ys.data());
    for (int u = 0; u < camera.width; ++u) {
      const Eigen::Vector2d exact = *geometry.SourcePixel(u, v);
      worst = std::max(worst, (Eigen::Vector2d(xs[u], ys[u]) - exact).norm());
    }
  }
  return worst;
}

// Float storage of the nodes adds ~1e-4 px to the checked error.
constexpr double kFloatNodesPx = 2e-4;

TEST(CorrectionMap, InterpolationStaysWithinItsToleranceEverywhere) {
  // Strong motion, a lens and translation: the map curves.
  const RigModel rig = SmallRig(200, 150);
  const TrueModel truth = TruthWith(rig, kEveryEffect);
  const FrameMotion motion = Motion(truth, ConstantRateTrace(Eigen::Vector3d(2.5, -3.0, 4.0)), 0.5);
  const CorrectionGeometry geometry(truth.rig.camera, motion, 0.0, rig.altitude_m);
  for (const double tolerance_px : {0.05, 0.002}) {
    CorrectionMapOptions options;
    options.tolerance_px = tolerance_px;
    const CorrectionMap map(geometry, options);
    EXPECT_LE(map.estimated_error_px(), tolerance_px);
    // Smooth: the checked points are where the error peaks.
    const double worst = WorstMapError(map, geometry);
    EXPECT_LE(worst, tolerance_px + kFloatNodesPx) << "cell " << map.cell_px();
    EXPECT_GE(worst, 0.5 * map.estimated_error_px()) << "the check is not far off";
    if (tolerance_px < 0.01) {
      EXPECT_LT(map.cell_px(), 32) << "a tight tolerance refines the grid";
    }
  }
}

TEST(CorrectionMap, RowsCrowdWhereTheRateJumps) {
  // A rate that jumps every 2 ms (vibration between gyro samples): the pose bends at every sample,
  // and the map's slope down a column with it. Node rows are added where the bends are; a kink
  // between two checked rows may leave up to twice the checked error.
  const RigModel rig = SmallRig(200, 150);
  std::vector<GyroSample> samples;
  for (int k = 0; k <= 2000; ++k) {
    const double sign = (k / 2) % 2 == 0 ? 1.0 : -1.0;
    samples.push_back({k * 1'000'000LL, Eigen::Vector3d(0.4 + 3.0 * sign, -0.3, 0.5)});
  }
  const TrueModel truth = TruthWith(rig);
  const FrameMotion motion = Motion(truth, GyroTrace(std::move(samples)), 0.5);
  const CorrectionGeometry geometry(truth.rig.camera, motion, 0.0, std::nullopt);
  const CorrectionMap map(geometry, {});
  EXPECT_LE(map.estimated_error_px(), CorrectionMapOptions{}.tolerance_px);
  EXPECT_GT(map.node_rows(), 150u / map.cell_px() + 2) << "bands were split";
  EXPECT_LE(WorstMapError(map, geometry), 2 * CorrectionMapOptions{}.tolerance_px + kFloatNodesPx);
}

// Renders the rolling-shutter frame and its reference from one smooth float scene; the corrected
// frame must equal the reference to bilinear interpolation error where it has a source, and the
// mask must mark exactly the pixels whose source lies outside the frame.
void ExpectCorrectionGivesTheReference(const RigModel& rig) {
  const TrueModel truth = TruthWith(rig, {"velocity=4m/s,2m/s,0"});
  const FrameMotion motion = Motion(truth, ConstantRateTrace(Eigen::Vector3d(0.8, -1.1, 1.4)), 0.5);
  const cv::Size scene_size(500, 400);
  const cv::Mat scene = SmoothTexture(scene_size, CV_32FC1, 3, 4.0);
  const FrameGeometry render(rig.camera, rig.altitude_m, motion, scene_size);
  const FrameGeometry reference(rig.camera, rig.altitude_m, motion.Reference(), scene_size);
  cv::Mat rs, ref;
  RenderFrame(scene, render, Interpolation::kBilinear, &rs);
  RenderFrame(scene, reference, Interpolation::kBilinear, &ref);
  const CorrectionGeometry geometry(rig.camera, motion, 0.0, rig.altitude_m);
  const CorrectionMap map(geometry, {});
  cv::Mat corrected;
  PackedMask packed;
  CorrectFrame(rs, map, Interpolation::kBilinear, &corrected, &packed);
  const cv::Mat mask = UnpackMask(packed);
  cv::Mat diff;
  cv::absdiff(corrected, ref, diff);
  // Texture 0..1 with a 4 px blur: two bilinear passes leave ~1e-3.
  EXPECT_LT(cv::mean(diff, mask)[0], 3e-3);
  cv::absdiff(rs, ref, diff);
  EXPECT_GT(cv::mean(diff, mask)[0], 1e-2) << "uncorrected must be clearly worse";
  int disagree = 0, masked = 0;
  for (int v = 0; v < rig.camera.height; ++v) {
    for (int u = 0; u < rig.camera.width; ++u) {
      const std::optional<Eigen::Vector2d> q = geometry.SourcePixel(u, v);
      const bool has = q && geometry.HasSource(*q);
      // Fixed-point rounding (1/256 px) may move a source across the border.
      const bool near_border = q && (std::abs(q->x()) < 0.01 || std::abs(q->y()) < 0.01 ||
                                     std::abs(q->x() - (rig.camera.width - 1)) < 0.01 ||
                                     std::abs(q->y() - (rig.camera.height - 1)) < 0.01);
      if (!near_border && has != (mask.at<uint8_t>(v, u) == 255)) ++disagree;
      masked += has ? 0 : 1;
    }
  }
  EXPECT_EQ(disagree, 0);
  EXPECT_GT(masked, 0) << "the motion must leave part of the view without a source";
}

// The mask takes a piece's ends for the whole piece where both lie inside: it must equal the
// taps' test of every pixel (InsideMaskBits of the map's own coordinates), row by row, on frames
// wider than a pass (512 columns) whose motion leaves bands without a source, through a lens
// whose corners are solved per pixel.
TEST(CorrectFrame, MaskIsEveryPixelsTapTest) {
  for (const RigModel& rig : {SmallRig(1203, 90), test::FisheyeRig(1203, 90, 75.0)}) {
    const TrueModel truth = TruthWith(rig, {"velocity=4m/s,2m/s,0"});
    const FrameMotion motion =
        Motion(truth, ConstantRateTrace(Eigen::Vector3d(0.8, -1.1, 1.4)), 0.5);
    const CorrectionGeometry geometry(rig.camera, motion, 45.0, rig.altitude_m);
    const CorrectionMap map(geometry, {});
    const cv::Mat image =
        SmoothTexture(cv::Size(rig.camera.width, rig.camera.height), CV_8UC3, 5, 1.0);
    cv::Mat out;
    PackedMask mask;
    CorrectFrame(image, map, Interpolation::kBilinear, &out, &mask);
    const int width = rig.camera.width, height = rig.camera.height;
    // The coordinates as CorrectFrame computes them, a pass of 512 columns at a time.
    std::vector<int> xi(512), yi(512);
    std::vector<uint8_t> expected((width + 7) / 8);
    for (int v = 0; v < height; ++v) {
      for (int u0 = 0; u0 < width; u0 += 512) {
        const int n = std::min(512, width - u0);
        map.SourceRowFixed(v, u0, n, xi.data(), yi.data());
        InsideMaskBits(xi.data(), yi.data(), n, width, height, &expected[u0 / 8]);
      }
      ASSERT_EQ(std::memcmp(expected.data(), mask.bits.ptr(v), expected.size()), 0) << "row " << v;
    }
    const size_t set = CountSetPixels(mask);
    EXPECT_GT(set, static_cast<size_t>(width) * height / 2);
    EXPECT_LT(set, static_cast<size_t>(width) * height) << "no band without a source";
  }
}

TEST(CorrectFrame, TrueModelGivesTheGlobalShutterReference) {
  ExpectCorrectionGivesTheReference(SmallRig(160, 120));
}

TEST(CorrectFrame, TrueModelGivesTheGlobalShutterReferenceThroughAFisheye) {
  ExpectCorrectionGivesTheReference(test::FisheyeRig(160, 120, 50.0));
}

TEST(CorrectFrame, MidReadoutIsRowZerosViewTurnedToTheMiddleRow) {
  // Rotation only: the corrected image at mid-readout is the row-0 one seen through the rotation
  // between the two poses, one homography.
  const RigModel rig = SmallRig(120, 90);
  const TrueModel truth = TruthWith(rig);
  const FrameMotion motion = Motion(truth, ConstantRateTrace(Eigen::Vector3d(1.0, -1.4, 2.0)), 0.5);
  const double mid = ReferenceRow(CorrectionReference::kMidReadout, rig.shutter, rig.camera.height);
  EXPECT_EQ(mid, 45.0);
  const CorrectionGeometry at_row0(rig.camera, motion, 0.0, std::nullopt);
  const CorrectionGeometry at_mid(rig.camera, motion, mid, std::nullopt);
  const Eigen::Matrix3d k = rig.camera.K();
  const Eigen::Matrix3d mid_from_row0 =
      k * motion.WorldFromCamAtRow(mid).transpose() * motion.WorldFromCamAtRow(0) * k.inverse();
  for (int v = 0; v < rig.camera.height; v += 10) {
    for (int u = 0; u < rig.camera.width; u += 10) {
      const Eigen::Vector3d h = mid_from_row0 * at_row0.OutputPixel(u, v)->homogeneous();
      EXPECT_NEAR((h.hnormalized() - *at_mid.OutputPixel(u, v)).norm(), 0.0, 1e-9);
    }
  }
  RollingShutter bottom_up = rig.shutter;
  bottom_up.direction = ReadoutDirection::kBottomToTop;
  EXPECT_EQ(ReferenceRow(CorrectionReference::kMidReadout, bottom_up, 90), 44.0);
  EXPECT_NEAR(bottom_up.RowTimeOffsetS(44.0, 90), 0.5 * bottom_up.readout_s, 1e-15);
}

TEST(CorrectFrame, OutputDoesNotDependOnThreadCount) {
  const RigModel rig = SmallRig(256, 192);
  const TrueModel truth = TruthWith(rig, {"lens_distortion=-0.2,0.05"});
  const FrameMotion motion = Motion(truth, ConstantRateTrace(Eigen::Vector3d(0.6, -0.8, 1.2)), 0.5);
  const CorrectionGeometry geometry(truth.rig.camera, motion, 0.0, rig.altitude_m);
  const CorrectionMap map(geometry, {});
  const cv::Mat image = SmoothTexture(cv::Size(256, 192), CV_16UC3, 4, 1.0);
  const int threads = cv::getNumThreads();
  cv::Mat one, many;
  cv::setNumThreads(1);
  CorrectFrame(image, map, Interpolation::kBilinear, &one);
  cv::setNumThreads(4);
  CorrectFrame(image, map, Interpolation::kBilinear, &many);
  cv::setNumThreads(threads);
  EXPECT_EQ(cv::norm(one, many, cv::NORM_INF), 0.0);
}

}  // namespace
}  // namespace shutterlab
