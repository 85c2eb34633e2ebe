// The trace commands read every supported log, not only gyro.csv: real flight logs go through the
// same dispatcher as `analyze`.

#include "sim/logs/flight_log_io.h"
#include "tests/app/cli_test_util.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <string>

namespace shutterlab {
namespace {

nlohmann::json RunJson(const std::string& args) {
  const test::CommandResult result = test::RunShutterlab(args + " 2>/dev/null");
  EXPECT_EQ(result.exit_code, 0) << args << "\n" << result.output;
  return nlohmann::json::parse(result.out, nullptr, /*allow_exceptions=*/false);
}

TEST(TraceFormatsCli, NoiseReadsARealULog) {
  // sample_log_small.ulg: a stationary PX4 board, vehicle_angular_velocity at ~280 Hz over ~6.5 s.
  SHUTTERLAB_REAL_DATA(log, "gyro/px4_ulog/sample_log_small.ulg");
  const nlohmann::json j = RunJson("noise " + log + " --bias 0:2s --json");
  ASSERT_TRUE(j.is_object());
  EXPECT_EQ(j["window_samples"], 120);
  for (const char* axis : {"x", "y", "z"}) {
    const auto& a = j["axes"][axis];
    EXPECT_GT(a["sigma_mean_arcsec"].get<double>(), 0.0) << axis;
    EXPECT_GE(a["range_max_arcsec"].get<double>(), a["range_mean_arcsec"].get<double>()) << axis;
  }
}

TEST(TraceFormatsCli, FlightReadsARealBlackboxLog) {
  // btfl_001.bbl log 1: 24,893 frames at 500 Hz; with --zero-bias every sample is analysed.
  SHUTTERLAB_REAL_DATA(log, "gyro/betaflight_blackbox/btfl_001.bbl");
  const nlohmann::json j = RunJson("flight " + log + " --zero-bias --no-vector --json");
  ASSERT_TRUE(j.is_object());
  EXPECT_EQ(j["samples"], 24893);
  ASSERT_EQ(j["rows"].size(), 4u);
  for (const auto& row : j["rows"]) {
    EXPECT_GT(row["flagged_percent"].get<double>(), 0.0);
    EXPECT_LE(row["flagged_percent"].get<double>(), 100.0);
  }
}

// Every command that reads a log lists every format of the reader table in its --format help
// (the list is made from the table, not typed: correct's once lacked gopro and gyro_dump).
TEST(TraceFormatsCli, EveryFormatOptionListsTheReaderTable) {
  for (const char* command : {"flight", "noise", "accuracy", "analyze", "correct"}) {
    const auto r = test::RunShutterlab(std::string(command) + " --help");
    ASSERT_EQ(r.exit_code, 0) << command << ": " << r.err;
    const size_t at = r.out.find("--format");
    ASSERT_NE(at, std::string::npos) << command;
    const std::string help = r.out.substr(at, r.out.find("\n  -", at) - at);  // its own lines
    for (const LogReader& reader : LogReaders()) {
      if (reader.detection == LogDetection::kNever) continue;  // chosen by --columns
      EXPECT_NE(help.find(reader.names[0]), std::string::npos)
          << command << " --format lacks " << reader.names[0] << ": " << help;
    }
  }
}

}  // namespace
}  // namespace shutterlab
