#include "sim/logs/gyro_io.h"
#include "sim/text_file.h"
#include "tests/app/cli_test_util.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

using test::RunShutterlab;
using test::TempDir;

// 1 kHz; 5 s still (the default bias segment), then 2 s at a constant y rate that turns 300" in the
// 9 ms a 10 ms window spans: over the 5 cm threshold (226"), under the 10 cm one (433").
std::string WriteTrace(const TempDir& dir) {
  const double rate = 300.0 / (180.0 * 3600.0 / M_PI) / 0.009;
  std::vector<GyroSample> samples;
  for (int i = 0; i < 7000; ++i) {
    samples.push_back(
        {static_cast<int64_t>(i) * 1000000, Eigen::Vector3d(0.0, i < 5000 ? 0.0 : rate, 0.0)});
  }
  const std::string path = dir / "gyro.csv";
  WriteGyroCsv(path, GyroTrace(std::move(samples)));
  return path;
}

// Lines of text (newline-terminated).
size_t CountLines(const std::string& text) { return std::count(text.begin(), text.end(), '\n'); }

TEST(FlightCli, JsonFollowsFormats) {
  TempDir dir;
  const std::string trace = WriteTrace(dir);
  const auto r = RunShutterlab("flight " + trace +
                               " --altitude 50 --limit 5cm,0.10m --window 10ms,0.02 --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j.at("altitude_m"), 50.0);
  EXPECT_EQ(j.at("noise_allowance_arcsec"), 20.0);
  EXPECT_EQ(j.at("windows_total"), 2000 - 10);
  ASSERT_EQ(j.at("rows").size(), 4u);
  EXPECT_EQ(j["rows"][0]["limit_m"], 0.05);
  EXPECT_EQ(j["rows"][0]["window_s"], 0.010);
  EXPECT_EQ(j["rows"][0]["flagged_percent"], 100.0);  // 300" > 226"
  EXPECT_EQ(j["rows"][0]["flagged_percent_vector"], 100.0);
  EXPECT_EQ(j["rows"][2]["flagged_percent"], 0.0);    // 10 cm, 10 ms: 300" < 433"
  EXPECT_EQ(j["rows"][3]["flagged_percent"], 100.0);  // 10 cm, 20 ms: 633" > 433"
}

TEST(FlightCli, TableAndSeries) {
  TempDir dir;
  const std::string trace = WriteTrace(dir);
  const std::string series = dir / "series.csv";
  const auto r = RunShutterlab("flight " + trace + " --series " + series);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("per-axis %"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("criteria:"), std::string::npos) << r.output;
  const std::string csv = ReadFileToString(series);
  EXPECT_EQ(csv.rfind("t,range_x,range_y,range_z,vector\n", 0), 0u);
  EXPECT_EQ(CountLines(csv), 1u + 2000u - 10u);
}

TEST(FlightCli, BadInputExitsTwoWithOneLine) {
  TempDir dir;
  const std::string trace = WriteTrace(dir);
  const std::string series = dir / "series.csv";
  for (const std::string args :
       {"--window 3s", "--limit 5in", "--bias 0:0.005", "--altitude -1", "--bias 0:100"}) {
    const auto r = RunShutterlab("flight " + trace + " " + args + " --series " + series);
    EXPECT_EQ(r.exit_code, 2) << args << ": " << r.output;
    EXPECT_EQ(CountLines(r.output), 1u) << args << ": " << r.output;
    EXPECT_EQ(r.output.rfind("error: ", 0), 0u) << r.output;
    EXPECT_FALSE(std::filesystem::exists(series)) << "partial output for " << args;
    if (args == "--window 3s") {
      EXPECT_NE(r.output.find("longer than"), std::string::npos) << r.output;
      EXPECT_NE(r.output.find(trace), std::string::npos)
          << "error must name the file: " << r.output;
    }
  }
}

}  // namespace
}  // namespace shutterlab
