// `--lens-profile FILE` through render, validate and analyze: the profile's lens, scaled to the
// images, and its readout (unless the user typed one) replace the declared ones, and every output
// says so. A small fisheye calibrated at twice the images' size.

#include "model/camera.h"
#include "sim/logs/gyro_io.h"
#include "sim/text_file.h"
#include "tests/app/cli_test_util.h"
#include "tests/render/render_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <string>

namespace shutterlab {
namespace {

using nlohmann::json;
using test::RunShutterlab;

// A Gyroflow profile of a 100 degree fisheye at 320x240, 25 ms readout.
constexpr char kProfile[] = R"({
  "name": "Test_Fisheye_320x240", "calibrated_by": "test", "calibrator_version": "1.5.2",
  "calib_dimension": {"w": 320, "h": 240}, "fps": 30.0, "frame_readout_time": 25.0,
  "use_opencv_fisheye": true, "official": false,
  "fisheye_params": {"RMS_error": 0.4,
    "camera_matrix": [[190.0, 0.0, 159.5], [0.0, 190.0, 119.5], [0.0, 0.0, 1.0]],
    "distortion_coeffs": [0.06, 0.04, -0.04, 0.015]}})";

struct LensInputs {
  test::TempDir dir;
  LensInputs() {
    WriteRigModel(dir / "camera.json", test::NadirRig(160, 120, 120.0, 0.030, 50.0));
    WriteGyroCsv(dir / "gyro.csv",
                 test::ConstantRateTrace(Eigen::Vector3d(0.4, -0.6, 0.9), 0.0, 8.0));
    WriteFileAtomically(dir / "times.csv", "frame,t_first_row\n0,0.5\n1,1.5\n");
    WriteImage(dir / "scene.png", test::SmoothTexture(cv::Size(900, 700), CV_8UC3));
    WriteFileAtomically(dir / "profile.json", kProfile);
  }
  std::string Render(const std::string& out, const std::string& extra) const {
    return "render --scene " + (dir / "scene.png") + " --camera " + (dir / "camera.json") +
           " --gyro " + (dir / "gyro.csv") + " --frames " + (dir / "times.csv") + " --out " + out +
           " --no-pictures --lens-profile " + (dir / "profile.json") + " " + extra;
  }
};

TEST(LensProfileCli, RenderTakesTheProfilesLensAndReadoutAndInjectsInItsModel) {
  LensInputs in;
  const std::string out = in.dir / "ds";
  const auto r = RunShutterlab(in.Render(out, "--inject lens_distortion=0.09,0.02"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.out.find("lens profile Test_Fisheye_320x240 (fisheye, calibrated at 320x240"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("readout 25.000 ms top_to_bottom from the profile replaces 30.000 ms"),
            std::string::npos)
      << r.out;
  // The written (declared) camera is the profile's at half size.
  const RigModel rig = ReadRigModel(out + "/camera.json");
  EXPECT_DOUBLE_EQ(rig.camera.fx, 95.0);
  EXPECT_DOUBLE_EQ(rig.camera.cx, 79.5);
  EXPECT_DOUBLE_EQ(rig.shutter.readout_s, 0.025);
  EXPECT_TRUE(rig.camera.distortion == LensDistortion(Fisheye({0.06, 0.04, -0.04, 0.015})));
  // The injected lens is a fisheye too: a list is read in the declared model.
  const json truth = json::parse(ReadFileToString(out + "/truth.json"));
  EXPECT_EQ(truth["injected"]["lens_distortion"],
            json::parse(R"({"model": "fisheye", "k1": 0.09, "k2": 0.02, "k3": 0.0, "k4": 0.0})"));
  // A Brown-Conrady value for the fisheye is refused, one line, exit 2.
  const auto bad =
      RunShutterlab(in.Render(in.dir / "bad", "--inject 'lens_distortion={\"k1\":0.1}'"));
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.err.find("a brown lens for a camera declared fisheye"), std::string::npos)
      << bad.err;
}

TEST(LensProfileCli, ValidateAndAnalyzeSayWhatTheProfileGave) {
  LensInputs in;
  const std::string out = in.dir / "ds";
  ASSERT_EQ(RunShutterlab(in.Render(out, "")).exit_code, 0);
  // validate: the dataset's camera.json back to a pinhole; the profile puts its lens back.
  WriteRigModel(out + "/camera.json", test::NadirRig(160, 120, 120.0, 0.030, 50.0));
  const auto v = RunShutterlab("validate " + out + " --report " + (in.dir / "report.json") +
                               " --lens-profile " + (in.dir / "profile.json"));
  ASSERT_EQ(v.exit_code, 0) << v.output;
  EXPECT_NE(v.out.find("readout 25.00 ms"), std::string::npos) << v.out;
  EXPECT_NE(v.out.find("  lens profile Test_Fisheye_320x240"), std::string::npos) << v.out;
  const json report = json::parse(ReadFileToString(in.dir / "report.json"));
  EXPECT_EQ(report["lens_profile"]["model"], "fisheye");
  EXPECT_EQ(report["lens_profile"]["readout_s"], 0.025);
  EXPECT_EQ(report["lens_profile"]["scale"], json::parse("[0.5, 0.5]"));

  // analyze: the profile's readout unless --readout is typed.
  const std::string analyze = "analyze " + (in.dir / "gyro.csv") +
                              " --every 0.5s --size 160x120 --json --lens-profile " +
                              (in.dir / "profile.json");
  const auto a = RunShutterlab(analyze);
  ASSERT_EQ(a.exit_code, 0) << a.output;
  EXPECT_NE(a.err.find("note: lens profile Test_Fisheye_320x240"), std::string::npos) << a.err;
  const json with_profile = json::parse(a.out);
  EXPECT_EQ(with_profile["lens_profile"]["readout_s"], 0.025);
  EXPECT_DOUBLE_EQ(with_profile["flight"]["rows"][0]["window_s"].get<double>(), 0.025);
  const auto typed = RunShutterlab(analyze + " --readout 10ms");
  ASSERT_EQ(typed.exit_code, 0) << typed.output;
  const json kept = json::parse(typed.out);
  EXPECT_EQ(kept["lens_profile"]["readout_s"], nullptr);
  EXPECT_DOUBLE_EQ(kept["flight"]["rows"][0]["window_s"].get<double>(), 0.010);
}

TEST(LensProfileCli, ABadProfileIsOneLineExitTwo) {
  LensInputs in;
  WriteFileAtomically(in.dir / "profile.json",
                      std::string(kProfile).replace(std::string(kProfile).find("\"use_opencv"), 0,
                                                    "\"distortion_model\": \"poly3\", "));
  const auto r = RunShutterlab(in.Render(in.dir / "ds", ""));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.err.find("profile.json: distortion_model 'poly3' is not one shutterlab models"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(std::filesystem::exists(in.dir / "ds"));
}

}  // namespace
}  // namespace shutterlab
