#pragma once
// Small vocabularies used across the libraries: unit conversions, time spans, and a median.

#include <algorithm>
#include <chrono>
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

}  // namespace shutterlab
