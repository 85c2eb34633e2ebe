// The survey (render/survey.h): its terrain against a brute-force march, its rows' geometry
// against the analytic shear of a camera moving over flat ground, and what it writes read back by
// the project's own readers (photo metadata, ULog, camera.json).

#include "render/survey.h"

#include "io/image_io.h"
#include "io/photo_metadata.h"
#include "model/camera.h"
#include "render/rs_warp.h"
#include "sim/logs/flight_log.h"
#include "sim/logs/flight_log_io.h"
#include "sim/text_file.h"
#include "tests/render/survey_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

namespace fs = std::filesystem;

using test::SmallSurvey;
using test::StillGyro;

TEST(Terrain, IntersectionMatchesABruteForceMarch) {
  // Rays from 50 m, up to 30 deg off nadir, over hills and buildings: the march and bisection
  // against 1 mm steps from the camera down (the twin's resolution).
  TerrainOptions options;
  options.width_m = options.depth_m = 80.0;
  options.hill_height_m = 4.0;
  options.buildings = 6;
  const Terrain terrain = MakeTerrain(options);
  ASSERT_GT(terrain.max_m, 6.0) << "buildings stand on the ground";
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> position(30.0, 50.0), angle(-0.4, 0.4);
  int on_buildings = 0;
  for (int k = 0; k < 200; ++k) {
    const Eigen::Vector3d from(position(rng), position(rng), 50.0);
    const Eigen::Vector3d direction =
        Eigen::Vector3d(std::tan(angle(rng)), std::tan(angle(rng)), -1.0).normalized();
    const std::optional<Eigen::Vector3d> hit = terrain.Intersect(from, direction);
    ASSERT_TRUE(hit) << "ray " << k;
    std::optional<Eigen::Vector3d> brute;
    for (double s = 0.0; s < 80.0; s += 1e-3) {
      const Eigen::Vector3d p = from + s * direction;
      const std::optional<double> h = terrain.HeightAt(p.x(), p.y());
      ASSERT_TRUE(h);
      if (p.z() <= *h) {
        brute = p;
        break;
      }
    }
    ASSERT_TRUE(brute) << "ray " << k;
    EXPECT_LT((*hit - *brute).norm(), 1.5e-3) << "ray " << k;
    // On the surface (a wall's slope turns the bisection's 1e-6 m into up to 5e-5 m of height).
    EXPECT_NEAR(hit->z(), *terrain.HeightAt(hit->x(), hit->y()), 1e-4) << "ray " << k;
    on_buildings += hit->z() > terrain.min_m + options.hill_height_m + 1.0;
  }
  EXPECT_GT(on_buildings, 5) << "some rays must end on roofs or walls to test them";
}

TEST(Survey, FlatGroundWithoutRotationShowsTheTranslationsShearOnBothLines) {
  // Flat ground at the datum, a still gyro: every rolling-shutter pixel of row v sees the ground
  // the camera passed (t_v - t_mid) earlier, which lies ahead of the reference's view by
  // speed (t_v - t_mid): d = (0, -speed (t_v - t_mid) f / altitude), whichever way the line runs.
  SurveyOptions options = SmallSurvey();
  options.terrain.hill_height_m = 0.0;
  options.terrain.buildings = 0;
  const GyroTrace gyro = StillGyro(SurveyEndS(options) + 1.0);
  const SurveyPlan plan(options, gyro);
  ASSERT_EQ(plan.photos().size(), 6u);
  TerrainOptions flat = options.terrain;
  flat.width_m = plan.east_extent_m();
  flat.depth_m = plan.north_extent_m();
  const Terrain terrain = MakeTerrain(flat);
  const cv::Mat texture(static_cast<int>(plan.north_extent_m() / 0.1),
                        static_cast<int>(plan.east_extent_m() / 0.1), CV_8UC3,
                        cv::Scalar(10, 20, 30));
  options.texture_gsd_m = 0.1;
  for (size_t k : {size_t{1}, size_t{4}}) {  // a photo on each line
    const SurveyPhoto& photo = plan.photos()[k];
    const RenderedSurveyPhoto rolling =
        RenderSurveyPhoto(plan, k, terrain, texture, options, false);
    const cv::Mat field = SurveyDisplacement(plan, k, rolling, options);
    double worst_px = 0.0;
    for (int v = 0; v < options.camera.height; ++v) {
      const double t_from_mid_s = v * options.readout_s / options.camera.height -
                                  (photo.t_mid_ns - photo.t_first_row_ns) * 1e-9;
      const double expected_dy =
          -options.speed_mps * t_from_mid_s * options.camera.fy / options.altitude_m;
      for (int u = 0; u < options.camera.width; u += 7) {
        const cv::Vec2f d = field.at<cv::Vec2f>(v, u);
        worst_px = std::max({worst_px, std::abs(double{d[0]}), std::abs(d[1] - expected_dy)});
      }
    }
    EXPECT_LT(worst_px, 1e-4) << photo.name << " on line " << photo.line;
    const double shear_px = options.speed_mps * options.readout_s * (options.camera.height - 1.0) /
                            options.camera.height * options.camera.fy / options.altitude_m;
    EXPECT_NEAR(FrameDistortionPx(field), shear_px, 1e-4) << photo.name;
    // The global-shutter photo sees the ground from one pose: no displacement to itself.
    const RenderedSurveyPhoto global = RenderSurveyPhoto(plan, k, terrain, texture, options, true);
    EXPECT_LT(FrameDistortionPx(SurveyDisplacement(plan, k, global, options)), 1e-6);
  }
}

TEST(Survey, WritesWhatADroneWritesAndTheTruthBesideIt) {
  test::TempDir dir;
  const SurveyOptions options = SmallSurvey();
  const GyroTrace gyro = StillGyro(SurveyEndS(options) + 1.0);
  const SurveySummary summary = WriteSurvey(options, gyro, dir / "survey");
  ASSERT_EQ(summary.photos.size(), 6u);
  const fs::path out = dir.path() / "survey";
  for (const std::string& file : summary.files) EXPECT_TRUE(fs::is_regular_file(file)) << file;

  // The photos' metadata, read as any DJI photo is.
  const SurveyPhoto& first = summary.photos[0];
  const SurveyPhoto& south = summary.photos[3];  // the second line, flown south
  const PhotoMetadata a = ReadPhotoMetadata((out / "images" / first.name).string());
  const PhotoMetadata b = ReadPhotoMetadata((out / "images" / south.name).string());
  EXPECT_EQ(a.width, 160);
  ASSERT_TRUE(a.speed_m_s && b.speed_m_s && a.gimbal && b.gimbal);
  EXPECT_NEAR(a.speed_m_s->x(), 8.0, 1e-9) << "north";
  EXPECT_NEAR(b.speed_m_s->x(), -8.0, 1e-9) << "south";
  EXPECT_NEAR(a.speed_m_s->y(), 0.0, 1e-9);
  EXPECT_NEAR(a.gimbal->pitch_deg, -90.0, 1e-9);
  EXPECT_NEAR(a.gimbal->yaw_deg, 0.0, 1e-9);
  EXPECT_NEAR(std::abs(b.gimbal->yaw_deg), 180.0, 1e-9);
  ASSERT_TRUE(a.relative_altitude_m && a.calibrated_focal_px && a.capture_time);
  EXPECT_NEAR(*a.relative_altitude_m, 40.0, 1e-9);
  EXPECT_NEAR(*a.calibrated_focal_px, 140.0, 1e-3);
  ASSERT_TRUE(a.latitude_deg && a.longitude_deg && b.latitude_deg);
  EXPECT_GT(*a.latitude_deg, 46.9);
  ASSERT_TRUE(b.capture_time);
  // The metadata of the reference is the photo's.
  const PhotoMetadata a_ref = ReadPhotoMetadata((out / "reference" / first.name).string());
  ASSERT_TRUE(a_ref.speed_m_s);
  EXPECT_EQ(*a_ref.speed_m_s, *a.speed_m_s);

  // The log: the gyro and one camera event at each photo's first row.
  const FlightLog log = ReadFlightLog((out / "flight.ulg").string());
  ASSERT_EQ(log.camera_events.size(), 6u);
  for (size_t k = 0; k < 6; ++k) {
    EXPECT_NEAR(log.camera_events[k].t_ns, summary.photos[k].t_first_row_ns, 1000) << k;
  }
  EXPECT_EQ(log.gyro.samples().size(), gyro.samples().size());
  // Its navigation: at each photo, the photo's own velocity (north, east, down); the line flown
  // south switches halfway through the turn.
  ASSERT_FALSE(log.velocity.empty());
  for (const SurveyPhoto& p : summary.photos) {
    const std::optional<Eigen::Vector3d> v = VelocityAt(log.velocity, p.t_mid_ns);
    ASSERT_TRUE(v.has_value()) << p.name;
    EXPECT_NEAR((*v - Eigen::Vector3d(p.velocity_mps.y(), p.velocity_mps.x(), 0.0)).norm(), 0.0,
                1e-6)
        << p.name;
  }
  const int64_t turn_middle_ns = (summary.photos[2].t_mid_ns + summary.photos[3].t_mid_ns) / 2;
  EXPECT_NEAR(VelocityAt(log.velocity, turn_middle_ns - 200'000'000)->x(), 8.0, 1e-6);
  EXPECT_NEAR(VelocityAt(log.velocity, turn_middle_ns + 200'000'000)->x(), -8.0, 1e-6);

  // The camera and the terrain as written.
  const RigModel rig = ReadRigModel((out / "truth/camera.json").string());
  EXPECT_EQ(rig.shutter.readout_s, options.readout_s);
  EXPECT_EQ(rig.altitude_m, options.altitude_m);
  const nlohmann::json terrain =
      nlohmann::json::parse(ReadFileToString(out / "truth/terrain.json"));
  const cv::Mat heights = ReadImage((out / "truth/terrain.png").string());
  ASSERT_EQ(heights.type(), CV_16UC1);
  ASSERT_EQ(heights.rows, summary.terrain.height_m.rows);
  const double offset = terrain["offset_m"], scale = terrain["scale_m"];
  double worst_m = 0.0;
  for (int r = 0; r < heights.rows; r += 3) {
    for (int c = 0; c < heights.cols; c += 3) {
      worst_m = std::max(worst_m, std::abs(offset + scale * heights.at<uint16_t>(r, c) -
                                           summary.terrain.height_m.at<double>(r, c)));
    }
  }
  EXPECT_LE(worst_m, 0.5 * scale + 1e-9);
  const std::string poses = ReadFileToString(out / "truth/poses.csv");
  EXPECT_EQ(std::count(poses.begin(), poses.end(), '\n'), 1 + 6 * 120) << "a line per photo row";
  // D of each photo: the truth's, positive where the camera moves.
  for (const SurveyPhoto& p : summary.photos) EXPECT_GT(p.d_px, 0.5) << p.name;
}

TEST(Survey, RefusesWhatNoFlightCanBe) {
  SurveyOptions options = SmallSurvey();
  options.front_overlap = 1.0;
  EXPECT_THROW(options.Check(), std::invalid_argument);
  options = SmallSurvey();
  options.altitude_m = 10.0;  // below the buildings
  EXPECT_THROW(options.Check(), std::invalid_argument);
  options = SmallSurvey();
  EXPECT_THROW(SurveyPlan(options, StillGyro(5.0)), std::invalid_argument)
      << "a trace that ends before the flight";
  // Roofs within 5 m of the camera (20 buildings of 6-12 m under a camera at 15.5 m, which the
  // options alone allow): refused once the terrain is made, before anything is written.
  test::TempDir dir;
  options.terrain.hill_height_m = 0.0;
  options.terrain.buildings = 20;
  options.altitude_m = 15.5;
  try {
    WriteSurvey(options, StillGyro(SurveyEndS(options) + 1.0), dir / "s");
    ADD_FAILURE() << "a camera inside a hill";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("does not clear the terrain"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "s/images"));
  // A ray at or above the horizon meets no ground.
  const Terrain flat = MakeTerrain(TerrainOptions{});
  EXPECT_FALSE(flat.Intersect(Eigen::Vector3d(50, 50, 40), Eigen::Vector3d(1, 0, 0)));
}

}  // namespace
}  // namespace shutterlab
