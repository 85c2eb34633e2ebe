// `shutterlab measure` end to end: outputs exist and parse, --truth prints the error, bad input
// gives one line and exit code 2 with nothing written.

#include "estimate/loop/measure.h"
#include "io/image_io.h"
#include "model/truth_model.h"
#include "render/rs_warp.h"
#include "tests/app/cli_test_util.h"
#include "tests/render/render_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace shutterlab {
namespace {

// The accuracy measure must reach on rendered pairs: RMS of |field - truth|, px.
constexpr double kMaxRmsPx = 0.08;

struct PairFiles {
  std::string ref, rs, truth, camera;
  double d_px = 0.0;
  RigModel rig;
};

// A 480x360 pair rendered from a real scene (halved) under a constant rate; files in dir.
PairFiles WritePair(const test::TempDir& dir) {
  cv::Mat scene = ReadImage(test::GroundScenePath(2));
  cv::resize(scene, scene, {}, 0.5, 0.5, cv::INTER_AREA);
  TrueModel truth;
  truth.rig = test::NadirRig(480, 360, 550.0);  // 30 ms, 50 m
  const CameraMotion motion(test::ConstantRateTrace({0.3, -0.2, 0.4}), truth);
  const FrameMotion fm = motion.Frame(SecondsToNs(0.5));
  const FrameGeometry geometry(truth.rig.camera, truth.rig.altitude_m, fm, scene.size());
  const FrameGeometry reference(truth.rig.camera, truth.rig.altitude_m, fm.Reference(),
                                scene.size());
  cv::Mat rs, ref;
  RenderFrame(scene, geometry, Interpolation::kBilinear, &rs);
  RenderFrame(scene, reference, Interpolation::kBilinear, &ref);
  const cv::Mat field = DisplacementField(geometry);
  PairFiles files{dir / "ref.png",     dir / "rs.png",           dir / "disp.exr",
                  dir / "camera.json", FrameDistortionPx(field), truth.rig};
  WriteImage(files.ref, ref);
  WriteImage(files.rs, rs);
  WriteImage(files.truth, field, {"dx", "dy"});
  WriteRigModel(files.camera, truth.rig);
  return files;
}

std::string Quote(const std::string& path) { return "'" + path + "'"; }

TEST(MeasureCli, JsonOutputsAndTruthError) {
  test::TempDir dir;
  const PairFiles files = WritePair(dir);
  const std::string out = dir / "out";
  const test::CommandResult r = test::RunShutterlab(
      "measure " + Quote(files.ref) + " " + Quote(files.rs) + " --camera " + Quote(files.camera) +
      " --truth " + Quote(files.truth) + " --out " + Quote(out) + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.at("format"), "measure/1");
  EXPECT_EQ(j.at("width"), 480);
  EXPECT_EQ(j.at("height"), 360);
  const double d_px = j.at("D_px");
  EXPECT_NEAR(d_px, files.d_px, 0.05 * files.d_px);
  EXPECT_NEAR(j.at("D_m").get<double>(), d_px * 50.0 / 550.0, 1e-9);
  EXPECT_GT(j.at("noise_px").get<double>(), 0.0);
  EXPECT_GT(j.at("measured_fraction").get<double>(), 0.8);
  EXPECT_GT(j.at("points").get<int>(), 300);
  EXPECT_LT(j.at("truth").at("rms_px").get<double>(), kMaxRmsPx);
  EXPECT_GT(j.at("truth").at("pixels").get<int>(), 480 * 360 * 8 / 10);

  // rows.csv: the header and one line per row, each with 10 fields.
  std::ifstream rows(out + "/rows.csv");
  std::string line;
  ASSERT_TRUE(std::getline(rows, line));
  EXPECT_EQ(line.rfind("row,measured_columns,mean_dx,mean_dy,", 0), 0u) << line;
  int count = 0;
  while (std::getline(rows, line)) {
    std::stringstream fields(line);
    std::string field;
    int n = 0;
    while (std::getline(fields, field, ',')) ++n;
    EXPECT_GE(n, 2) << line;
    if (count == 180) {  // a middle row is measured: numbers in every field
      EXPECT_EQ(n, 10) << line;
      EXPECT_EQ(line.rfind("180,", 0), 0u) << line;
    }
    ++count;
  }
  EXPECT_EQ(count, 360);
  std::vector<std::string> names;
  const cv::Mat field = ReadFloatImage(out + "/field.exr", &names);
  EXPECT_EQ(field.size(), cv::Size(480, 360));
  EXPECT_EQ(names, (std::vector<std::string>{"dx", "dy"}));
  const cv::Mat truth = ReadFloatImage(files.truth);
  EXPECT_LT(CompareFields(field, truth).rms_px, kMaxRmsPx);
  EXPECT_EQ(ReadImage(out + "/heatmap.png").channels(), 3);
  EXPECT_EQ(ReadImage(out + "/confidence.png").size(), cv::Size(480, 360));
}

TEST(MeasureCli, TablePrintsDInMetresAndTheTruthError) {
  test::TempDir dir;
  const PairFiles files = WritePair(dir);
  const test::CommandResult r =
      test::RunShutterlab("measure " + Quote(files.ref) + " " + Quote(files.rs) + " --camera " +
                          Quote(files.camera) + " --truth " + Quote(files.truth));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("frame distortion D"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("m on the ground"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("against the truth   rms 0.0"), std::string::npos) << r.output;
}

// One line "error: ... PATH ...", exit code 2, no output folder. (CLI11's own checks, such as a
// missing file, add its "Run with --help" hint on a second line.)
void ExpectBadInput(const test::TempDir& dir, const std::string& args, const std::string& path,
                    const std::string& problem, bool cli_check = false) {
  const std::string out = dir / "out";
  const test::CommandResult r = test::RunShutterlab("measure " + args + " --out " + Quote(out));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  ASSERT_FALSE(r.output.empty());
  if (!cli_check) {
    EXPECT_EQ(r.output.find('\n'), r.output.size() - 1) << "one line: " << r.output;
    EXPECT_EQ(r.output.rfind("error: ", 0), 0u) << r.output;
  }
  EXPECT_NE(r.output.find(path), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(problem), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(out)) << "output left behind";
}

TEST(MeasureCli, BadInputOneLineExitTwo) {
  test::TempDir dir;
  const PairFiles files = WritePair(dir);
  // A missing file.
  ExpectBadInput(dir, Quote(files.ref) + " " + Quote(dir / "missing.png"), "missing.png",
                 "not exist", true);
  // An unreadable image.
  const std::string text = dir / "text.png";
  std::ofstream(text) << "not an image\n";
  ExpectBadInput(dir, Quote(files.ref) + " " + Quote(text), text, "");
  // Sizes differ.
  cv::Mat small = ReadImage(files.rs)(cv::Rect(0, 0, 400, 300)).clone();
  const std::string small_path = dir / "small.png";
  WriteImage(small_path, small);
  ExpectBadInput(dir, Quote(files.ref) + " " + Quote(small_path), small_path,
                 "image is 400x300 but the reference");
  // Images too small for the matching windows, of one size.
  const std::string tiny_ref = dir / "tiny_ref.png", tiny = dir / "tiny.png";
  WriteImage(tiny_ref, ReadImage(files.ref)(cv::Rect(0, 0, 24, 40)).clone());
  WriteImage(tiny, ReadImage(files.rs)(cv::Rect(0, 0, 24, 40)).clone());
  ExpectBadInput(dir, Quote(tiny_ref) + " " + Quote(tiny), tiny,
                 "image is 24x40 pixels: a measurement needs at least 32x32 pixels");
  // A camera of another size.
  RigModel rig = files.rig;
  rig.camera.width = 640;
  rig.camera.cx = 319.5;
  const std::string camera = dir / "camera640.json";
  WriteRigModel(camera, rig);
  ExpectBadInput(dir, Quote(files.ref) + " " + Quote(files.rs) + " --camera " + Quote(camera),
                 camera, "camera is 640x360");
  // A truth field that is not a displacement field.
  ExpectBadInput(dir, Quote(files.ref) + " " + Quote(files.rs) + " --truth " + Quote(files.ref),
                 files.ref, "dx, dy");
}

}  // namespace
}  // namespace shutterlab
