#pragma once
// Small vocabularies used across the libraries: unit conversions, time spans, and a median.

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <stdexcept>
#include <string>
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

// Wall-clock seconds since start, for reports' timings.
inline double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// An instant on a log's clock for a message: "140.184 s" (ms resolution).
std::string SecondsText(int64_t t_ns);

// "5cm", "50mm", "0.05m", "0.05" (metres) -> metres. Throws std::invalid_argument
// naming the text otherwise.
double ParseLengthM(const std::string& text);
// "10ms", "0.01s", "10000us", "0.01" (seconds) -> seconds. Throws std::invalid_argument
// naming the text otherwise.
double ParseDurationS(const std::string& text);

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
