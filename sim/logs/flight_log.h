#pragma once
// What a flight-log reader (ULog, Betaflight blackbox, ArduPilot DataFlash, ...) hands on:
// the best gyro trace in the log, camera events, and what was skipped on the way.

#include "sim/gyro_trace.h"
#include "sim/log_warning.h"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

// A camera trigger or capture event from the log.
struct CameraEvent {
  int64_t t_ns = 0;       // on the gyro trace's clock
  int64_t sequence = -1;  // image sequence number from the log, -1 when absent
  std::string kind;       // e.g. "camera_trigger", "camera_capture", "CAM", "TRIG"
};

// One GPS fix's time: the log's clock against UTC, from the log's own GPS messages.
struct UtcFix {
  int64_t t_ns = 0;    // on the gyro trace's clock (when the log stamped the message)
  int64_t utc_ns = 0;  // UTC, ns since 1970-01-01 (GPS time less the leap seconds)
};

struct FlightLog {
  GyroTrace gyro;      // rad/s, sensor axes of the flight controller (FRD body for PX4 / ArduPilot)
  std::string format;  // "ulog", "betaflight", "dataflash", "gyro.csv", ...
  std::string gyro_source;  // which topic/field/message the trace came from, e.g.
                            // "sensor_combined.gyro_rad"
  std::vector<std::string> gyro_sources_available;  // every candidate seen, best first
  std::vector<CameraEvent> camera_events;
  // GPS time against the log's clock, one per GPS message with a valid time, in log order (PX4
  // vehicle_gps_position / sensor_gps time_utc_usec; ArduPilot GPS GWk + GMS). Empty when the log
  // has none. sim/logs/log_clock.h fits the relation.
  std::vector<UtcFix> utc_fixes;
  std::optional<double> altitude_above_ground_m;  // median over the flight when the log has it
  std::string altitude_source;  // how that altitude was formed, e.g. "median CAM.RelAlt ..."
  size_t records_skipped = 0;   // corrupt / undecodable records or frames that were skipped
  // One line each, with counts and times: what could not be read or trusted (truncation, corrupt
  // records, partial batches, gaps, rate changes, saturation, assumptions about units). Every
  // command prints them; every JSON output and report carries them.
  std::vector<LogWarning> warnings;
};

// A log may record each image twice: PX4's camera_trigger (the command) and camera_capture (the
// camera's feedback), ArduPilot's TRIG and CAM. Keeps the events of one kind, the camera's
// feedback where the log has it (camera_capture, CAM; otherwise camera_trigger, TRIG; otherwise
// the most frequent kind), and says in an unused_source warning how many of the others were left
// out. Events stay in time order.
void KeepOneCameraEventKind(FlightLog* log);

}  // namespace shutterlab
