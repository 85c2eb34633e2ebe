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

TEST(Units, CourseIsClockwiseFromNorthWithinOneTurn) {
  EXPECT_EQ(CourseDeg(1.0, 0.0), 0.0);
  EXPECT_NEAR(CourseDeg(0.0, 2.0), 90.0, 1e-12);
  EXPECT_NEAR(CourseDeg(-3.0, 0.0), 180.0, 1e-12);
  EXPECT_NEAR(CourseDeg(0.0, -0.5), 270.0, 1e-12);
  EXPECT_NEAR(CourseDeg(3.0, -4.0), 360.0 - std::atan2(4.0, 3.0) * 180.0 / M_PI, 1e-12);
  // Just west of north: a course a hair below 360 that must not print as 360.
  EXPECT_EQ(CourseDeg(1.0, -1e-20), 0.0);
  EXPECT_LT(CourseDeg(1.0, -1e-9), 360.0);
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

TEST(Units, QuantitiesConvertToTheUnitAsked) {
  const auto length_m = [](const char* text) { return ParseQuantity(text, "m", "--x", "cm"); };
  EXPECT_DOUBLE_EQ(length_m("5cm"), 0.05);
  EXPECT_DOUBLE_EQ(length_m("0.05m"), 0.05);
  EXPECT_DOUBLE_EQ(length_m("50mm"), 0.05);
  EXPECT_DOUBLE_EQ(length_m("5CM"), 0.05);
  EXPECT_DOUBLE_EQ(length_m(" 5 cm "), 0.05);
  EXPECT_DOUBLE_EQ(length_m("0.2km"), 200.0);
  const auto duration_s = [](const char* text) { return ParseQuantity(text, "s", "--x", "ms"); };
  EXPECT_DOUBLE_EQ(duration_s("10ms"), 0.010);
  EXPECT_DOUBLE_EQ(duration_s("0.01s"), 0.010);
  EXPECT_DOUBLE_EQ(duration_s("10000us"), 0.010);
  EXPECT_DOUBLE_EQ(duration_s("10000\xC2\xB5s"), 0.010);
  EXPECT_DOUBLE_EQ(duration_s("2min"), 120.0);
  EXPECT_DOUBLE_EQ(duration_s("1e-3s"), 0.001);
  EXPECT_DOUBLE_EQ(duration_s("-2.5ms"), -0.0025);
  EXPECT_DOUBLE_EQ(ParseQuantity("30ms", "ms", "--x", "ms"), 30.0);
  EXPECT_DOUBLE_EQ(ParseQuantity("2kHz", "Hz", "--x", "Hz"), 2000.0);
  EXPECT_DOUBLE_EQ(ParseQuantity("36km/h", "m/s", "--x", "m/s"), 10.0);
  EXPECT_DOUBLE_EQ(ParseQuantity("3600arcsec", "deg", "--x", "deg"), 1.0);
  EXPECT_DOUBLE_EQ(ParseQuantity("180deg", "rad", "--x", "deg"), kPi);
  EXPECT_DOUBLE_EQ(ParseQuantity("300ppm", "ppm", "--x", "ppm"), 300.0);
  // A whole number of a decimal prefix divides: the same double as the literal in SI, so a
  // script's `time_offset=4ms` injects what `time_offset=0.004` did.
  EXPECT_EQ(duration_s("4ms"), 0.004);
  EXPECT_EQ(duration_s("36ms"), 0.036);
  EXPECT_EQ(duration_s("23.5ms"), 0.0235);
  EXPECT_EQ(length_m("5cm"), 0.05);
  // The unit asked converts exactly: a gyro's full scale stays a whole number of deg/s.
  EXPECT_EQ(ParseQuantity("2000deg/s", "deg/s", "--x", "deg/s"), 2000.0);
  EXPECT_EQ(ParseQuantity("2000dps", "deg/s", "--x", "deg/s"), 2000.0);
  EXPECT_DOUBLE_EQ(ParseQuantity("1rad/s", "deg/s", "--x", "deg/s"), kDegPerRad);
}

TEST(Units, ZeroNeedsNoUnit) {
  EXPECT_EQ(ParseQuantity("0", "s", "--x", "ms"), 0.0);
  EXPECT_EQ(ParseQuantity("0.0", "m", "--x", "cm"), 0.0);
}

TEST(Units, ABareNumberIsRefusedWithWhatItProbablyMeant) {
  EXPECT_EQ(ErrorOf([] { ParseQuantity("5", "m", "--limit", "cm"); }),
            "--limit '5': a length needs a unit: did you mean 5cm or 5m? (m, cm, mm, km)");
  EXPECT_EQ(
      ErrorOf([] { ParseQuantity("30", "s", "--readout", "ms"); }),
      "--readout '30': a duration needs a unit: did you mean 30ms or 30s? (s, ms, us, ns, min, h)");
  EXPECT_EQ(ErrorOf([] { ParseQuantity("400", "Hz", "--rate", "Hz"); }),
            "--rate '400': a frequency needs a unit: did you mean 400Hz? (Hz, kHz)");
}

TEST(Units, AWrongOrUnknownUnitIsNamed) {
  EXPECT_EQ(ErrorOf([] { ParseQuantity("5in", "m", "--limit", "cm"); }),
            "--limit '5in': unknown unit 'in' for a length (m, cm, mm, km)");
  EXPECT_EQ(ErrorOf([] { ParseQuantity("5ms", "m", "--limit", "cm"); }),
            "--limit '5ms': ms is a unit of duration, --limit takes a length (m, cm, mm, km)");
  EXPECT_EQ(ErrorOf([] { ParseQuantity("cm", "m", "--limit", "cm"); }),
            "--limit 'cm': expected a length, a number and a unit, e.g. 5cm (m, cm, mm, km)");
  EXPECT_EQ(ErrorOf([] { ParseQuantity("ten ms", "s", "--every", "s"); }),
            "--every 'ten ms': expected a duration, a number and a unit, e.g. 5s (s, ms, us, ns, "
            "min, h)");
  EXPECT_THROW(ParseQuantity("inf s", "s", "--x", "s"), std::invalid_argument);
  EXPECT_THROW(ParseQuantity("", "s", "--x", "s"), std::invalid_argument);
}

TEST(Units, QuantityTextIsWhatParsesBack) {
  EXPECT_EQ(QuantityText(50.0, "m"), "50m");
  EXPECT_EQ(QuantityText(0.03, "s"), "0.03s");
  EXPECT_EQ(ParseQuantity(QuantityText(0.1 + 0.2, "s"), "s", "--x", "s"), 0.1 + 0.2);
  EXPECT_EQ(UnitsOf("ms"), "duration: s, ms, us, ns, min, h");
}

}  // namespace
}  // namespace shutterlab
