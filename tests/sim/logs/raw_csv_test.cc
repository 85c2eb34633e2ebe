#include "sim/logs/raw_csv.h"

#include "sim/check.h"
#include "sim/text_file.h"
#include "sim/units.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

// Counts are exact integers and the conversion is one multiply: only double rounding remains.
constexpr double kConversionTolRadS = 1e-15;

// Expects IoError whose message names path:line and contains `problem`.
void ExpectIoError(const std::string& path, int range_dps, TimeUnit unit, long line,
                   const std::string& problem) {
  try {
    ReadRawCsv(path, range_dps, unit);
    ADD_FAILURE() << "no error for " << path;
  } catch (const IoError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path + ":" + std::to_string(line) + ":"), std::string::npos) << what;
    EXPECT_NE(what.find(problem), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << "one line: " << what;
  }
}

TEST(RawCsv, SensitivitiesAreTheMpu9250Table) {
  EXPECT_EQ(RawSensitivityLsbPerDps(250), 131.0);
  EXPECT_EQ(RawSensitivityLsbPerDps(500), 65.5);
  EXPECT_EQ(RawSensitivityLsbPerDps(1000), 32.8);
  EXPECT_EQ(RawSensitivityLsbPerDps(2000), 16.4);
  EXPECT_THROW(RawSensitivityLsbPerDps(300), std::invalid_argument);
  EXPECT_THROW(RawSensitivityLsbPerDps(0), std::invalid_argument);
}

TEST(RawCsv, ConvertsCountsToRadPerSecond) {
  test::TempDir dir;
  // 131 counts at +-250 deg/s is exactly 1 deg/s; -32768 is the most negative register value.
  const std::string path =
      test::WriteText(dir, "a.csv", "t,gx,gy,gz\n0.0,131,-262,0\n0.001,0,-32768,32767\n");
  const GyroTrace trace = ReadRawCsv(path, 250, TimeUnit::kSeconds);
  ASSERT_EQ(trace.size(), 2u);
  EXPECT_EQ(trace[0].t_ns, 0);
  EXPECT_EQ(trace[1].t_ns, 1000000);
  const double deg = kRadPerDeg;
  EXPECT_NEAR(trace[0].omega_rad_s.x(), 1.0 * deg, kConversionTolRadS);
  EXPECT_NEAR(trace[0].omega_rad_s.y(), -2.0 * deg, kConversionTolRadS);
  EXPECT_EQ(trace[0].omega_rad_s.z(), 0.0);
  EXPECT_NEAR(trace[1].omega_rad_s.y(), -32768.0 / 131.0 * deg, kConversionTolRadS);
  EXPECT_NEAR(trace[1].omega_rad_s.z(), 32767.0 / 131.0 * deg, kConversionTolRadS);
}

TEST(RawCsv, RangeScalesTheCounts) {
  test::TempDir dir;
  const std::string path = test::WriteText(dir, "a.csv", "0,164,328,-164\n1,0,0,0\n");
  const GyroTrace trace = ReadRawCsv(path, 2000, TimeUnit::kSeconds);
  const double deg = kRadPerDeg;
  EXPECT_NEAR(trace[0].omega_rad_s.x(), 10.0 * deg, kConversionTolRadS);
  EXPECT_NEAR(trace[0].omega_rad_s.y(), 20.0 * deg, kConversionTolRadS);
  EXPECT_NEAR(trace[0].omega_rad_s.z(), -10.0 * deg, kConversionTolRadS);
}

TEST(RawCsv, TimeUnitsAreExactForIntegers) {
  test::TempDir dir;
  const std::string text = "t,gx,gy,gz\n1578551687123456789,0,0,0\n1578551687123457790,1,1,1\n";
  const std::string path = test::WriteText(dir, "ns.csv", text);
  const GyroTrace ns = ReadRawCsv(path, 250, TimeUnit::kNanoseconds);
  EXPECT_EQ(ns[0].t_ns, 1578551687123456789LL);  // beyond 2^53: a double would lose the last digits
  EXPECT_EQ(ns[1].t_ns - ns[0].t_ns, 1001);
  const std::string us_path = test::WriteText(dir, "us.csv", "1000,0,0,0\n2000.5,0,0,0\n");
  const GyroTrace us = ReadRawCsv(us_path, 250, TimeUnit::kMicroseconds);
  EXPECT_EQ(us[0].t_ns, 1000000);
  EXPECT_EQ(us[1].t_ns, 2000500);
  const GyroTrace ms = ReadRawCsv(us_path, 250, TimeUnit::kMilliseconds);
  EXPECT_EQ(ms[1].t_ns, 2000500000);
  // Fractions finer than a nanosecond and exponents fall back to double and round to the ns.
  const std::string odd_path =
      test::WriteText(dir, "odd.csv", "1e-3,0,0,0\n0.0020000004,0,0,0\n-0,0,0,0\n");
  EXPECT_THROW(ReadRawCsv(odd_path, 250, TimeUnit::kSeconds), IoError);  // -0 < 0.002: decreasing
  const std::string odd2 = test::WriteText(dir, "odd2.csv", "1e-3,0,0,0\n0.0020000004,0,0,0\n");
  const GyroTrace s = ReadRawCsv(odd2, 250, TimeUnit::kSeconds);
  EXPECT_EQ(s[0].t_ns, 1000000);
  EXPECT_EQ(s[1].t_ns, 2000000);
}

TEST(RawCsv, IgnoresExtraColumnsAndBlankLines) {
  test::TempDir dir;
  const std::string path = test::WriteText(
      dir, "a.csv", "t,gx,gy,gz,ax,ay,az\r\n0,1,2,3,16384,0,0\r\n\r\n0.01,4,5,6,0,0,0\r\n");
  const GyroTrace trace = ReadRawCsv(path, 250, TimeUnit::kSeconds);
  ASSERT_EQ(trace.size(), 2u);
  EXPECT_NEAR(trace[1].omega_rad_s.z(), 6.0 / 131.0 * kPi / 180.0, kConversionTolRadS);
}

TEST(RawCsv, WriterRoundTripsQuantisedTraces) {
  test::TempDir dir;
  // Rates on the count grid come back exactly (to double rounding); times exactly in every unit.
  std::vector<GyroSample> samples;
  const double rad_s_per_count = kRadPerDeg / 65.5;
  for (int k = 0; k < 200; ++k) {
    const int64_t t_ns = 1700000000000000000LL + k * 1000123LL;  // 1 kHz with a ragged period
    samples.push_back({t_ns, Eigen::Vector3d(k - 100, 3 * k - 32000, -k) * rad_s_per_count});
  }
  const GyroTrace trace(samples);
  for (TimeUnit unit : {TimeUnit::kSeconds, TimeUnit::kMilliseconds, TimeUnit::kMicroseconds,
                        TimeUnit::kNanoseconds}) {
    const std::string path = dir / "out.csv";
    EXPECT_EQ(WriteRawCsv(path, trace, 500, unit), 0u);
    const GyroTrace back = ReadRawCsv(path, 500, unit);
    ASSERT_EQ(back.size(), trace.size());
    for (size_t i = 0; i < trace.size(); ++i) {
      EXPECT_EQ(back[i].t_ns, trace[i].t_ns);  // decimal times parse exactly, beyond 2^53 ns too
      EXPECT_NEAR((back[i].omega_rad_s - trace[i].omega_rad_s).norm(), 0.0, 1e-12);
    }
  }
}

TEST(RawCsv, WriterQuantisesAndSaturates) {
  test::TempDir dir;
  const double deg = kRadPerDeg;
  // 0.4 count rounds down, 0.6 rounds up; 300 deg/s exceeds the 250 deg/s range on both sides.
  const GyroTrace trace({{0, Eigen::Vector3d(0.4 / 131 * deg, 0.6 / 131 * deg, 300 * deg)},
                         {1000000, Eigen::Vector3d(-300 * deg, 0, 0)}});
  const std::string path = dir / "q.csv";
  EXPECT_EQ(WriteRawCsv(path, trace, 250, TimeUnit::kMilliseconds), 2u);
  EXPECT_EQ(ReadFileToString(path), std::string(kRawCsvHeader) + "\n0,0,1,32767\n1,-32768,0,0\n");
}

TEST(RawCsv, RejectsBadInputNamingTheLine) {
  test::TempDir dir;
  ExpectIoError(test::WriteText(dir, "a", "t,gx,gy,gz\n0,1,2,3\n1,1,2\n"), 250, TimeUnit::kSeconds,
                3, "expected 4 columns");
  ExpectIoError(test::WriteText(dir, "b", "0,1,2,3\n1,1.5,2,3\n"), 250, TimeUnit::kSeconds, 2,
                "gx is not an integer count");
  ExpectIoError(test::WriteText(dir, "c", "0,1,2,3\n1,1,2,32768\n"), 250, TimeUnit::kSeconds, 2,
                "gz = 32768 is outside the int16 range");
  ExpectIoError(test::WriteText(dir, "d", "0,1,2,3\n1,1,-32769,3\n"), 250, TimeUnit::kSeconds, 2,
                "gy = -32769 is outside");
  ExpectIoError(test::WriteText(dir, "e", "0,1,2,3\nnan,1,2,3\n"), 250, TimeUnit::kSeconds, 2,
                "t is not a finite number");
  ExpectIoError(test::WriteText(dir, "f", "0,1,2,3\ninf,1,2,3\n"), 250, TimeUnit::kSeconds, 2,
                "t is not a finite number");
  ExpectIoError(test::WriteText(dir, "g", "5,1,2,3\n4,1,2,3\n"), 250, TimeUnit::kSeconds, 2,
                "timestamp decreases");
  ExpectIoError(test::WriteText(dir, "h", "0,1,2,3\n1,x,2,3\n"), 250, TimeUnit::kSeconds, 2,
                "gx is not an integer count: 'x'");
  // A time that overflows int64 ns.
  ExpectIoError(test::WriteText(dir, "i", "0,1,2,3\n99999999999999999,1,2,3\n"), 250,
                TimeUnit::kMilliseconds, 2, "t is not a finite number in range");
  EXPECT_THROW(ReadRawCsv(test::WriteText(dir, "j", "t,gx,gy,gz\n"), 250, TimeUnit::kSeconds),
               IoError);
  EXPECT_THROW(ReadRawCsv(test::WriteText(dir, "k", "0,1,2,3\n"), 300, TimeUnit::kSeconds),
               std::invalid_argument);
}

TEST(RawCsv, WriterLeavesNoFileOnFailure) {
  test::TempDir dir;
  const GyroTrace trace({{0, Eigen::Vector3d::Zero()}});
  const std::string path = dir / "no_such_folder/out.csv";
  EXPECT_THROW(WriteRawCsv(path, trace, 250, TimeUnit::kSeconds), IoError);
  EXPECT_THROW(WriteRawCsv(dir / "x.csv", trace, 42, TimeUnit::kSeconds), std::invalid_argument);
  EXPECT_FALSE(std::filesystem::exists(dir / "x.csv"));
}

}  // namespace
}  // namespace shutterlab
