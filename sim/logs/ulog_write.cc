#include "sim/logs/ulog_write.h"

#include "sim/check.h"
#include "sim/logs/ulog.h"  // kAirborneAltitudeM
#include "sim/logs/ulog_parser.h"
#include "sim/text_file.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string_view>

namespace shutterlab {
namespace {

constexpr uint8_t kFileVersion = 1;
constexpr uint64_t kAltitudePeriodUs = 100'000;  // 10 Hz, as PX4 logs vehicle_local_position

// Field lists follow PX4's uORB messages (types and order), cut down to what readers need; each
// ends in _padding0 up to a multiple of 8 bytes, as PX4 lays its structs out.
constexpr uint16_t kGyroMsgId = 0;
constexpr char kGyroTopic[] = "sensor_gyro";
constexpr char kGyroFormat[] =
    "sensor_gyro:uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;float x;float y;"
    "float z;float temperature;uint32_t error_count;uint8_t[3] clip_counter;uint8_t samples;"
    "uint8_t[4] _padding0;";
constexpr uint16_t kCameraMsgId = 1;
constexpr char kCameraTopic[] = "camera_capture";
constexpr char kCameraFormat[] =
    "camera_capture:uint64_t timestamp;uint32_t seq;uint8_t[4] _padding0;";
constexpr uint16_t kPositionMsgId = 2;
constexpr char kPositionTopic[] = "vehicle_local_position";
constexpr char kPositionFormat[] =
    "vehicle_local_position:uint64_t timestamp;float vx;float vy;float vz;float dist_bottom;"
    "bool v_xy_valid;bool v_z_valid;bool dist_bottom_valid;uint8_t[5] _padding0;";
constexpr uint16_t kGpsMsgId = 3;
constexpr char kGpsTopic[] = "vehicle_gps_position";
constexpr char kGpsFormat[] = "vehicle_gps_position:uint64_t timestamp;uint64_t time_utc_usec;";
constexpr uint16_t kAttitudeMsgId = 4;
constexpr char kAttitudeTopic[] = "vehicle_attitude";
constexpr char kAttitudeFormat[] = "vehicle_attitude:uint64_t timestamp;float[4] q;";

// Little-endian stores, independent of the host's byte order.
void PutLittleEndian(uint64_t value, size_t bytes, std::string* out) {
  for (size_t i = 0; i < bytes; ++i) out->push_back(static_cast<char>((value >> (8 * i)) & 0xff));
}
void PutU8(uint8_t value, std::string* out) { PutLittleEndian(value, 1, out); }
void PutU16(uint16_t value, std::string* out) { PutLittleEndian(value, 2, out); }
void PutU32(uint32_t value, std::string* out) { PutLittleEndian(value, 4, out); }
void PutU64(uint64_t value, std::string* out) { PutLittleEndian(value, 8, out); }
void PutFloat(float value, std::string* out) {
  uint32_t bits;
  std::memcpy(&bits, &value, sizeof(bits));
  PutU32(bits, out);
}

// One message: header (uint16 payload size, uint8 type), then the payload.
void AppendMessage(char type, std::string_view payload, std::string* out) {
  SHUTTERLAB_CHECK(payload.size() <= std::numeric_limits<uint16_t>::max())
      << "ULog message of " << payload.size() << " bytes exceeds the uint16 size field";
  PutU16(static_cast<uint16_t>(payload.size()), out);
  out->push_back(type);
  out->append(payload);
}

// 'I' message: uint8 key length, key "type name", value.
void AppendInfo(const std::string& name, const std::string& value, std::string* out) {
  const std::string key = "char[" + std::to_string(value.size()) + "] " + name;
  std::string payload;
  PutU8(static_cast<uint8_t>(key.size()), &payload);
  AppendMessage('I', payload + key + value, out);
}

// 'A' message: uint8 multi_id, uint16 msg_id, topic name. One instance (multi_id 0) per topic.
void AppendSubscription(uint16_t msg_id, const std::string& topic, std::string* out) {
  std::string payload;
  PutU8(0, &payload);
  PutU16(msg_id, &payload);
  AppendMessage('A', payload + topic, out);
}

// PX4 time: unsigned microseconds since boot, where 0 means "not set" (readers drop it).
uint64_t ToULogMicros(int64_t t_ns, const char* what, size_t index) {
  SHUTTERLAB_CHECK(t_ns >= 500) << what << " " << index << " at t = " << t_ns << " ns "
                                << (t_ns < 0 ? "is negative" : "rounds to 0 us")
                                << ": ULog times are microseconds since boot and must be at "
                                   "least 1 us (PX4 reads 0 as 'not set')";
  return static_cast<uint64_t>(t_ns / 1000 + (t_ns % 1000 >= 500 ? 1 : 0));
}

// One data message to write: which topic, and which sample / event / altitude tick of it.
struct Record {
  uint64_t t_us;
  uint16_t msg_id;
  size_t index;
};

// The fields of record r's topic after its timestamp, into payload.
void AppendFields(const Record& r, const GyroTrace& gyro,
                  const std::vector<CameraEvent>& camera_events, const ULogWriteOptions& options,
                  const std::optional<float>& altitude_m, std::string* payload_out) {
  std::string& payload = *payload_out;
  if (r.msg_id == kGyroMsgId) {
    const Eigen::Vector3d& omega_rad_s = gyro[r.index].omega_rad_s;
    PutU64(r.t_us, &payload);  // timestamp_sample: the sample is published when it is taken
    PutU32(0, &payload);       // device_id: 0, no real device
    for (int axis = 0; axis < 3; ++axis) {
      PutFloat(static_cast<float>(omega_rad_s[axis]), &payload);  // x, y, z
    }
    PutFloat(std::numeric_limits<float>::quiet_NaN(), &payload);  // temperature: not simulated
    PutU32(0, &payload);                                          // error_count
    PutLittleEndian(0, 3, &payload);                              // clip_counter[3]
    PutU8(1, &payload);                                           // samples in this message
    PutLittleEndian(0, 4, &payload);                              // _padding0
  } else if (r.msg_id == kCameraMsgId) {
    PutU32(static_cast<uint32_t>(camera_events[r.index].sequence), &payload);
    PutLittleEndian(0, 4, &payload);  // _padding0
  } else if (r.msg_id == kGpsMsgId) {
    const int64_t utc_ns = options.utc_fixes[r.index].utc_ns;
    PutU64(static_cast<uint64_t>(utc_ns / 1000), &payload);  // time_utc_usec
  } else if (r.msg_id == kAttitudeMsgId) {
    const Eigen::Quaterniond& q = options.attitude[r.index].ned_from_body;
    for (double c : {q.w(), q.x(), q.y(), q.z()}) PutFloat(static_cast<float>(c), &payload);
  } else {
    // The velocity sample r.index, or (without velocity) the altitude alone.
    const bool moving = !options.velocity.empty();
    const Eigen::Vector3d v = moving ? options.velocity[r.index].ned_mps : Eigen::Vector3d::Zero();
    for (int axis = 0; axis < 3; ++axis)
      PutFloat(std::isnan(v[axis]) ? 0.0f : static_cast<float>(v[axis]), &payload);  // vx..vz
    PutFloat(altitude_m.value_or(0.0f), &payload);                                   // dist_bottom
    PutU8(moving ? 1 : 0, &payload);                                                 // v_xy_valid
    PutU8(moving && !std::isnan(v.z()) ? 1 : 0, &payload);                           // v_z_valid
    PutU8(altitude_m ? 1 : 0, &payload);  // dist_bottom_valid
    PutLittleEndian(0, 5, &payload);      // _padding0
  }
}

}  // namespace

std::string SerializeULog(const GyroTrace& gyro, const std::vector<CameraEvent>& camera_events,
                          const ULogWriteOptions& options) {
  SHUTTERLAB_CHECK(gyro.size() >= 2)
      << "a ULog gyro trace needs at least 2 samples (readers measure its rate); got "
      << gyro.size();
  std::optional<float> altitude_m;
  if (options.altitude_above_ground_m) {
    // Compared as written (float32), so a value just above the threshold cannot round onto it.
    altitude_m = static_cast<float>(*options.altitude_above_ground_m);
    SHUTTERLAB_CHECK(std::isfinite(*altitude_m) && *altitude_m > kAirborneAltitudeM)
        << "altitude above ground " << *options.altitude_above_ground_m
        << " m: must be finite and above " << kAirborneAltitudeM
        << " m, below which readers take the vehicle to be on the ground";
  }

  for (size_t i = 0; i < options.velocity.size(); ++i) {
    const Eigen::Vector3d& v = options.velocity[i].ned_mps;
    SHUTTERLAB_CHECK(v.head<2>().allFinite() && !std::isinf(v.z()))
        << "velocity sample " << i << ": north and east must be finite (down finite or NaN)";
  }
  for (size_t i = 0; i < options.attitude.size(); ++i) {
    SHUTTERLAB_CHECK(options.attitude[i].ned_from_body.coeffs().allFinite())
        << "attitude sample " << i << " is not finite";
  }

  std::vector<Record> records;
  records.reserve(gyro.size() + camera_events.size() + options.utc_fixes.size() +
                  options.velocity.size() + options.attitude.size());
  for (size_t i = 0; i < gyro.size(); ++i) {
    records.push_back({ToULogMicros(gyro[i].t_ns, "gyro sample", i), kGyroMsgId, i});
  }
  for (size_t i = 0; i < camera_events.size(); ++i) {
    const int64_t seq = camera_events[i].sequence;
    SHUTTERLAB_CHECK(seq >= 0 && seq <= std::numeric_limits<uint32_t>::max())
        << "camera event " << i << " has sequence " << seq
        << ": camera_capture.seq is a uint32 (0.." << std::numeric_limits<uint32_t>::max() << ")";
    records.push_back({ToULogMicros(camera_events[i].t_ns, "camera event", i), kCameraMsgId, i});
  }
  for (size_t i = 0; i < options.velocity.size(); ++i) {
    records.push_back(
        {ToULogMicros(options.velocity[i].t_ns, "velocity sample", i), kPositionMsgId, i});
  }
  for (size_t i = 0; i < options.attitude.size(); ++i) {
    records.push_back(
        {ToULogMicros(options.attitude[i].t_ns, "attitude sample", i), kAttitudeMsgId, i});
  }
  const bool position = altitude_m || !options.velocity.empty();
  if (altitude_m && options.velocity.empty()) {
    // Over the gyro trace (records 0 .. gyro.size() - 1, non-decreasing in time).
    const uint64_t first_us = records.front().t_us;
    const uint64_t last_us = records[gyro.size() - 1].t_us;
    size_t tick = 0;
    for (uint64_t t_us = first_us; t_us <= last_us; t_us += kAltitudePeriodUs) {
      records.push_back({t_us, kPositionMsgId, tick++});
    }
  }
  for (size_t i = 0; i < options.utc_fixes.size(); ++i) {
    const int64_t utc_ns = options.utc_fixes[i].utc_ns;
    SHUTTERLAB_CHECK(utc_ns > 0) << "GPS fix " << i << " has UTC " << utc_ns
                                 << " ns: time_utc_usec is unsigned and 0 means 'not set'";
    records.push_back({ToULogMicros(options.utc_fixes[i].t_ns, "GPS fix", i), kGpsMsgId, i});
  }
  const bool gps = !options.utc_fixes.empty();
  // Data in time order, as a logger writes it; stable, so equal times keep gyro, camera, altitude.
  std::stable_sort(records.begin(), records.end(),
                   [](const Record& a, const Record& b) { return a.t_us < b.t_us; });

  std::string out;
  out.reserve(64 * records.size() + 1024);
  out.append(ulog::kMagic, sizeof(ulog::kMagic));
  PutU8(kFileVersion, &out);
  PutU64(records.front().t_us, &out);  // when logging started: the first data message
  // Flag bits, required right after the header: no compat or incompat flags, no appended data.
  AppendMessage('B', std::string(40, '\0'), &out);
  // Names the writer, so that nobody takes the file for a real flight.
  AppendInfo("sys_name", "shutterlab", &out);
  AppendMessage('F', kGyroFormat, &out);
  AppendMessage('F', kCameraFormat, &out);
  if (position) AppendMessage('F', kPositionFormat, &out);
  if (gps) AppendMessage('F', kGpsFormat, &out);
  if (!options.attitude.empty()) AppendMessage('F', kAttitudeFormat, &out);
  AppendSubscription(kGyroMsgId, kGyroTopic, &out);
  AppendSubscription(kCameraMsgId, kCameraTopic, &out);
  if (position) AppendSubscription(kPositionMsgId, kPositionTopic, &out);
  if (gps) AppendSubscription(kGpsMsgId, kGpsTopic, &out);
  if (!options.attitude.empty()) AppendSubscription(kAttitudeMsgId, kAttitudeTopic, &out);

  std::string payload;  // reused: 'D' payload = uint16 msg_id, then the topic's fields
  for (const Record& r : records) {
    payload.clear();
    PutU16(r.msg_id, &payload);
    PutU64(r.t_us, &payload);  // timestamp
    AppendFields(r, gyro, camera_events, options, altitude_m, &payload);
    AppendMessage('D', payload, &out);
  }
  return out;
}

void WriteULog(const std::string& path, const GyroTrace& gyro,
               const std::vector<CameraEvent>& camera_events, const ULogWriteOptions& options) {
  WriteFileAtomically(path, SerializeULog(gyro, camera_events, options));
}

}  // namespace shutterlab
