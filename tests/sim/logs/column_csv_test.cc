#include "sim/logs/column_csv.h"

#include "sim/check.h"
#include "sim/logs/flight_log_io.h"
#include "sim/text_file.h"
#include "sim/units.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <array>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace shutterlab {
namespace {

ColumnCsvOptions Columns(const std::string& list) {
  ColumnCsvOptions options;
  options.columns = ParseColumnList(list);
  return options;
}

struct Row {
  int64_t t_ns;
  double x, y, z;
};

void ExpectSamples(const GyroTrace& trace, const std::vector<Row>& rows) {
  ASSERT_EQ(trace.samples().size(), rows.size());
  for (size_t i = 0; i < rows.size(); ++i) {
    const GyroSample& s = trace.samples()[i];
    EXPECT_EQ(s.t_ns, rows[i].t_ns) << i;
    EXPECT_EQ(s.omega_rad_s.x(), rows[i].x) << i;
    EXPECT_EQ(s.omega_rad_s.y(), rows[i].y) << i;
    EXPECT_EQ(s.omega_rad_s.z(), rows[i].z) << i;
  }
}

// The IoError's whole message, or a test failure when none is thrown.
std::string ErrorOf(const std::string& text, const ColumnCsvOptions& options) {
  try {
    ParseColumnCsv(text, "f.csv", options);
  } catch (const IoError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no IoError for:\n" << text;
  return "";
}

TEST(ColumnCsv, CommaHeaderNamesInSeconds) {
  const ColumnCsvLog log =
      ParseColumnCsv("t,gx,gy,gz\n0.5,1,2,3\n0.75,4,5,6\n", "f.csv", Columns("t,gx,gy,gz"));
  ExpectSamples(log.trace, {{500000000, 1, 2, 3}, {750000000, 4, 5, 6}});
  EXPECT_EQ(log.source, "t,gx,gy,gz");
  EXPECT_EQ(log.delimiter, ',');
  EXPECT_TRUE(log.has_header);
}

TEST(ColumnCsv, SemicolonSpreadsheetInMillisecondsAndDegrees) {
  ColumnCsvOptions options = Columns("time_ms,wx,wy,wz");
  options.time_unit = TimeUnit::kMilliseconds;
  options.rate_unit = RateUnit::kDegPerSecond;
  const ColumnCsvLog log =
      ParseColumnCsv("time_ms;wx;wy;wz\n10;90;-45;0\n12.5;180;0;1\n", "f.csv", options);
  ExpectSamples(log.trace, {{10000000, 90 * kRadPerDeg, -45 * kRadPerDeg, 0},
                            {12500000, 180 * kRadPerDeg, 0, kRadPerDeg}});
  EXPECT_EQ(log.delimiter, ';');
  EXPECT_EQ(log.source, "time_ms,wx,wy,wz");
}

TEST(ColumnCsv, TabWithHeaderChosenByNumbers) {
  // Numbers pick the columns; the header still names them in the source.
  const ColumnCsvLog log =
      ParseColumnCsv("z\ty\tx\ttime\n3\t2\t1\t0.25\n6\t5\t4\t0.5\n", "f.csv", Columns("4,3,2,1"));
  ExpectSamples(log.trace, {{250000000, 1, 2, 3}, {500000000, 4, 5, 6}});
  EXPECT_EQ(log.delimiter, '\t');
  EXPECT_TRUE(log.has_header);
  EXPECT_EQ(log.source, "time,x,y,z");
}

TEST(ColumnCsv, WhitespaceRunsWithoutHeader) {
  const ColumnCsvLog log =
      ParseColumnCsv("  1   0.5 0.25\t-2\n2 \t 1 2 3   \n", "f.csv", Columns("1,2,3,4"));
  ExpectSamples(log.trace, {{1000000000, 0.5, 0.25, -2}, {2000000000, 1, 2, 3}});
  EXPECT_EQ(log.delimiter, ' ');
  EXPECT_FALSE(log.has_header);
  EXPECT_EQ(log.source, "1,2,3,4");
}

TEST(ColumnCsv, DelimiterDetectionRules) {
  // More semicolons than commas: ';' (a comma may sit inside a name).
  EXPECT_EQ(ParseColumnCsv("t;w,x;y;z\n1;2;3;4\n", "f", Columns("1,2,3,4")).delimiter, ';');
  // Tabs and no spaces: tab, so that an empty field still counts.
  const ColumnCsvLog tabbed = ParseColumnCsv("1\t2\t\t3\t4\n", "f", Columns("1,2,4,5"));
  EXPECT_EQ(tabbed.delimiter, '\t');
  ExpectSamples(tabbed.trace, {{1000000000, 2, 3, 4}});
}

TEST(ColumnCsv, PhoneGyroTxtShapeTimeLast) {
  // gyro.txt: gx,gy,gz,t in rad/s and s, no header, times in exponent form.
  const ColumnCsvLog log = ParseColumnCsv(
      "1.0e-01,2.5e-01,-5.0e-01,1.0005e+03\n7.5e-01,1.0e+00,0.0e+00,1.000515625e+03\n", "gyro.txt",
      Columns("4,1,2,3"));
  ExpectSamples(log.trace, {{1000500000000, 0.1, 0.25, -0.5}, {1000515625000, 0.75, 1.0, 0.0}});
  EXPECT_FALSE(log.has_header);
}

TEST(ColumnCsv, Ulog2csvSensorCombinedInMicroseconds) {
  const std::string text =
      "timestamp,gyro_rad[0],gyro_rad[1],gyro_rad[2],gyro_integral_dt,"
      "accelerometer_timestamp_relative,accelerometer_m_s2[0],accelerometer_m_s2[1],"
      "accelerometer_m_s2[2]\n"
      "20312345,0.0078125,-0.015625,0.5,4000,0,0.1,-0.2,-9.81\n"
      "20316345,0.0234375,-0.03125,0.25,4000,0,0.1,-0.2,-9.81\n";
  ColumnCsvOptions options = Columns("timestamp,gyro_rad[0],gyro_rad[1],gyro_rad[2]");
  options.time_unit = TimeUnit::kMicroseconds;
  const ColumnCsvLog log = ParseColumnCsv(text, "sensor_combined_0.csv", options);
  ExpectSamples(log.trace, {{20312345000, 0.0078125, -0.015625, 0.5},
                            {20316345000, 0.0234375, -0.03125, 0.25}});
  EXPECT_EQ(log.source, "timestamp,gyro_rad[0],gyro_rad[1],gyro_rad[2]");
}

TEST(ColumnCsv, NanosecondTimesKeepEveryTick) {
  ColumnCsvOptions options = Columns("1,2,3,4");
  options.time_unit = TimeUnit::kNanoseconds;
  const ColumnCsvLog log =
      ParseColumnCsv("9007199254740993,0,0,0\n9007199254740995,0,0,0\n", "f.csv", options);
  ExpectSamples(log.trace, {{9007199254740993, 0, 0, 0}, {9007199254740995, 0, 0, 0}});
}

TEST(ColumnCsv, HeaderModes) {
  const std::string named = "time,x,y,z\n1,0,0,0\n2,0,0,0\n";
  // Auto: a first line whose chosen fields are not numbers is a header, even for numbers.
  EXPECT_EQ(ParseColumnCsv(named, "f.csv", Columns("1,2,3,4")).trace.samples().size(), 2u);
  // No header: that line is data, and bad data.
  ColumnCsvOptions no = Columns("1,2,3,4");
  no.header = HeaderMode::kNo;
  EXPECT_EQ(ErrorOf(named, no), "f.csv:1: column 1 (time) is not a time in s: 'time'");
  // Yes: the first line is skipped whatever it holds.
  ColumnCsvOptions yes = Columns("1,2,3,4");
  yes.header = HeaderMode::kYes;
  const ColumnCsvLog numeric = ParseColumnCsv("0,1,2,3\n1,4,5,6\n2,7,8,9\n", "f.csv", yes);
  ExpectSamples(numeric.trace, {{1000000000, 4, 5, 6}, {2000000000, 7, 8, 9}});
  EXPECT_EQ(numeric.source, "0,1,2,3");  // the skipped line's fields name the columns
}

TEST(ColumnCsv, ExplicitDelimiterWinsOverDetection) {
  // The first line has more commas than semicolons, but the user says ';'.
  ColumnCsvOptions options = Columns("1,2,3,4");
  options.delimiter = ';';
  const ColumnCsvLog log =
      ParseColumnCsv("note,a,b,c;x;y;z\n1;2;3;4\n", "f.csv", options);  // header by auto
  ExpectSamples(log.trace, {{1000000000, 2, 3, 4}});
  EXPECT_EQ(log.source, "note,a,b,c,x,y,z");
}

TEST(ColumnCsv, BomCrlfBlankLinesAndQuotedNamesFromAFile) {
  test::TempDir dir;
  const std::string path = dir / "export.csv";
  std::ofstream(path, std::ios::binary)
      << "\xEF\xBB\xBF\"Time\";\"WX\";\"WY\";\"WZ\"\r\n\r\n1;2;3;4\r\n2;5;6;7\r\n\r\n";
  // Names match case-insensitively when no name matches exactly.
  const ColumnCsvLog log = ReadColumnCsv(path, Columns("time,wx,wy,wz"));
  ExpectSamples(log.trace, {{1000000000, 2, 3, 4}, {2000000000, 5, 6, 7}});
  EXPECT_EQ(log.source, "Time,WX,WY,WZ");
}

TEST(ColumnCsv, ErrorsNameTheLineAndTheColumn) {
  struct Case {
    const char* text;
    const char* columns;
    const char* message;
  };
  const Case cases[] = {
      {"time_ms;gyro_x;gyro_y;gyro_z\n1;2;3;4\n", "time_ms,wx,wy,wz",
       "f.csv:1: column 'wx' (x) not in the header: time_ms;gyro_x;gyro_y;gyro_z"},
      {"\n\nt,gx,gy,gz\n\n0,1,2,3\n1,1,2\n", "t,gx,gy,gz",
       "f.csv:6: column 'gz' (z) missing: the line has 3 fields split on ','"},
      {"t,gx,gy,gz\n0,1,2,3\n1,1,oops,3\n", "t,gx,gy,gz",
       "f.csv:3: column 'gy' (y) is not a number: 'oops'"},
      {"0,1,2,3\n1,1,2,nan\n", "1,2,3,4", "f.csv:2: column 4 (z) is not a number: 'nan'"},
      {"t,gx,gy,gz\n0.5,0,0,0\n0.75,0,0,0\n\n0.5,0,0,0\n", "t,gx,gy,gz",
       "f.csv:5: time goes backwards: column 't' is 0.5 here and 0.75 on line 3"},
      {"t,gx,gx,gz\n0,1,2,3\n", "t,gx,gx,gz",
       "f.csv:1: column 'gx' appears twice in the header: t,gx,gx,gz"},
      {"t,gx,gy,gz\n", "t,gx,gy,gz", "f.csv: no samples"},
      {"\r\n\r\n", "1,2,3,4", "f.csv: no samples (the file is empty)"},
  };
  for (const Case& c : cases) EXPECT_EQ(ErrorOf(c.text, Columns(c.columns)), c.message) << c.text;
}

TEST(ColumnCsv, EqualTimesAreKeptForTheAudit) {
  const ColumnCsvLog log = ParseColumnCsv("1,0,0,0\n1,1,1,1\n", "f.csv", Columns("1,2,3,4"));
  EXPECT_EQ(log.trace.samples().size(), 2u);
  EXPECT_EQ(log.trace.sampling().duplicate_timestamps, 1u);
}

TEST(ColumnCsv, OptionsAndFlagsAreChecked) {
  EXPECT_EQ(ParseColumnList(" t , gx,gy ,gz"), (std::vector<std::string>{"t", "gx", "gy", "gz"}));
  EXPECT_THROW(ParseColumnList("t,gx,gy"), std::invalid_argument);
  EXPECT_THROW(ParseColumnList("t,,gy,gz"), std::invalid_argument);
  EXPECT_THROW(Columns("0,1,2,3").Check(), std::invalid_argument);
  ColumnCsvOptions named_without_header = Columns("t,1,2,3");
  named_without_header.header = HeaderMode::kNo;
  EXPECT_THROW(named_without_header.Check(), std::invalid_argument);
  EXPECT_THROW(ColumnCsvOptions().Check(), std::invalid_argument);  // no columns
  EXPECT_THROW(ParseDelimiter("|"), std::invalid_argument);
  EXPECT_THROW(ParseRateUnit("rpm"), std::invalid_argument);
  const std::pair<const char*, char> delimiters[] = {
      {"auto", '\0'}, {"Semicolon", ';'}, {"tab", '\t'}, {"whitespace", ' '}, {",", ','}};
  for (const auto& [name, delimiter] : delimiters) EXPECT_EQ(ParseDelimiter(name), delimiter);
  EXPECT_EQ(ParseRateUnit("deg/s"), RateUnit::kDegPerSecond);
  EXPECT_EQ(ParseRateUnit("RAD/S"), RateUnit::kRadPerSecond);
}

TEST(ColumnCsv, ReadFlightLogTakesTheColumnReader) {
  test::TempDir dir;
  const std::string path = dir / "log.txt";
  std::ofstream(path) << "0.25 1 2 3\n0.5 4 5 6\n";
  FlightLogReadOptions options;
  options.format = LogFormat::kColumns;
  EXPECT_THROW(ReadFlightLog(path, options), std::invalid_argument);  // no columns given
  options.columns = Columns("1,2,3,4");
  const FlightLog log = ReadFlightLog(path, options);
  EXPECT_EQ(log.format, "columns");
  EXPECT_EQ(log.gyro_source, "1,2,3,4");
  ExpectSamples(log.gyro, {{250000000, 1, 2, 3}, {500000000, 4, 5, 6}});
}

// The phone's gyro.txt by flags alone, against a plain strtod parse of the same file (the phone
// clip reader is this reader, told the same columns, so it is no twin).
TEST(ColumnCsv, RealPhoneGyroTxtByFlagsEqualsAPlainParse) {
  SHUTTERLAB_REAL_DATA(clip_dir, "rs/phone_gyro_video_20200109_145447");
  FlightLogReadOptions options;
  options.format = LogFormat::kColumns;
  options.columns = Columns("4,1,2,3");  // gx,gy,gz,t in rad/s and s (SOURCES.md)
  const FlightLog log = ReadFlightLog(clip_dir + "/gyro.txt", options);
  std::vector<std::array<double, 4>> rows;
  std::istringstream text(ReadFileToString(clip_dir + "/gyro.txt"));
  for (std::string line; std::getline(text, line);) {
    if (line.empty()) continue;
    std::array<double, 4> row{};
    const char* p = line.c_str();
    for (double& value : row) {
      char* end = nullptr;
      value = std::strtod(p, &end);
      p = end + 1;  // past the comma
    }
    rows.push_back(row);
  }
  const auto& got = log.gyro.samples();
  ASSERT_EQ(got.size(), rows.size());
  ASSERT_EQ(got.size(), 29466u);
  for (size_t i = 0; i < got.size(); ++i) {
    // ~4.3e6 s as a double holds the nanosecond to within 1 ns; the reader's decimal parse is
    // exact.
    ASSERT_NEAR(got[i].t_ns, rows[i][3] * 1e9, 1.0) << i;
    ASSERT_EQ(got[i].omega_rad_s, Eigen::Vector3d(rows[i][0], rows[i][1], rows[i][2])) << i;
  }
}

}  // namespace
}  // namespace shutterlab
