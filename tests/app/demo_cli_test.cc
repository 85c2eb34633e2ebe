// `shutterlab demo`, the README's main command, end to end on the bundled assets: every step runs,
// writes what it says, and the closing-the-loop step finds the clock offset it hid.

#include "sim/text_file.h"
#include "tests/app/cli_test_util.h"
#include "tests/estimate/report/report_test_util.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>

namespace shutterlab {
namespace {

TEST(DemoCli, RunsEveryStepAndFindsTheHiddenOffset) {
  test::TempDir dir;
  const std::string out = dir / "demo";
  const test::CommandResult result = test::RunShutterlab("demo --out " + out);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  for (const char* section : {"== 0.", "== 1.", "== 2.", "== 3.", "== 4.", "== 5.", "== 6."}) {
    EXPECT_NE(result.output.find(section), std::string::npos) << section;
  }
  // The demo makes its own inputs: a flight log that the reader takes and a scene.
  for (const char* file :
       {"inputs/flight.ulg", "inputs/ground.png", "report.html", "images.csv", "exclude.txt",
        "render/frames.csv", "validate/report.json", "validate/plots/validate.html"}) {
    EXPECT_TRUE(std::filesystem::exists(std::filesystem::path(out) / file)) << file;
  }
  // It says where it wrote what and how much: the total it prints is what is on disk.
  uintmax_t bytes = 0;
  size_t files = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(out)) {
    if (!entry.is_regular_file()) continue;
    bytes += entry.file_size();
    ++files;
  }
  char total[64];
  std::snprintf(total, sizeof total, ": %.1f MB in %zu files ==", bytes / 1e6, files);
  EXPECT_NE(result.out.find("== Written to " + out + total), std::string::npos)
      << total << "\n"
      << result.out.substr(result.out.rfind("=="));
  EXPECT_NE(result.out.find("\ninputs/ "), std::string::npos);
  std::ifstream report_file(std::filesystem::path(out) / "validate/report.json");
  const nlohmann::json report = nlohmann::json::parse(report_file);
  ASSERT_EQ(report["effects"].size(), 1u) << report.dump(2);
  EXPECT_EQ(report["effects"][0]["name"], "time_offset");
  EXPECT_NEAR(report["effects"][0]["value"].get<double>(), 0.004, 0.3e-3);
  EXPECT_FALSE(report["unexplained"].get<bool>());
  EXPECT_LT(report["after"]["rms_px"].get<double>(), report["before"]["rms_px"].get<double>());
  // Its two pages draw in a browser (docs/report.png and docs/validate.png are their screenshots).
  for (const auto& [page, name] : {std::pair<std::string, std::string>{"report.html", "report"},
                                   {"validate/plots/validate.html", "validate"}}) {
    const std::string path = out + "/" + page;
    test::ExpectDrawsInChromium(path, test::ChartBlocks(ReadFileToString(path)).size(), name);
  }
}

}  // namespace
}  // namespace shutterlab
