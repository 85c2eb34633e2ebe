// Video validation on data nobody here made: `shutterlab import` then `shutterlab validate` on the
// real rolling-shutter clips in the shared real-data folder (provenance in its SOURCES.md and
// PROVENANCE.md files), through the CLI as a user runs them. What is asserted is what the clips
// show robustly (docs/real-footage.md):
//  - the phone clip, filmed from a moving car with its dashboard in the bottom third: per-pair
//    translation explains what rotation leaves; the time offset (-3.2 ms) and the readout do not
//    depend on the dashboard (full frames and frames cut above it agree);
//  - the GoPro on the Karma drone (gimbal-stabilised): the drone's translation dominates the image
//    motion and the camera hardly turns, so the data cannot settle the readout direction;
//  - the GoPro MAX with HyperSmooth on: the image does not follow the body's gyro, and no effect
//    is named.

#include "io/frames_csv.h"
#include "io/image_io.h"
#include "model/camera.h"
#include "sim/text_file.h"
#include "tests/app/cli_test_util.h"
#include "tests/estimate/report/report_test_util.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <string>
#include <utility>

namespace shutterlab {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using test::RunShutterlab;

json ImportAndValidate(const test::TempDir& dir, const std::string& source,
                       const std::string& import_args, const std::string& validate_args = "") {
  const auto imported =
      RunShutterlab("import '" + source + "' --out '" + (dir / "clip") + "' " + import_args);
  EXPECT_EQ(imported.exit_code, 0) << imported.output;
  const auto validated = RunShutterlab("validate '" + (dir / "clip") + "' --report '" +
                                       (dir / "report.json") + "' " + validate_args);
  EXPECT_EQ(validated.exit_code, 0) << validated.output;
  return json::parse(ReadFileToString(dir / "report.json"));
}

const json* Claim(const json& report, const std::string& name) {
  for (const json& c : report["claims"]) {
    if (c["claim"] == name) return &c;
  }
  return nullptr;
}

// The claim check's fit of a scalar claim: value and standard error, s.
std::pair<double, double> ClaimFit(const json& report, const std::string& name) {
  const json* claim = Claim(report, name);
  EXPECT_NE(claim, nullptr) << name;
  if (claim == nullptr) return {0.0, 0.0};
  return {(*claim)["found"].get<double>(), (*claim)["found_stderr"].get<double>()};
}

// A video dataset cut to its top `rows` rows: the images, camera.json's height and readout (rows
// keep their times: the readout scales with rows / height), import.json's readout claim alike.
void CropRows(const std::string& from, const std::string& to, int rows) {
  fs::create_directories(to + "/images");
  for (const char* file : {"gyro.csv", "frames.csv"})
    fs::copy_file(from + "/" + file, to + "/" + file);
  RigModel rig = ReadRigModel(from + "/camera.json");
  const double scale = static_cast<double>(rows) / rig.camera.height;
  for (const FrameEntry& f : ReadFramesCsv(from + "/frames.csv")) {
    WriteImage(to + "/" + f.image,
               ReadImage(from + "/" + f.image)(cv::Rect(0, 0, rig.camera.width, rows)).clone());
  }
  rig.camera.height = rows;
  rig.shutter.readout_s *= scale;
  WriteRigModel(to + "/camera.json", rig);
  json record = json::parse(ReadFileToString(from + "/import.json"));
  for (json& claim : record["claims"]) {
    if (claim["what"] == "readout_s") claim["value"] = claim["value"].get<double>() * scale;
  }
  WriteFileAtomically(to + "/import.json", record.dump(2));
}

// The phone clip's bottom third is the car's dashboard: low texture, its flow dragged along from
// the street above (it moves neither with the camera nor with the scene). The screening leaves out
// the matches no single camera motion explains (the dashboard's among them: moving cars, people),
// and the clip then shows a gyro 3.2 ms ahead of the frames' start-of-frame times, with a readout
// of about 30.5 ms (the source's 33.3 ms is 3-4 standard errors off, and fitting the readout beside
// the offset removes a sliver of the residual: not determined). Full frames and frames cut to the
// 390 rows above the dashboard agree within their standard errors.
TEST(RealClips, PhoneClipTimeOffsetAndReadoutDoNotDependOnTheDashboard) {
  if (test::kAsan) GTEST_SKIP() << "reduced set under ASan (the Karma clip runs)";
  SHUTTERLAB_REAL_DATA(clip, "rs/phone_gyro_video_20200109_145447");
  test::TempDir dir;
  const json report = ImportAndValidate(dir, clip, "", "--out '" + (dir / "plots") + "'");
  EXPECT_EQ(report["video"], true);
  EXPECT_EQ(report["frames"], 19);  // 20 frames, 19 pairs
  EXPECT_EQ(report["model"], "translation");
  EXPECT_EQ(report["rotation_only"]["unexplained"], true);
  EXPECT_GT(report["translation"]["explains_share"].get<double>(), 0.9);
  EXPECT_EQ(report["screening"]["gyro_follow"]["follows"], true);
  EXPECT_GT(report["screening"]["moving_share"].get<double>(), 0.05);
  // The identified effect of the preferred model: the time offset, with the pairs' jackknife.
  ASSERT_EQ(report["effects"].size(), 1u) << report.dump(2);
  EXPECT_EQ(report["effects"][0]["name"], "time_offset");
  EXPECT_EQ(report["effects"][0]["stderr_from"], "cluster jackknife");
  const double offset = report["effects"][0]["value"].get<double>();
  const double offset_se = report["effects"][0]["stderr"].get<double>();
  EXPECT_GT(offset, -0.0045);
  EXPECT_LT(offset, -0.002);
  for (const json& e : report["halves"][0]["effects"]) EXPECT_EQ(e["agree"], true) << e.dump();
  // The source's claims.
  const json* readout_claim = Claim(report, "readout_s");
  ASSERT_NE(readout_claim, nullptr);
  EXPECT_NE((*readout_claim)["verdict"].get<std::string>().rfind("claim contradicted", 0), 0u)
      << readout_claim->dump();
  const auto [readout, readout_se] = ClaimFit(report, "readout_s");
  EXPECT_GT(readout, 0.028);
  EXPECT_LT(readout, 0.033);
  for (const char* name : {"gyro_to_camera", "direction"}) {
    const json* claim = Claim(report, name);
    ASSERT_NE(claim, nullptr) << name;
    EXPECT_EQ((*claim)["verdict"].get<std::string>().rfind("claim holds", 0), 0u) << claim->dump();
  }
  const json* offset_claim = Claim(report, "time_offset_s");
  ASSERT_NE(offset_claim, nullptr);
  EXPECT_EQ((*offset_claim)["verdict"].get<std::string>().rfind("claim contradicted", 0), 0u)
      << offset_claim->dump();
  // The page for a person: the verdict first, residual pictures, per row.
  const std::string page = ReadFileToString(dir / "plots/validate.html");
  EXPECT_LT(page.find("Verdict"), page.find("What was left out")) << page.substr(0, 2000);
  EXPECT_TRUE(fs::exists(dir / "plots/residual_rows.png"));
  test::ExpectDrawsInChromium(dir / "plots/validate.html", test::ChartBlocks(page).size(),
                              "validate_phone");
  EXPECT_TRUE(fs::exists(dir / "plots/0119_residual.png"));

  // Cut to the 390 rows above the dashboard: the same offset and (scaled) readout.
  constexpr int kRows = 390;
  CropRows(dir / "clip", dir / "crop", kRows);
  const auto validated =
      RunShutterlab("validate '" + (dir / "crop") + "' --report '" + (dir / "crop.json") + "'");
  ASSERT_EQ(validated.exit_code, 0) << validated.output;
  const json crop = json::parse(ReadFileToString(dir / "crop.json"));
  ASSERT_EQ(crop["effects"].size(), 1u) << crop.dump(2);
  EXPECT_EQ(crop["effects"][0]["name"], "time_offset");
  const double crop_offset = crop["effects"][0]["value"].get<double>();
  const double crop_offset_se = crop["effects"][0]["stderr"].get<double>();
  EXPECT_LT(std::abs(crop_offset - offset), 3 * std::hypot(offset_se, crop_offset_se))
      << offset << " +- " << offset_se << " against " << crop_offset << " +- " << crop_offset_se;
  const auto [crop_readout, crop_readout_se] = ClaimFit(crop, "readout_s");
  const double full_frame = crop_readout * 600.0 / kRows,
               full_frame_se = crop_readout_se * 600.0 / kRows;
  EXPECT_LT(std::abs(full_frame - readout), 3 * std::hypot(readout_se, full_frame_se))
      << readout << " +- " << readout_se << " against " << full_frame << " +- " << full_frame_se;
}

TEST(RealClips, GoproKarmaIsMostlyTranslation) {
  SHUTTERLAB_REAL_DATA(karma, "rs/gopro_karma/karma.mp4");
  test::TempDir dir;
  const json report = ImportAndValidate(dir, karma, "--start-frame 100 --max-frames 31",
                                        "--out '" + (dir / "plots") + "'");
  EXPECT_EQ(report["frames"], 30);
  EXPECT_EQ(report["rotation_only"]["unexplained"], true);
  EXPECT_GT(report["translation"]["explains_share"].get<double>(), 0.8);
  const json* direction = Claim(report, "direction");
  ASSERT_NE(direction, nullptr);
  EXPECT_EQ((*direction)["verdict"].get<std::string>().rfind("not determined", 0), 0u)
      << direction->dump();
  // Every pair's residual picture is a file; the page inlines the 24 with the largest residual.
  for (int frame = 101; frame <= 130; ++frame) {
    EXPECT_TRUE(fs::exists(dir / ("plots/0" + std::to_string(frame) + "_residual.png")));
  }
  const std::string page = ReadFileToString(dir / "plots/validate.html");
  size_t images = 0;
  for (size_t at = page.find("<img "); at != std::string::npos; at = page.find("<img ", at + 1)) {
    ++images;
  }
  // The residual pictures, the screening's and the camera-fixed check's evidence (also a file).
  EXPECT_EQ(images, 24u + 2u);
  EXPECT_TRUE(fs::exists(dir / "plots/camera_fixed_evidence.png"));
  EXPECT_TRUE(fs::exists(dir / "plots/camera_fixed_mask.png"));
  EXPECT_NE(page.find("The 24 of 30 pairs with the largest residual before"), std::string::npos);
  // Whatever it says, nothing confident and wrong: no effect stands beside an unexplained residual.
  EXPECT_TRUE(report["effects"].empty() || report["unexplained"] == false) << report.dump(2);
}

// The MAX re-renders its image from its own orientation estimate (HyperSmooth, EISE "Y"): the
// image turns at about 0.6 of the rate of the body's gyro. Its own per-frame rotation (IORI) is
// tested on the images: on these 90 pairs the rotations pick a reading (55 % of the departure)
// under which almost nothing is left to move, and the screening's test cannot confirm it, so it
// is not applied (on the whole clip the reading CORI's axes give holds: docs/real-footage.md).
// Either way validate names no effect of the sensor on the stabiliser's rendering.
TEST(RealClips, GoproMaxStabilisedImageNamesNoEffect) {
  SHUTTERLAB_REAL_DATA(max, "incoming_rs/gopro_max_heromode/max-heromode.mp4");
  // The screening and the verdict run under ASan in ValidateVideo.*; 90 pairs of 848x480 there
  // would take minutes.
  if (test::kAsan) GTEST_SKIP() << "reduced set under ASan";
  test::TempDir dir;
  const json report = ImportAndValidate(dir, max, "--max-frames 91");
  const json& iori = report["image_orientation"];
  ASSERT_TRUE(report.contains("image_orientation")) << report.dump(2);
  EXPECT_LT(iori["gain_gyro_alone"].get<double>(), 0.7) << iori.dump();
  EXPECT_EQ(iori["pairs_tested"], 90) << iori.dump();
  EXPECT_EQ(iori["holds"], false) << iori.dump();
  EXPECT_TRUE(iori["gain_applied"].is_null()) << iori.dump();
  const json& follow = report["screening"]["gyro_follow"];
  EXPECT_EQ(follow["determined"], true) << follow.dump();
  EXPECT_EQ(follow["follows"], false) << follow.dump();
  EXPECT_EQ(report["unexplained"], true);
  EXPECT_TRUE(report["effects"].empty()) << report.dump(2);
  EXPECT_EQ(report["verdict"]["level"], "problem");
  for (const json& c : report["claims"]) {
    EXPECT_EQ(c["verdict"].get<std::string>().rfind("not determined", 0), 0u) << c.dump();
  }
}

}  // namespace
}  // namespace shutterlab
