#include "io/frames_csv.h"
#include "io/image_io.h"
#include "render/render_dataset.h"
#include "sim/logs/gyro_io.h"
#include "sim/text_file.h"
#include "tests/app/cli_test_util.h"
#include "tests/render/render_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <string>

namespace shutterlab {
namespace {

namespace fs = std::filesystem;

// A small rendered dataset: two frames of 96x72 with a 4 ms clock offset camera.json lacks.
std::string SmallDataset(const test::TempDir& dir) {
  WriteRigModel(dir / "camera.json", test::SmallRig(96, 72));
  WriteGyroCsv(dir / "gyro.csv", test::ConstantRateTrace(Eigen::Vector3d(0.4, -0.6, 0.9)));
  WriteFileAtomically(dir / "times.csv", "frame,t_first_row\n3,0.5\n12,1.25\n");
  WriteImage(dir / "scene.png", test::SmoothTexture(cv::Size(240, 200), CV_8UC3));
  RenderOptions render;
  render.scene_path = dir / "scene.png";
  render.camera_path = dir / "camera.json";
  render.gyro_path = dir / "gyro.csv";
  render.frames_path = dir / "times.csv";
  render.out_dir = dir / "ds";
  render.pictures = false;
  RenderDataset(render);
  return dir / "ds";
}

TEST(CorrectCommand, WritesADatasetAndItsRecord) {
  test::TempDir dir;
  const std::string dataset = SmallDataset(dir), out = dir / "out";
  const test::CommandResult result =
      test::RunShutterlab("correct " + dataset + " --out " + out + " --truth --reference row0");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.out.find("D before px"), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("corrected 2 frame(s)"), std::string::npos) << result.out;
  const nlohmann::json record =
      nlohmann::json::parse(ReadFileToString((fs::path(out) / "correct.json").string()));
  EXPECT_EQ(record["format"], "correction/1");
  EXPECT_EQ(record["reference"], "row0");
  ASSERT_EQ(record["frames"].size(), 2u);
  EXPECT_EQ(record["frames"][1]["frame"], 12);
  EXPECT_TRUE(record["frames"][1].contains("truth"));
  for (const char* file : {"camera.json", "gyro.csv", "frames.csv", "images/0003_rs.png",
                           "images/0003_ref.png", "masks/images/0003_rs.png.png",
                           "colmap/image_list.txt", "odm/images/0012_rs.png", "overview.png"}) {
    EXPECT_TRUE(fs::is_regular_file(fs::path(out) / file)) << file;
  }
  // --json prints the same record; a second run keeps what is there.
  const test::CommandResult again =
      test::RunShutterlab("correct " + dataset + " --out " + out + " --json");
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_EQ(nlohmann::json::parse(again.out)["frames"][0]["kept"], true);
}

TEST(CorrectCommand, PhotosWithTheirLogAndTriggers) {
  // The dataset's two frames as JPEG photos, its gyro.csv as the flight log, a trigger file naming
  // them: the photos are corrected under their names, the table says so.
  test::TempDir dir;
  const std::string dataset = SmallDataset(dir), out = dir / "out";
  fs::create_directories(dir / "photos");
  WriteImage(dir / "photos/A.jpg", ReadImage(dataset + "/images/0003_rs.png"));
  WriteImage(dir / "photos/B.jpg", ReadImage(dataset + "/images/0012_rs.png"));
  WriteFileAtomically(dir / "triggers.csv", "image,t\nA.jpg,0.5\nB.jpg,1.25\n");
  const std::string photos = "correct --photos " + (dir / "photos") + " " + dataset +
                             "/gyro.csv --camera " + dataset + "/camera.json --triggers " +
                             (dir / "triggers.csv");
  const test::CommandResult result = test::RunShutterlab(photos + " --out " + out);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.out.find("corrected 2 photo(s)"), std::string::npos) << result.out;
  EXPECT_NE(result.err.find("photos placed on gyro.csv: "), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("note: the corrected photos show the instant of their middle row"),
            std::string::npos)
      << result.err;
  const auto reference_of = [](const std::string& folder) {
    return nlohmann::json::parse(ReadFileToString(folder + "/correct.json"))["reference"];
  };
  EXPECT_EQ(reference_of(out), "mid");
  // Told otherwise, the first row, and nothing said.
  const test::CommandResult row0 =
      test::RunShutterlab(photos + " --reference row0 --out " + (dir / "row0"));
  ASSERT_EQ(row0.exit_code, 0) << row0.output;
  EXPECT_EQ(reference_of(dir / "row0"), "row0");
  EXPECT_EQ(row0.err.find("middle row"), std::string::npos) << row0.err;
  for (const char* file :
       {"images/A.jpg", "images/B.jpg", "masks/A.jpg.png", "frames.csv", "correct.json"}) {
    EXPECT_TRUE(fs::is_regular_file(fs::path(out) / file)) << file;
  }
  // Photo flags without --photos, and a trigger file that names no photo: one line, exit 2.
  WriteFileAtomically(dir / "other.csv", "image,t\nC.jpg,0.5\n");
  for (const std::string& args :
       {"correct " + dataset + " --out " + (dir / "o4") + " --latency 5ms",
        "correct --photos " + (dir / "photos") + " " + dataset + "/gyro.csv --camera " + dataset +
            "/camera.json --triggers " + (dir / "other.csv") + " --out " + (dir / "o5")}) {
    const test::CommandResult bad = test::RunShutterlab(args);
    EXPECT_EQ(bad.exit_code, 2) << args << "\n" << bad.output;
    EXPECT_EQ(bad.err.find('\n'), bad.err.size() - 1) << "one line: " << bad.err;
  }
  EXPECT_FALSE(fs::exists(dir / "o4"));
  EXPECT_FALSE(fs::exists(dir / "o5"));
}

TEST(CorrectCommand, RealPhotosWithTheirOwnCameraAndTriggerFile) {
  // Two real SIYI ZR10 photos (2560x1440, EXIF focal length) and the flight's own image list
  // (PX4 boot time per image) as the trigger file, over a synthetic log that pans at a constant
  // 0.01 rad/s about the camera's y axis: the photos' own camera is read, each photo is placed by
  // name, and D before is the pan's shear during the readout, f w T.
  SHUTTERLAB_REAL_DATA(siyi, "images/siyi_zr10");
  test::TempDir dir;
  fs::create_directories(dir / "photos");
  for (const char* name : {"IMG_0050.jpg", "IMG_0100.jpg"}) {
    fs::copy_file(fs::path(siyi) / name, dir.path() / "photos" / name);
  }
  WriteGyroCsv(dir / "log.csv",
               test::ConstantRateTrace(Eigen::Vector3d(0, 0.01, 0), 320.0, 170.0, 200.0));
  const std::string out = dir / "out";
  const test::CommandResult result = test::RunShutterlab(
      "correct --photos " + (dir / "photos") + " " + (dir / "log.csv") + " --triggers " + siyi +
      "/image_metadata.csv --readout 20ms --effect gyro_bias=0,0,0 --json --out " + out);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.err.find("the photos' SIYIKEJI ZR10 (2 of 2 photos), 2560x1440"),
            std::string::npos)
      << result.err;
  EXPECT_NE(result.err.find("2 paired with trigger file (csv, log clock) by name"),
            std::string::npos)
      << result.err;
  const nlohmann::json record = nlohmann::json::parse(result.out);
  EXPECT_EQ(record["kind"], "photos");
  ASSERT_EQ(record["frames"].size(), 2u);
  const double fx = record["model"]["camera"]["intrinsics"]["fx"].get<double>();
  EXPECT_EQ(record["model"]["camera"]["rolling_shutter"]["readout_s"], 0.020) << "--readout";
  const double shear_px = fx * 0.01 * 0.020;
  for (const auto& frame : record["frames"]) {
    EXPECT_GT(frame["D_before_px"].get<double>(), 0.95 * shear_px) << frame["image"];
    EXPECT_LT(frame["D_before_px"].get<double>(), 1.10 * shear_px) << frame["image"];
    const std::string image = (fs::path(out) / frame["image"].get<std::string>()).string();
    const auto metadata = ReadImageMetadata(image);
    const auto has = [&](const std::string& key, const std::string& value) {
      return std::find(metadata.begin(), metadata.end(), std::make_pair(key, value)) !=
             metadata.end();
    };
    EXPECT_TRUE(has("Exif.Image.Model", "ZR10")) << image << ": the photo's EXIF is carried";
    // Photos show their middle row's instant unless told: a photogrammetry tool's one pose.
    EXPECT_TRUE(has("Xmp.shutterlab.Reference", "mid")) << image;
  }
  EXPECT_NEAR(record["frames"][0]["t_first_row_s"].get<double>(), 329.091247, 1e-9);
}

TEST(CorrectCommand, BadInputIsOneLineAndExitCodeTwo) {
  test::TempDir dir;
  const std::string dataset = SmallDataset(dir);
  WriteFileAtomically(dir / "bad.json", R"({"format": "measure/1"})");
  for (const std::string& args :
       {"correct " + dataset + " --out " + dataset,
        "correct " + dataset + " --out " + (dir / "o1") + " --report " + (dir / "bad.json"),
        "correct " + dataset + " --out " + (dir / "o2") + " --reference middle"}) {
    const test::CommandResult result = test::RunShutterlab(args);
    EXPECT_EQ(result.exit_code, 2) << args << "\n" << result.output;
    EXPECT_EQ(result.err.find('\n'), result.err.size() - 1) << "one line: " << result.err;
    EXPECT_EQ(result.err.rfind("error: ", 0), 0u) << result.err;
  }
  EXPECT_FALSE(fs::exists(dir / "o1")) << "nothing written for bad input";
  EXPECT_FALSE(fs::exists(dir / "o2"));
  // CLI11's own check of the folder (its "Run with --help" hint on a second line).
  const test::CommandResult missing =
      test::RunShutterlab("correct " + (dir / "no_such_folder") + " --out " + (dir / "o3"));
  EXPECT_EQ(missing.exit_code, 2) << missing.output;
  EXPECT_NE(missing.err.find("no_such_folder"), std::string::npos) << missing.err;
}

}  // namespace
}  // namespace shutterlab
