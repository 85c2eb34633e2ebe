#include "render/frames_csv.h"
#include "render/image_io.h"
#include "render/render_dataset.h"
#include "sim/logs/gyro_io.h"
#include "sim/text_file.h"
#include "tests/app/cli_test_util.h"
#include "tests/render/render_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

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
  for (const char* file : {"A.jpg", "B.jpg", "masks/A.jpg.png", "frames.csv", "correct.json"}) {
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
