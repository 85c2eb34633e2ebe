#include "render/frames_csv.h"

#include "render/image_io.h"
#include "render/render_dataset.h"
#include "render/truth_model.h"
#include "sim/check.h"
#include "sim/logs/gyro_io.h"
#include "sim/text_file.h"
#include "tests/render/render_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace shutterlab {
namespace {

namespace fs = std::filesystem;

TEST(FramesCsv, RoundTripsExactly) {
  test::TempDir dir;
  const std::vector<FrameEntry> frames = {
      {0, 1'234'567'891, "images/0000_ref.png", "images/0000_rs.png"},
      {7, 99'000'000'001, "", "video/0007.png"}};
  WriteFramesCsv(dir / "frames.csv", frames);
  const std::vector<FrameEntry> back = ReadFramesCsv(dir / "frames.csv");
  ASSERT_EQ(back.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(back[i].frame, frames[i].frame);
    EXPECT_EQ(back[i].t_first_row_ns, frames[i].t_first_row_ns);
    EXPECT_EQ(back[i].ref, frames[i].ref);
    EXPECT_EQ(back[i].image, frames[i].image);
  }
}

TEST(FramesCsv, RejectsAWrongHeader) {
  test::TempDir dir;
  WriteFileAtomically(dir / "times.csv", "t,frame\n0.5,0\n");
  try {
    ReadFrameTimes(dir / "times.csv");
    ADD_FAILURE() << "accepted a wrong header";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("times.csv:1"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace shutterlab
