#include "sim/units.h"

#include "sim/check.h"
#include "sim/text_file.h"

#include <cctype>
#include <cstdio>
#include <limits>
#include <optional>
#include <string_view>

namespace shutterlab {
namespace {

enum class Dimension {
  kLength,
  kDuration,
  kFrequency,
  kAngle,
  kAngularRate,
  kSpeed,
  kRatio,
  kRateNoiseDensity,  // white rate noise (angle random walk)
  kRateRandomWalk,
  kDataSize,  // memory and files, in bytes
};

const char* DimensionNoun(Dimension dimension) {
  switch (dimension) {
    case Dimension::kLength:
      return "length";
    case Dimension::kDuration:
      return "duration";
    case Dimension::kFrequency:
      return "frequency";
    case Dimension::kAngle:
      return "angle";
    case Dimension::kAngularRate:
      return "angular rate";
    case Dimension::kSpeed:
      return "speed";
    case Dimension::kRatio:
      return "ratio";
    case Dimension::kRateNoiseDensity:
      return "rate noise density";
    case Dimension::kRateRandomWalk:
      return "rate random walk";
    case Dimension::kDataSize:
      return "data size";
  }
  return "quantity";
}

// A unit is `numerator / denominator` of its SI unit (m, s, Hz, rad, rad/s, m/s, 1, ...), kept as
// two numbers so that decimal prefixes convert by a division: 4ms is 4 / 1000 s, the double
// nearest 0.004, as the literal 0.004 is.
struct Unit {
  const char* name;  // as typed (matched ignoring case)
  Dimension dimension;
  double numerator;
  double denominator;
  bool listed;  // named in messages (an alias like "dps" is accepted but not listed)
};

constexpr Unit kUnits[] = {
    {"m", Dimension::kLength, 1, 1, true},
    {"cm", Dimension::kLength, 1, 1e2, true},
    {"mm", Dimension::kLength, 1, 1e3, true},
    {"km", Dimension::kLength, 1e3, 1, true},
    {"s", Dimension::kDuration, 1, 1, true},
    {"ms", Dimension::kDuration, 1, 1e3, true},
    {"us", Dimension::kDuration, 1, 1e6, true},
    {"\xC2\xB5s", Dimension::kDuration, 1, 1e6, false},  // µs
    {"ns", Dimension::kDuration, 1, 1e9, true},
    {"min", Dimension::kDuration, 60, 1, true},
    {"h", Dimension::kDuration, 3600, 1, true},
    {"Hz", Dimension::kFrequency, 1, 1, true},
    {"kHz", Dimension::kFrequency, 1e3, 1, true},
    {"deg", Dimension::kAngle, kPi, 180, true},
    {"\xC2\xB0", Dimension::kAngle, kPi, 180, false},  // °
    {"rad", Dimension::kAngle, 1, 1, true},
    {"mrad", Dimension::kAngle, 1, 1e3, true},
    {"arcsec", Dimension::kAngle, kPi, 180 * 3600, true},
    {"deg/s", Dimension::kAngularRate, kPi, 180, true},
    {"dps", Dimension::kAngularRate, kPi, 180, false},
    {"\xC2\xB0/s", Dimension::kAngularRate, kPi, 180, false},
    {"rad/s", Dimension::kAngularRate, 1, 1, true},
    {"m/s", Dimension::kSpeed, 1, 1, true},
    {"km/h", Dimension::kSpeed, 1, 3.6, true},
    {"ppm", Dimension::kRatio, 1, 1e6, true},
    // rtHz: the datasheets' spelling, and no parentheses for a shell to read.
    {"rad/s/rtHz", Dimension::kRateNoiseDensity, 1, 1, true},
    {"deg/s/rtHz", Dimension::kRateNoiseDensity, kPi, 180, true},
    {"deg/h/rtHz", Dimension::kRateNoiseDensity, kPi, 180 * 3600, true},
    {"rad/s/sqrt(Hz)", Dimension::kRateNoiseDensity, 1, 1, false},
    {"deg/s/sqrt(Hz)", Dimension::kRateNoiseDensity, kPi, 180, false},
    {"rad/s^2/rtHz", Dimension::kRateRandomWalk, 1, 1, true},
    {"deg/s^2/rtHz", Dimension::kRateRandomWalk, kPi, 180, true},
    {"rad/s^2/sqrt(Hz)", Dimension::kRateRandomWalk, 1, 1, false},
    // Binary prefixes, as free(1) and Slurm's --mem (whose M and G are MiB and GiB) count memory.
    {"B", Dimension::kDataSize, 1, 1, true},
    {"KiB", Dimension::kDataSize, 1024, 1, true},
    {"MiB", Dimension::kDataSize, 1024.0 * 1024, 1, true},
    {"GiB", Dimension::kDataSize, 1024.0 * 1024 * 1024, 1, true},
};

const Unit* FindUnit(std::string_view name) {
  const std::string lower = ToLower(name);
  for (const Unit& unit : kUnits) {
    if (ToLower(unit.name) == lower) return &unit;
  }
  return nullptr;
}

const Unit& RequireUnit(std::string_view name) {
  const Unit* unit = FindUnit(name);
  SHUTTERLAB_CHECK(unit != nullptr) << "no unit '" << name << "' in the unit table";
  return *unit;
}

std::string UnitList(Dimension dimension) {
  std::string list;
  for (const Unit& unit : kUnits) {
    if (unit.dimension != dimension || !unit.listed) continue;
    if (!list.empty()) list += ", ";
    list += unit.name;
  }
  return list;
}

// The length of the number at the start of text: sign, digits, point, exponent (what
// ParseDouble reads); the rest is the unit.
size_t NumberLength(std::string_view text) {
  size_t i = 0;
  const auto digits = [&] {
    while (i < text.size() && std::isdigit(static_cast<unsigned char>(text[i]))) ++i;
  };
  if (i < text.size() && (text[i] == '+' || text[i] == '-')) ++i;
  digits();
  if (i < text.size() && text[i] == '.') {
    ++i;
    digits();
  }
  if (i + 1 < text.size() && (text[i] == 'e' || text[i] == 'E')) {
    size_t exponent = i + 1;
    if (text[exponent] == '+' || text[exponent] == '-') ++exponent;
    if (exponent < text.size() && std::isdigit(static_cast<unsigned char>(text[exponent]))) {
      i = exponent;
      digits();
    }
  }
  return i;
}

std::string_view Trimmed(std::string_view text) {
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.front())))
    text.remove_prefix(1);
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back())))
    text.remove_suffix(1);
  return text;
}

}  // namespace

double ParseQuantity(std::string_view text, std::string_view unit, std::string_view what,
                     std::string_view bare_means) {
  const Unit& to = RequireUnit(unit);
  const std::string noun = DimensionNoun(to.dimension);
  const std::string units = "(" + UnitList(to.dimension) + ")";
  const std::string said = std::string(what) + " '" + std::string(text) + "': ";
  const std::string_view trimmed = Trimmed(text);
  const size_t number_length = NumberLength(trimmed);
  const std::optional<double> number = ParseDouble(trimmed.substr(0, number_length));
  if (!number) {
    throw std::invalid_argument(said + "expected a " + noun + ", a number and a unit, e.g. 5" +
                                std::string(bare_means) + " " + units);
  }
  const std::string_view typed_unit = Trimmed(trimmed.substr(number_length));
  if (typed_unit.empty()) {
    if (*number == 0.0) return 0.0;
    // A bare length or duration used to be read in metres or seconds: an old script's number is
    // offered that reading too, so that following the hint never scales it by 100 or 1000.
    const char* si = to.dimension == Dimension::kLength     ? "m"
                     : to.dimension == Dimension::kDuration ? "s"
                                                            : "";
    std::string meant = std::string(trimmed) + std::string(bare_means);
    if (*si != '\0' && bare_means != si) meant += " or " + std::string(trimmed) + si;
    throw std::invalid_argument(said + "a " + noun + " needs a unit: did you mean " + meant + "? " +
                                units);
  }
  const Unit* from = FindUnit(typed_unit);
  if (from == nullptr) {
    throw std::invalid_argument(said + "unknown unit '" + std::string(typed_unit) + "' for a " +
                                noun + " " + units);
  }
  if (from->dimension != to.dimension) {
    throw std::invalid_argument(said + std::string(typed_unit) + " is a unit of " +
                                DimensionNoun(from->dimension) + ", " + std::string(what) +
                                " takes a " + noun + " " + units);
  }
  // The same unit converts exactly (a ratio of 1), so "2000deg/s" stays 2000 in deg/s.
  return ConvertUnit(*number, from->name, to.name);
}

std::string DimensionOf(std::string_view unit) {
  return DimensionNoun(RequireUnit(unit).dimension);
}

std::string UnitsOf(std::string_view unit) {
  const Unit& to = RequireUnit(unit);
  return std::string(DimensionNoun(to.dimension)) + ": " + UnitList(to.dimension);
}

double ConvertUnit(double value, std::string_view from, std::string_view to) {
  const Unit& a = RequireUnit(from);
  const Unit& b = RequireUnit(to);
  SHUTTERLAB_CHECK(a.dimension == b.dimension) << "cannot convert " << from << " to " << to;
  if (a.numerator == b.numerator && a.denominator == b.denominator) return value;  // an alias
  return value * a.numerator * b.denominator / (a.denominator * b.numerator);
}

std::string QuantityText(double value, std::string_view unit) {
  std::string text;
  AppendDouble(value, &text);
  return text + std::string(unit);
}

std::string SecondsText(int64_t t_ns) {
  char text[48];
  std::snprintf(text, sizeof text, "%.3f s", static_cast<double>(t_ns) * 1e-9);
  return text;
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
