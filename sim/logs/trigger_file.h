#pragma once
// One reader for every file that says when photos were taken, told apart by content:
//  - DJI / Autel `.MRK` timestamp files (Phantom 4 RTK, Matrice, Mavic 3 Enterprise, Autel EVO II
//    RTK): one line a photo, tab-separated: photo number, GPS time of week (s), "[GPS week]", the
//    antenna-to-sensor offsets "n,N" "e,E" "v,V" (mm), "lat,Lat" "lon,Lon" "h,Ellh" (deg, deg,
//    ellipsoidal m), the position's standard deviations "sn, se, sv" (m) and "q,Q" (the fix:
//    50 = RTK fixed). Times are GPS time (DJI's user manuals, "Image Log File").
//  - A plain CSV: "t" or "image,t" without a header (seconds on the log's clock), or a header that
//    names an image column (image, name, file) and one time column: t / time / t_s (s), t_ms,
//    t_us, t_ns, timestamp (us, PX4's boot time) on the log's clock, or utc_usec (us since 1970)
//    / utc ("2026-01-13 03:04:17.875381+00:00") in UTC. Other columns are left alone.
//  - A flight log with camera events: PX4 ULog camera_capture / camera_trigger, ArduPilot
//    DataFlash CAM / TRIG (sim/logs/flight_log_io.h), on that log's clock.

#include "sim/gyro_sync.h"
#include "sim/gyro_trace.h"
#include "sim/log_warning.h"

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace shutterlab {

// The time line a trigger file's times are on.
enum class TriggerClock {
  kLog,  // a flight log's own clock (its boot time), as the gyro trace of that log
  kGps,  // GPS time: ns since 1980-01-06 00:00:00, no leap seconds (sim/civil_time.h)
  kUtc,  // UTC: ns since 1970-01-01
};
// "log clock", "GPS time", "UTC".
const char* TriggerClockName(TriggerClock clock);

struct TriggerEvent {
  int64_t t_ns = 0;       // on TriggerFile::clock
  int64_t sequence = -1;  // the file's photo number or sequence; -1 when it has none
  std::string name;       // the image's name when the file gives one
  // MRK: the camera's position at the exposure (deg, deg, m above the ellipsoid).
  std::optional<double> latitude_deg, longitude_deg, height_m;
};

struct TriggerFile {
  std::string format;  // "mrk", "csv", or the log's format ("ulog", "dataflash", ...)
  TriggerClock clock = TriggerClock::kLog;
  std::string source;  // where in the file the times came from, e.g. "camera events (CAM)"
  std::vector<TriggerEvent> events;  // in file order
  std::vector<LogWarning> warnings;  // what was skipped or doubted
};

// Reads any trigger file above by its content. Throws IoError("PATH:LINE: problem") on a file it
// cannot read or that holds no event.
TriggerFile ReadTriggerFile(const std::string& path);

// Triggers recorded on another gyro's clock (record's triggers file, on its .gcsv's clock) put on a
// log's: the two gyros aligned from the motion (sim/gyro_sync.h SyncGyros(log, clock_gyro)), each
// event's time mapped, and `source` extended to say so. Throws std::invalid_argument in one line
// when the file's times are GPS or UTC (no gyro's clock) or the gyros cannot be aligned.
GyroSync MoveTriggersToLogClock(const GyroTrace& log_gyro, const GyroTrace& clock_gyro,
                                const std::string& clock_name, TriggerFile* file);

// The parsers, on text already read; path is for messages.
bool LooksLikeMrk(std::string_view text);
TriggerFile ParseMrk(std::string_view text, const std::string& path);
TriggerFile ParseTriggerCsv(std::string_view text, const std::string& path);

}  // namespace shutterlab
