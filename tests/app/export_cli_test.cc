// `shutterlab export`: a camera.json into COLMAP's files, what it says, and the one-line refusals.

#include "model/camera.h"
#include "sim/text_file.h"
#include "tests/app/cli_test_util.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>

namespace shutterlab {
namespace {

RigModel ExportCliRig() {
  RigModel rig;
  rig.camera.width = 640, rig.camera.height = 480;
  rig.camera.fx = rig.camera.fy = 550.0;
  rig.camera.cx = 319.5, rig.camera.cy = 239.5;
  rig.shutter.readout_s = 0.02;
  return rig;
}

TEST(ExportCli, WritesColmapsFilesAndSaysWhatItWrote) {
  test::TempDir dir;
  WriteRigModel(dir / "camera.json", ExportCliRig());
  const auto r = test::RunShutterlab("export " + (dir / "camera.json") + " --to colmap --out " +
                                     (dir / "out") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json json = nlohmann::json::parse(r.out);
  EXPECT_EQ(json["to"], "colmap");
  EXPECT_EQ(json["files"].size(), 5u);  // cameras, images, points3D, colmap_args, side note
  EXPECT_NE(ReadFileToString(dir / "out/cameras.txt").find("\n1 OPENCV 640 480 550 550 320 240 "),
            std::string::npos);
  EXPECT_TRUE(std::filesystem::exists(dir / "out/shutterlab_export.txt"));
}

TEST(ExportCli, RefusesInOneLine) {
  test::TempDir dir;
  WriteRigModel(dir / "camera.json", ExportCliRig());
  for (const std::string& args : {"--to pix4dmapper --out " + (dir / "a"),         // no such format
                                  "--to kalibr --out " + (dir / "b") + " --x"}) {  // no such option
    const auto r = test::RunShutterlab("export " + (dir / "camera.json") + " " + args);
    EXPECT_EQ(r.exit_code, 2) << args << ": " << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "a")) << args;
  }
  const auto unknown = test::RunShutterlab("export " + (dir / "camera.json") +
                                           " --to pix4dmapper --out " + (dir / "a"));
  EXPECT_EQ(test::LineCount(unknown.err), 1u) << unknown.err;
  EXPECT_NE(unknown.err.find("colmap, odm, kalibr, gyroflow, metashape"), std::string::npos);
}

}  // namespace
}  // namespace shutterlab
