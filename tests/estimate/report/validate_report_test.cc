// The validation report (docs/FORMATS.md "Validation report") of rendered datasets with one
// undeclared effect (tests/estimate/loop/validate_fixtures.h): the JSON's keys and the table's
// bookkeeping, the verdict's words, both video models in the report.

#include "estimate/report/validate_report.h"

#include "estimate/loop/validate.h"
#include "estimate/loop/validate_video.h"
#include "estimate/report/validate_verdict.h"
#include "sim/logs/gyro_io.h"
#include "tests/estimate/loop/validate_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace shutterlab {
namespace {

// A fit that explains the residual only with a value no device has (a roll-only stabiliser's
// image: gyro_scale 0.1 about the optical axis with a 100 deg/s bias) is no fix: the verdict says
// which values are impossible and what they point to, and offers nothing for camera.json; the
// same loop with a real part's values is named as the fix.
TEST(ValidateVerdict, AnEffectNoDeviceHasIsNeverNamedAsTheFix) {
  ValidationResult result;
  IdentifiedEffect scale, bias;
  scale.effect = Effect::kGyroScale;
  scale.value = Eigen::Vector3d(1.0, 1.0, 0.1);
  scale.out_of_bounds = OutOfBounds(scale.effect, scale.value);
  bias.effect = Effect::kGyroBias;
  bias.value = Eigen::Vector3d(0.0, 0.0, 100.0 * M_PI / 180.0);
  bias.out_of_bounds = OutOfBounds(bias.effect, bias.value);
  result.loop.effects = {scale, bias};
  result.loop.noise_px = 0.05;
  result.loop.after.rms_px = 0.05;
  const ValidationVerdict impossible = MakeVerdict(result);
  EXPECT_EQ(impossible.level, ValidationVerdict::Level::kProblem);
  EXPECT_EQ(impossible.headline.rfind("No effect of the sensor explains this: the fit needs "
                                      "gyro_scale axis z at 0.1, outside 0.9 ... 1.1",
                                      0),
            0u)
      << impossible.headline;
  EXPECT_NE(impossible.headline.find("gyro_bias axis z at 100 deg/s"), std::string::npos);
  EXPECT_NE(impossible.headline.find("a stabiliser or re-rendering"), std::string::npos);
  for (const std::string& action : impossible.actions) {
    EXPECT_EQ(action.find("Put "), std::string::npos) << action;
  }
  // Within a real part's range: the fix to put into camera.json.
  result.loop.effects[0].value = Eigen::Vector3d(1.0, 1.0, 1.02);
  result.loop.effects[0].out_of_bounds.clear();
  result.loop.effects[1].value = Eigen::Vector3d(0.0, 0.0, 0.01);
  result.loop.effects[1].out_of_bounds.clear();
  const ValidationVerdict fix = MakeVerdict(result);
  EXPECT_EQ(fix.level, ValidationVerdict::Level::kAttention);
  ASSERT_FALSE(fix.actions.empty());
  EXPECT_EQ(fix.actions[0].rfind("Put gyro_scale = ", 0), 0u) << fix.actions[0];
}

// Every sentence the verdict can say, each with the condition that makes it true and a change that
// makes it false (estimate/report/validate_verdict.cc). A sentence with no case here fails
// nothing: add one with the sentence.
struct SentenceCase {
  std::string fragment;                         // a part of the sentence only it says
  std::function<void(ValidationResult*)> make;  // from the base: the sentence is said
  std::function<void(ValidationResult*)> undo;  // from make's: it is not
};

ValidationResult VerdictBase() {
  ValidationResult r;
  r.loop.noise_px = 0.05;
  r.loop.after.rms_px = 0.05;
  r.loop.after.points = 1000;
  r.loop.residual_components = 2;
  return r;
}

IdentifiedEffect TimeOffset(double value_s) {
  IdentifiedEffect e;
  e.effect = Effect::kTimeOffset;
  e.value = value_s;
  e.stderr_value = 0.0002;
  e.out_of_bounds = OutOfBounds(e.effect, e.value);
  return e;
}

GyroFollowCheck NotFollowingAboutZ() {
  GyroFollowCheck check;
  check.determined = true;
  for (int a = 0; a < 3; ++a) {
    AxisFollow& f = check.axes[a];
    f.determined = true;
    f.row_norm = f.gain = a == 2 ? 0.01 : 1.0;
    f.row_norm_stderr = 0.01;
    f.follows = f.clearly_follows = a != 2;
  }
  return check;
}

std::string AllText(const ValidationVerdict& v) {
  std::string text = v.headline + "\n" + v.certainty + "\n";
  for (const std::string& f : v.findings) text += f + "\n";
  for (const std::string& a : v.actions) text += a + "\n";
  return text;
}

TEST(ValidateVerdict, EverySentenceHasItsConditionAndATestThatMakesItFalse) {
  using R = ValidationResult*;
  const std::vector<SentenceCase> cases = {
      {"A stabiliser re-rendered the image: it follows the gyro only turned",
       [](R r) { r->video = r->image_orientation.present = r->image_orientation.holds = true; },
       [](R r) { r->image_orientation.holds = false; }},
      {"The stabiliser's own rotation (IORI)",
       [](R r) { r->video = r->image_orientation.present = true; },
       [](R r) { r->image_orientation.present = false; }},
      {"The image does not follow the gyro: it turns",
       [](R r) {
         r->video = r->screen.gyro_follow.determined = true;
         r->screen.gyro_follow.follows = false;
       },
       [](R r) { r->screen.gyro_follow.follows = true; }},
      {"Record with the stabiliser off",
       [](R r) {
         r->video = r->screen.gyro_follow.determined = true;
         r->screen.gyro_follow.follows = false;
       },
       [](R r) { r->screen.gyro_follow.determined = false; }},
      {"No effect of the sensor explains this", [](R r) { r->loop.effects = {TimeOffset(2.5)}; },
       [](R r) { r->loop.effects = {TimeOffset(0.004)}; }},
      {"Check camera.json's gyro_to_camera and intrinsics",
       [](R r) { r->loop.effects = {TimeOffset(2.5)}; }, [](R r) { r->loop.effects.clear(); }},
      {"Something the model lacks moves the image", [](R r) { r->loop.unexplained = true; },
       [](R r) { r->loop.unexplained = false; }},
      {"Look at the residual pictures", [](R r) { r->loop.unexplained = true; },
       [](R r) { r->loop.unexplained = false; }},
      {"The declared camera model is off", [](R r) { r->loop.effects = {TimeOffset(0.004)}; },
       [](R r) { r->loop.effects.clear(); }},
      {"Put time_offset = ", [](R r) { r->loop.effects = {TimeOffset(0.004)}; },
       [](R r) { r->loop.unexplained = true; }},
      {"time_offset = 4.000 ± 0.200 ms (declared 0.000 ms)",
       [](R r) { r->loop.effects = {TimeOffset(0.004)}; }, [](R r) { r->loop.effects.clear(); }},
      {"The declared camera model explains the measured motion", [](R) {},
       [](R r) { r->loop.unexplained = true; }},
      {"A stabiliser re-renders the image about camera axis z",
       [](R r) {
         r->video = true;
         r->axes_not_following = NotFollowingAboutZ();
       },
       [](R r) { r->axes_not_following.reset(); }},
      {"To test the sensor about every axis",
       [](R r) {
         r->video = true;
         r->axes_not_following = NotFollowingAboutZ();
       },
       [](R r) { r->loop.unexplained = true; }},
      // Translation is said only where the motion allows it: not on a stabiliser's rendering.
      {"The camera moved between frames",
       [](R r) {
         r->video = true;
         r->preferred = "translation";
         r->translation_loop = r->loop;
       },
       [](R r) {
         r->screen.gyro_follow.determined = true;
         r->screen.gyro_follow.follows = false;
       }},
      {"The camera moved between frames",
       [](R r) {
         r->video = true;
         r->preferred = "translation";
         r->translation_loop = r->loop;
       },
       [](R r) { r->preferred = "rotation_only"; }},
      {"The paper's per-axis threshold model gives",
       [](R r) {
         RatioGroup all;
         all.frames = 8;
         all.paper_median = 0.8;
         r->ratios = {all};
       },
       [](R r) { r->video = true; }},
      {"The source's readout_s (source claim): claim holds",
       [](R r) {
         ClaimCheck c;
         c.claim = "readout_s";
         c.status = "source claim";
         c.verdict = "claim holds";
         r->claims = {c};
       },
       [](R r) { r->claims.clear(); }},
      {"Where the source's claim is contradicted",
       [](R r) {
         ClaimCheck c;
         c.claim = "readout_s";
         c.verdict = "claim contradicted: 30 ms against 33 ms";
         r->claims = {c};
       },
       [](R r) { r->claims[0].verdict = "claim holds"; }},
      {"of the points were left out before the fit",
       [](R r) { r->screen.camera_fixed_share = r->screen.moving_share = 0.2; },
       [](R r) { r->screen.camera_fixed_share = r->screen.moving_share = 0.1; }},
      {"The halves disagree on time_offset",
       [](R r) {
         HalfCheck h;
         HalfAgreement a;
         a.agree = false;
         h.effects = {a};
         r->halves = {h};
       },
       [](R r) { r->halves[0].effects[0].agree = true; }},
      // How sure.
      {"Standard errors: model over 0 frames", [](R r) { r->loop.effects = {TimeOffset(0.004)}; },
       [](R r) { r->loop.effects.clear(); }},
      {"The two halves of the clip agree within their standard errors",
       [](R r) {
         r->halves = {HalfCheck{"rotation_only", 4, 4, {HalfAgreement{}}, {}, {}, {}, {}}};
       },
       [](R r) { r->halves.clear(); }},
      {"The two halves of the clip DISAGREE",
       [](R r) {
         r->halves = {HalfCheck{"rotation_only", 4, 4, {HalfAgreement{}}, {}, {}, {}, {}}};
         r->halves[0].effects[0].agree = false;
       },
       [](R r) { r->halves[0].effects[0].agree = true; }},
      {"do not both determine the effects",
       [](R r) {
         r->halves = {HalfCheck{"rotation_only", 4, 4, {HalfAgreement{}}, {}, {}, {}, {}}};
         r->halves[0].effects[0].determined = false;
       },
       [](R r) { r->halves[0].effects[0].determined = true; }},
      {"off their epipolar lines", [](R r) { r->video = true; }, [](R r) { r->video = false; }},
      {", and the masked pixels", [](R r) { r->mask = cv::Mat(4, 4, CV_8U, cv::Scalar(255)); },
       [](R r) { r->mask = cv::Mat(); }},
  };
  for (const SentenceCase& c : cases) {
    ValidationResult result = VerdictBase();
    c.make(&result);
    const std::string said = AllText(MakeVerdict(result));
    EXPECT_NE(said.find(c.fragment), std::string::npos) << c.fragment << "\nnot in\n" << said;
    c.undo(&result);
    const std::string unsaid = AllText(MakeVerdict(result));
    EXPECT_EQ(unsaid.find(c.fragment), std::string::npos) << c.fragment << "\nstill in\n" << unsaid;
  }
}

// The standard errors that the coverage study found do not hold, per model (here the
// pair-translation model's clock_rate) are withheld in the JSON, the table and the verdict, said
// why; the others, and the same effect's in a model where it holds, are kept.
TEST(ValidateReport, StandardErrorsThatDoNotHoldAreWithheld) {
  ValidationResult result = VerdictBase();
  result.video = true;
  result.preferred = "translation";
  IdentifiedEffect rate;
  rate.effect = Effect::kClockRate;
  rate.value = 250.0;
  rate.stderr_value = 3.0;
  rate.parameters = Eigen::VectorXd::Zero(2);
  rate.covariance = Eigen::MatrixXd::Identity(2, 2);
  result.translation_loop = result.loop;
  result.translation_loop.effects = {TimeOffset(0.004), rate};
  // In a model where its standard error holds (the rotation-only clock rate) it is kept.
  LoopResult rotation_only;
  rotation_only.effects = {rate};
  WithholdUncalibratedStderr(FitModel::kRotationOnly, &rotation_only);
  EXPECT_TRUE(rotation_only.effects[0].stderr_withheld.empty());
  EXPECT_EQ(std::get<double>(rotation_only.effects[0].stderr_value), 3.0);
  WithholdUncalibratedStderr(FitModel::kPairTranslation, &result.translation_loop);
  const IdentifiedEffect& offset = result.translation_loop.effects[0];
  const IdentifiedEffect& withheld = result.translation_loop.effects[1];
  EXPECT_TRUE(offset.stderr_withheld.empty());
  EXPECT_EQ(std::get<double>(offset.stderr_value), 0.0002);
  EXPECT_NE(withheld.stderr_withheld.find("does not hold"), std::string::npos);
  EXPECT_TRUE(std::isnan(std::get<double>(withheld.stderr_value)));
  EXPECT_FALSE(withheld.covariance.allFinite()) << "correct draws its uncertainty from it";
  // As written: NaN is null in the file.
  const nlohmann::json json = nlohmann::json::parse(ValidationToJson(result).dump());
  const nlohmann::json& effects = json["translation"]["effects"];
  ASSERT_EQ(effects.size(), 2u) << json.dump(2);
  EXPECT_TRUE(effects[1]["stderr"].is_null()) << effects[1].dump();
  EXPECT_EQ(effects[1]["stderr_withheld"], withheld.stderr_withheld);
  EXPECT_FALSE(effects[0].contains("stderr_withheld"));
  const std::string verdict = AllText(MakeVerdict(result));
  EXPECT_NE(
      verdict.find("clock_rate = 250.0 ppm, with no standard error (the pair-translation model's"),
      std::string::npos)
      << verdict;
  EXPECT_NE(ValidationReport(result).find("ppm, with no standard error (the pair-translation"),
            std::string::npos)
      << ValidationReport(result);
}

// The table's bookkeeping on one dataset: flags follow D against each limit, the confusion matrix
// counts every frame once per limit, and the JSON has docs/FORMATS.md's keys.
TEST(ValidateReport, TableAndReportAreConsistent) {
  if (test::kAsan) GTEST_SKIP() << "reduced set under ASan";
  test::TempDir dir;
  const ValidationResult result =
      test::ValidateWithoutResiduals(test::MakeDataset(dir, {{"time_offset=4ms"}}));
  ASSERT_EQ(result.frames.size(), static_cast<size_t>(test::kStillFrames));
  for (size_t l = 0; l < result.limits_m.size(); ++l) {
    const Confusion& c = result.confusion_paper[l];
    EXPECT_EQ(c.true_positive + c.false_positive + c.false_negative + c.true_negative,
              test::kStillFrames);
    for (const FrameValidation& f : result.frames) {
      EXPECT_EQ(f.flag_meas[l], f.d_meas_m > result.limits_m[l]);
      EXPECT_EQ(f.flag_paper[l], f.d_paper_m > result.limits_m[l]);
    }
  }
  const nlohmann::json json = ValidationToJson(result);
  for (const char* key :
       {"format", "frames", "before", "effects", "after", "noise_px", "unexplained"}) {
    EXPECT_TRUE(json.contains(key)) << key;
  }
  EXPECT_EQ(json["format"], "validation/1");
  EXPECT_EQ(json["frames"], test::kStillFrames);
  EXPECT_EQ(json["frames_detail"].size(), static_cast<size_t>(test::kStillFrames));
}

// A gyro log five times the image's rotation, as a stabiliser leaves it (the camera kept a fifth of
// its turning in the picture): the image does not follow the gyro, and the report names no effect.
TEST(ValidateReport, AStabilisedImageNamesNoEffect) {
  if (test::kAsan) GTEST_SKIP() << "reduced set under ASan";
  test::TempDir dir;
  test::ClipSpec spec;
  spec.frames = 10;
  const std::string clip = test::MakeClip(dir, spec);
  std::vector<GyroSample> logged = ReadGyroCsv(clip + "/gyro.csv").samples();
  for (GyroSample& s : logged) s.omega_rad_s *= 5.0;
  WriteGyroCsv(clip + "/gyro.csv", GyroTrace(std::move(logged)));
  const ValidationResult result = test::ValidateWithoutResiduals(clip);
  const std::string report = ValidationReport(result);
  ASSERT_TRUE(result.screen.gyro_follow.determined) << report;
  EXPECT_FALSE(result.screen.gyro_follow.follows) << report;
  EXPECT_NEAR(result.screen.gyro_follow.gain, 0.2, 0.05) << report;
  EXPECT_TRUE(result.screen.region.whole_image) << report;
  const nlohmann::json json = ValidationToJson(result);
  EXPECT_TRUE(json["effects"].empty()) << report;
  EXPECT_EQ(json["unexplained"], true);
  EXPECT_EQ(json["verdict"]["level"], "problem");
  EXPECT_NE(json["verdict"]["headline"].get<std::string>().find("does not follow the gyro"),
            std::string::npos);
}

// Horizon levelling held to the first frame (render --stabiliser roll-lock): the verdict says which
// axis does not follow, names no effect of the sensor and asks for nothing in camera.json; the
// JSON carries each axis's numbers.
TEST(ValidateReport, ARollLockedClipSaysWhichAxisAndNamesNoEffect) {
  test::TempDir dir;
  test::ClipSpec spec;
  spec.frames = test::kAsan ? 10 : 16;
  spec.stabiliser.mode = StabiliserMode::kRollLock;
  const ValidationResult result = test::ValidateWithoutResiduals(test::MakeClip(dir, spec));
  const std::string report = ValidationReport(result);
  const nlohmann::json json = ValidationToJson(result);
  EXPECT_TRUE(json["effects"].empty()) << report;
  EXPECT_EQ(json["verdict"]["level"], "attention") << report;
  const std::string headline = json["verdict"]["headline"];
  EXPECT_EQ(headline.find("A stabiliser re-renders the image about camera axis z"), 0u) << report;
  EXPECT_NE(headline.find("there is nothing to correct"), std::string::npos) << report;
  EXPECT_EQ(json["verdict"].dump().find("camera.json"), std::string::npos) << report;
  const nlohmann::json& axes = json["screening"]["axes_not_following"];
  EXPECT_EQ(axes["not_following"], nlohmann::json::array({"z"})) << report;
  EXPECT_EQ(axes["axes"]["z"]["follows"], false) << report;
  EXPECT_EQ(axes["axes"]["x"]["clearly_follows"], true) << report;
  EXPECT_NE(report.find("image against gyro, per axis: the image does not follow the gyro about "
                        "camera axis z"),
            std::string::npos)
      << report;
}

// A whole-image stabiliser with no translation at all: the sentence "the camera moved between
// frames" is not said (the pair-translation model absorbs the stabiliser's turning, no motion).
TEST(ValidateReport, AStabiliserIsNoTranslation) {
  if (test::kAsan) GTEST_SKIP() << "reduced set under ASan";
  test::TempDir dir;
  test::ClipSpec spec;
  spec.stabiliser.mode = StabiliserMode::kWhole;
  const ValidationResult result = test::ValidateWithoutResiduals(test::MakeClip(dir, spec));
  const nlohmann::json json = ValidationToJson(result);
  const std::string verdict = json["verdict"].dump();
  EXPECT_EQ(json["verdict"]["level"], "problem") << verdict;
  EXPECT_EQ(verdict.find("moved between frames"), std::string::npos) << verdict;
  EXPECT_EQ(verdict.find("translation explains"), std::string::npos) << verdict;
  EXPECT_EQ(json["model"], "rotation_only") << verdict;
}

TEST(ValidateReport, ReportAndJsonCarryBothModels) {
  if (test::kAsan) GTEST_SKIP() << "reduced set under ASan";
  test::TempDir dir;
  test::ClipSpec spec;
  spec.injections = {"time_offset=4ms"};
  spec.frames = 6;
  const ValidationResult result = test::ValidateWithoutResiduals(test::MakeClip(dir, spec));
  const nlohmann::json json = ValidationToJson(result);
  for (const char* key : {"format", "frames", "before", "effects", "after", "noise_px",
                          "unexplained", "model", "rotation_only", "translation", "pairs"}) {
    EXPECT_TRUE(json.contains(key)) << key;
  }
  EXPECT_EQ(json["format"], "validation/1");
  EXPECT_EQ(json["frames"], 5);  // pairs
  EXPECT_EQ(json["pairs"].size(), 5u);
  EXPECT_EQ(json["pairs"][0]["previous"], 0);
  EXPECT_EQ(json["pairs"][0]["frame"], 1);
  // The top level is the preferred model's loop, docs/FORMATS.md's keys with their types.
  const LoopResult& preferred =
      result.preferred == "translation" ? result.translation_loop : result.loop;
  EXPECT_EQ(json["after"]["rms_px"].get<double>(), preferred.after.rms_px);
  EXPECT_TRUE(json["log"].is_array());
  const std::string report = ValidationReport(result);
  EXPECT_NE(report.find("rotation only"), std::string::npos) << report;
  EXPECT_NE(report.find("with each pair's translation"), std::string::npos) << report;
  // Whether translation had anything to explain, said in words either way.
  EXPECT_TRUE(report.find("translation explains") != std::string::npos ||
              report.find("nothing for translation to explain") != std::string::npos)
      << report;
}

}  // namespace
}  // namespace shutterlab
