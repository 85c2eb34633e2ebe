#pragma once
// What a flight-log reader (ULog, Betaflight blackbox, ArduPilot DataFlash, ...) hands on:
// the best gyro trace in the log, camera events, and what was skipped on the way.

#include "sim/gyro_trace.h"
#include "sim/log_warning.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

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

// The vehicle's velocity over the ground from the log's navigation (PX4 vehicle_local_position,
// ArduPilot GPS): north, east, down, m/s; the down part NaN where the log gives none.
struct VelocitySample {
  int64_t t_ns = 0;  // on the gyro trace's clock
  Eigen::Vector3d ned_mps = Eigen::Vector3d::Zero();
};

// The vehicle's attitude from the log's estimator (PX4 vehicle_attitude, ArduPilot ATT): the
// rotation from the body frame (x forward, y right, z down: the flight controller's FRD) to NED.
struct AttitudeSample {
  int64_t t_ns = 0;  // on the gyro trace's clock
  Eigen::Quaterniond ned_from_body = Eigen::Quaterniond::Identity();
};

// Attitude is kept at 50 Hz at most: a mapping multirotor turns well under a degree in 20 ms, and
// an hour at 250 Hz would hold 900,000 samples.
constexpr int64_t kAttitudeStepNs = 20'000'000;
// The navigation's samples are used within this of an instant, and not across a longer gap.
constexpr int64_t kNavigationGapNs = 1'000'000'000;
// A logged velocity above this (over 500 km/h) is a corrupt message, not a flight.
constexpr double kMaxLogSpeedMps = 150.0;

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
  // The navigation's velocity and attitude, in time order; empty when the log has none. Attitude is
  // kept at most every kAttitudeStepNs (an estimator logs it at up to 250 Hz).
  std::vector<VelocitySample> velocity;
  std::string velocity_source;  // e.g. "vehicle_local_position.vx,vy,vz"
  std::vector<AttitudeSample> attitude;
  std::string attitude_source;                    // e.g. "vehicle_attitude.q"
  std::optional<double> altitude_above_ground_m;  // median over the flight when the log has it
  std::string altitude_source;  // how that altitude was formed, e.g. "median CAM.RelAlt ..."
  size_t records_skipped = 0;   // corrupt / undecodable records or frames that were skipped
  // One line each, with counts and times: what could not be read or trusted (truncation, corrupt
  // records, partial batches, gaps, rate changes, saturation, assumptions about units). Every
  // command prints them; every JSON output and report carries them.
  std::vector<LogWarning> warnings;
};

// The velocity at t_ns, linear between the two samples around it; nullopt when t_ns is not
// between two samples at most kNavigationGapNs apart (or within that of the first or last).
std::optional<Eigen::Vector3d> VelocityAt(const std::vector<VelocitySample>& samples, int64_t t_ns);
// The attitude at t_ns, spherical-linear between the two samples around it; nullopt as above.
std::optional<Eigen::Quaterniond> AttitudeAt(const std::vector<AttitudeSample>& samples,
                                             int64_t t_ns);

// A log may record each image twice: PX4's camera_trigger (the command) and camera_capture (the
// camera's feedback), ArduPilot's TRIG and CAM. Keeps the events of one kind, the camera's
// feedback where the log has it (camera_capture, CAM; otherwise camera_trigger, TRIG; otherwise
// the most frequent kind), and says in an unused_source warning how many of the others were left
// out. Events stay in time order.
void KeepOneCameraEventKind(FlightLog* log);

}  // namespace shutterlab
