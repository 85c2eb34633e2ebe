#include "model/camera.h"

#include "sim/check.h"
#include "sim/so3.h"
#include "sim/text_file.h"
#include "tests/model/model_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

namespace shutterlab {
namespace {

// Undistortion iterates to 1e-15 in normalised coordinates: ~1e-12 px after scaling by f.
constexpr double kRoundTripTolPx = 1e-9;

RigModel FullRig() {
  RigModel rig;
  rig.camera.width = 1280;
  rig.camera.height = 960;
  rig.camera.fx = 1100.5;
  rig.camera.fy = 1098.25;
  rig.camera.cx = 639.5;
  rig.camera.cy = 479.25;
  rig.camera.distortion = BrownConrady{{-0.12, 0.034, 0.001, -0.0007, 0.002}};
  rig.shutter.readout_s = 0.0312;
  rig.shutter.direction = ReadoutDirection::kBottomToTop;
  rig.cam_from_gyro = RotationZYX(0.3, -0.2, 0.1);
  rig.time_offset_s = -0.0041;
  rig.altitude_m = 73.5;
  rig.velocity_mps = Eigen::Vector3d(1.5, -2.25, 0.125);
  rig.bounds["gyro_scale"] = {0.5, 1.5};
  return rig;
}

std::string ValidJson() {
  return R"({"format": "rig/1", "image": {"width": 1280, "height": 960},
    "intrinsics": {"fx": 1100.0, "fy": 1100.0, "cx": 639.5, "cy": 479.5},
    "rolling_shutter": {"readout_s": 0.030, "direction": "top_to_bottom"}})";
}

TEST(RigModel, RoundTripsThroughCameraJson) {
  test::TempDir dir;
  const RigModel rig = FullRig();
  WriteRigModel(dir / "camera.json", rig);
  const RigModel back = ReadRigModel(dir / "camera.json");
  EXPECT_EQ(back.camera.width, rig.camera.width);
  EXPECT_EQ(back.camera.height, rig.camera.height);
  EXPECT_EQ(back.camera.fx, rig.camera.fx);
  EXPECT_EQ(back.camera.fy, rig.camera.fy);
  EXPECT_EQ(back.camera.cx, rig.camera.cx);
  EXPECT_EQ(back.camera.cy, rig.camera.cy);
  EXPECT_TRUE(back.camera.distortion == rig.camera.distortion);
  EXPECT_EQ(back.shutter.readout_s, rig.shutter.readout_s);
  EXPECT_EQ(back.shutter.direction, rig.shutter.direction);
  EXPECT_EQ(back.cam_from_gyro, rig.cam_from_gyro);
  EXPECT_EQ(back.time_offset_s, rig.time_offset_s);
  EXPECT_EQ(back.altitude_m, rig.altitude_m);
  EXPECT_EQ(back.velocity_mps, rig.velocity_mps);
  EXPECT_EQ(back.bounds, rig.bounds);
}

TEST(RigModel, OptionalFieldsDefault) {
  test::TempDir dir;
  WriteFileAtomically(dir / "camera.json", ValidJson());
  const RigModel rig = ReadRigModel(dir / "camera.json");
  EXPECT_FALSE(rig.camera.HasDistortion());
  EXPECT_EQ(rig.cam_from_gyro, Eigen::Matrix3d::Identity());
  EXPECT_EQ(rig.time_offset_s, 0.0);
  EXPECT_EQ(rig.velocity_mps, Eigen::Vector3d::Zero());
  EXPECT_EQ(rig.shutter.direction, ReadoutDirection::kTopToBottom);
}

// Replaces the first occurrence of `from` in the valid camera.json and expects a clear IoError.
void ExpectRejected(const std::string& from, const std::string& to,
                    const std::string& message_part) {
  test::TempDir dir;
  std::string text = ValidJson();
  const size_t at = text.find(from);
  ASSERT_NE(at, std::string::npos) << from;
  text.replace(at, from.size(), to);
  WriteFileAtomically(dir / "camera.json", text);
  try {
    ReadRigModel(dir / "camera.json");
    ADD_FAILURE() << "accepted " << to;
  } catch (const IoError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("camera.json"), std::string::npos) << what;
    EXPECT_NE(what.find(message_part), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << "one line: " << what;
  }
}

TEST(RigModel, ReadoutZeroIsAGlobalShutter) {
  test::TempDir dir;
  RigModel rig = test::MappingRig();
  rig.shutter.readout_s = 0.0;
  WriteRigModel(dir / "camera.json", rig);
  const RigModel back = ReadRigModel(dir / "camera.json");
  EXPECT_EQ(back.shutter.readout_s, 0.0);
  EXPECT_EQ(back.shutter.RowTimeOffsetS(959, 960), 0.0) << "every row at t_first_row";
}

TEST(RigModel, RejectsNonsenseWithAClearError) {
  ExpectRejected("\"fx\": 1100.0", "\"fx\": -5", "focal length");
  ExpectRejected("\"fy\": 1100.0", "\"fy\": 0", "focal length");
  ExpectRejected("\"readout_s\": 0.030", "\"readout_s\": -0.01", "readout_s");
  ExpectRejected("\"top_to_bottom\"", "\"left_to_right\"", "direction");
  ExpectRejected("\"width\": 1280", "\"width\": 0", "image.width 0 is not a whole number");
  ExpectRejected("\"fx\": 1100.0", "\"fx\": \"big\"", "fx");
  ExpectRejected("\"rig/1\"", "\"rig/9\"", "format");
  ExpectRejected("\"format\": \"rig/1\",",
                 "\"format\": \"rig/1\", \"gyro_to_camera\": [[1,0,0],[0,1,0],[0,0,2]],",
                 "gyro_to_camera");
  ExpectRejected("\"format\": \"rig/1\",",
                 "\"format\": \"rig/1\", \"gyro_to_camera\": [[1,0,0],[0,1,0],[0,0,-1]],",
                 "gyro_to_camera");  // a reflection is orthonormal but not a rotation
  ExpectRejected("\"intrinsics\"", "\"intrinsic\"", "camera.json");
  // Bounds only for effects that have them, as [lo, hi] with lo below hi.
  ExpectRejected("\"format\": \"rig/1\",", "\"format\": \"rig/1\", \"bounds\": [0, 1],",
                 "bounds is not an object");
  ExpectRejected("\"format\": \"rig/1\",",
                 "\"format\": \"rig/1\", \"bounds\": {\"lens_distortion\": [0, 1]},",
                 "bounds: 'lens_distortion' is no effect with bounds (time_offset, readout_time");
  ExpectRejected("\"format\": \"rig/1\",", "\"format\": \"rig/1\", \"bounds\": {\"warp\": [0, 1]},",
                 "bounds: 'warp' is no effect with bounds");
  ExpectRejected("\"format\": \"rig/1\",",
                 "\"format\": \"rig/1\", \"bounds\": {\"gyro_scale\": [1.2, 0.8]},",
                 "bounds: gyro_scale is not [lo, hi] with lo below hi");
  ExpectRejected("\"format\": \"rig/1\",",
                 "\"format\": \"rig/1\", \"bounds\": {\"gyro_scale\": [0.8]},",
                 "bounds: gyro_scale is not [lo, hi]");
}

TEST(RigModel, AFisheyeRoundTripsThroughCameraJson) {
  test::TempDir dir;
  RigModel rig = FullRig();
  rig.camera.distortion = Fisheye({0.0646, 0.0391, -0.0414, 0.0149});
  WriteRigModel(dir / "camera.json", rig);
  const std::string text = ReadFileToString(dir / "camera.json");
  EXPECT_NE(text.find("\"model\": \"fisheye\""), std::string::npos) << text;
  EXPECT_TRUE(ReadRigModel(dir / "camera.json").camera.distortion == rig.camera.distortion);
  // docs/FORMATS.md's example, and "brown" spelled out.
  WriteFileAtomically(dir / "camera.json",
                      ValidJson().substr(0, ValidJson().size() - 1) +
                          R"(, "distortion": {"model": "fisheye", "k1": 0.05, "k2": 0.01,
                          "k3": -0.002, "k4": 0.0}})");
  EXPECT_TRUE(ReadRigModel(dir / "camera.json").camera.distortion ==
              LensDistortion(Fisheye({0.05, 0.01, -0.002, 0.0})));
  WriteFileAtomically(dir / "camera.json", ValidJson().substr(0, ValidJson().size() - 1) +
                                               R"(, "distortion": {"model": "brown", "k1": 0.1}})");
  EXPECT_TRUE(ReadRigModel(dir / "camera.json").camera.distortion ==
              LensDistortion(BrownConrady{{0.1, 0, 0, 0, 0}}));
}

TEST(RigModel, RejectsADistortionOfNoModel) {
  const std::string open = "\"rolling_shutter\"";
  ExpectRejected(open, R"("distortion": {"model": "kb8", "k1": 0.1}, "rolling_shutter")",
                 "distortion.model 'kb8' is not brown or fisheye");
  ExpectRejected(open, R"("distortion": {"model": "fisheye", "p1": 0.1}, "rolling_shutter")",
                 "distortion.p1 is not a coefficient of the fisheye model (k1 k2 k3 k4)");
  ExpectRejected(open, R"("distortion": {"k4": 0.1}, "rolling_shutter")",
                 "distortion.k4 is not a coefficient of the brown model");
  ExpectRejected(open, R"("distortion": {"model": "fisheye", "k1": "big"}, "rolling_shutter")",
                 "distortion.k1 is not a number");
}

// Regression (fuzz/camera_json_fuzz): a width too large for an int was cast anyway (undefined
// behaviour); a fractional or non-positive side was truncated or left to a later check.
TEST(RigModel, RejectsAnImageSideThatIsNotAWholePixelCount) {
  const std::string width = "\"width\": 1280";
  ExpectRejected(width, "\"width\": 8.49e52",
                 "image.width 8.49e+52 is not a whole number of pixels from 1 to 1048576");
  ExpectRejected(width, "\"width\": 1280.5", "image.width 1280.5 is not a whole number");
  ExpectRejected("\"height\": 960", "\"height\": -960", "image.height -960 is not a whole");
}

TEST(RigModel, RejectsInvalidJsonWithItsLine) {
  test::TempDir dir;
  WriteFileAtomically(dir / "camera.json", "{\n\"image\": {\"width\": 10,\n oops\n}");
  try {
    ReadRigModel(dir / "camera.json");
    ADD_FAILURE() << "accepted invalid JSON";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("camera.json:3"), std::string::npos) << e.what();
  }
}

// Regression (fuzz/camera_json_fuzz): a number too large for a double made nlohmann throw its
// out_of_range, which escaped as an uncaught exception instead of a one-line error.
TEST(RigModel, NumberOverflowIsAnIoError) {
  test::TempDir dir;
  WriteFileAtomically(dir / "camera.json",
                      "{\"format\": \"rig/1\", \"intrinsics\": {\"fx\": 10e900}}");
  try {
    ReadRigModel(dir / "camera.json");
    ADD_FAILURE() << "accepted 10e900";
  } catch (const IoError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("camera.json: invalid JSON"), std::string::npos) << message;
    EXPECT_NE(message.find("10e900"), std::string::npos) << message;
  }
}

TEST(PinholeCamera, ImgFromCamInvertsCamFromImg) {
  PinholeCamera camera = FullRig().camera;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-100.0, camera.width + 100.0),
      v(-100.0, camera.height + 100.0);
  for (const LensDistortion& lens : {LensDistortion(BrownConrady{}), camera.distortion,
                                     LensDistortion(BrownConrady{{0.25, -0.1, 0, 0, 0.02}})}) {
    camera.distortion = lens;
    for (int i = 0; i < 500; ++i) {
      const Eigen::Vector2d px(u(rng), v(rng));
      const std::optional<Eigen::Vector2d> back = camera.ImgFromCam(camera.CamFromImg(px));
      ASSERT_TRUE(back.has_value());
      ASSERT_NEAR((*back - px).norm(), 0.0, kRoundTripTolPx) << px.transpose();
    }
    // Named edge cases: the principal point and the corners.
    for (const Eigen::Vector2d& px : {Eigen::Vector2d(camera.cx, camera.cy), Eigen::Vector2d(0, 0),
                                      Eigen::Vector2d(camera.width - 1, camera.height - 1)}) {
      EXPECT_NEAR((*camera.ImgFromCam(camera.CamFromImg(px)) - px).norm(), 0.0, kRoundTripTolPx);
    }
  }
}

TEST(PinholeCamera, PointsBehindTheCameraHaveNoPixel) {
  const PinholeCamera camera = FullRig().camera;
  EXPECT_FALSE(camera.ImgFromCam(Eigen::Vector3d(0.1, 0.2, -1.0)).has_value());
  EXPECT_FALSE(camera.ImgFromCam(Eigen::Vector3d(0.1, 0.2, 0.0)).has_value());
}

TEST(RollingShutter, RowTimesFollowTheDirection) {
  RollingShutter shutter;
  shutter.readout_s = 0.030;
  EXPECT_EQ(shutter.RowTimeOffsetS(0, 960), 0.0);
  EXPECT_DOUBLE_EQ(shutter.RowTimeOffsetS(480, 960), 0.015);
  shutter.direction = ReadoutDirection::kBottomToTop;
  EXPECT_EQ(shutter.RowTimeOffsetS(959, 960), 0.0);
  EXPECT_DOUBLE_EQ(shutter.RowTimeOffsetS(0, 960), 959 * 0.030 / 960);
}

}  // namespace
}  // namespace shutterlab
