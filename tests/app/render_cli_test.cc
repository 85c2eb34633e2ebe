#include "io/frames_csv.h"
#include "io/image_io.h"
#include "model/effect_io.h"
#include "model/effects.h"
#include "model/truth_model.h"
#include "render/render_dataset.h"
#include "sim/check.h"
#include "sim/logs/gyro_io.h"
#include "sim/text_file.h"
#include "tests/app/cli_test_util.h"
#include "tests/render/render_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace shutterlab {
namespace {

namespace fs = std::filesystem;

// Inputs of a small render: declared camera, constant-rate gyro log, two frames, a scene.
struct Inputs {
  test::TempDir dir;
  RigModel declared;
  GyroTrace gyro = test::ConstantRateTrace(Eigen::Vector3d(0.4, -0.6, 0.9), 0.0, 2.0);
  cv::Mat scene = test::SmoothTexture(cv::Size(240, 200), CV_8UC3);
  explicit Inputs(int width = 96, int height = 72) : declared(test::SmallRig(width, height)) {
    WriteRigModel(dir / "camera.json", declared);
    WriteGyroCsv(dir / "gyro.csv", gyro);
    WriteFileAtomically(dir / "times.csv", "frame,t_first_row\n3,0.5\n12,1.25\n");
    WriteImage(dir / "scene.png", scene);
  }
  std::string Args(const std::string& out, const std::string& extra = "",
                   const std::string& frames = "times.csv",
                   const std::string& scene = "scene.png") const {
    return "render --scene " + (dir / scene) + " --camera " + (dir / "camera.json") + " --gyro " +
           (dir / "gyro.csv") + " --frames " + (dir / frames) + " --out " + out + " " + extra;
  }
};

TEST(RenderCommand, WritesACompleteDatasetWithTruth) {
  Inputs in;
  const std::string out = in.dir / "out";
  const test::CommandResult result =
      test::RunShutterlab(in.Args(out, "--inject time_offset=4ms --inject gyro_scale=1.01,1,1"));
  ASSERT_EQ(result.exit_code, 0) << result.output;

  // The declared camera and the logged gyro, unchanged.
  const RigModel written = ReadRigModel(out + "/camera.json");
  EXPECT_EQ(written.time_offset_s, 0.0);
  EXPECT_EQ(written.camera.fx, in.declared.camera.fx);
  const GyroTrace gyro = ReadGyroCsv(out + "/gyro.csv");
  ASSERT_EQ(gyro.size(), in.gyro.size());
  EXPECT_EQ(gyro[17].t_ns, in.gyro[17].t_ns);
  EXPECT_EQ(gyro[17].omega_rad_s, in.gyro[17].omega_rad_s);

  // The truth the test computes itself from the library, with the injected effects.
  TrueModel truth;
  truth.rig = in.declared;
  ApplyInjection("time_offset=4ms", &truth);
  ApplyInjection("gyro_scale=1.01,1,1", &truth);
  const CameraMotion motion(in.gyro, truth);

  const std::vector<FrameEntry> frames = ReadFramesCsv(out + "/frames.csv");
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[1].frame, 12);
  EXPECT_EQ(frames[1].t_first_row_ns, 1'250'000'000);
  const nlohmann::json truth_json = nlohmann::json::parse(ReadFileToString(out + "/truth.json"));
  EXPECT_EQ(truth_json["injected"]["time_offset"], 0.004);
  EXPECT_EQ(truth_json["injected"]["gyro_scale"], nlohmann::json::parse("[1.01, 1.0, 1.0]"));
  for (size_t i = 0; i < frames.size(); ++i) {
    const FrameGeometry geometry(truth.rig.camera, truth.rig.altitude_m,
                                 motion.Frame(frames[i].t_first_row_ns), in.scene.size());
    const FrameGeometry reference(truth.rig.camera, truth.rig.altitude_m,
                                  geometry.motion().Reference(), in.scene.size());
    cv::Mat rs, ref;
    RenderFrame(in.scene, geometry, Interpolation::kBilinear, &rs);
    RenderFrame(in.scene, reference, Interpolation::kBilinear, &ref);
    EXPECT_EQ(cv::norm(ReadImage(out + "/" + frames[i].image), rs, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(ReadImage(out + "/" + frames[i].ref), ref, cv::NORM_INF), 0.0);
    std::vector<std::string> channels;
    char name[16];
    std::snprintf(name, sizeof(name), "%04lld", static_cast<long long>(frames[i].frame));
    const cv::Mat field = ReadFloatImage(out + "/truth/" + name + "_disp.exr", &channels);
    EXPECT_EQ(channels, (std::vector<std::string>{"dx", "dy"}));
    const cv::Mat expected = DisplacementField(geometry);
    EXPECT_EQ(cv::norm(field, expected, cv::NORM_INF), 0.0);
    const double d_px = FrameDistortionPx(expected);
    EXPECT_GT(d_px, 0.5);
    EXPECT_EQ(truth_json["frames"][i]["frame"], frames[i].frame);
    EXPECT_DOUBLE_EQ(truth_json["frames"][i]["D_px"].get<double>(), d_px);
    EXPECT_DOUBLE_EQ(
        truth_json["frames"][i]["D_m"].get<double>(),
        d_px * in.declared.altitude_m / ((in.declared.camera.fx + in.declared.camera.fy) / 2));
    EXPECT_TRUE(fs::exists(out + "/truth/" + name + "_heat.png"));
    EXPECT_TRUE(fs::exists(out + "/truth/" + name + "_side.png"));
  }
  EXPECT_TRUE(fs::exists(out + "/overview.png"));
}

// Frames smaller than a picture's captions and scale bar (a heatmap's bar needs about 40 rows):
// rendered with their pictures, each as big as its frame at least.
TEST(RenderCommand, FramesOfAFewPixelsAreRenderedWithTheirPictures) {
  for (const auto& [width, height] : {std::pair{8, 6}, {64, 2}, {1, 1}}) {
    Inputs in(width, height);
    const std::string out = in.dir / "out";
    const test::CommandResult result = test::RunShutterlab(in.Args(out));
    ASSERT_EQ(result.exit_code, 0) << width << "x" << height << ": " << result.output;
    for (const char* picture : {"/truth/0003_heat.png", "/truth/0003_side.png", "/overview.png"}) {
      const cv::Mat image = ReadImage(out + picture);
      EXPECT_GE(image.cols, width) << picture;
      EXPECT_GE(image.rows, height) << picture;
    }
  }
}

// A gyro log with a pause is rendered as it is, and the command says what it lost, as every
// command that reads a log does.
TEST(RenderCommand, SaysWhatTheGyroLogLost) {
  Inputs in;
  std::vector<GyroSample> samples;
  for (const GyroSample& s : in.gyro.samples()) {
    if (s.t_ns < 800'000'000 || s.t_ns >= 1'000'000'000) samples.push_back(s);  // 0.2 s lost
  }
  WriteGyroCsv(in.dir / "gyro.csv", GyroTrace(samples));
  const test::CommandResult result = test::RunShutterlab(in.Args(in.dir / "out", "--no-pictures"));
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("gyro.csv: gap: 1 interval(s) over 3x the median 1.000 ms"),
            std::string::npos)
      << result.output;
}

TEST(RenderCommand, BadInputExitsTwoAndWritesNothing) {
  Inputs in;
  WriteFileAtomically(in.dir / "late.csv", "frame,t_first_row\n0,0.5\n1,5.0\n");
  WriteFileAtomically(in.dir / "broken.csv", "frame,t_first_row\n0,0.5\n1,soon\n");
  WriteFileAtomically(in.dir / "twice.csv", "frame,t_first_row\n0,0.5\n0,0.6\n");
  const std::string out = in.dir / "out";
  struct Case {
    std::string args, message;
  };
  const std::vector<Case> cases = {
      {in.Args(out, "", "late.csv"), "late.csv"},
      {in.Args(out, "", "broken.csv"), "broken.csv:3"},
      {in.Args(out, "", "twice.csv"), "twice.csv:3"},
      {in.Args(out, "--inject warp=9"), "warp"},
      {in.Args(out, "--inject gyro_scale=1,1"), "gyro_scale"},
      {in.Args(out, "", "times.csv", "gyro.csv"), "gyro.csv"},
      {in.Args(out, "", "times.csv", "missing.png"), "missing.png"},
  };
  for (const Case& c : cases) {
    const test::CommandResult result = test::RunShutterlab(c.args);
    EXPECT_EQ(result.exit_code, 2) << c.args << "\n" << result.output;
    EXPECT_NE(result.output.find(c.message), std::string::npos) << result.output;
    EXPECT_FALSE(fs::exists(out)) << "partial output for " << c.args;
  }
}

}  // namespace
}  // namespace shutterlab
