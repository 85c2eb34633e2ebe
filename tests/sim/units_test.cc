#include "sim/units.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

// The message of the std::invalid_argument that body throws ("" when it throws none).
template <typename Body>
std::string ErrorOf(Body body) {
  try {
    body();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(Units, AngleConstantsMatchTheirDefinitions) {
  EXPECT_EQ(kPi, M_PI);
  EXPECT_EQ(kRadPerDeg, M_PI / 180.0);
  EXPECT_EQ(kDegPerRad, 180.0 / M_PI);
  EXPECT_EQ(kArcsecPerRad, 180.0 * 3600.0 / M_PI);
  EXPECT_EQ(kArcsecPerRad, 180.0 / M_PI * 3600.0);
  EXPECT_DOUBLE_EQ(kRadPerArcsec * kArcsecPerRad, 1.0);
}

TEST(Units, MedianOfOddEvenOneAndNone) {
  EXPECT_EQ(Median({3.0, 1.0, 2.0}), 2.0);
  EXPECT_EQ(Median({4.0, 1.0, 3.0, 2.0}), 2.5);  // the mean of the two middle values
  EXPECT_EQ(Median({7.0}), 7.0);
  EXPECT_TRUE(std::isnan(Median({})));
}

TEST(Units, UpperMedianIsTheElementAtHalfTheCount) {
  EXPECT_EQ(UpperMedian(std::vector<double>{3.0, 1.0, 2.0}), 2.0);
  EXPECT_EQ(UpperMedian(std::vector<double>{4.0, 1.0, 3.0, 2.0}), 3.0);  // the upper middle
  EXPECT_EQ(UpperMedian(std::vector<int64_t>{5}), 5);
  EXPECT_THROW(UpperMedian(std::vector<int64_t>{}), std::invalid_argument);
}

TEST(Units, ParsesLengthsAndDurations) {
  EXPECT_DOUBLE_EQ(ParseLengthM("5cm"), 0.05);
  EXPECT_DOUBLE_EQ(ParseLengthM("0.05m"), 0.05);
  EXPECT_DOUBLE_EQ(ParseLengthM("0.05"), 0.05);
  EXPECT_DOUBLE_EQ(ParseLengthM("50mm"), 0.05);
  EXPECT_DOUBLE_EQ(ParseLengthM("5CM"), 0.05);
  EXPECT_DOUBLE_EQ(ParseDurationS("10ms"), 0.010);
  EXPECT_DOUBLE_EQ(ParseDurationS("0.01s"), 0.010);
  EXPECT_DOUBLE_EQ(ParseDurationS("0.01"), 0.010);
  EXPECT_DOUBLE_EQ(ParseDurationS("10000us"), 0.010);
  EXPECT_DOUBLE_EQ(ParseDurationS("2s"), 2.0);
}

TEST(Units, BadLengthsAndDurationsNameTheText) {
  EXPECT_EQ(ErrorOf([] {
              ParseLengthM("5in");
            }).rfind("unknown length unit 'in' in '5in' (m, cm, mm)", 0),
            0u);
  EXPECT_EQ(ErrorOf([] { ParseLengthM("cm"); }).rfind("length 'cm' is not a number with a unit", 0),
            0u);
  EXPECT_EQ(ErrorOf([] {
              ParseDurationS("10min");
            }).rfind("unknown duration unit 'min' in '10min' (s, ms, us)", 0),
            0u);
  EXPECT_EQ(ErrorOf([] {
              ParseDurationS("ten ms");
            }).rfind("duration 'ten ms' is not a number with a unit", 0),
            0u);
}

}  // namespace
}  // namespace shutterlab
