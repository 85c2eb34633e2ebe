#include "sim/gyro_trace.h"

#include <cmath>
#include <algorithm>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "sim/check.h"
#include "sim/gyro_io.h"
#include "sim/text_file.h"
#include "tests/test_util.h"

namespace shutterlab {
namespace {

TEST(GyroTrace, RejectsDecreasingTimestamps) {
  std::vector<GyroSample> s = {{0, {0, 0, 0}}, {10, {0, 0, 0}}, {5, {0, 0, 0}}};
  EXPECT_THROW(GyroTrace{s}, std::invalid_argument);
}

TEST(GyroTrace, RejectsNonFiniteRates) {
  std::vector<GyroSample> s = {{0, {0, 0, 0}}, {10, {0, std::nan(""), 0}}};
  EXPECT_THROW(GyroTrace{s}, std::invalid_argument);
}

TEST(GyroTrace, ReportsGapsAndDuplicates) {
  std::vector<GyroSample> s;
  int64_t t = 0;
  for (int k = 0; k < 100; ++k) {
    s.push_back({t, {0, 0, 0}});
    t += (k == 40) ? 3'500'000 : (k == 70 ? 0 : 1'000'000);  // one 3.5x gap, one duplicate
  }
  const GyroTrace trace(s);
  EXPECT_EQ(trace.sampling().median_interval_ns, 1'000'000);
  ASSERT_EQ(trace.sampling().gap_indices.size(), 1u);
  EXPECT_EQ(trace.sampling().gap_indices[0], 40u);
  EXPECT_EQ(trace.sampling().duplicate_timestamps, 1u);
  EXPECT_NEAR(trace.sampling().RateHz(), 1000.0, 1e-9);
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

}  // namespace
}  // namespace shutterlab

namespace shutterlab {
namespace {

// The median interval is exact on both paths: few distinct intervals (histogram) and many
// (nth_element); both are checked against a sort.
TEST(GyroTrace, MedianIntervalIsExactForRegularAndIrregularClocks) {
  std::mt19937_64 rng(7);
  for (int distinct : {3, 1000}) {
    std::uniform_int_distribution<int64_t> interval(1000, 1000 + distinct - 1);
    std::vector<GyroSample> s;
    std::vector<int64_t> intervals;
    int64_t t = 0;
    for (int k = 0; k < 5001; ++k) {
      s.push_back({t, {0, 0, 0}});
      const int64_t dt = interval(rng);
      if (k < 5000) intervals.push_back(dt);
      t += dt;
    }
    std::sort(intervals.begin(), intervals.end());
    EXPECT_EQ(GyroTrace(s).sampling().median_interval_ns, intervals[intervals.size() / 2])
        << distinct << " distinct intervals";
  }
}

}  // namespace
}  // namespace shutterlab
