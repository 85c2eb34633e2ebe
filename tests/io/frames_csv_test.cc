#include "io/frames_csv.h"

#include "sim/check.h"
#include "sim/text_file.h"
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

// The capture-times file render reads: frames 0..n-1, exact to the nanosecond.
TEST(FramesCsv, FrameTimesRoundTripExactly) {
  test::TempDir dir;
  const std::vector<int64_t> times_ns = {0, 2'000'000'001, 86'400'123'456'789};
  WriteFrameTimes(dir / "times.csv", times_ns);
  const std::vector<FrameEntry> read = ReadFrameTimes(dir / "times.csv");
  ASSERT_EQ(read.size(), times_ns.size());
  for (size_t i = 0; i < read.size(); ++i) {
    EXPECT_EQ(read[i].frame, static_cast<int64_t>(i));
    EXPECT_EQ(read[i].t_first_row_ns, times_ns[i]);
  }
  EXPECT_EQ(ReadFileToString(dir / "times.csv").substr(0, 20), "frame,t_first_row\n0,");
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
