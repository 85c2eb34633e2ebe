#include "sim/logs/gyro_io.h"

#include "sim/check.h"
#include "sim/logs/column_csv.h"
#include "sim/text_file.h"
#include "sim/units.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

LogFormat Detect(const std::string& text) { return DetectGyroFormat(text, "mem.csv"); }

// Expects DetectGyroFormat to throw IoError naming mem.csv:line and containing problem.
void ExpectDetectError(const std::string& text, long line, const std::string& problem) {
  try {
    Detect(text);
    ADD_FAILURE() << "no error for:\n" << text;
  } catch (const IoError& e) {
    const std::string what = e.what();
    const std::string where = line > 0 ? "mem.csv:" + std::to_string(line) + ":" : "mem.csv: ";
    EXPECT_NE(what.find(where), std::string::npos) << what;
    EXPECT_NE(what.find(problem), std::string::npos) << what;
  }
}

TEST(GyroIo, DetectsGcsvFromTheFirstLine) {
  EXPECT_EQ(Detect("GYROFLOW IMU LOG\nversion,1.3\n"), LogFormat::kGcsv);
  EXPECT_EQ(Detect("\xEF\xBB\xBFGYROFLOW IMU LOG\r\nversion,1.3\r\n"),
            LogFormat::kGcsv);  // BOM, CRLF
  EXPECT_EQ(Detect("\nCAMERA IMU LOG\n"), LogFormat::kGcsv);
}

TEST(GyroIo, DetectsGyroCsvByAnyNonIntegerRate) {
  EXPECT_EQ(Detect("t,gx,gy,gz\n0.0,0.01,-0.02,0.5\n"), LogFormat::kGyroCsv);
  // Integers first, one fraction late in the file: still gyro.csv (the whole file is scanned).
  EXPECT_EQ(Detect("t,gx,gy,gz\n0.0,0,0,0\n0.1,1,2,3\n0.2,0,1e-3,0\n"), LogFormat::kGyroCsv);
  EXPECT_EQ(Detect("T,GX,GY,GZ,extra\n0,1,2,3.5,x\n"), LogFormat::kGyroCsv);
  // A header and no rows: gyro.csv, whose reader then reports "no samples".
  EXPECT_EQ(Detect("t,gx,gy,gz\n"), LogFormat::kGyroCsv);
  // A non-numeric rate after the header goes to the gyro.csv reader, which names it.
  EXPECT_EQ(Detect("t,gx,gy,gz\n0,1,abc,3\n"), LogFormat::kGyroCsv);
}

TEST(GyroIo, DetectsRawCountsByIntegerRates) {
  // Another header with integer rates only: raw counts (t may still be fractional).
  EXPECT_EQ(Detect("t,gx_counts,gy_counts,gz_counts\n0.001,12,-7,3\n0.002,11,-8,2\n"),
            LogFormat::kRaw);
  EXPECT_EQ(Detect("time_us,x,y,z\n1000,12,-7,3\n"), LogFormat::kRaw);
  // No header, integers: raw.
  EXPECT_EQ(Detect("1000,12,-7,3\n2000,11,-8,2\n"), LogFormat::kRaw);
  // docs/FORMATS.md's header always means gyro.csv, even with whole-number rates (--raw overrides).
  EXPECT_EQ(Detect("t,gx,gy,gz\n0,0,0,0\n0.01,0,0,0\n"), LogFormat::kGyroCsv);
  EXPECT_EQ(Detect("t,gx,gy,gz\n0.001,12,-7,3\n"), LogFormat::kGyroCsv);
}

TEST(GyroIo, DetectionRejectsNeitherFormat) {
  // No header and fractional rates: neither a raw log nor a gyro.csv.
  ExpectDetectError("0.0,1,2,3\n0.1,0.5,2,3\n", 2, "no header line and a non-integer rate '0.5'");
  // The real phone log's layout gx,gy,gz,t with exponents.
  ExpectDetectError("3.97e-03,3.83e-02,1.47e-02,4.328040426741000265e+06\n", 1, "non-integer rate");
  // Some other header.
  ExpectDetectError("time,x,y,z\n0,1,2,3.5\n", 2, "unrecognised header 'time,x,y,z'");
  ExpectDetectError("\n\n", 0, "empty file");
}

TEST(GyroIo, ReadGyroDispatchesOnDetectionAndOverride) {
  test::TempDir dir;
  const std::string raw =
      test::WriteText(dir, "raw.csv", "t,gx_counts,gy_counts,gz_counts\n0,131,0,0\n0.01,0,262,0\n");
  // Auto: raw counts at the default +-250 deg/s: 131 counts = 1 deg/s.
  const GyroTrace as_raw = ReadGyro(raw);
  EXPECT_NEAR(as_raw[0].omega_rad_s.x(), kRadPerDeg, 1e-15);
  // --format csv insists on gyro.csv's header.
  GyroReadOptions csv;
  csv.format = LogFormat::kGyroCsv;
  EXPECT_THROW(ReadGyro(raw, csv), IoError);
  // --raw reads docs/FORMATS.md's header as counts when told to.
  const std::string counts_with_csv_header =
      test::WriteText(dir, "counts.csv", "t,gx,gy,gz\n0,131,0,0\n0.01,0,262,0\n");
  GyroReadOptions raw_forced;
  raw_forced.format = LogFormat::kRaw;
  EXPECT_NEAR(ReadGyro(counts_with_csv_header, raw_forced)[0].omega_rad_s.x(), kRadPerDeg, 1e-15);
  EXPECT_EQ(ReadGyro(counts_with_csv_header)[0].omega_rad_s.x(), 131.0);
  // --range 2000deg/s --time-unit ms.
  GyroReadOptions wide;
  wide.raw.range_dps = 2000;
  wide.raw.time_unit = TimeUnit::kMilliseconds;
  const GyroTrace as_wide = ReadGyro(raw, wide);
  EXPECT_NEAR(as_wide[0].omega_rad_s.x(), 131.0 / 16.4 * kPi / 180.0, 1e-15);
  EXPECT_EQ(as_wide[1].t_ns, 10000);  // 0.01 ms
  // Gcsv.
  const GyroTrace trace(
      {{0, Eigen::Vector3d(0.1, 0.2, 0.3)}, {1000000, Eigen::Vector3d(-0.1, 0, 1)}});
  WriteGcsv(dir / "a.gcsv", trace);
  const GyroTrace as_gcsv = ReadGyro(dir / "a.gcsv");
  EXPECT_EQ(as_gcsv[1].omega_rad_s, trace[1].omega_rad_s);
  // Gyro.csv.
  WriteGyroCsv(dir / "g.csv", trace);
  EXPECT_EQ(ReadGyro(dir / "g.csv")[0].omega_rad_s, trace[0].omega_rad_s);
  // Unknown range.
  GyroReadOptions bad;
  bad.raw.range_dps = 300;
  EXPECT_THROW(ReadGyro(raw, bad), std::invalid_argument);
}

TEST(GyroIo, GyroCsvTimesAreExactAtLargeEpochs) {
  test::TempDir dir;
  // 1.7e9 s with 9 decimals is beyond double's ns resolution; the decimal parser keeps every ns.
  const GyroTrace trace({{1700000000123456789LL, Eigen::Vector3d(1e-3, -2e-3, 0.5)},
                         {1700000000124456790LL, Eigen::Vector3d(0, 0, 0)}});
  WriteGyroCsv(dir / "g.csv", trace);
  const GyroTrace back = ReadGyroCsv(dir / "g.csv");
  EXPECT_EQ(back[0].t_ns, trace[0].t_ns);
  EXPECT_EQ(back[1].t_ns, trace[1].t_ns);
  EXPECT_EQ(back[0].omega_rad_s, trace[0].omega_rad_s);
  // The largest times int64 ns holds are read exactly too (the fast path stops at 9e9 s).
  WriteFileAtomically(dir / "late.csv",
                      "t,gx,gy,gz\n9000000000.5,0,0,0\n9200000000.000000001,0,0,0\n");
  const GyroTrace late = ReadGyroCsv(dir / "late.csv");
  EXPECT_EQ(late[0].t_ns, 9000000000500000000LL);
  EXPECT_EQ(late[1].t_ns, 9200000000000000001LL);
}

TEST(GyroIo, GyroCsvRejectsBadInputNamingTheLine) {
  test::TempDir dir;
  const auto expect = [&](const std::string& text, long line, const std::string& problem) {
    const std::string path = test::WriteText(dir, "bad.csv", text);
    try {
      ReadGyroCsv(path);
      ADD_FAILURE() << text;
    } catch (const IoError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(path + ":" + std::to_string(line) + ":"), std::string::npos) << what;
      EXPECT_NE(what.find(problem), std::string::npos) << what;
    }
  };
  expect("0,1,2,3\n", 1, "missing header");
  expect("t,gx,gy,gz\n0,1,2\n", 2, "expected 4 columns");
  expect("t,gx,gy,gz\n0,1,2,3\n1,1,x,3\n", 3, "gy is not a finite number: 'x'");
  expect("t,gx,gy,gz\n0,1,2,3\n1,1,2,inf\n", 3, "gz is not a finite number");
  expect("t,gx,gy,gz\n0,1,2,3\nnan,1,2,3\n", 3, "t is not a finite number");
  expect("t,gx,gy,gz\n1,1,2,3\n0.5,1,2,3\n", 3, "timestamp decreases");
  // A '\r' that ends no line is part of its field, on the fast path as on the general one (the
  // fast path once skipped it and took the rest as extra columns).
  expect("t,gx,gy,gz\n0,1,2,3\r,x\n1,1,2,3\n", 2, "gz is not a finite number");
}

TEST(GyroIo, ParsesFormatNames) {
  EXPECT_EQ(ParseGyroFormat("AUTO"), LogFormat::kAuto);
  EXPECT_EQ(ParseGyroFormat("gyro.csv"), LogFormat::kGyroCsv);
  EXPECT_EQ(ParseGyroFormat("gcsv"), LogFormat::kGcsv);
  EXPECT_EQ(ParseGyroFormat("raw"), LogFormat::kRaw);
  EXPECT_THROW(ParseGyroFormat("ulog"), std::invalid_argument);
  EXPECT_EQ(ParseTimeUnit("us"), TimeUnit::kMicroseconds);
  EXPECT_THROW(ParseTimeUnit("min"), std::invalid_argument);
}

TEST(GyroCsv, WriteReadRoundTripIsExact) {
  test::TempDir dir;
  std::vector<GyroSample> s = {{1'234'567'890'123, {0.1, -1e-7, 3.14159}},
                               {1'234'568'890'124, {1.0 / 3.0, 2e-300, -0.0}}};
  WriteGyroCsv(dir / "g.csv", GyroTrace(s));
  const GyroTrace back = ReadGyroCsv(dir / "g.csv");
  ASSERT_EQ(back.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(back[i].t_ns, s[i].t_ns);
    EXPECT_EQ(back[i].omega_rad_s, s[i].omega_rad_s);
  }
}

TEST(GyroCsv, ToleratesExtraColumnsAndCrLf) {
  test::TempDir dir;
  WriteFileAtomically(dir / "g.csv", "t,gx,gy,gz,temp\r\n0.0,1,2,3,25\r\n0.001,4,5,6,25\r\n");
  const GyroTrace trace = ReadGyroCsv(dir / "g.csv");
  ASSERT_EQ(trace.size(), 2u);
  EXPECT_EQ(trace[1].t_ns, 1'000'000);
  EXPECT_EQ(trace[1].omega_rad_s, Eigen::Vector3d(4, 5, 6));
}

// Brute-force twin of the fast row parser: every row of a gyro.csv in all the forms a writer may
// use (fixed decimals of any length, shortest round-trip doubles, exponents, '+', spaces, long
// digit runs, 0 to 12 time decimals, epoch seconds, extra columns, CR LF, empty lines, a last line
// without its break) reads exactly as the general path reads it field by field (SplitFields,
// ParseTimeInUnitNs) and std::from_chars reads its rates, whatever the block and chunk sizes.
TEST(GyroCsv, FastRowsReadAsTheGeneralFieldByFieldPath) {
  std::mt19937_64 rng(18);
  const auto number = [&rng](double x) {
    char buffer[64];
    std::to_chars_result r{};
    switch (rng() % 8) {
      case 0:  // shortest round trip, exponents where it likes them
        r = std::to_chars(buffer, buffer + sizeof(buffer), x);
        break;
      case 1:
        r = std::to_chars(buffer, buffer + sizeof(buffer), x, std::chars_format::scientific,
                          static_cast<int>(rng() % 10));
        break;
      case 2:  // more digits than the fast path takes (19 in all)
        r = std::to_chars(buffer, buffer + sizeof(buffer), x * 1e6, std::chars_format::fixed,
                          14 + static_cast<int>(rng() % 4));
        break;
      case 3:
        return std::string(rng() % 2 ? " " : "+") + std::to_string(std::abs(x));
      default:  // as loggers write them
        r = std::to_chars(buffer, buffer + sizeof(buffer), x, std::chars_format::fixed,
                          static_cast<int>(rng() % 13));
    }
    return std::string(buffer, r.ptr);
  };
  for (int trial = 0; trial < 40; ++trial) {
    const bool crlf = rng() % 4 == 0, epoch = rng() % 2 == 0;
    std::string text = crlf ? "t,gx,gy,gz\r\n" : "t,gx,gy,gz\n";
    const int64_t t0_ns = epoch ? 1'700'000'000'000'000'000 : 0;
    const int rows = 1 + static_cast<int>(rng() % 400);
    for (int i = 0; i < rows; ++i) {
      // A second apart, so that times cut to any number of decimals still do not decrease.
      const int64_t t_ns =
          t0_ns + i * int64_t{1'000'000'000} + static_cast<int64_t>(rng() % 1'000'000'000);
      const int decimals = static_cast<int>(rng() % 13);  // 10 to 12: more than ns, general path
      std::string line = std::to_string(t_ns / 1'000'000'000);
      if (decimals > 0) {
        char fraction[16];
        std::snprintf(fraction, sizeof(fraction), "%09lld",
                      static_cast<long long>(t_ns % 1'000'000'000));
        line += "." + (std::string(fraction) + "000").substr(0, decimals);
      }
      for (int a = 0; a < 3; ++a) {
        const double scale = std::pow(10.0, static_cast<int>(rng() % 9) - 4);
        line += "," + number(scale * std::normal_distribution<double>()(rng));
      }
      if (rng() % 10 == 0) line += ",25.5,extra";
      text += line + (crlf ? "\r\n" : "\n");
      if (rng() % 50 == 0) text += "\n";
    }
    if (rng() % 3 == 0) text.resize(text.size() - (crlf ? 2 : 1));  // no break after the last row
    // The reference: each non-empty line through the general field-by-field path.
    std::vector<GyroSample> expected;
    LineCursor lines(text);
    lines.Next();  // the header
    std::vector<std::string_view> fields;
    while (auto line = lines.Next()) {
      if (line->empty()) continue;
      SplitFields(*line, ',', &fields);
      ASSERT_GE(fields.size(), 4u);
      GyroSample s;
      const auto t_ns = ParseTimeInUnitNs(fields[0], TimeUnit::kSeconds);
      ASSERT_TRUE(t_ns) << *line;
      s.t_ns = *t_ns;
      for (int a = 0; a < 3; ++a) {  // std::from_chars itself: no code shared with the reader
        std::string_view field = fields[a + 1];
        if (field.front() == '+') field.remove_prefix(1);
        const auto [end, ec] =
            std::from_chars(field.data(), field.data() + field.size(), s.omega_rad_s[a]);
        ASSERT_TRUE(ec == std::errc() && end == field.data() + field.size()) << *line;
      }
      expected.push_back(s);
    }
    const size_t block_bytes = 16 + rng() % 3000, chunk = 1 + rng() % 300;
    std::unique_ptr<GyroSource> source =
        OpenGyroCsv(TextBlocks::InMemory(text, block_bytes), "mem.csv", chunk);
    std::vector<GyroSample> got;
    for (GyroChunk c = source->Next(); !c.empty(); c = source->Next())
      got.insert(got.end(), c.data, c.data + c.size);
    EXPECT_TRUE(source->Warnings().empty()) << trial;
    ASSERT_EQ(got.size(), expected.size()) << trial;
    for (size_t i = 0; i < got.size(); ++i) {
      ASSERT_EQ(got[i].t_ns, expected[i].t_ns) << trial << " row " << i;
      for (int a = 0; a < 3; ++a) {
        ASSERT_TRUE(test::SameBits(got[i].omega_rad_s[a], expected[i].omega_rad_s[a]))
            << trial << " row " << i << " axis " << a;
      }
    }
  }
}

// Each bad file gives an IoError whose message names the file, the line and the problem.
struct BadCsvCase {
  const char* name;
  const char* content;
  const char* expected_fragment;
};

TEST(GyroCsv, BadInputNamesFileLineAndProblem) {
  const BadCsvCase cases[] = {
      {"missing_header", "0,1,2,3\n", ":1: missing header"},
      {"columns", "t,gx,gy,gz\n0,1,2,3\n0.1,1,2\n", ":3: expected 4 columns"},
      {"non_numeric", "t,gx,gy,gz\n0,1,abc,3\n", ":2: gy is not a finite number: 'abc'"},
      {"non_finite", "t,gx,gy,gz\n0,1,2,inf\n", ":2: gz is not a finite number"},
      {"decreasing", "t,gx,gy,gz\n1,0,0,0\n0.5,0,0,0\n", ":3: timestamp decreases"},
      {"empty", "t,gx,gy,gz\n", "no samples"},
      // Found by fuzz/gyro_csv_fuzz: 12 digits of seconds overflowed int64 ns in the fast path.
      {"time_overflow", "t,gx,gy,gz\n044444444444,444,4,3.5\n",
       ":2: t is not a finite number in range"},
      {"time_overflow_10_digits", "t,gx,gy,gz\n9999999999.5,1,2,3\n",
       ":2: t is not a finite number in range"},
  };
  test::TempDir dir;
  for (const auto& c : cases) {
    const std::string path = dir / (std::string(c.name) + ".csv");
    WriteFileAtomically(path, c.content);
    try {
      ReadGyroCsv(path);
      ADD_FAILURE() << c.name << ": no error";
    } catch (const IoError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(path), std::string::npos) << what;
      EXPECT_NE(what.find(c.expected_fragment), std::string::npos) << c.name << ": " << what;
    }
  }
}

// Every sample of a streaming source, checking that no chunk holds more than chunk_samples.
std::vector<GyroSample> Drain(GyroSource* source, size_t chunk_samples) {
  std::vector<GyroSample> all;
  for (GyroChunk chunk = source->Next(); !chunk.empty(); chunk = source->Next()) {
    EXPECT_LE(chunk.size, chunk_samples);
    all.insert(all.end(), chunk.begin(), chunk.end());
  }
  return all;
}

TEST(StreamingReaders, AnyChunkSizeGivesTheSameSamples) {
  // 40 rows in each text format; every reader, at chunk sizes that split the rows anywhere and
  // at the default, hands on the same samples in the same order.
  std::string gyro = "t,gx,gy,gz\n", raw = "",
              gcsv =
                  "GYROFLOW IMU "
                  "LOG\nversion,1.3\nid,x\norientation,XYZ\ntscale,0.001\ngscale,1\nt,gx,gy,gz\n";
  std::string columns = "time_ms;wx;wy;wz\n";
  for (int i = 0; i < 40; ++i) {
    const std::string t = std::to_string(i), r = std::to_string(i % 7 - 3) + ".25";
    gyro += "0." + std::string(i < 10 ? "00" : "0") + t + "," + r + ",0.5," + r + "\n";
    raw += t + "," + std::to_string(i * 3 - 50) + ",7,-9\n";
    gcsv += t + "," + r + ",1," + r + "\n";
    columns += t + ";" + r + ";2;" + r + "\n";
  }
  ColumnCsvOptions column_options;
  column_options.columns = {"time_ms", "wx", "wy", "wz"};
  column_options.time_unit = TimeUnit::kMilliseconds;
  const auto open = [&](int format, size_t chunk) -> std::unique_ptr<GyroSource> {
    switch (format) {
      case 0:
        return OpenGyroCsv(TextBlocks::InMemory(gyro, 16), "g.csv", chunk);
      case 1:
        return OpenRawCsv(TextBlocks::InMemory(raw, 16), "r.csv", 250, TimeUnit::kMilliseconds,
                          chunk);
      case 2:
        return OpenGcsv(TextBlocks::InMemory(gcsv, 16), "l.gcsv", chunk).samples;
      default:
        return OpenColumnCsv(TextBlocks::InMemory(columns, 16), "c.csv", column_options, chunk)
            .samples;
    }
  };
  for (int format = 0; format < 4; ++format) {
    const std::vector<GyroSample> expected =
        Drain(open(format, FillingSource::kDefaultChunkSamples).get(),
              FillingSource::kDefaultChunkSamples);
    ASSERT_EQ(expected.size(), 40u) << "format " << format;
    for (size_t chunk : {size_t{1}, size_t{3}, size_t{39}, size_t{40}, size_t{41}}) {
      const std::vector<GyroSample> got = Drain(open(format, chunk).get(), chunk);
      ASSERT_EQ(got.size(), expected.size()) << "format " << format << ", chunk " << chunk;
      for (size_t i = 0; i < got.size(); ++i) {
        EXPECT_EQ(got[i].t_ns, expected[i].t_ns) << "format " << format << ", chunk " << chunk;
        EXPECT_EQ(got[i].omega_rad_s, expected[i].omega_rad_s);
      }
    }
  }
}

}  // namespace
}  // namespace shutterlab
