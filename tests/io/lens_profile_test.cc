#include "io/lens_profile.h"

#include "sim/check.h"
#include "sim/text_file.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <string>

namespace shutterlab {
namespace {

using nlohmann::json;

// A profile as Gyroflow's calibrator writes one (the keys that matter), at 2704x1520.
json ProfileJson() {
  return json::parse(R"({
    "name": "Test_Cam_Wide_2.7k_16by9_2704x1520-29.97fps", "calibrated_by": "Tester",
    "camera_brand": "Test", "camera_model": "Cam", "lens_model": "Wide",
    "calib_dimension": {"w": 2704, "h": 1520}, "orig_dimension": {"w": 2704, "h": 1520},
    "frame_readout_time": 26.69333, "input_horizontal_stretch": 1.0, "fps": 29.97,
    "official": true, "use_opencv_fisheye": true,
    "fisheye_params": {"RMS_error": 0.219,
      "camera_matrix": [[1394.85, 0.0, 1353.25], [0.0, 1407.70, 769.32], [0.0, 0.0, 1.0]],
      "distortion_coeffs": [0.0464, 0.0052, 0.0209, -0.0179]},
    "use_opencv_standard": false,
    "calib_params": {"RMS_error": 0.0, "camera_matrix": [], "distortion_coeffs": []},
    "compatible_settings": [
      {"width": 1920, "height": 1080, "fps": 59.94, "frame_readout_time": 16.68333},
      {"width": 1920, "height": 1080, "fps": 29.97, "frame_readout_time": -33.36667}]})");
}

LensProfile Read(const test::TempDir& dir, const json& j) {
  WriteFileAtomically(dir / "profile.json", j.dump(2));
  return ReadLensProfile(dir / "profile.json");
}

TEST(LensProfile, ReadsGyroflowsFields) {
  test::TempDir dir;
  const LensProfile p = Read(dir, ProfileJson());
  EXPECT_EQ(p.name, "Test_Cam_Wide_2.7k_16by9_2704x1520-29.97fps");
  EXPECT_EQ(p.calibrated_by, "Tester");
  EXPECT_TRUE(p.official);
  EXPECT_EQ(p.camera.width, 2704);
  EXPECT_EQ(p.camera.height, 1520);
  EXPECT_EQ(p.camera.fx, 1394.85);
  EXPECT_EQ(p.camera.cy, 769.32);
  EXPECT_TRUE(p.camera.distortion == LensDistortion(Fisheye({0.0464, 0.0052, 0.0209, -0.0179})));
  EXPECT_DOUBLE_EQ(*p.mode.readout_s, 0.02669333);
  EXPECT_EQ(p.mode.fps, 29.97);
  ASSERT_EQ(p.compatible.size(), 2u);
  // Gyroflow's negative readout: rows read bottom to top.
  EXPECT_EQ(p.compatible[1].direction, ReadoutDirection::kBottomToTop);
  EXPECT_DOUBLE_EQ(*p.compatible[1].readout_s, 0.03336667);
}

TEST(LensProfile, ScalesToTheImageKeepingEachScenePointInPlace) {
  test::TempDir dir;
  const LensProfile p = Read(dir, ProfileJson());
  // Half size: a pixel's centre at calibration (x) is at (x + 0.5) / 2 - 0.5.
  const LensProfileUse half = ScaleLensProfile(p, 1352, 760);
  EXPECT_FALSE(half.aspect_differs);
  EXPECT_DOUBLE_EQ(half.camera.fx, 1394.85 / 2);
  EXPECT_DOUBLE_EQ(half.camera.cx, (1353.25 + 0.5) / 2 - 0.5);
  EXPECT_TRUE(half.camera.distortion == p.camera.distortion);
  // A ray's pixel at calibration size maps to its pixel at half size by the resize.
  const Eigen::Vector3d ray(0.4, -0.3, 1.0);
  const Eigen::Vector2d full = *p.camera.ImgFromCam(ray), small = *half.camera.ImgFromCam(ray);
  EXPECT_NEAR(small.x(), (full.x() + 0.5) / 2 - 0.5, 1e-9);
  EXPECT_NEAR(small.y(), (full.y() + 0.5) / 2 - 0.5, 1e-9);
  // No compatible setting of this size: the profile's own readout, and the notes say so.
  ASSERT_TRUE(half.readout.has_value());
  EXPECT_DOUBLE_EQ(*half.readout->readout_s, 0.02669333);
  EXPECT_NE(half.notes.back().find("26.693 ms"), std::string::npos) << half.notes.back();
  EXPECT_NE(half.notes.back().find("2704x1520 at 30 fps"), std::string::npos) << half.notes.back();
}

TEST(LensProfile, PicksTheCompatibleSettingOfTheImagesSizeAndRate) {
  test::TempDir dir;
  const LensProfile p = Read(dir, ProfileJson());
  EXPECT_DOUBLE_EQ(*ScaleLensProfile(p, 1920, 1080, 59.94).readout->readout_s, 0.01668333);
  const LensProfileUse at30 = ScaleLensProfile(p, 1920, 1080, 29.97);
  EXPECT_DOUBLE_EQ(*at30.readout->readout_s, 0.03336667);
  EXPECT_EQ(at30.readout->direction, ReadoutDirection::kBottomToTop);
  // Without a frame rate the first setting of the size.
  EXPECT_DOUBLE_EQ(*ScaleLensProfile(p, 1920, 1080).readout->readout_s, 0.01668333);
}

TEST(LensProfile, SaysWhenTheAspectDiffers) {
  // The GoPro MAX's 848x480 low-resolution copy of a 1920x1080 mode.
  test::TempDir dir;
  json j = ProfileJson();
  j["calib_dimension"] = {{"w", 1920}, {"h", 1080}};
  const LensProfileUse use = ScaleLensProfile(Read(dir, j), 848, 480);
  EXPECT_TRUE(use.aspect_differs);
  EXPECT_DOUBLE_EQ(use.scale_x, 848.0 / 1920);
  EXPECT_DOUBLE_EQ(use.scale_y, 480.0 / 1080);
  EXPECT_DOUBLE_EQ(use.camera.fy, 1407.70 * 480 / 1080);
  ASSERT_GE(use.notes.size(), 2u);
  EXPECT_NE(use.notes[1].find("differs from the profile's 1.7778 by 0.62 %"), std::string::npos)
      << use.notes[1];
}

TEST(LensProfile, AppliedToARigItReplacesTheLensAndTheReadoutUnlessKept) {
  test::TempDir dir;
  const LensProfile p = Read(dir, ProfileJson());
  RigModel rig;
  rig.camera.width = 1352;
  rig.camera.height = 760;
  rig.camera.fx = rig.camera.fy = 500;
  rig.shutter.readout_s = 0.015;
  LensProfileUse use = ScaleLensProfile(p, 1352, 760);
  RigModel kept = rig;
  LensProfileUse kept_use = use;
  ApplyLensProfile(&use, &rig);
  EXPECT_EQ(rig.camera.fx, use.camera.fx);
  EXPECT_DOUBLE_EQ(rig.shutter.readout_s, 0.02669333);
  EXPECT_NE(use.notes.back().find("replaces 15.000 ms"), std::string::npos) << use.notes.back();
  ApplyLensProfile(&kept_use, &kept, /*keep_readout=*/true);
  EXPECT_EQ(kept.shutter.readout_s, 0.015);
  EXPECT_FALSE(kept_use.readout.has_value());
  EXPECT_EQ(LensProfileUseJson(kept_use)["readout_s"], nullptr);
  EXPECT_EQ(LensProfileUseJson(use)["readout_s"], 0.02669333);
  EXPECT_EQ(LensProfileUseJson(use)["model"], "fisheye");
}

TEST(LensProfile, ReadsOpenCvsStandardModel) {
  test::TempDir dir;
  json j = ProfileJson();
  j["use_opencv_fisheye"] = false;
  j["use_opencv_standard"] = true;
  j["calib_params"] = json::parse(R"({"RMS_error": 0.3,
      "camera_matrix": [[1000, 0, 1350], [0, 1000, 760], [0, 0, 1]],
      "distortion_coeffs": [-0.1, 0.02, 0.001, -0.002, 0.003, 0, 0, 0]})");
  const LensProfile p = Read(dir, j);
  EXPECT_TRUE(p.camera.distortion ==
              LensDistortion(BrownConrady{{-0.1, 0.02, 0.001, -0.002, 0.003}}));
  EXPECT_EQ(p.camera.fx, 1000);
}

// A Gyroflow project (.gyroflow, as Gyroflow writes it: the lens profile in calibration_data, the
// clip's readout under stabilization with the direction by name or by number) reads as its lens
// with the project's readout, which wins over the profile's.
TEST(LensProfile, ReadsAGyroflowProjectsLensAndItsReadout) {
  test::TempDir dir;
  json project = {{"title", "Gyroflow data file"},
                  {"version", 4},
                  {"calibration_data", ProfileJson()},
                  {"stabilization",
                   {{"frame_readout_time", 31.5}, {"frame_readout_direction", "BottomToTop"}}}};
  LensProfile p = Read(dir, project);
  EXPECT_EQ(p.camera.fx, 1394.85);
  EXPECT_EQ(p.camera.width, 2704);
  ASSERT_TRUE(p.mode.readout_s);
  EXPECT_DOUBLE_EQ(*p.mode.readout_s, 0.0315);
  EXPECT_EQ(p.mode.direction, ReadoutDirection::kBottomToTop);
  EXPECT_NE(p.name.find("Gyroflow project"), std::string::npos) << p.name;
  project["stabilization"]["frame_readout_direction"] = 0;  // Gyroflow's number for TopToBottom
  EXPECT_EQ(Read(dir, project).mode.direction, ReadoutDirection::kTopToBottom);
  // No readout set for the clip: the profile's own.
  project["stabilization"]["frame_readout_time"] = 0.0;
  EXPECT_DOUBLE_EQ(*Read(dir, project).mode.readout_s, 0.02669333);
  project["stabilization"] = {{"frame_readout_time", 20.0},
                              {"frame_readout_direction", "Sideways"}};
  EXPECT_THROW(Read(dir, project), IoError);
  project["calibration_data"] = "lens.json";
  EXPECT_THROW(Read(dir, project), IoError);
}

TEST(LensProfile, RefusesWhatItDoesNotModelWithAClearError) {
  const std::vector<std::pair<std::function<void(json*)>, std::string>> cases = {
      {[](json* j) { (*j)["distortion_model"] = "poly5"; },
       "distortion_model 'poly5' is not one shutterlab models"},
      {[](json* j) { (*j)["digital_lens"] = "gopro_superview"; }, "digital_lens"},
      {[](json* j) { (*j)["input_horizontal_stretch"] = 1.33; }, "input_horizontal_stretch 1.33"},
      {[](json* j) {
         (*j)["fisheye_params"]["distortion_coeffs"] = {0.1, 0.2};
       },
       "has 2 coefficients"},
      {[](json* j) { (*j)["fisheye_params"]["camera_matrix"] = json::array(); }, "3x3"},
      {[](json* j) {
         (*j)["calib_dimension"] = {{"w", 0}, {"h", 1080}};
       },
       "calib_dimension"},
      {[](json* j) { (*j)["frame_readout_time"] = "fast"; }, "frame_readout_time is not a number"},
      {[](json* j) { (*j)["calib_dimension"]["w"] = 1e20; }, "w 1e+20 is not a size in pixels"},
  };
  for (const auto& [change, message] : cases) {
    test::TempDir dir;
    json j = ProfileJson();
    change(&j);
    try {
      Read(dir, j);
      ADD_FAILURE() << "accepted: " << message;
    } catch (const IoError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("profile.json"), std::string::npos) << what;
      EXPECT_NE(what.find(message), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  }
  test::TempDir dir;
  WriteFileAtomically(dir / "profile.json", "{ not json");
  EXPECT_THROW(ReadLensProfile(dir / "profile.json"), IoError);
}

// The shared folder's real profiles: the GoPro MAX's (HS EIS, 1920x1080, no readout) and the
// HERO5's (official, with readouts and compatible settings).
TEST(LensProfile, ReadsTheRealGyroflowProfiles) {
  SHUTTERLAB_REAL_DATA(max,
                       "incoming_rs/gopro_max_heromode/reference/"
                       "gyroflow_GoPro_Max_Wide_HS-EIS_1080p_16by9_1920x1080-50fps.json");
  const LensProfile p = ReadLensProfile(max);
  EXPECT_EQ(p.camera.width, 1920);
  EXPECT_NEAR(p.camera.fx, 834.714, 1e-3);
  EXPECT_FALSE(p.mode.readout_s.has_value()) << "frame_readout_time is null";
  const LensProfileUse use = ScaleLensProfile(p, 848, 480, 29.97);
  EXPECT_TRUE(use.aspect_differs);
  EXPECT_NEAR(use.camera.fx, 368.7, 0.05);
  EXPECT_NEAR(use.camera.fy, 370.8, 0.05);
  // PROVENANCE.md: this profile's corner rays span 136.0 degrees diagonally.
  const Eigen::Vector3d a = p.camera.CamFromImg({0, 0}).normalized(),
                        b = p.camera.CamFromImg({1919, 1079}).normalized();
  EXPECT_NEAR(std::acos(a.dot(b)) * 180 / M_PI, 136.0, 0.1);
  EXPECT_FALSE(use.readout.has_value());
  SHUTTERLAB_REAL_DATA(hero5,
                       "incoming_rs/gopro_karma_refs/reference/"
                       "gyroflow_GoPro_HERO5_Black_Wide_EIS-Y_16by9.json");
  const LensProfile h = ReadLensProfile(hero5);
  EXPECT_DOUBLE_EQ(*h.mode.readout_s, 0.02669333);
  EXPECT_EQ(h.compatible.size(), 22u);
  EXPECT_DOUBLE_EQ(*ScaleLensProfile(h, 1920, 1080, 50.0).readout->readout_s, 0.0175994);
}

}  // namespace
}  // namespace shutterlab
