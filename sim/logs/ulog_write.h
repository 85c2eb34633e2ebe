#pragma once
// PX4 ULog writer (file version 1): a gyro trace, camera events and optionally the height above
// ground, as the topics sim/logs/ulog.h reads back. Lets the project ship synthetic flights in a
// real log format instead of other people's logs.
//
// Spec: PX4 "ULog File Format" (docs.px4.io, dev_log/ulog_file_format). Layout written:
//   header (magic, version 1, timestamp = first data time), flag bits 'B' (all zero), info 'I'
//   sys_name = "shutterlab", formats 'F', subscriptions 'A', then data 'D' in time order.
// Topics (the subset of the PX4 message fields the reader needs, with PX4's field types and a
// uint64 timestamp first, padded to 8 bytes as PX4 pads):
//   sensor_gyro            one message per gyro sample: timestamp = timestamp_sample = sample time,
//                          x, y, z in rad/s (float32), sensor axes as in the trace; samples 1,
//                          temperature NaN (not simulated), device_id and counters 0;
//   camera_capture         one message per camera event: timestamp, seq (uint32);
//   vehicle_local_position with ULogWriteOptions::velocity, one message a sample: vx, vy, vz (NED,
//                          m/s), v_xy_valid, v_z_valid (false where down is NaN); with
//                          altitude_above_ground_m, dist_bottom and dist_bottom_valid in each
//                          (at 10 Hz over the gyro trace when there is no velocity);
//   vehicle_attitude       with ULogWriteOptions::attitude: q (w, x, y, z; FRD body to NED);
//   vehicle_gps_position   only with ULogWriteOptions::utc_fixes: timestamp and time_utc_usec
//                          (UTC, us, truncated), one message a fix.
// Times: the trace's int64 ns rounded to the nearest PX4 microsecond (uint64 since boot).

#include "sim/gyro_trace.h"
#include "sim/logs/flight_log.h"

#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

struct ULogWriteOptions {
  // Written as vehicle_local_position.dist_bottom (float32, m) with dist_bottom_valid, at 10 Hz
  // over the trace. Must be finite and above kAirborneAltitudeM (sim/logs/ulog.h): readers take
  // lower heights for the vehicle on the ground and would not report it.
  std::optional<double> altitude_above_ground_m;
  // GPS time messages (log time, UTC), for readers that place photos on the log's clock.
  std::vector<UtcFix> utc_fixes;
  // The navigation: velocity (north and east finite, down finite or NaN) and attitude samples,
  // each written as one message at its time.
  std::vector<VelocitySample> velocity;
  std::vector<AttitudeSample> attitude;
};

// Serialises a flight as ULog bytes. Preconditions (std::invalid_argument naming the offending
// sample or event otherwise): the trace has at least 2 samples (readers measure its rate); every
// gyro and camera time rounds to at least 1 us (PX4 times are unsigned, and 0 means "not set", so
// readers drop it); every camera event's sequence fits camera_capture.seq (0..2^32-1; -1, "absent",
// does not). CameraEvent::kind is not written: the events read back as "camera_capture".
std::string SerializeULog(const GyroTrace& gyro, const std::vector<CameraEvent>& camera_events,
                          const ULogWriteOptions& options = {});

// Writes SerializeULog's bytes to path whole or not at all (WriteFileAtomically). Throws
// std::invalid_argument as SerializeULog does (before touching the file), IoError when the file
// cannot be written.
void WriteULog(const std::string& path, const GyroTrace& gyro,
               const std::vector<CameraEvent>& camera_events, const ULogWriteOptions& options = {});

}  // namespace shutterlab
