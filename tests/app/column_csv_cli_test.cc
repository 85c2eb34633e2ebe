// Any CSV read by flags: --columns, --delimiter, --time-unit and --rate-unit reach the column
// reader from every command that takes a log.

#include "sim/logs/gyro_io.h"
#include "sim/text_file.h"
#include "tests/app/cli_test_util.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

using test::RunShutterlab;
using test::TempDir;

// 1 kHz for 7 s: still for 5 s (the default bias segment), then turning about y.
GyroTrace TestTrace() {
  std::vector<GyroSample> samples;
  for (int i = 0; i < 7000; ++i) {
    const double wy = i < 5000 ? 0.0 : 0.1 + 0.05 * std::sin(i * 0.01);
    samples.push_back({static_cast<int64_t>(i) * 1000000, Eigen::Vector3d(0.001, wy, -0.002)});
  }
  return GyroTrace(std::move(samples));
}

// The same samples as a spreadsheet export: `time_ms;wx;wy;wz`, a column the reader skips.
void WriteSpreadsheet(const std::string& path, const GyroTrace& trace) {
  std::string text = "time_ms;note;wx;wy;wz\n";
  for (const GyroSample& s : trace.samples()) {
    text += std::to_string(s.t_ns / 1000000) + ";-;";
    for (int k = 0; k < 3; ++k) {
      AppendDouble(s.omega_rad_s[k], &text);
      text += k < 2 ? ";" : "\n";
    }
  }
  WriteFileAtomically(path, text);
}

TEST(ColumnCsvCli, FlightReadsASpreadsheetByFlagsAsItReadsTheSameGyroCsv) {
  TempDir dir;
  const GyroTrace trace = TestTrace();
  WriteGyroCsv(dir / "gyro.csv", trace);
  WriteSpreadsheet(dir / "export.csv", trace);
  const auto reference = RunShutterlab("flight " + (dir / "gyro.csv") + " --json");
  ASSERT_EQ(reference.exit_code, 0) << reference.output;
  const auto r = RunShutterlab("flight " + (dir / "export.csv") +
                               " --columns time_ms,wx,wy,wz --delimiter semicolon --time-unit ms "
                               "--rate-unit rad/s --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto expected = nlohmann::json::parse(reference.out);
  const auto got = nlohmann::json::parse(r.out);
  EXPECT_EQ(got.at("rows"), expected.at("rows"));
  EXPECT_EQ(got.at("samples"), expected.at("samples"));
  EXPECT_EQ(got.at("samples"), 2000);  // after the 5 s bias segment
}

TEST(ColumnCsvCli, AnalyzeSaysTheColumnsItRead) {
  TempDir dir;
  WriteSpreadsheet(dir / "export.csv", TestTrace());
  const auto r = RunShutterlab("analyze " + (dir / "export.csv") +
                               " --columns 1,3,4,5 --time-unit ms --every 1s --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["source"]["format"], "columns");
  EXPECT_EQ(j["source"]["gyro"], "time_ms,wx,wy,wz");
  EXPECT_EQ(j["source"]["samples"], 7000);
}

TEST(ColumnCsvCli, BadFlagsAndBadColumnsSayWhatIsWrong) {
  TempDir dir;
  WriteSpreadsheet(dir / "export.csv", TestTrace());
  const std::string file = dir / "export.csv";
  auto r = RunShutterlab("noise " + file + " --rate-unit deg/s");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("give --columns TIME,X,Y,Z too"), std::string::npos) << r.err;
  r = RunShutterlab("flight " + file + " --columns time_ms,gx,gy,gz --time-unit ms --json");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find(file + ":1: column 'gx' (x) not in the header: time_ms;note;wx;wy;wz"),
            std::string::npos)
      << r.err;
  r = RunShutterlab("flight " + file + " --columns 1,3,4,5 --format ulog");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("cannot go with --format ulog"), std::string::npos) << r.err;
}

TEST(ColumnCsvCli, FlightReadsThePhoneGyroTxtByFlagsAlone) {
  SHUTTERLAB_REAL_DATA(gyro_txt, "rs/phone_gyro_video_20200109_145447/gyro.txt");
  const auto r =
      RunShutterlab("flight " + gyro_txt +
                    " --columns 4,1,2,3 --time-unit s --rate-unit rad/s --zero-bias --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.at("samples"), 29466);  // every line of gyro.txt (SOURCES.md), no bias segment
  EXPECT_FALSE(j.at("rows").empty());
}

}  // namespace
}  // namespace shutterlab
