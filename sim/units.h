#pragma once
// Small vocabularies used across the libraries: unit conversions, time spans, and a median.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace shutterlab {

// Angles. Each is written the way the libraries computed it before they shared one set, so every
// value is bit-identical to the local copies it replaced (180 / pi * 3600 == 180 * 3600 / pi).
inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kTwoPi = 2.0 * kPi;
inline constexpr double kRadPerDeg = kPi / 180.0;
inline constexpr double kDegPerRad = 180.0 / kPi;
inline constexpr double kArcsecPerRad = 180.0 / kPi * 3600.0;
inline constexpr double kRadPerArcsec = kPi / (180.0 * 3600.0);

// Metres along the ground per degree of latitude (the mean Earth radius, 6,371 km); a degree of
// longitude is this times cos(latitude). Over a photo-to-photo baseline the error is about 0.3 %.
inline constexpr double kMetresPerDegree = 6'371'000.0 * kPi / 180.0;

// The course of a horizontal velocity: degrees clockwise from north, in [0, 360).
inline double CourseDeg(double north_m_s, double east_m_s) {
  const double deg = std::atan2(east_m_s, north_m_s) * kDegPerRad;
  return deg >= 0 ? deg : std::fmod(deg + 360.0, 360.0);  // fmod: -1e-15 deg is 0, not 360
}

// Wall-clock seconds since start, for reports' timings.
inline double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// An instant on a log's clock for a message: "140.184 s" (ms resolution).
std::string SecondsText(int64_t t_ns);

// A quantity a person typed: "5cm", "30 ms", "400Hz", "2000dps", "-0.5deg/s". Returns it in `unit`,
// any unit of kUnits (m, s, Hz, deg, deg/s, m/s, ppm, ...); the text may carry any unit of the same
// dimension (case does not matter). A bare number is refused, 0 excepted (the same in every unit):
// `bare_means` is the unit a person most likely meant, so "--limit 5" is answered "did you mean
// 5cm?". `what` names the option. Throws std::invalid_argument, one line naming `what` and the
// text:
//   --limit '5': a length needs a unit: did you mean 5cm? (m, cm, mm, km)
double ParseQuantity(std::string_view text, std::string_view unit, std::string_view what,
                     std::string_view bare_means);

// The dimension of a unit: "length", "duration", "frequency", "angle", "angular rate", "speed",
// "ratio".
std::string DimensionOf(std::string_view unit);
// The dimension and the units it may be typed in ("length: m, cm, mm, km"), for help texts.
std::string UnitsOf(std::string_view unit);

// value in `from` converted to `to`, a unit of the same dimension (exact when they are one unit).
double ConvertUnit(double value, std::string_view from, std::string_view to);

// A value in `unit` as a person types it: "50m", "0.03s", "400Hz" (shortest round trip).
std::string QuantityText(double value, std::string_view unit);

// Median of values (a copy, reordered): the middle value for an odd count, the mean of the two
// middle values for an even count; NaN when empty.
double Median(std::vector<double> values);

// The value at sorted position size() / 2 (for an even count the upper of the two middle values),
// for callers that want a value that occurs in the data (a sampling interval, a residual).
// Throws std::invalid_argument when values is empty.
template <typename T>
T UpperMedian(std::vector<T> values) {
  if (values.empty()) throw std::invalid_argument("median of no values");
  const auto mid = values.begin() + values.size() / 2;
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

}  // namespace shutterlab
