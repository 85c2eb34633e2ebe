#pragma once
// A photo folder with its flight's log, as `analyze --photos LOG` places it (by capture time
// through the log's GPS time): the case tests/app/photos_cli_test.cc checks in detail and the
// batch tests run as one item of a fleet.

#include "sim/civil_time.h"
#include "sim/gyro_trace.h"
#include "sim/logs/ulog_write.h"
#include "sim/text_file.h"
#include "tests/io/photo_fixtures.h"

#include <Eigen/Core>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace shutterlab::test {

// 2024-07-16 01:00:00 UTC: the UTC time of the log's clock zero.
inline constexpr int64_t kPlacedFlightUtcAtLogZeroNs = 1'721'091'600'000'000'000;

// Writes FOLDER/flight.ulg (40 s at 200 Hz: still for 5 s, then a 0.7 Hz roll of 0.2 rad/s; a
// GPS time every second; a camera event at 10, 12, ..., 18 s) and FOLDER/photos/DJI_000K.JPG,
// K = 1..5: nadir DJI photos, 400 x 300, 24 mm equivalent, at 100 m and 5 m/s north, their camera
// clock on UTC+8, each taken error_ms[K-1] ms after its event. Returns the events.
inline std::vector<CameraEvent> WritePlacedFlight(const std::string& folder,
                                                  const int (&error_ms)[5]) {
  std::vector<GyroSample> samples;
  for (int i = 0; i < 40 * 200; ++i) {
    const double t_s = i / 200.0;
    const double wx = t_s < 5.0 ? 0.0 : 0.2 * std::sin(2.0 * M_PI * 0.7 * t_s);
    samples.push_back({5'000'000 + i * 5'000'000LL, Eigen::Vector3d(wx, 0.0, 0.0)});
  }
  std::vector<CameraEvent> events;
  for (int k = 0; k < 5; ++k) events.push_back({10'000'000'000 + k * 2'000'000'000LL, k, ""});
  ULogWriteOptions options;
  for (int k = 1; k < 40; ++k) {
    options.utc_fixes.push_back(
        {k * 1'000'000'000LL, kPlacedFlightUtcAtLogZeroNs + k * 1'000'000'000LL});
  }
  std::filesystem::create_directories(folder + "/photos");
  WriteULog(folder + "/flight.ulg", GyroTrace(samples), events, options);
  for (int k = 0; k < 5; ++k) {
    const int64_t face_ns = kPlacedFlightUtcAtLogZeroNs + events[k].t_ns + 8 * 3'600'000'000'000LL +
                            error_ms[k] * 1'000'000LL;
    FixturePhoto p;
    p.width = 400;
    p.height = 300;
    p.focal_length_35mm = 24;
    const int64_t s = face_ns / 1'000'000'000;
    const int ms = static_cast<int>(face_ns / 1'000'000 % 1000);
    p.date_time_original = UtcText(s * 1'000'000'000).substr(0, 19);  // "2024-07-16 09:00:10"
    p.date_time_original[4] = p.date_time_original[7] = ':';          // EXIF's "2024:07:16"
    p.sub_sec_time_original = FormatNumber("%03.0f", ms);
    p.xmp = DjiXmp({{"RelativeAltitude", "+100.0"},
                    {"GimbalPitchDegree", "-90.0"},
                    {"GimbalRollDegree", "0.0"},
                    {"GimbalYawDegree", "0.0"},
                    {"FlightXSpeed", "5.0"},
                    {"FlightYSpeed", "0.0"},
                    {"FlightZSpeed", "0.0"}},
                   false);
    WriteFileAtomically(folder + "/photos/DJI_000" + std::to_string(k + 1) + ".JPG",
                        JpegWithMetadata(p));
  }
  return events;
}

}  // namespace shutterlab::test
