// Bad input through the CLI, for every gyro reader: one line "error: PATH:LINE: problem", exit code
// 2, and no output file left behind. One test per case, so that ctest can run them in parallel
// (each starts the executable once).

#include "tests/app/cli_test_util.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace shutterlab {
namespace {

const char kGcsvHeader[] =
    "GYROFLOW IMU LOG\nversion,1.3\nid,test\norientation,XYZ\ntscale,0.001\ngscale,0.001\n";

// A still gyro.csv of 3000 samples at 1 kHz, for the options that fail after reading.
std::string StillTrace() {
  std::string text = "t,gx,gy,gz\n";
  for (int k = 0; k < 3000; ++k) text += std::to_string(k * 0.001) + ",0.001,-0.002,0.0005\n";
  return text;
}

struct BadCase {
  const char* name;
  std::string content;  // the trace file
  std::string args;     // options after `noise TRACE`
  long line;            // expected PATH:LINE: in the message; 0: the path alone; -1: no path
  std::string problem;  // part of the message
};

// Names the case in test output instead of GoogleTest's byte dump.
void PrintTo(const BadCase& c, std::ostream* os) { *os << c.name; }

class BadInputCli : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadInputCli, OneLineExitTwoNoOutput) {
  const BadCase& c = GetParam();
  test::TempDir dir;
  const std::string trace = dir / (std::string(c.name) + ".log");
  std::ofstream(trace) << c.content;
  const std::string out = dir / "allan.csv";
  const test::CommandResult r =
      test::RunShutterlab("noise '" + trace + "' " + c.args + " --allan '" + out + "'");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  ASSERT_FALSE(r.output.empty());
  EXPECT_EQ(r.output.rfind("error: ", 0), 0u) << r.output;
  EXPECT_EQ(r.output.find('\n'), r.output.size() - 1) << "one line: " << r.output;
  if (c.line >= 0) {
    const std::string where = c.line > 0 ? trace + ":" + std::to_string(c.line) + ":" : trace + ":";
    EXPECT_NE(r.output.find(where), std::string::npos) << r.output;
  }
  EXPECT_NE(r.output.find(c.problem), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("check failed"), std::string::npos) << "an internal tag: " << r.output;
  EXPECT_FALSE(std::filesystem::exists(out)) << "output left behind: " << out;
}

const std::string kG(kGcsvHeader);

INSTANTIATE_TEST_SUITE_P(
    Readers, BadInputCli,
    ::testing::Values(
        // gyro.csv
        BadCase{"csv_missing_header", "0,1,2,3\n", "--format csv", 1, "missing header"},
        BadCase{"csv_columns", "t,gx,gy,gz\n0,1,2,3\n0.001,1,2\n", "", 3, "expected 4 columns"},
        BadCase{"csv_text", "t,gx,gy,gz\n0,1.5,2,3\n0.001,1.5,two,3\n", "", 3,
                "gy is not a finite number: 'two'"},
        BadCase{"csv_nan", "t,gx,gy,gz\n0,1.5,2,3\n0.001,nan,2,3\n", "", 3,
                "gx is not a finite number"},
        BadCase{"csv_decreasing", "t,gx,gy,gz\n0.002,1.5,2,3\n0.001,1.5,2,3\n", "", 3,
                "timestamp decreases"},
        // raw counts
        BadCase{"raw_range", "0,1,2,3\n1,1,2,3\n", "--raw --range 300deg/s", -1,
                "unknown gyro range 300"},
        BadCase{"raw_int16", "t,gx,gy,gz\n0,1,2,3\n1,40000,2,3\n", "--format raw", 3,
                "gx = 40000 is outside the int16 range"},
        BadCase{"raw_fraction", "0,1,2,3\n1,1,2.5,3\n", "--raw", 2, "gy is not an integer count"},
        BadCase{"raw_decreasing", "10,1,2,3\n9,1,2,3\n", "--raw --time-unit ms", 2,
                "timestamp decreases"},
        BadCase{"raw_time_unit", "0,1,2,3\n", "--raw --time-unit min", -1,
                "unknown time unit 'min'"},
        // .gcsv
        BadCase{"gcsv_truncated", "GYROFLOW IMU LOG\nversion,1.3\nid,te", "", 3,
                "header ends before the column line"},
        BadCase{"gcsv_no_tscale", "GYROFLOW IMU LOG\nversion,1.3\nt,gx,gy,gz\n0,1,2,3\n", "", 3,
                "no tscale"},
        BadCase{"gcsv_orientation",
                "GYROFLOW IMU "
                "LOG\nversion,1.3\norientation,XXZ\ntscale,1\ngscale,1\nt,gx,gy,gz\n0,1,2,3\n",
                "", 3, "orientation 'XXZ'"},
        BadCase{"gcsv_columns", kG + "t,gx,gy,gz,ax,ay,az\n0,1,2,3,4,5,6\n1,1,2,3\n", "", 9,
                "expected 7 columns"},
        BadCase{"gcsv_inf", kG + "t,gx,gy,gz\n0,1,2,3\n1,1,2,inf\n", "", 9,
                "gz is not a finite number"},
        BadCase{"gcsv_forced_on_csv", "t,gx,gy,gz\n0,1.5,2,3\n", "--format gcsv", 1,
                "missing first line 'GYROFLOW IMU LOG'"},
        // format detection
        BadCase{"detect_neither", "0.0,0.5,0.25,0.125\n", "", 1,
                "no header line and a non-integer rate"},
        BadCase{"detect_other_header", "time,x,y,z\n0,1,2,3.5\n", "", 2, "unrecognised header"},
        BadCase{"detect_empty", "", "", 0, "empty file"},
        // options that fail once the trace is read
        BadCase{"bias_too_few_samples", StillTrace(), "--bias 0:0.005s", 0,
                "holds 5 samples (need at least 10; the trace lasts 2.999 s): give a --bias A:B "
                "over a still part of the log, --auto-bias, or a longer log"},
        BadCase{"window_longer_than_trace", StillTrace(), "--bias 0:1s --window-samples 100000", 0,
                "100000 samples is longer than the 2000 samples after the bias segment (0:1 s; the "
                "trace lasts 2.999 s): give an earlier --bias A:B, a shorter --window, or a longer "
                "log"},
        BadCase{"bias_reversed", StillTrace(), "--bias 5:2s", -1, "must satisfy 0 <= A < B"}),
    [](const ::testing::TestParamInfo<BadCase>& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace shutterlab
