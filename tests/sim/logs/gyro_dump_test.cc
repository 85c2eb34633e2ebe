#include "sim/logs/gyro_dump.h"

#include "sim/check.h"
#include "sim/logs/flight_log_io.h"
#include "sim/text_file.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

// A dump as the phone app writes it: start-of-frame lines (each twice), and each frame's batch
// starting with the last sample of the batch before.
constexpr const char* kDump =
    "SOF  1000000246,  frameNum :1 exp time 0.005248\n"
    "SOF  1000000246,  frameNum :1 exp time 0.005248\n"
    "frameid:1 gyro:0 x 0.003973 y 0.038338 z 0.014778 ts 1000000741\n"
    "frameid:1 gyro:1 x 0.006416 y -0.042003 z 0.018444 ts 1000003167\n"
    "SOF  1000033559,  frameNum :2 exp time 0.005248\r\n"
    "frameid:2 gyro:0 x 0.006416 y -0.042003 z 0.018444 ts 1000003167\r\n"
    "frameid:2 gyro:1 x 1e-3 y 2 z -3.5 ts 1000005593.5\n"
    "\n"
    "frameid:3 gyro:0 x 1e-3 y 2 z -3.5 ts 1000005593.5\n"
    "frameid:3 gyro:1 x 0 y 0 z 0 ts 1000005593.5\n";

std::vector<GyroSample> ReadAll(std::string_view text, size_t block_bytes, size_t chunk,
                                std::vector<LogWarning>* warnings = nullptr) {
  auto source = OpenGyroDump(TextBlocks::InMemory(text, block_bytes), "dump.txt", chunk);
  std::vector<GyroSample> all;
  for (GyroChunk c = source->Next(); !c.empty(); c = source->Next())
    all.insert(all.end(), c.data, c.data + c.size);
  if (warnings) *warnings = source->Warnings();
  return all;
}

TEST(GyroDump, ReadsTheGyroLinesLeavesOutRepeatsAndSaysSo) {
  for (size_t block : {size_t{1}, size_t{40}, size_t{4096}}) {
    for (size_t chunk : {size_t{1}, size_t{2}, size_t{100}}) {
      std::vector<LogWarning> warnings;
      const std::vector<GyroSample> s = ReadAll(kDump, block, chunk, &warnings);
      ASSERT_EQ(s.size(), 4u) << block << " " << chunk;
      EXPECT_EQ(s[0].t_ns, 1000000741000);  // microseconds, exactly
      EXPECT_EQ(s[1].t_ns, 1000003167000);
      EXPECT_EQ(s[2].t_ns, 1000005593500);
      EXPECT_EQ(s[3].t_ns, 1000005593500);  // the same time with other rates is a sample
      EXPECT_EQ(s[0].omega_rad_s, Eigen::Vector3d(0.003973, 0.038338, 0.014778));
      EXPECT_EQ(s[2].omega_rad_s, Eigen::Vector3d(1e-3, 2, -3.5));
      ASSERT_EQ(warnings.size(), 1u);
      EXPECT_EQ(warnings[0].kind, "repeated_sample");
      EXPECT_EQ(warnings[0].count, 2u);
      EXPECT_NE(warnings[0].message.find("first at line 6"), std::string::npos)
          << warnings[0].message;
    }
  }
}

TEST(GyroDump, IsDetectedByItsFirstLine) {
  EXPECT_TRUE(LooksLikeGyroDump(kDump));
  EXPECT_TRUE(LooksLikeGyroDump("\n  frameid:7 gyro:0 x 0 y 0 z 0 ts 5\n"));
  EXPECT_FALSE(LooksLikeGyroDump("t,gx,gy,gz\n0,1,2,3\n"));
  EXPECT_FALSE(LooksLikeGyroDump("SOFA,1,2,3\n"));
  EXPECT_FALSE(LooksLikeGyroDump(""));
  // With a byte-order mark, as some editors save it: the same dump.
  const std::string with_bom = std::string("\xEF\xBB\xBF") + kDump;
  EXPECT_TRUE(LooksLikeGyroDump(with_bom));
  EXPECT_EQ(ReadAll(with_bom, 4096, 16).size(), 4u);
  test::TempDir dir;
  WriteFileAtomically(dir / "gyro_dump.txt", kDump);
  const FlightLog log = ReadFlightLog(dir / "gyro_dump.txt");
  EXPECT_EQ(log.format, "gyro_dump");
  EXPECT_EQ(log.gyro.size(), 4u);
  EXPECT_TRUE(test::AnyWarningContains(log.warnings, "repeated_sample: 2 sample(s)"))
      << test::JoinedWarnings(log.warnings);
}

TEST(GyroDump, BadLinesAreOneLineErrorsNamingTheLineAndACutLastLineIsSaid) {
  struct Case {
    std::string text;
    long line;
    std::string problem;
  };
  const std::string good = "frameid:1 gyro:0 x 1 y 2 z 3 ts 100\n";
  const Case cases[] = {
      {good + "frameid:1 gyro:1 x 1 y 2 z 3\n", 2, "expected 'frameid:N gyro:K x X y Y z Z ts"},
      {good + "frameid:1 gyro:1 x 1 y two z 3 ts 200\n", 2, "y is not a number: 'two'"},
      {good + "frameid:1 gyro:1 x 1 y 2 z 3 ts -\n", 2, "ts is not a finite time"},
      {good + "frameid:1 gyro:1 x 1 y 2 z 3 ts 99\n", 2, "timestamp decreases"},
      {good + "gyro:1 frameid:1 x 1 y 2 z 3 ts 200\n", 2, "expected 'frameid:N"},
      {good + "SOFTWARE 2.1\n", 2, "expected 'frameid:N"},  // only the word SOF starts a frame
      {"SOF  1,  frameNum :1 exp time 0.005\n", 0, "no gyro lines"},
  };
  for (const Case& c : cases) {
    try {
      ReadAll(c.text, 4096, 16);
      ADD_FAILURE() << c.text;
    } catch (const IoError& e) {
      const std::string what = e.what();
      const std::string where = c.line > 0 ? ":" + std::to_string(c.line) + ":" : ":";  // 0: file
      EXPECT_NE(what.find("dump.txt" + where), std::string::npos) << what;
      EXPECT_NE(what.find(c.problem), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  }
  // Cut anywhere inside its last gyro line before the time's digits (a cut time that still
  // reads, in order, cannot be told from a whole one): the lines before are read, and the cut is
  // said.
  const std::string two = good + "frameid:1 gyro:1 x -0.25 y 2 z 3 ts 1000\n";
  for (size_t cut = good.size() + 1; cut <= two.rfind("ts ") + 3; ++cut) {
    std::vector<LogWarning> warnings;
    const std::vector<GyroSample> s = ReadAll(two.substr(0, cut), 4096, 16, &warnings);
    ASSERT_EQ(s.size(), 1u) << cut;
    ASSERT_EQ(warnings.size(), 1u) << cut;
    EXPECT_EQ(warnings[0].kind, "truncated") << cut;
  }
}

// The phone clip's dump holds the samples of its gyro.txt (made from it), each repeat once.
TEST(GyroDump, TheRealDumpHoldsItsGyroTxtsSamples) {
  SHUTTERLAB_REAL_DATA(clip, "rs/phone_gyro_video_20200109_145447");
  const FlightLog dump = ReadFlightLog(clip + "/gyro_dump.txt");
  FlightLogReadOptions columns;
  columns.format = LogFormat::kColumns;
  columns.columns.columns = {"4", "1", "2", "3"};
  const FlightLog txt = ReadFlightLog(clip + "/gyro.txt", columns);
  EXPECT_EQ(dump.format, "gyro_dump");
  ASSERT_EQ(dump.gyro.size(), 29'466u);
  ASSERT_EQ(dump.gyro.size(), txt.gyro.size());
  for (size_t i = 0; i < dump.gyro.size(); ++i) {
    // gyro.txt holds the times as seconds in a double: within a microsecond.
    ASSERT_LE(std::llabs(dump.gyro[i].t_ns - txt.gyro[i].t_ns), 1000) << i;
    ASSERT_EQ(dump.gyro[i].omega_rad_s, txt.gyro[i].omega_rad_s) << i;
  }
  EXPECT_TRUE(test::AnyWarningContains(dump.warnings, "repeated_sample: 1280 sample(s)"))
      << test::JoinedWarnings(dump.warnings);
  // Cut inside a line, it is read up to the cut and says so.
  const std::string bytes = ReadFileToString(clip + "/gyro_dump.txt");
  test::TempDir dir;
  for (const double fraction : {0.3, 0.7}) {
    size_t size = static_cast<size_t>(fraction * bytes.size());
    while (bytes[size - 1] == '\n') ++size;
    WriteFileAtomically(dir / "cut.txt", bytes.substr(0, size));
    const FlightLog cut = ReadFlightLog(dir / "cut.txt");
    EXPECT_LT(cut.gyro.size(), dump.gyro.size());
    EXPECT_TRUE(test::AnyWarningContains(cut.warnings, "truncated: "))
        << test::JoinedWarnings(cut.warnings);
  }
}

}  // namespace
}  // namespace shutterlab
