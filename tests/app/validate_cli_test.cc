// `shutterlab validate` through the CLI: the report JSON has docs/FORMATS.md's keys, --out writes
// the residual pictures, and bad input gives one line "error: PATH[:LINE]: problem", exit code 2
// and no output. The dataset is small (3 frames of 320x240) so the whole file stays fast under
// ASan.

#include "model/camera.h"
#include "render/render_dataset.h"
#include "sim/logs/gyro_io.h"
#include "sim/text_file.h"
#include "tests/app/cli_test_util.h"
#include "tests/estimate/loop/effect_fixtures.h"
#include "tests/render/render_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <string>

namespace shutterlab {
namespace {

namespace fs = std::filesystem;

// Renders dir/ds: 3 frames of 320x240 (f 275 px, 30 ms, 50 m), 3 ms undeclared time offset.
std::string SmallValidateDataset(const test::TempDir& dir, int width = 320, int height = 240) {
  WriteRigModel(dir / "camera.json", test::NadirRig(width, height, 275.0 * width / 320.0));
  WriteGyroCsv(dir / "gyro.csv", test::FlightTrace(14.0, 5));
  WriteFileAtomically(dir / "times.csv", "frame,t_first_row\n0,8.5\n1,10.0\n2,12.0\n");
  RenderOptions render;
  render.scene_path = test::GroundScenePath(2);
  render.camera_path = dir / "camera.json";
  render.gyro_path = dir / "gyro.csv";
  render.frames_path = dir / "times.csv";
  render.out_dir = dir / "ds";
  render.injections = {"time_offset=3ms"};
  render.pictures = false;
  RenderDataset(render);
  return dir / "ds";
}

void ExpectOneLineError(const test::CommandResult& r, const std::string& where,
                        const std::string& problem) {
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(r.output.rfind("error: ", 0), 0u) << r.output;
  EXPECT_EQ(r.output.find('\n'), r.output.size() - 1) << "one line: " << r.output;
  EXPECT_NE(r.output.find(where), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(problem), std::string::npos) << r.output;
}

TEST(ValidateCli, WritesReportAndPlots) {
  test::TempDir dir;
  const std::string dataset = SmallValidateDataset(dir);
  const std::string report = dir / "report.json";
  const std::string out = dir / "plots";
  const test::CommandResult r = test::RunShutterlab(
      "validate '" + dataset + "' --report '" + report + "' --out '" + out + "' --limit 5cm,10cm");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("D_meas"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("closing the loop"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("time: read"), std::string::npos) << r.output;
  std::ifstream in(report);
  const nlohmann::json json = nlohmann::json::parse(in);
  for (const char* key : {"format", "frames", "before", "effects", "after", "noise_px",
                          "unexplained", "frames_detail", "confusion", "timing_s"}) {
    EXPECT_TRUE(json.contains(key)) << key;
  }
  EXPECT_EQ(json["format"], "validation/1");
  EXPECT_EQ(json["frames"], 3);
  EXPECT_TRUE(json["before"].contains("rms_px") && json["before"].contains("max_px"));
  EXPECT_TRUE(json["after"].contains("rms_px") && json["after"].contains("max_px"));
  for (const nlohmann::json& effect : json["effects"]) {
    for (const char* key : {"name", "value", "stderr", "unit"}) EXPECT_TRUE(effect.contains(key));
  }
  for (const char* file : {"0000_residual.png", "0001_residual.png", "0002_residual.png",
                           "residual_rows.png", "residual_rows.csv", "validate.html"}) {
    EXPECT_TRUE(fs::exists(fs::path(out) / file)) << file;
  }
  // What was written is said, the page first.
  EXPECT_NE(r.output.find("wrote " + out + "/: validate.html, "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("wrote " + report + "\n"), std::string::npos) << r.output;
  // The page: one "Per frame" section, whole-number frame ticks, and the overlay of what was left
  // out only when something was.
  const std::string page = ReadFileToString(fs::path(out) / "validate.html");
  EXPECT_EQ(page.find("<h2>Per frame</h2>"), page.rfind("<h2>Per frame</h2>"));
  EXPECT_NE(page.find("<h2>Per frame</h2>"), std::string::npos);
  EXPECT_NE(page.find("\"integer_x\":true"), std::string::npos);
  const nlohmann::json& screening = json["screening"];
  const bool left_out = !screening["mask"].is_null() ||
                        screening["camera_fixed"]["share_of_points"].get<double>() > 0 ||
                        screening["moving_share"].get<double>() > 0;
  EXPECT_EQ(page.find("points moving on their own</figcaption>") != std::string::npos, left_out);
}

TEST(ValidateCli, MissingCameraJson) {
  test::TempDir dir;
  const std::string dataset = SmallValidateDataset(dir);
  fs::remove(fs::path(dataset) / "camera.json");
  const std::string report = dir / "report.json";
  const test::CommandResult r =
      test::RunShutterlab("validate '" + dataset + "' --report '" + report + "'");
  ExpectOneLineError(r, dataset + "/camera.json", "missing");
  EXPECT_FALSE(fs::exists(report));
}

// Video datasets (ref empty on every line): one line with a ref, one frame, two frames at one time.
TEST(ValidateCli, BadVideoDatasets) {
  test::TempDir dir;
  const std::string dataset = SmallValidateDataset(dir);
  const std::string report = dir / "report.json";
  const auto run = [&](const std::string& frames_csv) {
    WriteFileAtomically(fs::path(dataset) / "frames.csv", frames_csv);
    return test::RunShutterlab("validate '" + dataset + "' --report '" + report + "'");
  };
  ExpectOneLineError(run("frame,t_first_row,ref,image\n0,8.5,,images/0000_rs.png\n"
                         "1,10.0,images/0001_ref.png,images/0001_rs.png\n"),
                     dataset + "/frames.csv:3:", "a ref image in a video dataset");
  ExpectOneLineError(run("frame,t_first_row,ref,image\n0,8.5,,images/0000_rs.png\n"),
                     dataset + "/frames.csv", "a video dataset needs at least two frames");
  ExpectOneLineError(run("frame,t_first_row,ref,image\n0,8.5,,images/0000_rs.png\n"
                         "1,8.5,,images/0001_rs.png\n"),
                     dataset + "/frames.csv:3:", "the same t_first_row as frame 0");
  // import.json (the source's claims) is checked before any measuring.
  const std::string video =
      "frame,t_first_row,ref,image\n0,8.5,,images/0000_rs.png\n"
      "1,10.0,,images/0001_rs.png\n";
  WriteFileAtomically(fs::path(dataset) / "import.json", "{\"claims\": [");
  ExpectOneLineError(run(video), dataset + "/import.json", "not JSON");
  WriteFileAtomically(fs::path(dataset) / "import.json",
                      R"({"claims": [{"what": "readout_s", "value": "fast"}]})");
  ExpectOneLineError(run(video), dataset + "/import.json",
                     "claim 1: \"readout_s\" has an unusable value \"fast\"");
  WriteFileAtomically(fs::path(dataset) / "import.json",
                      R"({"claims": [{"what": "gyro_to_camera", "value": [[1, 0], [0, 1]]}]})");
  ExpectOneLineError(run(video), dataset + "/import.json", "claim 1: \"gyro_to_camera\"");
  EXPECT_FALSE(fs::exists(report));
}

// A clip whose frames are one image (a camera on a tripod, duplicated decoded frames) measures
// exactly no motion, so no measurement noise: the loop still runs against a floor of the noise.
TEST(ValidateCli, VideoOfIdenticalFrames) {
  test::TempDir dir;
  const std::string dataset = SmallValidateDataset(dir);
  const std::string report = dir / "report.json";
  WriteFileAtomically(fs::path(dataset) / "frames.csv",
                      "frame,t_first_row,ref,image\n0,8.5,,images/0000_rs.png\n"
                      "1,8.6,,images/0000_rs.png\n2,8.7,,images/0000_rs.png\n");
  const auto r = test::RunShutterlab("validate '" + dataset + "' --report '" + report +
                                     "' --candidates time_offset");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(ReadFileToString(report));
  EXPECT_GE(j["noise_px"].get<double>(), 1e-3);
  EXPECT_EQ(j["frames"], 2);
}

TEST(ValidateCli, WrongImageSize) {
  test::TempDir dir;
  const std::string dataset = SmallValidateDataset(dir);
  // camera.json now declares a size the images do not have.
  RigModel rig = ReadRigModel(fs::path(dataset) / "camera.json");
  rig.camera.width = 330;
  WriteRigModel(fs::path(dataset) / "camera.json", rig);
  const std::string report = dir / "report.json";
  const std::string out = dir / "plots";
  const test::CommandResult r = test::RunShutterlab("validate '" + dataset + "' --report '" +
                                                    report + "' --out '" + out + "'");
  ExpectOneLineError(r, dataset + "/frames.csv:2:", "camera.json declares 330x240");
  EXPECT_FALSE(fs::exists(report));
  EXPECT_FALSE(fs::exists(out));
}

// A dataset of 30 x 24 frames, rendered whole: too small for the measurement's windows.
TEST(ValidateCli, ACameraTooSmallToMeasure) {
  test::TempDir dir;
  const std::string dataset = SmallValidateDataset(dir, 30, 24);
  const std::string report = dir / "report.json";
  const test::CommandResult r =
      test::RunShutterlab("validate '" + dataset + "' --report '" + report + "'");
  ExpectOneLineError(r, dataset + "/camera.json", "the camera is 30x24 pixels");
  EXPECT_NE(r.output.find("at least 32x32 pixels"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(report));
}

TEST(ValidateCli, FrameOutsideGyroLog) {
  test::TempDir dir;
  const std::string dataset = SmallValidateDataset(dir);
  WriteFileAtomically(fs::path(dataset) / "frames.csv",
                      "frame,t_first_row,ref,image\n0,8.5,images/0000_ref.png,images/0000_rs.png\n"
                      "1,99.0,images/0001_ref.png,images/0001_rs.png\n");
  const test::CommandResult r = test::RunShutterlab("validate '" + dataset + "'");
  ExpectOneLineError(r, dataset + "/frames.csv:3:", "frame 1");
}

TEST(ValidateCli, BadLimitAndCandidate) {
  test::TempDir dir;
  const std::string dataset = SmallValidateDataset(dir);
  ExpectOneLineError(test::RunShutterlab("validate '" + dataset + "' --limit 5parsecs"), "",
                     "5parsecs");
  ExpectOneLineError(test::RunShutterlab("validate '" + dataset + "' --candidates warp_drive"), "",
                     "warp_drive");
}

}  // namespace
}  // namespace shutterlab
