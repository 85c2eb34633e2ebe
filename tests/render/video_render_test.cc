// Video rendering: frames of one flight in one world (CameraMotion::Frame with an
// anchor), the match of a pixel in the previous rolling-shutter frame (VideoMatch), and
// `render --video` datasets.

#include "io/frames_csv.h"
#include "io/image_io.h"
#include "model/truth_model.h"
#include "render/render_dataset.h"
#include "render/rs_warp.h"
#include "sim/check.h"
#include "sim/logs/gyro_io.h"
#include "sim/so3.h"
#include "sim/text_file.h"
#include "tests/render/render_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>

namespace shutterlab {
namespace {

// Integration of a constant rate is exact to rounding; the fixed point stops at 1e-7 px.
constexpr double kExactPx = 1e-6;
constexpr double kVideoRotationTolRad = 1e-12;

TrueModel Model(int width = 96, int height = 72) {
  TrueModel model;
  model.rig = test::SmallRig(width, height);
  return model;
}

TEST(CameraMotionAnchor, OwnAnchorIsTheUnanchoredFrame) {
  const GyroTrace gyro = test::ConstantRateTrace({0.3, -0.2, 0.5});
  TrueModel model = Model();
  model.rig.velocity_mps = {2.0, -1.0, 0.5};
  const CameraMotion motion(gyro, model);
  const int64_t t = SecondsToNs(0.7);
  const FrameMotion a = motion.Frame(t), b = motion.Frame(t, t);
  for (size_t v = 0; v < a.world_from_cam.size(); ++v) {
    EXPECT_TRUE(a.world_from_cam[v].isApprox(b.world_from_cam[v], 1e-15));
    EXPECT_TRUE(a.cam_center_m[v].isApprox(b.cam_center_m[v], 1e-15));
  }
  EXPECT_EQ(a.world_from_ref, Eigen::Matrix3d::Identity());
  EXPECT_EQ(a.ref_center_m, Eigen::Vector3d::Zero());
}

TEST(CameraMotionAnchor, LaterFrameContinuesTheAnchorsWorld) {
  // Constant camera rate w: R(t) = Exp(w (t - t_anchor)) in the anchor's world.
  const Eigen::Vector3d w(0.3, -0.2, 0.5);
  const GyroTrace gyro = test::ConstantRateTrace(w);
  TrueModel model = Model();
  model.rig.velocity_mps = {2.0, -1.0, 0.5};
  const CameraMotion motion(gyro, model);
  const int64_t anchor = SecondsToNs(0.5), t = SecondsToNs(0.8);
  const FrameMotion f = motion.Frame(t, anchor);
  const double row_s = model.rig.shutter.readout_s / model.rig.camera.height;
  for (int v : {0, 17, 71}) {
    const double since_s = 0.3 + v * row_s;
    test::ExpectRotationNear(Eigen::Quaterniond(f.world_from_cam[v]), ExpSO3(w * since_s),
                             kVideoRotationTolRad);
    EXPECT_LT((f.cam_center_m[v] - model.rig.velocity_mps * since_s).norm(), 1e-12);
  }
  test::ExpectRotationNear(Eigen::Quaterniond(f.world_from_ref), ExpSO3(w * 0.3),
                           kVideoRotationTolRad);
}

TEST(FrameMotionRows, FractionalRowsInterpolateBetweenRows) {
  const Eigen::Vector3d w(0.0, 0.4, 0.0);
  const GyroTrace gyro = test::ConstantRateTrace(w);
  TrueModel model = Model();
  model.rig.velocity_mps = {1.0, 0.0, 0.0};
  const FrameMotion f = CameraMotion(gyro, model).Frame(SecondsToNs(0.5));
  const double row_s = model.rig.shutter.readout_s / model.rig.camera.height;
  // Constant rate: the orientation at row 10.25 is Exp(w 10.25 row_s) exactly (slerp of a
  // one-parameter subgroup), the centre linear in time.
  test::ExpectRotationNear(Eigen::Quaterniond(f.WorldFromCamAtRow(10.25)),
                           ExpSO3(w * 10.25 * row_s), 1e-12);
  EXPECT_NEAR(f.CamCenterAtRow(10.25).x(), 10.25 * row_s, 1e-15);
  EXPECT_TRUE(f.WorldFromCamAtRow(71.0).isApprox(f.world_from_cam[71]));
  EXPECT_THROW(f.WorldFromCamAtRow(71.5), std::invalid_argument);
  EXPECT_THROW(f.CamCenterAtRow(-0.1), std::invalid_argument);
}

struct Pair {
  FrameGeometry later, earlier;
};

Pair MakePair(const TrueModel& model, const GyroTrace& gyro, double t_earlier_s, double dt_s) {
  const CameraMotion motion(gyro, model);
  const int64_t anchor = SecondsToNs(t_earlier_s);
  const cv::Size scene(2000, 2000);
  const PinholeCamera& cam = model.rig.camera;
  return {FrameGeometry(cam, model.rig.altitude_m,
                        motion.Frame(SecondsToNs(t_earlier_s + dt_s), anchor), scene),
          FrameGeometry(cam, model.rig.altitude_m, motion.Frame(anchor, anchor), scene)};
}

TEST(VideoMatch, StillCameraMatchesItself) {
  const TrueModel model = Model();
  const Pair pair = MakePair(model, test::ConstantRateTrace({0, 0, 0}), 0.5, 1.0 / 30);
  for (const auto& [u, v] : {std::pair{0, 0}, {40, 33}, {95, 71}}) {
    const std::optional<Eigen::Vector2d> q = VideoMatch(pair.later, pair.earlier, u, v);
    ASSERT_TRUE(q);
    EXPECT_NEAR(q->x(), u, kExactPx);
    EXPECT_NEAR(q->y(), v, kExactPx);
  }
}

TEST(VideoMatch, PanMovesTheCentreRowByTheRotationBetweenFrames) {
  // A pan (camera y axis) at w for dt: the principal point's row stays a row (w = v), and the ray
  // turns by w dt: q.x = cx + f tan(w dt) (rotation Exp(theta y) takes z to (sin, 0, cos)).
  const double w = 0.8, dt = 1.0 / 30;
  TrueModel model = Model();
  model.rig.camera.cy = 36.0;  // an integer row: the pixel sits on it exactly
  const Pair pair = MakePair(model, test::ConstantRateTrace({0, w, 0}), 0.5, dt);
  const std::optional<Eigen::Vector2d> q =
      VideoMatch(pair.later, pair.earlier, model.rig.camera.cx, 36);
  ASSERT_TRUE(q);
  EXPECT_NEAR(q->x(), model.rig.camera.cx + model.rig.camera.fx * std::tan(w * dt), kExactPx);
  EXPECT_NEAR(q->y(), 36.0, kExactPx);
}

TEST(VideoMatch, TiltSolvesTheMatchesOwnRowTime) {
  // A tilt (camera x axis) at w: a pixel of the principal column at row v, time t_v, and its match
  // at row m, time t_m: the ray's elevation angle a = atan((row - cy) / fy) turns by w (t_v - t_m):
  // a_m = a_v - w (dt + (v - m) tau), m = cy + fy tan(a_m). Solved here by bisection on m.
  const double w = 1.5, dt = 1.0 / 30;
  const TrueModel model = Model();
  const PinholeCamera& cam = model.rig.camera;
  const double tau = model.rig.shutter.readout_s / cam.height;
  const Pair pair = MakePair(model, test::ConstantRateTrace({w, 0, 0}), 0.5, dt);
  for (int v : {5, 36, 60}) {
    const double a_v = std::atan((v - cam.cy) / cam.fy);
    const auto g = [&](double m) {
      return cam.cy + cam.fy * std::tan(a_v - w * (dt + (v - m) * tau)) - m;
    };
    double lo = -200, hi = 200;  // g decreases: g(lo) > 0 > g(hi)
    for (int i = 0; i < 200; ++i) {
      const double mid = 0.5 * (lo + hi);
      (g(mid) > 0 ? lo : hi) = mid;
    }
    const double m = 0.5 * (lo + hi);
    const std::optional<Eigen::Vector2d> q = VideoMatch(pair.later, pair.earlier, cam.cx, v);
    if (m < 0 || m > cam.height - 1) {
      EXPECT_FALSE(q) << "row " << v << ": the match is outside the earlier frame";
      continue;
    }
    ASSERT_TRUE(q) << "row " << v;
    EXPECT_NEAR(q->y(), m, kExactPx) << "row " << v;
    EXPECT_NEAR(q->x(), cam.cx, kExactPx) << "row " << v;
  }
}

TEST(VideoDisplacementField, EqualsVideoMatchAtEveryPixel) {
  TrueModel model = Model();
  model.rig.camera.distortion = BrownConrady{{-0.1, 0.02, 0, 0, 0}};
  model.rig.velocity_mps = {3.0, -1.0, 0.5};
  const Pair pair = MakePair(model, test::ConstantRateTrace({0.4, -0.7, 0.9}), 0.5, 1.0 / 25);
  const cv::Mat field = VideoDisplacementField(pair.later, pair.earlier);
  int defined = 0;
  for (int v = 0; v < field.rows; v += 7) {
    for (int u = 0; u < field.cols; u += 5) {
      const std::optional<Eigen::Vector2d> q = VideoMatch(pair.later, pair.earlier, u, v);
      const cv::Vec2f d = field.at<cv::Vec2f>(v, u);
      if (!q) {
        EXPECT_TRUE(std::isnan(d[0]));
        continue;
      }
      ++defined;
      EXPECT_NEAR(d[0], q->x() - u, 1e-4);
      EXPECT_NEAR(d[1], q->y() - v, 1e-4);
    }
  }
  EXPECT_GT(defined, 100);
}

// `render --video`: a dataset another tool could read by docs/FORMATS.md alone.
class RenderVideo : public ::testing::Test {
 protected:
  void SetUp() override {
    TrueModel model = Model(64, 48);
    WriteRigModel(dir_ / "camera.json", model.rig);
    WriteGyroCsv(dir_ / "gyro.csv", test::ConstantRateTrace({0.3, -0.5, 0.2}));
    WriteImage(dir_ / "scene.png", test::SmoothTexture({400, 400}, CV_8UC3));
    options_.scene_path = dir_ / "scene.png";
    options_.camera_path = dir_ / "camera.json";
    options_.gyro_path = dir_ / "gyro.csv";
    options_.frames_path = dir_ / "times.csv";
    options_.out_dir = dir_ / "out";
    options_.video = true;
  }
  test::TempDir dir_;
  RenderOptions options_;
};

TEST_F(RenderVideo, WritesAVideoDatasetWithPairTruth) {
  WriteFileAtomically(dir_ / "times.csv", "frame,t_first_row\n7,0.5\n8,0.54\n9,0.58\n");
  options_.injections = {"time_offset=3ms"};
  const RenderSummary summary = RenderDataset(options_);
  ASSERT_EQ(summary.frames.size(), 3u);
  const std::vector<FrameEntry> frames = ReadFramesCsv(dir_ / "out/frames.csv");
  ASSERT_EQ(frames.size(), 3u);
  for (const FrameEntry& f : frames) {
    EXPECT_TRUE(f.ref.empty());
    EXPECT_TRUE(std::filesystem::is_regular_file(dir_.path() / "out" / f.image));
  }
  const std::string truth = dir_ / "out/truth";
  EXPECT_FALSE(std::filesystem::exists(truth + "/0007_disp.exr"));  // the first has no previous
  const nlohmann::json json = nlohmann::json::parse(ReadFileToString(dir_ / "out/truth.json"));
  EXPECT_EQ(json["video"], true);
  EXPECT_TRUE(json["frames"][0]["previous"].is_null());
  EXPECT_EQ(json["frames"][2]["previous"], 8);
  EXPECT_EQ(json["injected"]["time_offset"], 0.003);

  // The truth of frame 9 is its match in frame 8 under the TRUE model, in the first frame's world.
  TrueModel model = Model(64, 48);
  model.rig.time_offset_s = 0.003;
  const CameraMotion motion(ReadGyroCsv(dir_ / "gyro.csv"), model);
  const int64_t anchor = SecondsToNs(0.5);
  const FrameGeometry later(model.rig.camera, model.rig.altitude_m,
                            motion.Frame(SecondsToNs(0.58), anchor), {400, 400});
  const FrameGeometry earlier(model.rig.camera, model.rig.altitude_m,
                              motion.Frame(SecondsToNs(0.54), anchor), {400, 400});
  const cv::Mat field = ReadFloatImage(truth + "/0009_disp.exr");
  for (const auto& [u, v] : {std::pair{10, 5}, {32, 24}, {60, 40}}) {
    const std::optional<Eigen::Vector2d> q = VideoMatch(later, earlier, u, v);
    ASSERT_TRUE(q);
    EXPECT_NEAR(field.at<cv::Vec2f>(v, u)[0], q->x() - u, 1e-4);
    EXPECT_NEAR(field.at<cv::Vec2f>(v, u)[1], q->y() - v, 1e-4);
  }
}

// render --camera-fixed-patch and --moving-patch (render/clutter.h): the bottom rows are the same
// bytes in every frame and their truth is 0; the moving patch is where truth.json says, its truth
// NaN, and it moves across the ground between frames.
TEST_F(RenderVideo, CameraFixedAndMovingPatchesAreWhereTheTruthSays) {
  WriteFileAtomically(dir_ / "times.csv", "frame,t_first_row\n0,0.5\n1,0.54\n2,0.58\n");
  options_.clutter.camera_fixed_share = 0.25;
  options_.clutter.moving_patch_mps = 20.0;
  RenderDataset(options_);
  const nlohmann::json json = nlohmann::json::parse(ReadFileToString(dir_ / "out/truth.json"));
  const int rows_from = json["camera_fixed_rows_from"].get<int>();
  EXPECT_EQ(rows_from, 36);  // 48 - 0.25 * 48
  EXPECT_EQ(json["moving_patch"]["speed_mps"], 20.0);
  const std::vector<FrameEntry> frames = ReadFramesCsv(dir_ / "out/frames.csv");
  std::vector<cv::Mat> images;
  for (const FrameEntry& f : frames) images.push_back(ReadImage(dir_.path() / "out" / f.image));
  const cv::Rect fixed(0, rows_from, 64, 48 - rows_from), scene(0, 0, 64, rows_from);
  for (size_t k = 1; k < images.size(); ++k) {
    EXPECT_EQ(cv::norm(images[k](fixed), images[0](fixed), cv::NORM_INF), 0.0) << k;
    EXPECT_GT(cv::norm(images[k](scene), images[0](scene), cv::NORM_INF), 0.0) << k;
  }
  // The truth: 0 in the fixed rows, NaN where the patch is seen, finite elsewhere.
  const cv::Mat truth = ReadFloatImage(dir_ / "out/truth/0002_disp.exr");
  int patch = 0, scene_pixels = 0;
  for (int v = 0; v < truth.rows; ++v) {
    for (int u = 0; u < truth.cols; ++u) {
      const cv::Vec2f d = truth.at<cv::Vec2f>(v, u);
      if (v >= rows_from) {
        EXPECT_EQ(d, cv::Vec2f(0, 0)) << u << "," << v;
      } else if (std::isnan(d[0])) {
        ++patch;
      } else {
        ++scene_pixels;
      }
    }
  }
  // The patch's side is 20 % of the height (about 10 px) and lies above the fixed rows.
  EXPECT_GT(patch, 40);
  EXPECT_GT(scene_pixels, 1000);
}

TEST_F(RenderVideo, FrameTimesMustIncreaseAndNothingIsWritten) {
  WriteFileAtomically(dir_ / "times.csv", "frame,t_first_row\n0,0.5\n1,0.5\n");
  try {
    RenderDataset(options_);
    FAIL() << "expected an error";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("times.csv:3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("must increase"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir_ / "out"));
}

}  // namespace
}  // namespace shutterlab
