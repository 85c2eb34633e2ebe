#include "io/rig_dataset.h"

#include "sim/check.h"
#include "sim/logs/gyro_io.h"
#include "sim/text_file.h"
#include "tests/model/model_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

// A dataset folder with camera.json, a 1 kHz gyro.csv (with a 0.2 s pause when asked) and
// frames.csv naming empty image files (ReadRigDataset checks they exist, not what they hold).
void WriteDataset(const test::TempDir& dir, bool video, bool gyro_pause) {
  WriteRigModel(dir / "camera.json", test::MappingRig());
  std::vector<GyroSample> samples;
  for (int k = 0; k < 2000; ++k) {
    const int64_t t_ns = k * int64_t{1'000'000} + (gyro_pause && k >= 1000 ? 200'000'000 : 0);
    samples.push_back({t_ns, Eigen::Vector3d(0.01, 0, 0)});
  }
  WriteGyroCsv(dir / "gyro.csv", GyroTrace(samples));
  std::filesystem::create_directories(dir / "images");
  std::vector<FrameEntry> frames;
  for (int64_t f = 0; f < 3; ++f) {
    FrameEntry e{f, 100'000'000 + f * 400'000'000, video ? "" : "images/ref.png",
                 "images/" + FrameName(f) + ".png"};
    WriteFileAtomically(dir / e.image, "");
    frames.push_back(e);
  }
  WriteFileAtomically(dir / "images/ref.png", "");
  WriteFramesCsv(dir / "frames.csv", frames);
}

TEST(ReadRigDataset, StillAndVideoAlike) {
  for (const bool video : {false, true}) {
    test::TempDir dir;
    WriteDataset(dir, video, /*gyro_pause=*/false);
    const RigDataset d = ReadRigDataset(dir.path().string());
    EXPECT_EQ(d.video, video);
    EXPECT_EQ(d.gyro.size(), 2000u);
    ASSERT_EQ(d.frames.size(), 3u);
    EXPECT_EQ(d.frames[2].t_first_row_ns, 900'000'000);
    EXPECT_EQ(d.declared.camera.width, test::MappingRig().camera.width);
    EXPECT_TRUE(d.gyro_warnings.empty()) << test::JoinedWarnings(d.gyro_warnings);
  }
}

TEST(ReadRigDataset, AuditsTheGyroLikeAnyLog) {
  test::TempDir dir;
  WriteDataset(dir, false, /*gyro_pause=*/true);
  const RigDataset d = ReadRigDataset(dir.path().string());
  ASSERT_EQ(d.gyro_warnings.size(), 1u);
  EXPECT_EQ(d.gyro_warnings[0].kind, "gap");
  EXPECT_DOUBLE_EQ(*d.gyro_warnings[0].t_s, 0.999);
}

// Every refusal names the file (and frames.csv's line) and the problem.
TEST(ReadRigDataset, RefusesWhatIsMissingOrMixed) {
  auto expect_error = [](const std::string& dir, const std::string& text) {
    try {
      ReadRigDataset(dir);
      ADD_FAILURE() << "no error for " << text;
    } catch (const IoError& e) {
      EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
    }
  };
  test::TempDir dir;
  expect_error(dir / "nowhere", "nowhere: not a dataset folder");
  WriteDataset(dir, false, false);
  std::filesystem::remove(dir / "images/0001.png");
  expect_error(dir.path().string(), "frames.csv:3: image 'images/0001.png' not found");
  WriteFileAtomically(dir / "frames.csv",
                      "frame,t_first_row,ref,image\n0,0.1,images/ref.png,images/0000.png\n"
                      "2,0.9,,images/0002.png\n");
  expect_error(dir.path().string(), "frames.csv:3: no ref image");
  WriteFileAtomically(dir / "frames.csv", "frame,t_first_row,ref,image\n");
  expect_error(dir.path().string(), "frames.csv: no frames");
  std::filesystem::remove(dir / "gyro.csv");
  expect_error(dir.path().string(), "gyro.csv: missing");
}

}  // namespace
}  // namespace shutterlab
