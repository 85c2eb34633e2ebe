#pragma once
// Whether two reads of a log agree in everything a command prints: the streamed readers' twin tests
// (chunked against uninterrupted, streamed against whole) compare with this.

#include "sim/logs/flight_log.h"

#include <gtest/gtest.h>

#include <cstring>
#include <string>

namespace shutterlab::test {

// Every field of a and b equal: rates bit for bit (memcmp: -0 and NaN payloads count), warnings
// with their times and counts, events, fixes and altitude.
inline void ExpectSameLog(const FlightLog& a, const FlightLog& b, const std::string& what) {
  EXPECT_EQ(a.format, b.format) << what;
  EXPECT_EQ(a.gyro_source, b.gyro_source) << what;
  EXPECT_EQ(a.gyro_sources_available, b.gyro_sources_available) << what;
  EXPECT_EQ(a.records_skipped, b.records_skipped) << what;
  ASSERT_EQ(a.warnings.size(), b.warnings.size()) << what;
  for (size_t i = 0; i < a.warnings.size(); ++i) {
    EXPECT_EQ(a.warnings[i].kind, b.warnings[i].kind) << what;
    EXPECT_EQ(a.warnings[i].message, b.warnings[i].message) << what;
    EXPECT_EQ(a.warnings[i].t_s, b.warnings[i].t_s) << what;
    EXPECT_EQ(a.warnings[i].count, b.warnings[i].count) << what;
  }
  ASSERT_EQ(a.camera_events.size(), b.camera_events.size()) << what;
  for (size_t i = 0; i < a.camera_events.size(); ++i) {
    EXPECT_EQ(a.camera_events[i].t_ns, b.camera_events[i].t_ns) << what;
    EXPECT_EQ(a.camera_events[i].sequence, b.camera_events[i].sequence) << what;
    EXPECT_EQ(a.camera_events[i].kind, b.camera_events[i].kind) << what;
  }
  ASSERT_EQ(a.utc_fixes.size(), b.utc_fixes.size()) << what;
  EXPECT_EQ(a.altitude_above_ground_m, b.altitude_above_ground_m) << what;
  EXPECT_EQ(a.altitude_source, b.altitude_source) << what;
  ASSERT_EQ(a.gyro.size(), b.gyro.size()) << what;
  for (size_t i = 0; i < a.gyro.size(); ++i) {
    ASSERT_EQ(a.gyro[i].t_ns, b.gyro[i].t_ns) << what << " sample " << i;
    ASSERT_EQ(
        std::memcmp(a.gyro[i].omega_rad_s.data(), b.gyro[i].omega_rad_s.data(), 3 * sizeof(double)),
        0)
        << what << " sample " << i;
  }
}

}  // namespace shutterlab::test
