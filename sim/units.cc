#include "sim/units.h"

#include "sim/check.h"
#include "sim/text_file.h"

#include <cctype>
#include <cstdio>
#include <limits>
#include <string_view>
#include <utility>

namespace shutterlab {
namespace {

std::pair<double, std::string> SplitNumberUnit(const std::string& text, const char* what) {
  size_t split = text.size();
  while (split > 0 && std::isalpha(static_cast<unsigned char>(text[split - 1]))) --split;
  const auto value = ParseDouble(std::string_view(text).substr(0, split));
  SHUTTERLAB_CHECK(value.has_value()) << what << " '" << text << "' is not a number with a unit";
  return {*value, ToLower(text.substr(split))};
}

}  // namespace

std::string SecondsText(int64_t t_ns) {
  char text[48];
  std::snprintf(text, sizeof text, "%.3f s", static_cast<double>(t_ns) * 1e-9);
  return text;
}

double ParseLengthM(const std::string& text) {
  const auto [value, unit] = SplitNumberUnit(text, "length");
  double scale = 0;
  if (unit.empty() || unit == "m")
    scale = 1.0;
  else if (unit == "cm")
    scale = 0.01;
  else if (unit == "mm")
    scale = 0.001;
  SHUTTERLAB_CHECK(scale > 0) << "unknown length unit '" << unit << "' in '" << text
                              << "' (m, cm, mm)";
  return value * scale;
}

double ParseDurationS(const std::string& text) {
  const auto [value, unit] = SplitNumberUnit(text, "duration");
  double scale = 0;
  if (unit.empty() || unit == "s")
    scale = 1.0;
  else if (unit == "ms")
    scale = 1e-3;
  else if (unit == "us")
    scale = 1e-6;
  SHUTTERLAB_CHECK(scale > 0) << "unknown duration unit '" << unit << "' in '" << text
                              << "' (s, ms, us)";
  return value * scale;
}

double Median(std::vector<double> values) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  const size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + mid, values.end());
  const double upper = values[mid];
  if (values.size() % 2 == 1) return upper;
  const double lower = *std::max_element(values.begin(), values.begin() + mid);
  return 0.5 * (lower + upper);
}

}  // namespace shutterlab
