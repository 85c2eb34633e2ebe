#include "sim/logs/gyro_io.h"
#include "sim/logs/raw_csv.h"
#include "sim/text_file.h"
#include "tests/app/cli_test_util.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

using test::RunShutterlab;

TEST(SynthCli, WritesATraceThatReadGyroReadsBack) {
  test::TempDir dir;
  const std::string out = dir / "still.csv";
  const auto result = RunShutterlab("synth still --out " + out + " --duration 2s --rate 2000Hz");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const GyroTrace trace = ReadGyro(out);
  EXPECT_EQ(trace.size(), 4001u);
  EXPECT_NEAR(trace.sampling().RateHz(), 2000.0, 1e-9);
  EXPECT_NE(result.output.find("4001 samples"), std::string::npos) << result.output;
}

TEST(SynthCli, StepsToRawCountsWithASecondSensor) {
  test::TempDir dir;
  const std::string out = dir / "a.csv", out2 = dir / "b.csv";
  const auto result = RunShutterlab("synth steps --turns 2 --angle 1deg --out " + out + " --out2 " +
                                    out2 + " --format raw --range 500deg/s --time-unit ms");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("turn 2:"), std::string::npos) << result.output;
  const GyroTrace a = ReadRawCsv(out, 500, TimeUnit::kMilliseconds);
  const GyroTrace b = ReadRawCsv(out2, 500, TimeUnit::kMilliseconds);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_GT(a.size(), 3000u * 12);  // 6 s lead + two turns with 3 s still after each
  EXPECT_EQ(a[0].t_ns, b[0].t_ns);
  EXPECT_NE(ReadFileToString(out), ReadFileToString(out2));
}

TEST(SynthCli, SameSeedSameBytes) {
  test::TempDir dir;
  const std::string common =
      " flight --duration 7s --jitter 1e-6s --gap-period 2s --gap-duration 0.01s --out ";
  ASSERT_EQ(RunShutterlab("synth --seed 5" + common + (dir / "a.csv")).exit_code, 0);
  ASSERT_EQ(RunShutterlab("synth --seed 5" + common + (dir / "b.csv")).exit_code, 0);
  ASSERT_EQ(RunShutterlab("synth --seed 6" + common + (dir / "c.csv")).exit_code, 0);
  EXPECT_EQ(ReadFileToString(dir / "a.csv"), ReadFileToString(dir / "b.csv"));
  EXPECT_NE(ReadFileToString(dir / "a.csv"), ReadFileToString(dir / "c.csv"));
}

// synth's --format names are the readers' (flight --format gyro.csv reads what synth --format
// gyro.csv writes); "csv", its old name, writes the same bytes; a format synth cannot write is
// refused in one line.
TEST(SynthCli, FormatNamesAreTheReadersNames) {
  test::TempDir dir;
  const std::string common = "synth still --duration 1s --out ";
  ASSERT_EQ(RunShutterlab(common + (dir / "a.csv") + " --format gyro.csv").exit_code, 0);
  ASSERT_EQ(RunShutterlab(common + (dir / "b.csv") + " --format csv").exit_code, 0);
  ASSERT_EQ(RunShutterlab(common + (dir / "c.csv")).exit_code, 0);
  EXPECT_EQ(ReadFileToString(dir / "a.csv"), ReadFileToString(dir / "b.csv"));
  EXPECT_EQ(ReadFileToString(dir / "a.csv"), ReadFileToString(dir / "c.csv"));
  EXPECT_EQ(
      RunShutterlab("noise " + (dir / "a.csv") + " --format gyro.csv --bias 0:0.5s").exit_code, 0);
  const auto gcsv = RunShutterlab(common + (dir / "d.gcsv") + " --format gcsv");
  EXPECT_EQ(gcsv.exit_code, 2);
  EXPECT_NE(gcsv.err.find("synth writes gyro.csv or raw counts, not gcsv"), std::string::npos)
      << gcsv.err;
}

TEST(SynthCli, IdealSensorWritesTheExactMotion) {
  test::TempDir dir;
  const std::string out = dir / "ideal.csv";
  ASSERT_EQ(RunShutterlab("synth still --ideal --duration 1s --out " + out).exit_code, 0);
  // ReadGyroCsv, not ReadGyro: format detection takes a file whose rates are all integers (here
  // every rate is "0") for raw counts.
  const GyroTrace ideal =
      ReadGyroCsv(out);  // named: a range-for over a temporary's samples dangles
  ASSERT_EQ(ideal.size(), 3001u);
  for (const GyroSample& s : ideal.samples()) ASSERT_EQ(s.omega_rad_s, Eigen::Vector3d::Zero());
  // An error option given with --ideal still applies.
  ASSERT_EQ(
      RunShutterlab("synth still --ideal --const-bias 0.5rad/s,0,0 --duration 1s --out " + out)
          .exit_code,
      0);
  const GyroTrace biased = ReadGyroCsv(out);
  for (const GyroSample& s : biased.samples()) ASSERT_EQ(s.omega_rad_s.x(), 0.5);
}

TEST(SynthCli, BadArgumentsExitTwoWithOneLineAndNoFile) {
  test::TempDir dir;
  const std::string out = dir / "bad.csv";
  for (const std::string& args : std::vector<std::string>{
           "synth wobble --out " + out, "synth still --rate -5Hz --out " + out,
           "synth still --range 300deg/s --out " + out,
           "synth still --time-unit h --raw --out " + out, std::string("synth still --duration 1s"),
           "synth still --duration 1s --out " + (dir / "missing_folder/x.csv")}) {
    const auto result = RunShutterlab(args);
    EXPECT_EQ(result.exit_code, 2) << args << "\n" << result.output;
    EXPECT_EQ(test::LineCount(result.output), 1u) << args << "\n" << result.output;
    EXPECT_EQ(result.output.rfind("error: ", 0), 0u) << args << "\n" << result.output;
    EXPECT_FALSE(std::filesystem::exists(out)) << args;
  }
  // Malformed numbers are CLI11's parse errors: exit 2 as well.
  EXPECT_EQ(RunShutterlab("synth still --rate fast --out " + out).exit_code, 2);
  EXPECT_FALSE(std::filesystem::exists(out));
}

}  // namespace
}  // namespace shutterlab
