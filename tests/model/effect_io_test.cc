// The edge of the effect table: `--inject` text and JSON in, JSON out, and the typed value between.
#include "model/effect_io.h"

#include "tests/model/model_fixtures.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

using nlohmann::json;

// One `--inject` text per spelling, every effect of the table at least once.
const std::vector<std::string>& InjectionTexts() {
  static const std::vector<std::string> texts = {
      "time_offset=4ms",
      "time_offset=-0.01ms",
      "readout_time=21ms",
      "gyro_to_camera=0,-1,0,1,0,0,0,0,1",
      "gyro_to_camera=[[0,0,1],[0,1,0],[-1,0,0]]",
      "gyro_scale=1.01,0.99,1.02",
      "gyro_scale=[1.01,0.99,1.0]",
      "gyro_bias=0.001rad/s,-0.002rad/s,0.003rad/s",
      "velocity=5m/s,1m/s,0",
      "lens_distortion=-0.1,0.02",
      "lens_distortion=-0.1,0.02,0.001,-0.0005,0.03",
      "lens_distortion={\"k1\":-0.1,\"p2\":0.001}",
      "lens_distortion=-0.05",
      "lens_distortion={\"model\":\"fisheye\",\"k1\":0.06,\"k2\":0.04,\"k3\":-0.04}",
      "readout_direction=bottom_to_top",
      "readout_direction=\"top_to_bottom\"",
      "clock_rate=-35ppm",
  };
  return texts;
}

// text -> EffectValue -> JSON -> EffectValue, and through the JSON's text, for every effect.
TEST(EffectIo, EveryEffectRoundTripsThroughJson) {
  std::set<Effect> seen;
  for (const std::string& text : InjectionTexts()) {
    const Injection parsed = ParseInjection(text);
    seen.insert(parsed.effect);
    EXPECT_TRUE(HasShape(parsed.value, Spec(parsed.effect).shape)) << text;
    const json j = EffectValueToJson(parsed.value);
    EXPECT_TRUE(EffectValueFromJson(parsed.effect, j, "test") == parsed.value)
        << text << " -> " << j.dump();
    const json reread = json::parse(j.dump());
    EXPECT_TRUE(EffectValueFromJson(parsed.effect, reread, "test") == parsed.value)
        << text << " -> " << j.dump();
    EXPECT_EQ(EffectValueText(parsed.value), j.dump()) << text;
  }
  EXPECT_EQ(seen.size(), AllEffects().size());
}

// What truth.json records: the same value, whichever spelling `--inject` got.
TEST(EffectIo, SpellingsOfOneValueAgree) {
  const auto value = [](const std::string& text) { return ParseInjection(text).value; };
  EXPECT_TRUE(value("gyro_to_camera=0,-1,0,1,0,0,0,0,1") ==
              value("gyro_to_camera=[[0,-1,0],[1,0,0],[0,0,1]]"));
  EXPECT_TRUE(value("gyro_scale=1.01,1,1") == value("gyro_scale=[1.01,1,1]"));
  EXPECT_TRUE(value("lens_distortion=-0.1") == value("lens_distortion={\"k1\":-0.1}"));
  EXPECT_TRUE(value("readout_direction=bottom_to_top") ==
              value("readout_direction=\"bottom_to_top\""));
  EXPECT_TRUE(value("readout_direction=bottom_to_top") ==
              EffectValue(ReadoutDirection::kBottomToTop));
  EXPECT_TRUE(value("clock_rate=30ppm") == EffectValue(30.0));
}

// docs/FORMATS.md's JSON of each shape.
TEST(EffectIo, WritesTheFormatsShapes) {
  EXPECT_EQ(EffectValueToJson(0.004).dump(), "0.004");
  EXPECT_EQ(EffectValueToJson(30.0).dump(), "30.0");
  EXPECT_EQ(EffectValueToJson(std::numeric_limits<double>::quiet_NaN()).dump(), "null");
  EXPECT_EQ(EffectValueToJson(std::monostate()).dump(), "null");
  EXPECT_EQ(EffectValueToJson(Eigen::Vector3d(1.01, 1, 1)).dump(), "[1.01,1.0,1.0]");
  Eigen::Matrix3d m;
  m << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  EXPECT_EQ(EffectValueToJson(m).dump(), "[[0.0,-1.0,0.0],[1.0,0.0,0.0],[0.0,0.0,1.0]]");
  // k1 and k2 always; p1, p2, k3 only where set.
  EXPECT_EQ(EffectValueToJson(LensDistortion(BrownConrady{{-0.1, 0.0}})).dump(),
            R"({"k1":-0.1,"k2":0.0})");
  EXPECT_EQ(EffectValueToJson(LensDistortion(BrownConrady{{-0.1, 0.02, 0.0, 0.001}})).dump(),
            R"({"k1":-0.1,"k2":0.02,"p2":0.001})");
  // A fisheye: its model and all four coefficients; an undetermined standard error is null.
  EXPECT_EQ(EffectValueToJson(LensDistortion(Fisheye({0.5, 0.25, 0.0, 0.0}))).dump(),
            R"({"k1":0.5,"k2":0.25,"k3":0.0,"k4":0.0,"model":"fisheye"})");
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(EffectValueToJson(LensDistortion(Fisheye({0.5, 0.25, nan, nan}))).dump(),
            R"({"k1":0.5,"k2":0.25,"k3":null,"k4":null,"model":"fisheye"})");
  EXPECT_EQ(EffectValueToJson(ReadoutDirection::kBottomToTop).dump(), "\"bottom_to_top\"");
}

// docs/FORMATS.md: the lens value is in the declared camera's model. A list of numbers is read in
// it; a value of the other model is refused, and the model stays as it was.
TEST(EffectIo, LensInjectionFollowsTheDeclaredModel) {
  TrueModel fisheye;
  fisheye.rig = test::SmallRig(64, 48);
  fisheye.rig.camera.distortion = Fisheye({0.01, 0.0, 0.0, 0.0});
  const Injection list = ApplyInjection("lens_distortion=0.05,0.01,-0.002,0.0005", &fisheye);
  EXPECT_TRUE(fisheye.rig.camera.distortion ==
              LensDistortion(Fisheye({0.05, 0.01, -0.002, 0.0005})));
  EXPECT_EQ(EffectValueToJson(list.value).dump(),
            R"({"k1":0.05,"k2":0.01,"k3":-0.002,"k4":0.0005,"model":"fisheye"})");
  const TrueModel before = fisheye;
  for (const std::string& text :
       {std::string("lens_distortion={\"k1\":-0.1}"), std::string("lens_distortion=1,2,3,4,5")}) {
    EXPECT_THROW(ApplyInjection(text, &fisheye), std::invalid_argument) << text;
    EXPECT_TRUE(fisheye.rig.camera.distortion == before.rig.camera.distortion);
  }
  TrueModel brown;
  brown.rig = test::SmallRig(64, 48);
  try {
    ApplyInjection("lens_distortion={\"model\":\"fisheye\",\"k1\":0.05}", &brown);
    ADD_FAILURE() << "a fisheye lens for a Brown-Conrady camera";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("a fisheye lens for a camera declared brown"),
              std::string::npos)
        << e.what();
  }
}

TEST(EffectIo, ReadingRejectsAnotherShapeNamingWhere) {
  const std::vector<std::pair<Effect, std::string>> bad = {
      {Effect::kTimeOffset, "\"soon\""},
      {Effect::kTimeOffset, "[0.1]"},
      {Effect::kGyroScale, "[1, 1]"},
      {Effect::kGyroBias, "0.1"},
      {Effect::kGyroToCamera, "[[1, 0], [0, 1]]"},
      {Effect::kGyroToCamera, "[1, 0, 0, 0, 1, 0, 0, 0, 1]"},  // `--inject` only
      {Effect::kLensDistortion, "[-0.1, 0.02]"},               // `--inject` only
      {Effect::kLensDistortion, R"({"k9": 1})"},
      {Effect::kLensDistortion, "[1, 2, 3, 4, 5, 6]"},
      {Effect::kLensDistortion, "[]"},
      {Effect::kLensDistortion, R"({"model": "fisheye", "p1": 0.1})"},
      {Effect::kLensDistortion, R"({"model": "kb8"})"},
      {Effect::kReadoutDirection, "\"left_to_right\""},
      {Effect::kReadoutDirection, "1"},
      {Effect::kClockRate, "null"},
  };
  for (const auto& [effect, text] : bad) {
    try {
      EffectValueFromJson(effect, json::parse(text), "claim 3");
      ADD_FAILURE() << Spec(effect).name << " took " << text;
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()).rfind("claim 3: ", 0), 0u) << e.what();
    }
  }
}

TEST(EffectIo, InjectionTextNamesTheProblem) {
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"time_offset", "expected NAME=VALUE"},
      {"warp_speed=9", "'warp_speed'"},
      {"gyro_scale=1,1", "--inject gyro_scale: expected 3 numbers"},
      {"time_offset=soon", "--inject time_offset 'soon': expected a duration"},
      {"time_offset=0.004",
       "--inject time_offset '0.004': a duration needs a unit: did you mean "
       "0.004ms or 0.004s?"},
      {"gyro_bias=0.5,0,0", "did you mean 0.5deg/s?"},
      {"clock_rate=30", "did you mean 30ppm?"},
      {"velocity=4km,0,0", "km is a unit of length, --inject velocity takes a speed"},
      {"readout_direction=sideways", "'sideways' is not top_to_bottom or bottom_to_top"},
  };
  for (const auto& [text, message] : bad) {
    try {
      ParseInjection(text);
      ADD_FAILURE() << text;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  }
}

// The typed injection checks the value's shape and range itself (callers need not come through
// the text).
TEST(EffectIo, TypedInjectionChecksShapeAndRange) {
  TrueModel model;
  model.rig = test::SmallRig(64, 48);
  const TrueModel before = model;
  EXPECT_THROW(ApplyInjection(Injection{Effect::kGyroScale, 1.0}, &model), std::invalid_argument);
  EXPECT_THROW(ApplyInjection(Injection{Effect::kTimeOffset, std::monostate()}, &model),
               std::invalid_argument);
  EXPECT_THROW(
      ApplyInjection(Injection{Effect::kReadoutDirection, ReadoutDirection::kLeftToRight}, &model),
      std::invalid_argument);
  EXPECT_THROW(ApplyInjection(Injection{Effect::kGyroToCamera,
                                        Eigen::Matrix3d(2 * Eigen::Matrix3d::Identity())},
                              &model),
               std::invalid_argument);
  // A rejected value leaves the model as it was.
  EXPECT_EQ(model.rig.cam_from_gyro, before.rig.cam_from_gyro);
  EXPECT_EQ(model.rig.shutter.direction, before.rig.shutter.direction);
  const EffectValue recorded = ApplyInjection(
      Injection{Effect::kLensDistortion, LensDistortion(BrownConrady{{-0.1, 0.02, 0, 0, 0.5}})},
      &model);
  EXPECT_TRUE(model.rig.camera.distortion == LensDistortion(BrownConrady{{-0.1, 0.02, 0, 0, 0.5}}));
  EXPECT_TRUE(recorded == EffectValue(LensDistortion(BrownConrady{{-0.1, 0.02, 0, 0, 0.5}})));
  // The effect's value holds what the loop fits: k1 and k2.
  EXPECT_TRUE(Spec(Effect::kLensDistortion).value(model) ==
              EffectValue(LensDistortion(BrownConrady{{-0.1, 0.02, 0, 0, 0}})));
}

}  // namespace
}  // namespace shutterlab
