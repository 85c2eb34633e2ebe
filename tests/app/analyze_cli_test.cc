#include "sim/text_file.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

namespace shutterlab {
namespace {

using test::RunShutterlab;
using test::SourcePath;

std::string Bbl() { return SourcePath("tests/data/betaflight/btfl_001.bbl"); }

size_t LineCount(const std::string& text) {
  return static_cast<size_t>(std::count(text.begin(), text.end(), '\n'));
}

TEST(AnalyzeCli, BlackboxEveryTwoSecondsJsonAndOutputs) {
  test::TempDir dir;
  const auto r =
      RunShutterlab("analyze " + Bbl() + " --every 2s --readout 20ms --altitude 40 --json --out " +
                    (dir / "out"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json json = nlohmann::json::parse(r.output);
  EXPECT_EQ(json["source"]["format"], "betaflight");
  EXPECT_EQ(json["source"]["gyro"], "gyroADC");
  const double duration_s = json["source"]["duration_s"];
  ASSERT_EQ(json["images"].size(), static_cast<size_t>(duration_s / 2.0));
  EXPECT_DOUBLE_EQ(json["flight"]["altitude_m"].get<double>(), 40.0);
  EXPECT_DOUBLE_EQ(json["flight"]["rows"][0]["window_s"].get<double>(), 0.020);
  for (const auto& image : json["images"]) {
    EXPECT_TRUE(image["D_paper_m"].is_number());
    EXPECT_TRUE(image["flagged"]["0.05"].is_boolean());
  }
  const std::string csv = ReadFileToString(dir / "out/images.csv");
  EXPECT_EQ(LineCount(csv), json["images"].size() + 1);
  EXPECT_TRUE(std::filesystem::exists(dir / "out/exclude.txt"));
}

TEST(AnalyzeCli, TableHasVerdict) {
  const auto r = RunShutterlab("analyze " + Bbl() + " --every 5s --limit 5cm");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("verdict: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("with a 10 ms readout"), std::string::npos) << r.output;
}

TEST(AnalyzeCli, BadTriggersCsvIsOneLineExitTwoAndNoOutput) {
  test::TempDir dir;
  std::ofstream(dir / "times.csv") << "image,t\nIMG_1,1.0\nIMG_2,abc\n";
  const auto r = RunShutterlab("analyze " + Bbl() + " --triggers " + (dir / "times.csv") +
                               " --out " + (dir / "out"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(LineCount(r.output), 1u) << r.output;
  EXPECT_NE(r.output.find("times.csv:3:"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "out/images.csv"));
}

TEST(AnalyzeCli, UnknownLogIsOneLineExitTwo) {
  test::TempDir dir;
  std::ofstream(dir / "notes.txt") << "hello\n";
  const auto r = RunShutterlab("analyze " + (dir / "notes.txt"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(LineCount(r.output), 1u) << r.output;
}

}  // namespace
}  // namespace shutterlab
