#include "sim/civil_time.h"

#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace shutterlab {
namespace {

// Reads exactly `digits` decimal digits at text[*pos], advancing pos.
std::optional<int> Digits(std::string_view text, size_t* pos, int digits) {
  if (*pos + digits > text.size()) return std::nullopt;
  int value = 0;
  for (int i = 0; i < digits; ++i) {
    const char c = text[*pos + i];
    if (!std::isdigit(static_cast<unsigned char>(c))) return std::nullopt;
    value = value * 10 + (c - '0');
  }
  *pos += digits;
  return value;
}

bool Expect(std::string_view text, size_t* pos, std::string_view accepted) {
  if (*pos >= text.size() || accepted.find(text[*pos]) == std::string_view::npos) return false;
  ++*pos;
  return true;
}

std::string_view TrimSpaces(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\0')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\0')) s.remove_suffix(1);
  return s;
}

}  // namespace

std::optional<int> ParseUtcOffset(std::string_view text) {
  if (text == "Z") return 0;
  size_t pos = 0;
  if (!Expect(text, &pos, "+-")) return std::nullopt;
  const int sign = text[0] == '-' ? -1 : 1;
  const auto hours = Digits(text, &pos, 2);
  if (!hours || !Expect(text, &pos, ":")) return std::nullopt;
  const auto minutes = Digits(text, &pos, 2);
  if (!minutes || pos != text.size() || *hours > 14 || *minutes > 59) return std::nullopt;
  return sign * (*hours * 3600 + *minutes * 60);
}

namespace {

// UTC instants (s since 1970) from which GPS - UTC took the next value: 1 from 1981-07-01, ...,
// 18 from 2017-01-01 (IERS Bulletin C; the GPS epoch started at 0).
struct LeapStep {
  int year, month;
};
constexpr std::array<LeapStep, 18> kLeapSteps{{{1981, 7},
                                               {1982, 7},
                                               {1983, 7},
                                               {1985, 7},
                                               {1988, 1},
                                               {1990, 1},
                                               {1991, 1},
                                               {1992, 7},
                                               {1993, 7},
                                               {1994, 7},
                                               {1996, 1},
                                               {1997, 7},
                                               {1999, 1},
                                               {2006, 1},
                                               {2009, 1},
                                               {2012, 7},
                                               {2015, 7},
                                               {2017, 1}}};

int64_t LeapStepUnixS(const LeapStep& step) {
  return DaysFromCivil(step.year, static_cast<unsigned>(step.month), 1) * kSecondsPerDay;
}

}  // namespace

int64_t DaysFromCivil(int64_t year, unsigned month, unsigned day) {
  year -= month <= 2;
  const int64_t era = (year >= 0 ? year : year - 399) / 400;
  const unsigned yoe = static_cast<unsigned>(year - era * 400);
  const unsigned doy = (153 * (month > 2 ? month - 3 : month + 9) + 2) / 5 + day - 1;
  const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + static_cast<int64_t>(doe) - 719468;
}

std::optional<int64_t> ClockFace::UtcNs() const {
  if (!utc_offset_s) return std::nullopt;
  return face_ns - static_cast<int64_t>(*utc_offset_s) * kNsPerSecond;
}

std::optional<ClockFace> ParseExifDateTime(std::string_view date_time, std::string_view sub_second,
                                           std::string_view offset, std::string* problem) {
  const std::string_view text = TrimSpaces(date_time);
  auto fail = [&](const std::string& why) -> std::optional<ClockFace> {
    if (problem) *problem = why;
    return std::nullopt;
  };
  size_t pos = 0;
  const auto year = Digits(text, &pos, 4);
  const bool date_sep1 = Expect(text, &pos, ":-");
  const auto month = Digits(text, &pos, 2);
  const bool date_sep2 = Expect(text, &pos, ":-");
  const auto day = Digits(text, &pos, 2);
  const bool time_sep = Expect(text, &pos, " T");
  const auto hour = Digits(text, &pos, 2);
  const bool sep3 = Expect(text, &pos, ":");
  const auto minute = Digits(text, &pos, 2);
  const bool sep4 = Expect(text, &pos, ":");
  const auto second = Digits(text, &pos, 2);
  if (!year || !month || !day || !hour || !minute || !second || !date_sep1 || !date_sep2 ||
      !time_sep || !sep3 || !sep4 || pos != text.size()) {
    return fail("date and time '" + std::string(date_time) +
                "' is not 'YYYY:MM:DD HH:MM:SS' (blank or unknown)");
  }
  if (*month < 1 || *month > 12 || *day < 1 || *day > 31 || *hour > 23 || *minute > 59 ||
      *second > 60 || *year < 1900 || *year > 2200) {  // int64 ns spans 1677..2262
    return fail("date and time '" + std::string(date_time) + "' is out of range");
  }
  ClockFace face;
  face.face_ns = (DaysFromCivil(*year, static_cast<unsigned>(*month), static_cast<unsigned>(*day)) *
                      kSecondsPerDay +
                  *hour * 3600 + *minute * 60 + *second) *
                 kNsPerSecond;
  const std::string_view fraction = TrimSpaces(sub_second);
  if (!fraction.empty()) {
    if (fraction.size() > 9 || fraction.find_first_not_of("0123456789") != std::string_view::npos) {
      return fail("sub-second time '" + std::string(sub_second) + "' is not digits");
    }
    int64_t ns = 0;
    for (size_t i = 0; i < 9; ++i) ns = ns * 10 + (i < fraction.size() ? fraction[i] - '0' : 0);
    face.face_ns += ns;
    face.resolution_s = std::pow(10.0, -static_cast<double>(fraction.size()));
  }
  const std::string_view zone = TrimSpaces(offset);
  if (!zone.empty()) {
    face.utc_offset_s = ParseUtcOffset(zone);
    if (!face.utc_offset_s)
      return fail("time offset '" + std::string(offset) + "' is not '+HH:MM'");
  }
  return face;
}

std::string UtcText(int64_t t_ns) {
  int64_t s = t_ns >= 0 ? t_ns / kNsPerSecond : -((-t_ns + kNsPerSecond - 1) / kNsPerSecond);
  const int64_t ms = (t_ns - s * kNsPerSecond) / 1'000'000;
  int64_t days = s >= 0 ? s / kSecondsPerDay : -((-s + kSecondsPerDay - 1) / kSecondsPerDay);
  const int64_t secs_of_day = s - days * kSecondsPerDay;
  // civil_from_days (Hinnant), inverse of DaysFromCivil.
  days += 719468;
  const int64_t era = (days >= 0 ? days : days - 146096) / 146097;
  const unsigned doe = static_cast<unsigned>(days - era * 146097);
  const unsigned yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
  const unsigned doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
  const unsigned mp = (5 * doy + 2) / 153;
  const unsigned day = doy - (153 * mp + 2) / 5 + 1;
  const unsigned month = mp < 10 ? mp + 3 : mp - 9;
  const int64_t year = static_cast<int64_t>(yoe) + era * 400 + (month <= 2);
  char text[64];
  std::snprintf(text, sizeof text, "%04lld-%02u-%02u %02lld:%02lld:%02lld.%03lld",
                static_cast<long long>(year), month, day,
                static_cast<long long>(secs_of_day / 3600),
                static_cast<long long>(secs_of_day / 60 % 60),
                static_cast<long long>(secs_of_day % 60), static_cast<long long>(ms));
  return text;
}

std::string UtcOffsetText(int offset_s) {
  char text[16];
  const int a = std::abs(offset_s);
  std::snprintf(text, sizeof text, "%c%02d:%02d", offset_s < 0 ? '-' : '+', a / 3600, a / 60 % 60);
  return text;
}

int LeapSecondsAtUtc(int64_t utc_ns) {
  int leap = 0;
  for (const LeapStep& step : kLeapSteps) {
    if (utc_ns >= LeapStepUnixS(step) * kNsPerSecond) ++leap;
  }
  return leap;
}

int64_t UtcFromGpsNs(int64_t gps_ns) {
  const int64_t unix_gps_ns = gps_ns + kGpsEpochUnixS * kNsPerSecond;
  // GPS - UTC at the UTC instant itself: try the leap count of the GPS instant, then one less
  // (within a leap second of a step).
  int leap = LeapSecondsAtUtc(unix_gps_ns);
  while (leap > 0 && LeapSecondsAtUtc(unix_gps_ns - leap * kNsPerSecond) < leap) --leap;
  return unix_gps_ns - static_cast<int64_t>(leap) * kNsPerSecond;
}

int64_t GpsNsFromWeek(int64_t week, double seconds_of_week) {
  const double whole = std::floor(seconds_of_week);
  return (week * kSecondsPerWeek + static_cast<int64_t>(whole)) * kNsPerSecond +
         std::llround((seconds_of_week - whole) * 1e9);
}

}  // namespace shutterlab
