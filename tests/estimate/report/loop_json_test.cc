// The loop's typed results as docs/FORMATS.md's JSON: every key the contract names, with the values
// the typed results hold.
#include "estimate/report/loop_json.h"

#include "model/reported_model.h"
#include "sim/check.h"
#include "sim/text_file.h"
#include "tests/render/render_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace shutterlab {
namespace {

TEST(LoopToJson, HasTheFormatsKeys) {
  LoopResult r;
  r.before = {1.8, 4.1, 100};
  r.after = {0.05, 0.2, 100};
  r.noise_px = 0.04;
  r.log = {"round 1: added gyro_bias"};
  IdentifiedEffect e;
  e.effect = Effect::kGyroBias;
  e.value = Eigen::Vector3d(0.01, 0.0, 0.0);
  e.stderr_value = Eigen::Vector3d(0.001, 0.002, std::numeric_limits<double>::quiet_NaN());
  e.ambiguous_with = {Effect::kVelocity};
  r.effects.push_back(e);
  const nlohmann::json j = LoopToJson(r, 12);
  EXPECT_EQ(j["format"], "validation/1");
  EXPECT_EQ(j["frames"], 12);
  EXPECT_DOUBLE_EQ(j["before"]["rms_px"].get<double>(), 1.8);
  EXPECT_DOUBLE_EQ(j["before"]["max_px"].get<double>(), 4.1);
  EXPECT_DOUBLE_EQ(j["after"]["rms_px"].get<double>(), 0.05);
  EXPECT_DOUBLE_EQ(j["noise_px"].get<double>(), 0.04);
  EXPECT_EQ(j["unexplained"], false);
  EXPECT_EQ(j["log"][0], "round 1: added gyro_bias");
  EXPECT_FALSE(j.contains("residual_components"));
  ASSERT_EQ(j["effects"].size(), 1u);
  const nlohmann::json& je = j["effects"][0];
  EXPECT_EQ(je["name"], "gyro_bias");
  EXPECT_EQ(je["value"], nlohmann::json::parse("[0.01, 0.0, 0.0]"));
  // An undetermined standard error is written as null.
  EXPECT_EQ(je["stderr"].dump(), "[0.001,0.002,null]");
  EXPECT_EQ(je["unit"], "rad/s");
  EXPECT_EQ(je["ambiguous_with"][0], "velocity");
  // No ambiguous_with key when there is no ambiguity.
  r.effects[0].ambiguous_with.clear();
  EXPECT_FALSE(LoopToJson(r, 12)["effects"][0].contains("ambiguous_with"));
  // One residual component (video pairs with translation) is named.
  r.residual_components = 1;
  EXPECT_EQ(LoopToJson(r, 12)["residual_components"], 1);
}

TEST(LoopToJson, ReadoutDirectionIsAWordWithANullStandardError) {
  LoopResult r;
  IdentifiedEffect e;
  e.effect = Effect::kReadoutDirection;
  e.value = ReadoutDirection::kBottomToTop;
  r.effects.push_back(e);
  const nlohmann::json je = LoopToJson(r, 3)["effects"][0];
  EXPECT_EQ(je["value"], "bottom_to_top");
  EXPECT_TRUE(je["stderr"].is_null());
  EXPECT_EQ(je["unit"], "");
}

TEST(ReadValidationReport, ReadsBackTheFittedModelAndTheCovariances) {
  LoopResult r;
  r.model.rig = test::MappingRig();
  r.model.rig.time_offset_s = 0.0042;
  r.model.clock_rate_ppm = 35.0;
  r.model.gyro_scale = Eigen::Vector3d(1.01, 0.99, 1.0);
  r.after = {0.03, 0.1, 50};
  r.noise_px = 0.025;
  IdentifiedEffect e;
  e.effect = Effect::kClockRate;
  e.value = 35.0;
  e.stderr_value = 2.0;
  e.parameters = Eigen::Vector2d(35.0, 0.0042);
  e.covariance = (Eigen::Matrix2d() << 4.0, -1e-5, -1e-5, 1e-10).finished();
  r.effects.push_back(e);
  test::TempDir dir;
  WriteFileAtomically(dir / "report.json", LoopToJson(r, 6).dump(2));
  const ReportedModel back = ReadValidationReport(dir / "report.json");
  ASSERT_TRUE(back.fitted);
  EXPECT_EQ(back.fitted->rig.time_offset_s, 0.0042);
  EXPECT_EQ(back.fitted->clock_rate_ppm, 35.0);
  EXPECT_EQ(back.fitted->gyro_scale, r.model.gyro_scale);
  EXPECT_EQ(back.fitted->rig.camera.width, 1280);
  ASSERT_EQ(back.effects.size(), 1u);
  EXPECT_EQ(back.effects[0].effect, Effect::kClockRate);
  EXPECT_EQ(std::get<double>(back.effects[0].value), 35.0);
  EXPECT_EQ(back.effects[0].parameters, e.parameters);
  EXPECT_EQ(back.effects[0].covariance, e.covariance);
  EXPECT_DOUBLE_EQ(back.noise_px, 0.025);
  EXPECT_DOUBLE_EQ(back.after_rms_px, 0.03);
  // What is not a report is refused, naming the file.
  WriteFileAtomically(dir / "other.json", R"({"format": "measure/1"})");
  try {
    ReadValidationReport(dir / "other.json");
    ADD_FAILURE() << "read a measure report as a validation report";
  } catch (const IoError& error) {
    EXPECT_NE(std::string(error.what()).find("other.json"), std::string::npos) << error.what();
  }
}

// fuzz/validation_report_fuzz's find (2,916,119 executions on 80032a5): a fitted camera whose width
// is 6.4e68 pixels was cast to int (undefined behaviour). It is refused with the reason, naming the
// file.
TEST(ReadValidationReport, RefusesAFittedCameraWithAnImpossibleWidth) {
  test::TempDir dir;
  WriteFileAtomically(dir / "report.json", R"({"format": "validation/1", "frames": 2,
    "before": {"rms_px": 1.0, "max_px": 2.0}, "after": {"rms_px": 0.1, "max_px": 0.2},
    "noise_px": 0.1, "unexplained": false, "effects": [],
    "fitted_model": {"camera": {"format": "rig/1",
      "image": {"width": 644444444444444444444444444444444444444444444444444441444444444444444, "height": 48},
      "intrinsics": {"fx": 50, "fy": 50, "cx": 31.5, "cy": 23.5},
      "rolling_shutter": {"readout_s": 0.03}}}})");
  try {
    ReadValidationReport(dir / "report.json");
    ADD_FAILURE() << "read a camera 6.4e68 pixels wide";
  } catch (const IoError& error) {
    const std::string what = error.what();
    EXPECT_NE(what.find("report.json"), std::string::npos) << what;
    EXPECT_NE(what.find("1048576"), std::string::npos) << what;
  }
}

TEST(MeasureToJson, HasTheFormatsKeys) {
  MeasureReport report;
  report.measurement.field = cv::Mat(6, 8, CV_32FC2, cv::Scalar(0.5f, 0.0f));
  report.measurement.points.resize(4);
  report.measurement.noise_px = 0.02;
  report.measurement.d_px = 1.5;
  report.measurement.measured_fraction = 0.9;
  nlohmann::json j = MeasureToJson(report);
  EXPECT_EQ(j["format"], "measure/1");
  EXPECT_EQ(j["width"], 8);
  EXPECT_EQ(j["height"], 6);
  EXPECT_DOUBLE_EQ(j["D_px"].get<double>(), 1.5);
  EXPECT_DOUBLE_EQ(j["noise_px"].get<double>(), 0.02);
  EXPECT_DOUBLE_EQ(j["measured_fraction"].get<double>(), 0.9);
  EXPECT_EQ(j["points"], 4);
  EXPECT_FALSE(j.contains("D_m"));
  EXPECT_FALSE(j.contains("truth"));
  // D in metres with a camera, the error against a truth field with one.
  report.ground_m_per_px = 0.04;
  report.truth = FieldComparison{0.1, 0.3, 48};
  j = MeasureToJson(report);
  EXPECT_DOUBLE_EQ(j["D_m"].get<double>(), 1.5 * 0.04);
  EXPECT_DOUBLE_EQ(j["truth"]["rms_px"].get<double>(), 0.1);
  EXPECT_DOUBLE_EQ(j["truth"]["max_px"].get<double>(), 0.3);
  EXPECT_EQ(j["truth"]["pixels"], 48);
}

}  // namespace
}  // namespace shutterlab
