#pragma once
// Calendar dates and clock faces as int64 nanoseconds, and GPS time against UTC: what photos
// (EXIF DateTimeOriginal), trigger files (GPS week and seconds of week) and flight logs (GPS fixes)
// write down, brought onto one time line. No time zone database: an offset is either written in
// the file (EXIF OffsetTimeOriginal) or found by the caller.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace shutterlab {

inline constexpr int64_t kNsPerSecond = 1'000'000'000;
inline constexpr int64_t kSecondsPerDay = 86'400;
inline constexpr int64_t kSecondsPerWeek = 604'800;
// The GPS epoch, 1980-01-06 00:00:00 UTC, in seconds since 1970-01-01 (no leap seconds counted
// before it).
inline constexpr int64_t kGpsEpochUnixS = 315'964'800;

// Days since 1970-01-01 of a proleptic Gregorian date (month 1..12, day 1..31). Howard Hinnant,
// "chrono-Compatible Low-Level Date Algorithms", days_from_civil (public domain).
int64_t DaysFromCivil(int64_t year, unsigned month, unsigned day);

// A clock face: a calendar date and time of day without a time zone, as cameras write it
// (EXIF 2.32 DateTimeOriginal "YYYY:MM:DD HH:MM:SS", SubSecTimeOriginal, OffsetTimeOriginal).
struct ClockFace {
  // The date and time read as if they were UTC, ns since 1970-01-01, the fraction of a second
  // included. Equals the UTC instant only when utc_offset_s is 0.
  int64_t face_ns = 0;
  // The zone the face is in, seconds east of UTC ("+08:00" -> 28800), when the file says so.
  std::optional<int> utc_offset_s;
  // The face's resolution: 1 s without a fraction, 10^-digits with one.
  double resolution_s = 1.0;
  // The UTC instant: face_ns - utc_offset_s, or nullopt without an offset.
  std::optional<int64_t> UtcNs() const;
};

// Parses EXIF's "YYYY:MM:DD HH:MM:SS" (also with '-' between date fields, or 'T' before the time),
// an optional fraction (sub_second: the digits of SubSecTimeOriginal, e.g. "07" = 0.07 s; spaces
// and an empty field mean none) and an optional offset ("+08:00", "-05:30", "Z"; empty = none).
// nullopt with *problem set (one line naming the text) when a part cannot be read: a blank face
// ("    :  :     :  :  ", as some cameras write for "unknown"), a date out of range, ...
std::optional<ClockFace> ParseExifDateTime(std::string_view date_time, std::string_view sub_second,
                                           std::string_view offset, std::string* problem);

// "+08:00", "-05:30", "Z" -> seconds east of UTC; nullopt when the text is not one.
std::optional<int> ParseUtcOffset(std::string_view text);

// "2024-07-16 09:41:37.250" (UTC, ms) for t_ns since 1970-01-01; "+08:00" style for an offset.
std::string UtcText(int64_t t_ns);
std::string UtcOffsetText(int offset_s);

// GPS - UTC at a UTC instant, whole seconds (leap seconds since the GPS epoch: 0 before
// 1981-07-01, 18 since 2017-01-01). The table ends with the leap second of 2016-12-31; a later one
// (none announced as of 2025) would need a new row.
int LeapSecondsAtUtc(int64_t utc_ns);
// GPS time (ns since the GPS epoch, no leap seconds) -> UTC ns since 1970-01-01.
int64_t UtcFromGpsNs(int64_t gps_ns);
// GPS week and seconds of week -> GPS ns since the GPS epoch.
int64_t GpsNsFromWeek(int64_t week, double seconds_of_week);

}  // namespace shutterlab
