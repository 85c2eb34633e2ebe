#include "sim/logs/gyro_row_shapes.h"

#include "sim/check.h"
#include "sim/logs/gyro_io.h"
#include "sim/text_file.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

// A row with the bytes after it that Read may load (another row's worth of digits).
std::string Padded(const std::string& row) {
  return row + std::string(GyroRowShapes::kReadBytes, '7');
}

TEST(GyroRowShapes, ReadsARowOfALearnedShapeExactly) {
  GyroRowShapes shapes;
  if (!shapes.enabled()) GTEST_SKIP() << "no AVX2 on this CPU: rows are read byte by byte";
  const std::string first = Padded("12.345,-0.000294,0.008589,0.12\n");
  GyroSample s{};
  EXPECT_EQ(shapes.Read(first.data(), &s), nullptr) << "no shape learned yet";
  shapes.Learn(first.data(), first.data() + first.find('\n') + 1);
  // The same shape, other digits: read by it.
  const std::string second = Padded("98.761,-9.876543,1.000001,7.99\n");
  const char* end = shapes.Read(second.data(), &s);
  ASSERT_EQ(end, second.data() + second.find('\n') + 1);
  EXPECT_EQ(s.t_ns, 98'761'000'000);
  EXPECT_TRUE(test::SameBits(s.omega_rad_s[0], -9.876543));
  EXPECT_TRUE(test::SameBits(s.omega_rad_s[1], 1.000001));
  EXPECT_TRUE(test::SameBits(s.omega_rad_s[2], 7.99));
  // Non-digits in the same places but not the same bytes: not this shape.
  EXPECT_EQ(shapes.Read(Padded("98.761,-9.876543,1.000001.7,99\n").data(), &s), nullptr);
  EXPECT_EQ(shapes.Read(Padded("98.761,-9.876543,1.000001,7.9x\n").data(), &s), nullptr);
  // Another sign is another shape.
  EXPECT_EQ(shapes.Read(Padded("12.345,0.0002945,0.008589,0.12\n").data(), &s), nullptr);
}

TEST(GyroRowShapes, EpochTimesAndLongNumbersAreExact) {
  GyroRowShapes shapes;
  if (!shapes.enabled()) GTEST_SKIP() << "no AVX2 on this CPU: rows are read byte by byte";
  // t over both lanes (20 bytes, 19 digits), rates of 15 digits.
  const std::string row = Padded("1700000000.123456789,12345.6789012345,0.00000000000001,1\n");
  shapes.Learn(row.data(), row.data() + row.find('\n') + 1);
  const std::string other = Padded("8999999999.999999999,99999.9999999999,0.99999999999999,0\n");
  GyroSample s{};
  ASSERT_NE(shapes.Read(other.data(), &s), nullptr);
  EXPECT_EQ(s.t_ns, 8'999'999'999'999'999'999);
  EXPECT_TRUE(test::SameBits(s.omega_rad_s[0], 99999.9999999999));
  EXPECT_TRUE(test::SameBits(s.omega_rad_s[1], 0.99999999999999));
  EXPECT_TRUE(test::SameBits(s.omega_rad_s[2], 0.0));
  // At most 9e9 whole seconds, as the byte loop takes them (t_ns then fits in 63 bits).
  ASSERT_NE(
      shapes.Read(Padded("9000000000.999999999,99999.9999999999,0.99999999999999,0\n").data(), &s),
      nullptr);
  EXPECT_EQ(s.t_ns, 9'000'000'000'999'999'999);
  EXPECT_EQ(
      shapes.Read(Padded("9000000001.000000000,99999.9999999999,0.99999999999999,0\n").data(), &s),
      nullptr);
  // 16 digits, CR LF, an extra column, an exponent: no shape is learned.
  for (const char* unlearnable :
       {"1.5,0.1234567890123456,1,2\n", "1.5,0.1,1,2\r\n", "1.5,0.1,1,2,3\n", "1.5,1e-3,1,2\n",
        "1.5,-,1,2\n", ".5,0.1,1,2\n", "1.5, 0.1,1,2\n"}) {
    GyroRowShapes fresh;
    const std::string text = Padded(unlearnable);
    fresh.Learn(text.data(), text.data() + text.find('\n') + 1);
    EXPECT_EQ(fresh.Read(text.data(), &s), nullptr) << unlearnable;
  }
}

// 64 bytes without a line break are no row, whatever they hold: 64 digits once passed for a row
// of the empty slot's shape (found by review; a sample of NaN rates, then the next row a byte on).
TEST(GyroRowShapes, SixtyFourBytesWithoutALineBreakAreNoRow) {
  GyroRowShapes shapes;
  if (!shapes.enabled()) GTEST_SKIP() << "no AVX2 on this CPU: rows are read byte by byte";
  GyroSample s{};
  for (const char fill : {'0', '7', '\0', ','}) {
    const std::string bytes(GyroRowShapes::kReadBytes, fill);
    EXPECT_EQ(shapes.Read(bytes.data(), &s), nullptr) << static_cast<int>(fill);
  }
}

// What a reading gave: its samples bit for bit and its warnings, or its error.
std::string Outcome(const std::string& text, GyroCsvRows rows) {
  std::string out;
  try {
    auto source = OpenGyroCsv(TextBlocks::InMemory(text), "mem.csv", 1000, rows);
    for (GyroChunk c = source->Next(); !c.empty(); c = source->Next()) {
      for (size_t i = 0; i < c.size; ++i) {
        out.append(reinterpret_cast<const char*>(&c.data[i].t_ns), sizeof(int64_t));
        out.append(reinterpret_cast<const char*>(c.data[i].omega_rad_s.data()), 3 * sizeof(double));
      }
    }
    for (const LogWarning& w : source->Warnings()) out += "|" + w.kind + ":" + w.message;
  } catch (const IoError& e) {
    out = std::string("error: ") + e.what();
  }
  return out;
}

// Texts at the edges of what a shape reads give what the byte loop gives: the same samples,
// warnings or error.
TEST(GyroRowShapes, EdgeTextsReadAsTheByteLoopReadsThem) {
  const std::string header = "t,gx,gy,gz\n";
  const std::string row = "1.000,0.100000,-0.200000,0.300000\n";
  std::string repeated;
  for (int i = 0; i < 20; ++i) repeated += row;
  const std::string texts[] = {
      header + std::string(79, '0') + "\n",
      header + "0,0,0,0\n" + std::string(80, '0'),
      header + repeated + std::string(100, '0') + "\n",
      header + repeated + "0.999,0.100000,-0.200000,0.300000\n" + repeated,  // time decreases
      header + repeated + "1.000,0.100000,-0.200000,0.300000,9\n" + repeated,
      header + repeated + "1.000,0.100000,-0.200000,0.300000\r\n" + repeated,
      header + repeated + "\n\n" + repeated + "1.000,0.100000,-0.200000,0.3",
      header + repeated + "1.000,0.100000,-0.200000,0.30000x\n" + repeated,
      header + repeated + "1.000,0.100000,-0.200000.0,300000\n" + repeated,
      header + repeated + "9000000001,0.100000,-0.200000,0.300000\n",
  };
  for (const std::string& text : texts) {
    EXPECT_EQ(Outcome(text, GyroCsvRows::kByShape), Outcome(text, GyroCsvRows::kByteLoop))
        << text.substr(header.size(), 120);
  }
}

// The whole reader on rows of a few shapes over and over, as loggers write them (fixed decimals,
// random signs, times growing a digit now and then): read by shape, it gives what the byte loop
// and std::from_chars give, bit for bit, whatever the block size.
TEST(GyroRowShapes, ReaderGivesTheByteLoopsSamples) {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 12; ++trial) {
    const int rate_decimals = 1 + static_cast<int>(rng() % 12);
    const int time_decimals = static_cast<int>(rng() % 10);
    const double rate_scale = trial % 3 == 0 ? 100.0 : 1.0;
    const int64_t t0_ns = trial % 2 ? 1'700'000'000'000'000'000 : 0;
    std::string text = "t,gx,gy,gz\n";
    std::vector<GyroSample> expected;
    for (int i = 0; i < 3000; ++i) {
      // 3.7 s apart: the whole seconds grow a digit within the trial.
      const int64_t t_ns = t0_ns + i * int64_t{3'700'000'000};
      char line[160];
      int n =
          std::snprintf(line, sizeof(line), "%lld", static_cast<long long>(t_ns / 1'000'000'000));
      if (time_decimals > 0) {
        char fraction[16];
        std::snprintf(fraction, sizeof(fraction), "%09lld",
                      static_cast<long long>(t_ns % 1'000'000'000));
        n += std::snprintf(line + n, sizeof(line) - n, ".%.*s", time_decimals, fraction);
      }
      GyroSample s;
      s.t_ns = t_ns - t_ns % static_cast<int64_t>(std::pow(10, 9 - time_decimals));
      for (int a = 0; a < 3; ++a) {
        const double rate = rate_scale * std::normal_distribution<double>()(rng);
        const int start = n + 1;
        n += std::snprintf(line + n, sizeof(line) - n, ",%.*f", rate_decimals, rate);
        std::from_chars(line + start, line + n, s.omega_rad_s[a]);  // independent of the reader
      }
      text += std::string(line, n) + "\n";
      expected.push_back(s);
    }
    const auto read = [&](GyroCsvRows rows, size_t block_bytes) {
      auto source = OpenGyroCsv(TextBlocks::InMemory(text, block_bytes), "mem.csv", 1000, rows);
      std::vector<GyroSample> got;
      for (GyroChunk c = source->Next(); !c.empty(); c = source->Next())
        got.insert(got.end(), c.data, c.data + c.size);
      return got;
    };
    const size_t block_bytes = 100 + rng() % 5000;
    const std::vector<GyroSample> by_shape = read(GyroCsvRows::kByShape, block_bytes);
    const std::vector<GyroSample> byte_loop = read(GyroCsvRows::kByteLoop, block_bytes);
    ASSERT_EQ(by_shape.size(), expected.size());
    ASSERT_EQ(byte_loop.size(), expected.size());
    for (size_t i = 0; i < expected.size(); ++i) {
      ASSERT_EQ(by_shape[i].t_ns, expected[i].t_ns) << trial << " row " << i;
      ASSERT_EQ(byte_loop[i].t_ns, expected[i].t_ns) << trial << " row " << i;
      for (int a = 0; a < 3; ++a) {
        ASSERT_TRUE(test::SameBits(by_shape[i].omega_rad_s[a], expected[i].omega_rad_s[a]))
            << trial << " row " << i << " axis " << a;
        ASSERT_TRUE(test::SameBits(byte_loop[i].omega_rad_s[a], expected[i].omega_rad_s[a]))
            << trial << " row " << i << " axis " << a;
      }
    }
  }
}

// The shapes are what read those rows: most rows of such a log are read by a learned shape.
TEST(GyroRowShapes, MostRowsOfAFixedDecimalLogAreReadByShape) {
  GyroRowShapes shapes;
  if (!shapes.enabled()) GTEST_SKIP() << "no AVX2 on this CPU: rows are read byte by byte";
  std::mt19937_64 rng(3);
  std::string text;
  for (int i = 0; i < 2000; ++i) {
    char line[96];
    const int n = std::snprintf(line, sizeof(line), "%d.%03d,%.6f,%.6f,%.6f\n", 100 + i / 1000,
                                i % 1000, std::normal_distribution<double>(0, 0.3)(rng),
                                std::normal_distribution<double>(0, 0.3)(rng),
                                std::normal_distribution<double>(0, 0.3)(rng));
    text.append(line, n);
  }
  text += std::string(GyroRowShapes::kReadBytes, '\n');
  size_t by_shape = 0, rows = 0;
  for (const char* p = text.data();
       p + GyroRowShapes::kReadBytes <= text.data() + text.size() && *p != '\n'; ++rows) {
    GyroSample s;
    const char* next = shapes.Read(p, &s);
    if (next) {
      ++by_shape;
    } else {
      next = static_cast<const char*>(std::memchr(p, '\n', 96)) + 1;
      shapes.Learn(p, next);
    }
    p = next;
  }
  EXPECT_EQ(rows, 2000u);
  // 8 sign patterns (values under 1 in magnitude keep one whole digit, 3 of them beyond): each
  // shape is learned from its first row.
  EXPECT_GE(by_shape, 1900u);
}

}  // namespace
}  // namespace shutterlab
