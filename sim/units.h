#pragma once
// Small vocabularies used across the libraries: unit conversions, time spans, and a median.

#include <algorithm>
#include <chrono>
#include <vector>

namespace shutterlab {

// Wall-clock seconds since start, for reports' timings.
inline double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace shutterlab
