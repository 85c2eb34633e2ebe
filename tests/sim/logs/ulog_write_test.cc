#include "sim/logs/ulog_write.h"

#include "sim/logs/ulog.h"
#include "sim/text_file.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

constexpr double kRateHz = 500.0;
constexpr double kDurationS = 10.0;
// Off the microsecond grid by 123 ns, so that the writer's rounding is exercised.
constexpr int64_t kStartNs = 1'000'000'123;

Eigen::Vector3d KnownRates(double t_s) {
  return {0.5 * std::sin(2 * M_PI * 0.7 * t_s), 0.3 * std::cos(2 * M_PI * 1.3 * t_s),
          -0.2 * std::sin(2 * M_PI * 0.2 * t_s + 0.4)};
}

// 500 Hz for 10 s of sinusoidal rates.
GyroTrace SyntheticTrace() {
  std::vector<GyroSample> samples;
  const int n = static_cast<int>(kRateHz * kDurationS);
  for (int k = 0; k < n; ++k) {
    const int64_t t_ns = kStartNs + static_cast<int64_t>(k * (1e9 / kRateHz));
    samples.push_back({t_ns, KnownRates(t_ns * 1e-9)});
  }
  return GyroTrace(std::move(samples));
}

// One camera event every 2 s, 567 ns off the microsecond grid (rounds up).
std::vector<CameraEvent> CameraEvery2s() {
  std::vector<CameraEvent> events;
  for (int i = 0; i < 5; ++i) {
    events.push_back({kStartNs + 500'000'444 + i * 2'000'000'000LL, 100 + i, "camera_capture"});
  }
  return events;
}

int64_t RoundToMicrosecondNs(int64_t t_ns) { return (t_ns + 500) / 1000 * 1000; }

// The message of the std::invalid_argument that f throws, or "" when it throws none.
template <typename F>
std::string RefusalOf(F f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

uint64_t LoadU64(const std::string& bytes, size_t at) {
  uint64_t v = 0;
  for (int i = 0; i < 8; ++i)
    v |= static_cast<uint64_t>(static_cast<uint8_t>(bytes[at + i])) << (8 * i);
  return v;
}
uint16_t LoadU16(const std::string& bytes, size_t at) {
  return static_cast<uint16_t>(static_cast<uint8_t>(bytes[at]) | static_cast<uint8_t>(bytes[at + 1])
                                                                     << 8);
}

TEST(ULogWrite, GyroAndCameraEventsRoundTripThroughTheReader) {
  const GyroTrace trace = SyntheticTrace();
  const std::vector<CameraEvent> events = CameraEvery2s();
  const FlightLog log = ParseULog(SerializeULog(trace, events), "synthetic.ulg");

  EXPECT_EQ(log.format, "ulog");
  EXPECT_EQ(log.gyro_source, "sensor_gyro.x,y,z");
  ASSERT_EQ(log.gyro_sources_available.size(), 1u);
  EXPECT_EQ(log.gyro_sources_available[0], "sensor_gyro.x,y,z (500.0 Hz, 5000 samples)");
  EXPECT_TRUE(log.warnings.empty()) << test::JoinedWarnings(log.warnings);
  EXPECT_EQ(log.records_skipped, 0u);
  EXPECT_FALSE(log.altitude_above_ground_m.has_value());

  ASSERT_EQ(log.gyro.size(), trace.size());
  for (size_t i = 0; i < trace.size(); ++i) {
    const int64_t t_ns = trace[i].t_ns;
    ASSERT_EQ(log.gyro[i].t_ns, RoundToMicrosecondNs(t_ns)) << "sample " << i;
    ASSERT_LE(std::abs(log.gyro[i].t_ns - t_ns), 500) << "sample " << i;
    for (int axis = 0; axis < 3; ++axis) {
      // float32 on the wire: exactly the nearest float, within its relative precision.
      const double written = trace[i].omega_rad_s[axis];
      ASSERT_EQ(log.gyro[i].omega_rad_s[axis], static_cast<double>(static_cast<float>(written)))
          << "sample " << i << " axis " << axis;
      ASSERT_NEAR(log.gyro[i].omega_rad_s[axis], written, 6e-8 * std::abs(written) + 1e-30);
    }
  }

  ASSERT_EQ(log.camera_events.size(), events.size());
  for (size_t i = 0; i < events.size(); ++i) {
    EXPECT_EQ(log.camera_events[i].t_ns, RoundToMicrosecondNs(events[i].t_ns)) << "event " << i;
    EXPECT_EQ(log.camera_events[i].sequence, events[i].sequence) << "event " << i;
    EXPECT_EQ(log.camera_events[i].kind, "camera_capture");
  }
}

TEST(ULogWrite, AltitudeRoundTripsWhenGiven) {
  ULogWriteOptions options;
  options.altitude_above_ground_m = 12.3;
  const FlightLog log =
      ParseULog(SerializeULog(SyntheticTrace(), CameraEvery2s(), options), "synthetic.ulg");
  ASSERT_TRUE(log.altitude_above_ground_m.has_value());
  // dist_bottom is float32, as in PX4.
  EXPECT_EQ(*log.altitude_above_ground_m, static_cast<double>(static_cast<float>(12.3)));
  EXPECT_EQ(log.records_skipped, 0u);
  // The reader notes where the altitude came from; a clean file has nothing to warn about.
  EXPECT_TRUE(log.warnings.empty()) << test::JoinedWarnings(log.warnings);
  EXPECT_EQ(log.altitude_source.rfind("median vehicle_local_position.dist_bottom", 0), 0u)
      << log.altitude_source;
  EXPECT_EQ(log.gyro.size(), 5000u);
  EXPECT_EQ(log.camera_events.size(), 5u);
}

TEST(ULogWrite, NavigationRoundTripsThroughTheReader) {
  // Velocity at 10 Hz (one sample without a vertical part) with the altitude, attitude at 100 Hz:
  // the velocity comes back sample for sample as float32, the down part NaN where v_z_valid is
  // false; the attitude one sample every 20 ms (the reader's 50 Hz), each the quaternion written.
  ULogWriteOptions options;
  options.altitude_above_ground_m = 40.0;
  for (int k = 0; k < 100; ++k) {
    const int64_t t_ns = kStartNs + k * 100'000'000LL;
    options.velocity.push_back(
        {t_ns, Eigen::Vector3d(5.0 * std::cos(0.1 * k), 3.0 + 0.01 * k, k == 7 ? NAN : -0.25)});
  }
  for (int k = 0; k < 1000; ++k) {
    const double yaw_rad = 0.002 * k;
    options.attitude.push_back(
        {kStartNs + k * 10'000'000LL,
         Eigen::Quaterniond(Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitX()))});
  }
  const FlightLog log =
      ParseULog(SerializeULog(SyntheticTrace(), CameraEvery2s(), options), "synthetic.ulg");
  EXPECT_TRUE(log.warnings.empty()) << test::JoinedWarnings(log.warnings);
  EXPECT_EQ(log.altitude_above_ground_m, static_cast<double>(40.0f));
  EXPECT_EQ(log.velocity_source, "vehicle_local_position.vx,vy,vz (where v_xy_valid)");
  ASSERT_EQ(log.velocity.size(), options.velocity.size());
  for (size_t k = 0; k < log.velocity.size(); ++k) {
    const Eigen::Vector3d& written = options.velocity[k].ned_mps;
    EXPECT_EQ(log.velocity[k].t_ns, RoundToMicrosecondNs(options.velocity[k].t_ns));
    for (int axis = 0; axis < 3; ++axis) {
      if (std::isnan(written[axis])) {
        EXPECT_TRUE(std::isnan(log.velocity[k].ned_mps[axis])) << "sample " << k;
      } else {
        EXPECT_EQ(log.velocity[k].ned_mps[axis],
                  static_cast<double>(static_cast<float>(written[axis])))
            << "sample " << k << " axis " << axis;
      }
    }
  }
  EXPECT_EQ(log.attitude_source, "vehicle_attitude.q");
  ASSERT_EQ(log.attitude.size(), 500u) << "one in two of the 100 Hz samples";
  for (size_t k = 0; k < log.attitude.size(); ++k) {
    const AttitudeSample& written = options.attitude[2 * k];
    EXPECT_EQ(log.attitude[k].t_ns, RoundToMicrosecondNs(written.t_ns));
    EXPECT_LT(log.attitude[k].ned_from_body.angularDistance(written.ned_from_body), 1e-6)
        << "sample " << k;
  }
}

TEST(ULogWrite, HeaderFlagBitsAndDataInTimeOrder) {
  const GyroTrace trace = SyntheticTrace();
  ULogWriteOptions options;
  options.altitude_above_ground_m = 20.0;
  const std::string bytes = SerializeULog(trace, CameraEvery2s(), options);

  ASSERT_TRUE(LooksLikeULog(bytes));
  EXPECT_EQ(bytes[7], 1) << "file version";
  EXPECT_EQ(LoadU64(bytes, 8), static_cast<uint64_t>(RoundToMicrosecondNs(kStartNs) / 1000))
      << "header timestamp: the first sample's time in us";
  EXPECT_EQ(LoadU16(bytes, 16), 40) << "flag bits payload size";
  EXPECT_EQ(bytes[18], 'B') << "flag bits must follow the header";
  EXPECT_EQ(bytes.substr(19, 40), std::string(40, '\0')) << "no flags, no appended data";

  // Walks the messages: every data message's timestamp (its first field) is no earlier than the
  // one before, across topics, and each topic's messages have their format's size.
  size_t pos = 16;
  uint64_t last_us = 0;
  size_t data_messages = 0, position_messages = 0;
  bool gyro_after_camera = false, seen_camera = false;
  while (pos < bytes.size()) {
    ASSERT_LE(pos + 3, bytes.size());
    const uint16_t size = LoadU16(bytes, pos);
    const char type = bytes[pos + 2];
    ASSERT_LE(pos + 3 + size, bytes.size()) << "message at byte " << pos << " runs past the end";
    if (type == 'D') {
      const uint16_t msg_id = LoadU16(bytes, pos + 3);
      const uint64_t t_us = LoadU64(bytes, pos + 5);
      EXPECT_GE(t_us, last_us) << "data message at byte " << pos;
      last_us = t_us;
      ++data_messages;
      if (msg_id == 0) {
        EXPECT_EQ(size, 2 + 48) << "sensor_gyro at byte " << pos;
        gyro_after_camera |= seen_camera;
      } else {
        // camera_capture 16 bytes, vehicle_local_position 32 (velocity, altitude, flags)
        EXPECT_EQ(size, 2 + (msg_id == 2 ? 32 : 16)) << "msg_id " << msg_id << " at byte " << pos;
        seen_camera |= msg_id == 1;
        position_messages += msg_id == 2;
      }
    }
    pos += 3 + size;
  }
  EXPECT_TRUE(gyro_after_camera) << "camera events interleaved with gyro samples by time";
  // 10 Hz over the trace's 9.998 s: ticks at 0, 0.1, ..., 9.9 s.
  EXPECT_EQ(position_messages, 100u);
  EXPECT_EQ(data_messages, trace.size() + 5 + 100);
}

TEST(ULogWrite, WriteULogWritesTheSerialisedBytes) {
  test::TempDir dir;
  const std::string path = dir / "synthetic.ulg";
  const GyroTrace trace = SyntheticTrace();
  WriteULog(path, trace, CameraEvery2s());
  EXPECT_EQ(ReadFileToString(path), SerializeULog(trace, CameraEvery2s()));
  const FlightLog log = ReadULog(path);
  EXPECT_EQ(log.gyro.size(), trace.size());
  EXPECT_EQ(log.camera_events.size(), 5u);
}

TEST(ULogWrite, RefusedInputWritesNoFile) {
  test::TempDir dir;
  const std::string path = dir / "refused.ulg";
  std::vector<CameraEvent> events = CameraEvery2s();
  events[3].t_ns = -1;
  EXPECT_THROW(WriteULog(path, SyntheticTrace(), events), std::invalid_argument);
  EXPECT_FALSE(std::filesystem::exists(path));
}

TEST(ULogWrite, NegativeTimesAreRefused) {
  const GyroTrace negative({{-2'000'000, {0, 0, 0}}, {0, {0, 0, 0}}, {2'000'000, {0, 0, 0}}});
  const std::string gyro_message = RefusalOf([&] { SerializeULog(negative, {}); });
  EXPECT_NE(gyro_message.find("gyro sample 0 at t = -2000000 ns is negative"), std::string::npos)
      << gyro_message;

  std::vector<CameraEvent> events = CameraEvery2s();
  events[2].t_ns = -5;
  const std::string camera_message = RefusalOf([&] { SerializeULog(SyntheticTrace(), events); });
  EXPECT_NE(camera_message.find("camera event 2 at t = -5 ns is negative"), std::string::npos)
      << camera_message;
}

TEST(ULogWrite, TimesThatRoundToZeroAreRefused) {
  // PX4 reads a zero timestamp as "not set", and readers drop such samples.
  const GyroTrace at_zero({{499, {0, 0, 0}}, {2'000'000, {0, 0, 0}}, {4'000'000, {0, 0, 0}}});
  const std::string message = RefusalOf([&] { SerializeULog(at_zero, {}); });
  EXPECT_NE(message.find("gyro sample 0 at t = 499 ns rounds to 0 us"), std::string::npos)
      << message;
  const GyroTrace at_one_us({{500, {0, 0, 0}}, {2'000'000, {0, 0, 0}}, {4'000'000, {0, 0, 0}}});
  EXPECT_EQ(ParseULog(SerializeULog(at_one_us, {}), "t.ulg").gyro[0].t_ns, 1000);
}

TEST(ULogWrite, EmptyOrSingleSampleTraceIsRefused) {
  const std::string empty = RefusalOf([] { SerializeULog(GyroTrace(), {}); });
  EXPECT_NE(empty.find("at least 2 samples"), std::string::npos) << empty;
  const std::string single = RefusalOf([] {
    SerializeULog(GyroTrace({{1'000'000, {0, 0, 0}}}), {});
  });
  EXPECT_NE(single.find("at least 2 samples"), std::string::npos) << single;
}

TEST(ULogWrite, SequenceOutsideUint32IsRefused) {
  std::vector<CameraEvent> events = CameraEvery2s();
  events[1].sequence = -1;  // "absent" in CameraEvent; camera_capture.seq cannot say that
  const std::string message = RefusalOf([&] { SerializeULog(SyntheticTrace(), events); });
  EXPECT_NE(message.find("camera event 1 has sequence -1"), std::string::npos) << message;
  events[1].sequence = int64_t{1} << 32;
  EXPECT_THROW(SerializeULog(SyntheticTrace(), events), std::invalid_argument);
  events[1].sequence = 0xffffffffLL;
  EXPECT_EQ(ParseULog(SerializeULog(SyntheticTrace(), events), "s.ulg").camera_events[1].sequence,
            0xffffffffLL);
}

TEST(ULogWrite, AltitudeAGroundReaderWouldNotReportIsRefused) {
  ULogWriteOptions options;
  for (double bad : {kAirborneAltitudeM, 0.5, -3.0, std::nan("")}) {
    options.altitude_above_ground_m = bad;
    const std::string message =
        RefusalOf([&] { SerializeULog(SyntheticTrace(), CameraEvery2s(), options); });
    EXPECT_NE(message.find("must be finite and above 1 m"), std::string::npos)
        << bad << ": " << message;
  }
}

}  // namespace
}  // namespace shutterlab
