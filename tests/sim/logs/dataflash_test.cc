#include "sim/logs/dataflash.h"

#include "sim/check.h"
#include "sim/civil_time.h"
#include "sim/logs/trigger_file.h"
#include "sim/text_file.h"
#include "sim/units.h"
#include "tests/test_util.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

// Most files here are written by the test from FMT definitions laid out as ArduPilot's AP_Logger
// writes them, so that every value is known exactly; the real logs in the shared data folder
// (../shared/data/incoming/ardupilot_*) check the same reader on what ArduPilot really wrote.

namespace shutterlab {
namespace {

void PutText(std::string* out, const std::string& text, size_t width) {
  std::string padded = text.substr(0, width);
  padded.resize(width, '\0');
  *out += padded;
}

// Message type numbers as in ArduPilot's LogStructure.h are arbitrary per build; these are ours.
enum : uint8_t { kGyr = 10, kImu = 11, kIsbh = 12, kIsbd = 13, kCam = 14, kTrig = 15, kParm = 16 };

class DataFlashBuilder {
 public:
  DataFlashBuilder() {
    Fmt(128, 89, "FMT", "BBnNZ", "Type,Length,Name,Format,Columns");
    Fmt(kGyr, 3 + 8 + 1 + 8 + 12, "GYR", "QBQfff", "TimeUS,I,SampleUS,GyrX,GyrY,GyrZ");
    Fmt(kImu, 3 + 8 + 1 + 24, "IMU", "QBffffff", "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ");
    Fmt(kIsbh, 3 + 8 + 2 + 1 + 1 + 2 + 2 + 8 + 4, "ISBH", "QHBBHHQf",
        "TimeUS,N,type,instance,mul,smp_cnt,SampleUS,smp_rate");
    Fmt(kIsbd, 3 + 8 + 2 + 2 + 3 * 64, "ISBD", "QHHaaa", "TimeUS,N,seqno,x,y,z");
    const std::string cam_labels = "TimeUS,I,Img,GPSTime,GPSWeek,Lat,Lng,Alt,RelAlt,GPSAlt,R,P,Y";
    Fmt(kCam, 46, "CAM", "QBHIHLLeeeccC", cam_labels);
    Fmt(kTrig, 46, "TRIG", "QBHIHLLeeeccC", cam_labels);
    Fmt(kParm, 3 + 8 + 16 + 4, "PARM", "QNf", "TimeUS,Name,Value");
  }
  void Fmt(uint8_t type, uint8_t length, const std::string& name, const std::string& format,
           const std::string& labels) {
    Header(128);
    test::PutLittleEndian<uint8_t>(&bytes_, type);
    test::PutLittleEndian<uint8_t>(&bytes_, length);
    PutText(&bytes_, name, 4);
    PutText(&bytes_, format, 16);
    PutText(&bytes_, labels, 64);
  }
  void Gyr(uint64_t t_us, uint8_t instance, uint64_t sample_us, float x, float y, float z) {
    Header(kGyr);
    test::PutLittleEndian(&bytes_, t_us);
    test::PutLittleEndian(&bytes_, instance);
    test::PutLittleEndian(&bytes_, sample_us);
    test::PutLittleEndian(&bytes_, x);
    test::PutLittleEndian(&bytes_, y);
    test::PutLittleEndian(&bytes_, z);
  }
  void Imu(uint64_t t_us, uint8_t instance, float x, float y, float z) {
    Header(kImu);
    test::PutLittleEndian(&bytes_, t_us);
    test::PutLittleEndian(&bytes_, instance);
    test::PutLittleEndian(&bytes_, x);
    test::PutLittleEndian(&bytes_, y);
    test::PutLittleEndian(&bytes_, z);
    for (int i = 0; i < 3; ++i) test::PutLittleEndian(&bytes_, 9.81f);
  }
  void Isbh(uint16_t n, uint8_t type, uint8_t instance, uint16_t mul, uint16_t count,
            uint64_t sample_us, float rate_hz) {
    Header(kIsbh);
    test::PutLittleEndian<uint64_t>(&bytes_, sample_us + 100);
    test::PutLittleEndian(&bytes_, n);
    test::PutLittleEndian(&bytes_, type);
    test::PutLittleEndian(&bytes_, instance);
    test::PutLittleEndian(&bytes_, mul);
    test::PutLittleEndian(&bytes_, count);
    test::PutLittleEndian(&bytes_, sample_us);
    test::PutLittleEndian(&bytes_, rate_hz);
  }
  void Isbd(uint16_t n, uint16_t seqno, const std::vector<int16_t>& x,
            const std::vector<int16_t>& y, const std::vector<int16_t>& z) {
    Header(kIsbd);
    test::PutLittleEndian<uint64_t>(&bytes_, 1);
    test::PutLittleEndian(&bytes_, n);
    test::PutLittleEndian(&bytes_, seqno);
    for (const auto* axis : {&x, &y, &z}) {
      for (size_t i = 0; i < 32; ++i)
        test::PutLittleEndian<int16_t>(&bytes_, i < axis->size() ? (*axis)[i] : int16_t{0});
    }
  }
  void Cam(uint8_t type, uint64_t t_us, uint16_t image, double rel_alt_m) {
    Header(type);
    test::PutLittleEndian(&bytes_, t_us);
    test::PutLittleEndian<uint8_t>(&bytes_, 0);
    test::PutLittleEndian(&bytes_, image);
    test::PutLittleEndian<uint32_t>(&bytes_, 0);
    test::PutLittleEndian<uint16_t>(&bytes_, 0);
    test::PutLittleEndian<int32_t>(&bytes_, 473'977'000);
    test::PutLittleEndian<int32_t>(&bytes_, 85'456'000);
    test::PutLittleEndian<int32_t>(&bytes_, 50'000);
    test::PutLittleEndian<int32_t>(&bytes_, static_cast<int32_t>(std::lround(rel_alt_m * 100)));
    test::PutLittleEndian<int32_t>(&bytes_, 50'000);
    test::PutLittleEndian<int16_t>(&bytes_, 0);
    test::PutLittleEndian<int16_t>(&bytes_, 0);
    test::PutLittleEndian<uint16_t>(&bytes_, 0);
  }
  void Parm(uint64_t t_us, const std::string& name, float value) {
    Header(kParm);
    test::PutLittleEndian(&bytes_, t_us);
    PutText(&bytes_, name, 16);
    test::PutLittleEndian(&bytes_, value);
  }
  // An IMU message of the logs before ArduPilot 3.4: TimeMS (ms), no instance column; IMU2 and
  // IMU3 are other message types with the same layout.
  void ImuMs(uint8_t type, uint32_t t_ms, float x, float y, float z) {
    Header(type);
    test::PutLittleEndian(&bytes_, t_ms);
    for (float v : {x, y, z, 0.0f, 0.0f, -9.81f}) test::PutLittleEndian(&bytes_, v);
    test::PutLittleEndian<uint32_t>(&bytes_, 0);
    test::PutLittleEndian<uint32_t>(&bytes_, 0);
    test::PutLittleEndian(&bytes_, 25.0f);
  }
  void Unit(uint8_t type, char id, const std::string& label) {
    Header(type);
    test::PutLittleEndian<uint64_t>(&bytes_, 1);
    test::PutLittleEndian<int8_t>(&bytes_, id);
    PutText(&bytes_, label, 64);
  }
  void Fmtu(uint8_t type, uint8_t of_type, const std::string& unit_ids) {
    Header(type);
    test::PutLittleEndian<uint64_t>(&bytes_, 1);
    test::PutLittleEndian(&bytes_, of_type);
    PutText(&bytes_, unit_ids, 16);
    PutText(&bytes_, "", 16);
  }
  std::string& bytes() { return bytes_; }

 private:
  void Header(uint8_t type) {
    bytes_.push_back(static_cast<char>(0xA3));
    bytes_.push_back(static_cast<char>(0x95));
    bytes_.push_back(static_cast<char>(type));
  }
  std::string bytes_;
};

// A 1 kHz GYR stream (instance 0 and a 500 Hz instance 1), a 400 Hz IMU stream, parameters and
// camera events. Values are exact in float32, so they must come back exactly.
DataFlashBuilder FlightFile(int gyr_samples) {
  DataFlashBuilder b;
  b.Parm(1000, "INS_LOG_BAT_OPT", 4.0f);
  for (int k = 0; k < gyr_samples; ++k) {
    const uint64_t sample_us = 2'000'000 + k * 1000;
    b.Gyr(sample_us + 250, 0, sample_us, 0.5f * (k % 7), -0.25f * (k % 5), 0.125f * k);
    if (k % 2 == 0) b.Gyr(sample_us + 300, 1, sample_us + 10, 1.0f, 1.0f, 1.0f);
    if (k % 5 == 0) b.Imu(sample_us + 500, 0, 0.1f, 0.2f, 0.3f);
    if (k % 100 == 50)
      b.Cam(kCam, sample_us + 700, static_cast<uint16_t>(k / 100 + 1), 40.0 + k / 100);
    if (k % 100 == 49) b.Cam(kTrig, sample_us + 600, static_cast<uint16_t>(k / 100 + 1), 0.0);
  }
  return b;
}

TEST(DataFlash, ReadsGyrBackExactly) {
  DataFlashBuilder b = FlightFile(1000);
  ASSERT_TRUE(LooksLikeDataFlash(b.bytes()));
  const FlightLog log = ParseDataFlash(b.bytes(), "flight.bin");
  EXPECT_EQ(log.format, "dataflash");
  EXPECT_EQ(log.gyro_source, "GYR");
  ASSERT_EQ(log.gyro.size(), 1000u);
  for (int k = 0; k < 1000; ++k) {
    EXPECT_EQ(log.gyro[k].t_ns, (2'000'000 + k * 1000) * int64_t{1000}) << "SampleUS, not TimeUS";
    EXPECT_EQ(log.gyro[k].omega_rad_s, Eigen::Vector3d(0.5 * (k % 7), -0.25 * (k % 5), 0.125 * k))
        << k;
  }
  ASSERT_EQ(log.gyro_sources_available.size(), 3u);
  EXPECT_EQ(log.gyro_sources_available[0], "GYR (1000.0 Hz, 1000 samples)");
  EXPECT_EQ(log.gyro_sources_available[1], "GYR/1 (500.0 Hz, 500 samples)");
  EXPECT_EQ(log.gyro_sources_available[2], "IMU (200.0 Hz, 200 samples)");
  EXPECT_EQ(log.records_skipped, 0u);
  // Nothing lost; only the note that the TRIG copies of the pictures were not used.
  ASSERT_EQ(log.warnings.size(), 1u) << test::JoinedWarnings(log.warnings);
  EXPECT_EQ(log.warnings[0].kind, "unused_source");
}

// The one trigger reader takes a DataFlash file by its content and keeps the log's clock.
TEST(DataFlash, IsATriggerFile) {
  test::TempDir dir;
  WriteFileAtomically(dir / "00000042.BIN", FlightFile(300).bytes());
  const TriggerFile f = ReadTriggerFile(dir / "00000042.BIN");
  EXPECT_EQ(f.format, "dataflash");
  EXPECT_EQ(f.clock, TriggerClock::kLog);
  ASSERT_GE(f.events.size(), 3u);
  const FlightLog log = ParseDataFlash(FlightFile(300).bytes(), "f.bin");
  ASSERT_EQ(f.events.size(), log.camera_events.size());
  for (size_t i = 0; i < f.events.size(); ++i) {
    EXPECT_EQ(f.events[i].t_ns, log.camera_events[i].t_ns);
    EXPECT_EQ(f.events[i].sequence, log.camera_events[i].sequence);
  }
  EXPECT_NE(f.source.find("CAM"), std::string::npos) << f.source;
}

TEST(DataFlash, ReadsCameraEventsAndAltitude) {
  DataFlashBuilder b = FlightFile(1000);
  const FlightLog log = ParseDataFlash(b.bytes(), "flight.bin");
  // Each picture as TRIG (the command) and CAM (the feedback): the 10 CAM are kept.
  ASSERT_EQ(log.camera_events.size(), 10u);
  EXPECT_EQ(log.camera_events[0].kind, "CAM");
  EXPECT_EQ(log.camera_events[0].t_ns, (2'050'000 + 700) * int64_t{1000});
  EXPECT_EQ(log.camera_events[0].sequence, 1);
  EXPECT_EQ(log.camera_events[9].sequence, 10);
  EXPECT_TRUE(test::AnyWarningContains(log.warnings,
                                       "camera events: used the 10 CAM events; 10 TRIG not used"))
      << test::JoinedWarnings(log.warnings);
  ASSERT_TRUE(log.altitude_above_ground_m.has_value());
  // CAM RelAlt 40..49 m ('e': centimetres); the TRIG copies say 0 m and are not used.
  constexpr double kCentimetre = 1e-9;  // 'e' is int32 * 0.01: exact to rounding only
  EXPECT_NEAR(*log.altitude_above_ground_m, 44.5, kCentimetre);
  EXPECT_NE(log.altitude_source.find("CAM.RelAlt"), std::string::npos) << log.altitude_source;
}

TEST(DataFlash, ReadsBatchSamplerGyroBatches) {
  DataFlashBuilder b;
  const uint16_t mul = 938;  // int16 full scale 34.9 rad/s: the MPU6000's 2000 deg/s
  const float rate_hz = 2000.0f;
  std::vector<double> expected_x;
  std::vector<int64_t> expected_t_ns;
  for (uint16_t batch = 0; batch < 3; ++batch) {
    const uint64_t start_us = 5'000'000 + batch * 100'000;
    b.Isbh(batch * 2, 0, 0, 2000, 64, start_us, rate_hz);  // accelerometer: ignored
    b.Isbd(batch * 2, 0, std::vector<int16_t>(32, 99), {}, {});
    b.Isbh(batch * 2 + 1, 1, 0, mul, 40, start_us, rate_hz);  // 40 of the 64 slots are valid
    for (uint16_t seq = 0; seq < 2; ++seq) {
      std::vector<int16_t> x, y, z;
      for (int i = 0; i < 32; ++i) {
        const int index = seq * 32 + i;
        x.push_back(static_cast<int16_t>(batch * 1000 + index));
        y.push_back(static_cast<int16_t>(-index));
        z.push_back(static_cast<int16_t>(mul));
        if (index < 40) {
          expected_x.push_back((batch * 1000 + index) / static_cast<double>(mul));
          expected_t_ns.push_back(static_cast<int64_t>(start_us) * 1000 + index * 500'000);
        }
      }
      b.Isbd(batch * 2 + 1, seq, x, y, z);
    }
    for (int k = 0; k < 40; ++k) b.Imu(start_us + k * 2500, 0, 0, 0, 0);  // 400 Hz
  }
  const FlightLog log = ParseDataFlash(b.bytes(), "batch.bin");
  EXPECT_EQ(log.gyro_source, "ISBD");
  ASSERT_EQ(log.gyro.size(), expected_x.size());
  for (size_t k = 0; k < expected_x.size(); ++k) {
    EXPECT_EQ(log.gyro[k].t_ns, expected_t_ns[k]) << k;
    EXPECT_EQ(log.gyro[k].omega_rad_s.x(), expected_x[k]) << k;
    EXPECT_EQ(log.gyro[k].omega_rad_s.z(), 1.0) << k;
  }
  EXPECT_EQ(log.gyro.sampling().median_interval_ns, 500'000);
  EXPECT_EQ(log.gyro.sampling().gap_indices.size(), 2u) << "between the three batches";
}

TEST(DataFlash, ReadsOldTimeMsLogsWithEveryImuInstance) {
  // ArduCopter 3.3: IMU, IMU2 and IMU3 share one layout with TimeMS first.
  DataFlashBuilder b;
  const char* kOldImu = "IffffffIIf";
  const char* kOldLabels = "TimeMS,GyrX,GyrY,GyrZ,AccX,AccY,AccZ,ErrG,ErrA,Temp";
  b.Fmt(131, 43, "IMU", kOldImu, kOldLabels);
  b.Fmt(135, 43, "IMU2", kOldImu, kOldLabels);
  b.Fmt(149, 43, "IMU3", kOldImu, kOldLabels);
  for (uint32_t k = 0; k < 100; ++k) {
    const uint32_t t_ms = 11'500 + 20 * k;  // 50 Hz
    b.ImuMs(131, t_ms, 0.01f * k, 0, 0);
    b.ImuMs(135, t_ms, 0, 0.02f * k, 0);
    if (k % 2 == 0) b.ImuMs(149, t_ms, 0, 0, 1.0f);  // a slower third IMU
  }
  const FlightLog log = ParseDataFlash(b.bytes(), "old.bin");
  EXPECT_EQ(log.gyro_source, "IMU");
  ASSERT_EQ(log.gyro.size(), 100u);
  EXPECT_EQ(log.gyro[0].t_ns, 11'500 * int64_t{1'000'000}) << "TimeMS is milliseconds";
  EXPECT_EQ(log.gyro.sampling().median_interval_ns, 20'000'000);
  EXPECT_EQ(log.gyro[99].omega_rad_s.x(), static_cast<double>(0.01f * 99));
  ASSERT_EQ(log.gyro_sources_available.size(), 3u);
  EXPECT_EQ(log.gyro_sources_available[1], "IMU/1 (50.0 Hz, 100 samples)");
  EXPECT_EQ(log.gyro_sources_available[2], "IMU/2 (25.0 Hz, 50 samples)");
}

TEST(DataFlash, SaysWhenABatchEndsShortOfItsDeclaredSamples) {
  DataFlashBuilder b;
  b.Isbh(7, 1, 0, 938, 1024, 140'184'099, 2000.0f);
  for (uint16_t seq = 0; seq < 18; ++seq) b.Isbd(7, seq, std::vector<int16_t>(32, 5), {}, {});
  const FlightLog log = ParseDataFlash(b.bytes(), "short_batch.bin");
  EXPECT_EQ(log.gyro.size(), 576u);
  EXPECT_TRUE(
      test::AnyWarningContains(log, "gyro batch 7 (ISBH at 140.184 s): 576 of the 1024 samples"))
      << test::JoinedWarnings(log.warnings);
  EXPECT_TRUE(test::AnyWarningContains(log, "448 declared samples never logged"));
}

TEST(DataFlash, AppliesTheUnitsTableToGyroFields) {
  // A log whose FMTU/UNIT tables say GyrX..GyrZ are in deg/s ('k'); TimeUS in 's' units is ignored.
  DataFlashBuilder b;
  b.Fmt(40, 3 + 8 + 1 + 64, "UNIT", "QbZ", "TimeUS,Id,Label");
  b.Fmt(41, 3 + 8 + 1 + 16 + 16, "FMTU", "QBNN", "TimeUS,FmtType,UnitIds,MultIds");
  b.Unit(40, 'k', "deg/s");
  b.Unit(40, 's', "s");
  b.Fmtu(41, kImu, "s#kkk");  // TimeUS, I, GyrX, GyrY, GyrZ
  for (int k = 0; k < 20; ++k) b.Imu(1000 + k * 1000, 0, 90.0f, -180.0f, 0.0f);
  const FlightLog log = ParseDataFlash(b.bytes(), "units.bin");
  ASSERT_EQ(log.gyro.size(), 20u);
  EXPECT_DOUBLE_EQ(log.gyro[3].omega_rad_s.x(), 90.0 * kRadPerDeg);
  EXPECT_DOUBLE_EQ(log.gyro[3].omega_rad_s.y(), -180.0 * kRadPerDeg);
}

TEST(DataFlash, CameraEventsWithoutBootTimeAreCountedNotPlaced) {
  DataFlashBuilder b;
  b.Fmt(148, 31, "CAM", "IHLLeeccC", "GPSTime,GPSWeek,Lat,Lng,Alt,RelAlt,Roll,Pitch,Yaw");
  b.bytes() += std::string("\xA3\x95\x94", 3) + std::string(28, '\0');
  for (int k = 0; k < 10; ++k) b.Imu(1000 + k * 1000, 0, 0, 0, 0);
  const FlightLog log = ParseDataFlash(b.bytes(), "oldcam.bin");
  EXPECT_TRUE(log.camera_events.empty());
  EXPECT_TRUE(test::AnyWarningContains(log, "1 camera event(s) without a boot-time stamp"));
}

// GPS (TimeUS, I, Status, GMS, GWk): the boot clock against UTC from 3-D fixes of instance 0.
TEST(DataFlash, ReadsGpsTimeAgainstTheBootClock) {
  DataFlashBuilder b;
  b.Fmt(149, 3 + 8 + 1 + 1 + 4 + 2, "GPS", "QBBIH", "TimeUS,I,Status,GMS,GWk");
  auto gps = [&b](uint64_t t_us, uint8_t instance, uint8_t status, uint32_t gms) {
    b.bytes() += std::string("\xA3\x95\x95", 3);
    test::PutLittleEndian(&b.bytes(), t_us);
    test::PutLittleEndian(&b.bytes(), instance);
    test::PutLittleEndian(&b.bytes(), status);
    test::PutLittleEndian(&b.bytes(), gms);
    test::PutLittleEndian<uint16_t>(&b.bytes(), 2211);
  };
  gps(5'000'000, 0, 3, 296'288'242);
  gps(5'200'000, 1, 3, 296'288'442);  // a second receiver: not used
  gps(5'400'000, 0, 1, 296'288'642);  // no fix: not used
  gps(5'600'000, 0, 6, 296'288'842);  // RTK fixed
  for (int k = 0; k < 10; ++k) b.Imu(1000 + k * 1000, 0, 0, 0, 0);
  const FlightLog log = ParseDataFlash(b.bytes(), "gps.bin");
  ASSERT_EQ(log.utc_fixes.size(), 2u);
  EXPECT_EQ(log.utc_fixes[0].t_ns, 5'000'000'000);
  // GPS week 2211, 296288.242 s of week, less 18 leap seconds: 2022-05-25 10:17:50.242 UTC.
  EXPECT_EQ(UtcText(log.utc_fixes[0].utc_ns), "2022-05-25 10:17:50.242");
  EXPECT_EQ(log.utc_fixes[1].utc_ns - log.utc_fixes[0].utc_ns, 600'000'000);
}

// GPS Spd, GCrs, VZ: the velocity of instance 0's 3-D fixes, north, east, down; ATT Roll, Pitch,
// Yaw (degrees as floats, or centidegrees as an older log writes them): the attitude, Z-Y-X.
TEST(DataFlash, ReadsTheGpsVelocityAndTheAttitude) {
  DataFlashBuilder b;
  b.Fmt(149, 3 + 8 + 1 + 1 + 4 + 2 + 12, "GPS", "QBBIHfff", "TimeUS,I,Status,GMS,GWk,Spd,GCrs,VZ");
  b.Fmt(150, 3 + 8 + 12, "ATT", "Qfff", "TimeUS,Roll,Pitch,Yaw");
  auto gps = [&b](uint64_t t_us, uint8_t instance, uint8_t status, float speed, float course_deg,
                  float down) {
    b.bytes() += std::string("\xA3\x95\x95", 3);
    test::PutLittleEndian(&b.bytes(), t_us);
    test::PutLittleEndian(&b.bytes(), instance);
    test::PutLittleEndian(&b.bytes(), status);
    test::PutLittleEndian<uint32_t>(&b.bytes(), 296'288'242);
    test::PutLittleEndian<uint16_t>(&b.bytes(), 2211);
    for (float v : {speed, course_deg, down}) test::PutLittleEndian(&b.bytes(), v);
  };
  auto att = [&b](uint64_t t_us, float roll, float pitch, float yaw) {
    b.bytes() += std::string("\xA3\x95\x96", 3);
    test::PutLittleEndian(&b.bytes(), t_us);
    for (float v : {roll, pitch, yaw}) test::PutLittleEndian(&b.bytes(), v);
  };
  gps(5'000'000, 0, 3, 10.0f, 30.0f, -1.5f);  // 10 m/s toward 30 deg, climbing 1.5 m/s
  gps(5'100'000, 1, 3, 99.0f, 0.0f, 0.0f);    // a second receiver: not used
  gps(5'200'000, 0, 1, 99.0f, 0.0f, 0.0f);    // no fix: not used
  gps(5'400'000, 0, 3, 4.0f, 270.0f, 0.0f);   // 4 m/s west
  gps(5'600'000, 0, 3, 900.0f, 0.0f, 0.0f);   // beyond any flight: not used
  att(5'000'000, 10.0f, -20.0f, 90.0f);
  att(5'010'000, 11.0f, -20.0f, 90.0f);  // within 20 ms of the one before: not kept
  att(5'020'000, 0.0f, 0.0f, 350.0f);
  for (int k = 0; k < 10; ++k) b.Imu(1000 + k * 1000, 0, 0, 0, 0);
  const FlightLog log = ParseDataFlash(b.bytes(), "navigation.bin");
  EXPECT_EQ(log.velocity_source, "GPS.Spd,GCrs,VZ (3-D fix)");
  ASSERT_EQ(log.velocity.size(), 2u);
  EXPECT_EQ(log.velocity[0].t_ns, 5'000'000'000);
  EXPECT_NEAR((log.velocity[0].ned_mps - Eigen::Vector3d(10 * std::sqrt(0.75), 5.0, -1.5)).norm(),
              0.0, 1e-5);
  EXPECT_NEAR((log.velocity[1].ned_mps - Eigen::Vector3d(0.0, -4.0, 0.0)).norm(), 0.0, 1e-5);
  EXPECT_EQ(log.attitude_source, "ATT.Roll,Pitch,Yaw");
  ASSERT_EQ(log.attitude.size(), 2u);
  // Yaw 90 deg, pitch -20 deg (nose down), roll 10 deg: the nose points east and down by 20 deg,
  // the right wing south and down by 10 deg.
  const Eigen::Matrix3d ned_from_body = log.attitude[0].ned_from_body.toRotationMatrix();
  const double p = 20 * M_PI / 180, r = 10 * M_PI / 180;
  EXPECT_NEAR((ned_from_body.col(0) - Eigen::Vector3d(0.0, std::cos(p), std::sin(p))).norm(), 0.0,
              1e-6);
  EXPECT_NEAR(ned_from_body.col(1).z(), std::sin(r) * std::cos(p), 1e-6);
  EXPECT_LT(ned_from_body.col(1).x(), -0.9) << "the right wing to the south";
  EXPECT_EQ(log.attitude[1].t_ns, 5'020'000'000);
  EXPECT_NEAR(log.attitude[1].ned_from_body.angularDistance(Eigen::Quaterniond(
                  Eigen::AngleAxisd(-10 * M_PI / 180, Eigen::Vector3d::UnitZ()))),
              0.0, 1e-6);
}

// The EKF's velocity (XKF1 VN, VE, VD of core 0) is preferred to the GPS receiver's; a second EKF
// logged beside the first (NKF1 after XKF1) is not mixed in.
TEST(DataFlash, TheEkfsVelocityOverTheGps) {
  DataFlashBuilder b;
  b.Fmt(149, 3 + 8 + 1 + 1 + 4 + 2 + 12, "GPS", "QBBIHfff", "TimeUS,I,Status,GMS,GWk,Spd,GCrs,VZ");
  b.Fmt(151, 3 + 8 + 1 + 12, "XKF1", "QBfff", "TimeUS,C,VN,VE,VD");
  b.Fmt(152, 3 + 8 + 12, "NKF1", "Qfff", "TimeUS,VN,VE,VD");
  b.bytes() += std::string("\xA3\x95\x95", 3);
  test::PutLittleEndian<uint64_t>(&b.bytes(), 5'000'000);
  for (uint8_t v : {uint8_t{0}, uint8_t{3}}) test::PutLittleEndian(&b.bytes(), v);
  test::PutLittleEndian<uint32_t>(&b.bytes(), 296'288'242);
  test::PutLittleEndian<uint16_t>(&b.bytes(), 2211);
  for (float v : {10.0f, 30.0f, 0.0f}) test::PutLittleEndian(&b.bytes(), v);
  auto ekf = [&b](uint64_t t_us, uint8_t core, float n, float e, float d) {
    b.bytes() += std::string("\xA3\x95\x97", 3);
    test::PutLittleEndian(&b.bytes(), t_us);
    test::PutLittleEndian(&b.bytes(), core);
    for (float v : {n, e, d}) test::PutLittleEndian(&b.bytes(), v);
  };
  ekf(5'000'000, 0, 1.0f, 2.0f, 0.5f);
  ekf(5'000'000, 1, 7.0f, 7.0f, 7.0f);          // the second core: not used
  b.bytes() += std::string("\xA3\x95\x98", 3);  // the other EKF: not used
  test::PutLittleEndian<uint64_t>(&b.bytes(), 5'050'000);
  for (float v : {9.0f, 9.0f, 9.0f}) test::PutLittleEndian(&b.bytes(), v);
  ekf(5'100'000, 0, 1.5f, 2.5f, 0.0f);
  for (int k = 0; k < 10; ++k) b.Imu(1000 + k * 1000, 0, 0, 0, 0);
  const FlightLog log = ParseDataFlash(b.bytes(), "ekf.bin");
  EXPECT_EQ(log.velocity_source, "XKF1.VN,VE,VD (core 0)") << "the first EKF logged";
  ASSERT_EQ(log.velocity.size(), 2u);
  EXPECT_EQ(log.velocity[0].ned_mps, Eigen::Vector3d(1.0, 2.0, 0.5));
  EXPECT_EQ(log.velocity[1].t_ns, 5'100'000'000);

  // AHRS_EKF_TYPE names the EKF the autopilot flew on; the last value logged counts.
  DataFlashBuilder flown_on_ekf2 = b;
  flown_on_ekf2.Parm(6'000'000, "AHRS_EKF_TYPE", 3.0f);
  flown_on_ekf2.Parm(6'000'001, "AHRS_EKF_TYPE", 2.0f);
  const FlightLog ekf2 = ParseDataFlash(flown_on_ekf2.bytes(), "ekf2.bin");
  EXPECT_EQ(ekf2.velocity_source, "NKF1.VN,VE,VD, the EKF flown on (AHRS_EKF_TYPE 2)");
  ASSERT_EQ(ekf2.velocity.size(), 1u);
  EXPECT_EQ(ekf2.velocity[0].ned_mps, Eigen::Vector3d(9.0, 9.0, 9.0));
  DataFlashBuilder flown_on_ekf3 = b;
  flown_on_ekf3.Parm(6'000'000, "AHRS_EKF_TYPE", 3.0f);
  EXPECT_EQ(ParseDataFlash(flown_on_ekf3.bytes(), "ekf3.bin").velocity_source,
            "XKF1.VN,VE,VD (core 0), the EKF flown on (AHRS_EKF_TYPE 3)");
  DataFlashBuilder flown_on_dcm = b;  // no EKF flown: the first logged
  flown_on_dcm.Parm(6'000'000, "AHRS_EKF_TYPE", 0.0f);
  EXPECT_EQ(ParseDataFlash(flown_on_dcm.bytes(), "dcm.bin").velocity_source,
            "XKF1.VN,VE,VD (core 0)");
}

TEST(DataFlash, TruncatedCopyKeepsWhatCameBefore) {
  DataFlashBuilder b = FlightFile(1000);
  const std::string& bytes = b.bytes();
  const std::string cut = bytes.substr(0, bytes.size() / 2 + 7);
  const FlightLog log = ParseDataFlash(cut, "cut.bin");
  EXPECT_TRUE(test::AnyWarningContains(log, "truncated")) << log.warnings.size();
  EXPECT_GT(log.gyro.size(), 400u);
  EXPECT_LT(log.gyro.size(), 1000u);
  for (size_t k = 0; k < log.gyro.size(); ++k) {
    ASSERT_EQ(log.gyro[k].t_ns, (2'000'000 + static_cast<int64_t>(k) * 1000) * 1000) << k;
  }
}

TEST(DataFlash, CorruptedCopySkipsDamageAndReadsOn) {
  DataFlashBuilder b = FlightFile(1000);
  std::string bytes = b.bytes();
  // Destroy the header of one GYR message in the middle and scribble over another's header.
  const size_t first_gyr = bytes.find(std::string("\xA3\x95\x0A", 3));
  size_t damaged = first_gyr;
  for (int i = 0; i < 300; ++i) damaged = bytes.find(std::string("\xA3\x95\x0A", 3), damaged + 1);
  bytes[damaged] = 0x00;
  size_t second = damaged;
  for (int i = 0; i < 200; ++i) second = bytes.find(std::string("\xA3\x95\x0A", 3), second + 1);
  bytes.replace(second + 1, 3, "xyz");
  const FlightLog log = ParseDataFlash(bytes, "corrupt.bin");
  EXPECT_EQ(log.gyro_source, "GYR");
  EXPECT_EQ(log.records_skipped, 2u);
  EXPECT_TRUE(test::AnyWarningContains(log, "corrupt bytes skipped in total"));
  // The two damaged GYR messages are lost (of instance 0 or 1), nothing else.
  EXPECT_GE(log.gyro.size(), 998u);
  EXPECT_EQ(log.camera_events.size(), 10u);  // the CAM ones (TRIG not used)
}

TEST(DataFlash, RandomDamageGivesErrorOrPartialResult) {
  const std::string bytes = FlightFile(400).bytes();
  std::mt19937_64 rng(99);
  std::uniform_int_distribution<size_t> where(0, bytes.size() - 1);
  std::uniform_int_distribution<int> value(0, 255);
  for (int trial = 0; trial < 20; ++trial) {
    std::string copy = bytes.substr(0, where(rng));
    for (int k = 0; k < 16 && !copy.empty(); ++k) {
      const size_t at = where(rng) % copy.size();
      copy[at] = static_cast<char>(value(rng));
    }
    const std::string name = "damaged_" + std::to_string(trial) + ".bin";
    try {
      const FlightLog log = ParseDataFlash(copy, name);
      EXPECT_GE(log.gyro.size(), 2u);
      EXPECT_LE(log.gyro.size(), 400u);
    } catch (const IoError& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
}

TEST(DataFlash, SkipsInconsistentFmt) {
  DataFlashBuilder b;
  b.Fmt(20, 50, "GYR2", "QBQfff", "TimeUS,I,SampleUS,GyrX,GyrY,GyrZ");  // needs 32, says 50
  b.Fmt(21, 14, "BAD", "QX", "TimeUS,What");                            // unknown format char
  b.Fmt(22, 11, "LBL", "Q", "TimeUS,Extra");                            // label count mismatch
  for (int k = 0; k < 10; ++k) b.Gyr(1000 + k * 1000, 0, 1000 + k * 1000, 0, 0, 0);
  const FlightLog log = ParseDataFlash(b.bytes(), "fmt.bin");
  EXPECT_EQ(log.records_skipped, 3u);
  EXPECT_TRUE(test::AnyWarningContains(log, "declares length 50 but its format 'QBQfff' needs 32"));
  EXPECT_TRUE(test::AnyWarningContains(log, "unknown format character 'X'"));
  EXPECT_TRUE(test::AnyWarningContains(log, "2 labels"));
  EXPECT_EQ(log.gyro.size(), 10u);
}

TEST(DataFlash, RejectsWhatIsNotDataFlash) {
  EXPECT_FALSE(LooksLikeDataFlash(std::string("\xA3\x95", 2)));
  EXPECT_FALSE(LooksLikeDataFlash("ULog\x01\x12\x35\x01"));
  EXPECT_FALSE(LooksLikeDataFlash(std::string("\xA3\x95\x80\x80\x10", 5)));
  EXPECT_TRUE(LooksLikeDataFlash(std::string("\xA3\x95\x80\x80\x59", 5)));
  EXPECT_THROW(ParseDataFlash("H Product:Blackbox flight data recorder", "bf.bin"), IoError);
  DataFlashBuilder b;
  b.Parm(1, "X", 1.0f);
  try {
    ParseDataFlash(b.bytes(), "nogyro.bin");
    FAIL() << "a log without gyro data must throw";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("nogyro.bin: no usable gyro data"), std::string::npos)
        << e.what();
  }
}

TEST(DataFlash, ReadsFromDisk) {
  test::TempDir dir;
  const std::string path = dir / "flight.bin";
  WriteFileAtomically(path, FlightFile(50).bytes());
  EXPECT_EQ(ReadDataFlash(path).gyro.size(), 50u);
  EXPECT_THROW(ReadDataFlash(dir / "missing.bin"), IoError);
}

// ---- The streamed reader (OpenDataFlash): pass 2 in chunks gives what the whole read gives.

// What a streamed read gives: the log, or the error's text.
struct Outcome {
  FlightLog log;
  std::string error;
};

Outcome Streamed(std::string_view bytes, const std::string& path, size_t chunk_samples,
                 internal::CandidateLimits limits) {
  Outcome out;
  try {
    DataFlashStream stream = OpenDataFlash(bytes, path, chunk_samples, limits);
    out.log = std::move(stream.log);
    std::vector<GyroSample> samples;
    for (GyroChunk chunk = stream.samples->Next(); !chunk.empty(); chunk = stream.samples->Next()) {
      EXPECT_LE(chunk.size, chunk_samples);
      samples.insert(samples.end(), chunk.begin(), chunk.end());
    }
    EXPECT_EQ(stream.samples->Fraction(), 1.0);
    out.log.gyro = GyroTrace(std::move(samples));
  } catch (const IoError& e) {
    out.error = e.what();
  }
  return out;
}

Outcome Whole(std::string_view bytes, const std::string& path) {
  Outcome out;
  try {
    out.log = ParseDataFlash(bytes, path);
  } catch (const IoError& e) {
    out.error = e.what();
  }
  return out;
}

// Equal in every field; a "memory" warning (pass 1 redone without limits) is allowed in `a` only.
void ExpectSameOutcome(const Outcome& a, const Outcome& b, const std::string& what) {
  ASSERT_EQ(a.error, b.error) << what;
  EXPECT_EQ(a.log.format, b.log.format) << what;
  EXPECT_EQ(a.log.gyro_source, b.log.gyro_source) << what;
  EXPECT_EQ(a.log.gyro_sources_available, b.log.gyro_sources_available) << what;
  EXPECT_EQ(a.log.records_skipped, b.log.records_skipped) << what;
  EXPECT_EQ(a.log.altitude_above_ground_m, b.log.altitude_above_ground_m) << what;
  EXPECT_EQ(a.log.camera_events.size(), b.log.camera_events.size()) << what;
  EXPECT_EQ(a.log.utc_fixes.size(), b.log.utc_fixes.size()) << what;
  std::vector<std::string> wa, wb;
  for (const LogWarning& w : a.log.warnings) {
    if (w.kind != "memory") wa.push_back(w.kind + ": " + w.message);
  }
  for (const LogWarning& w : b.log.warnings) wb.push_back(w.kind + ": " + w.message);
  EXPECT_EQ(wa, wb) << what;
  ASSERT_EQ(a.log.gyro.size(), b.log.gyro.size()) << what;
  for (size_t i = 0; i < a.log.gyro.size(); ++i) {
    ASSERT_EQ(a.log.gyro[i].t_ns, b.log.gyro[i].t_ns) << what << " sample " << i;
    ASSERT_EQ(a.log.gyro[i].omega_rad_s, b.log.gyro[i].omega_rad_s) << what << " sample " << i;
  }
}

// A GYR stream with its times out of order: 40 samples stamped 300 samples late and a run of 5
// stamped back by 20 samples (both are sorted), so that pass 2 must hold samples back.
std::string DisorderedFile() {
  DataFlashBuilder b;
  for (int k = 0; k < 1200; ++k) {
    int64_t sample_us = 2'000'000 + k * 1000;
    if (k >= 500 && k < 540) sample_us += 300'000;
    if (k >= 900 && k < 905) sample_us -= 20'000;
    b.Gyr(sample_us + 250, 0, static_cast<uint64_t>(sample_us), 0.5f * k, 0.0f, 1.0f);
    if (k % 3 == 0) b.Imu(2'000'500 + k * 1000, 0, 0.1f, 0.2f, 0.3f);
  }
  return b.bytes();
}

// Gyro batches (ISBH/ISBD) at 2 kHz, a batch of 100 samples every 50 ms, one cut short.
std::string BatchFile() {
  DataFlashBuilder b;
  for (uint16_t n = 0; n < 20; ++n) {
    const uint64_t start_us = 1'000'000 + n * 50'000;
    b.Isbh(n, 1, 0, 100, 100, start_us, 2000.0f);
    for (uint16_t seq = 0; seq < (n == 7 ? 2 : 4); ++seq) {
      std::vector<int16_t> x(32), y(32), z(32);
      for (int k = 0; k < 32; ++k) x[k] = static_cast<int16_t>(n * 100 + seq * 32 + k);
      b.Isbd(n, seq, x, y, z);
    }
  }
  for (int k = 0; k < 200; ++k) b.Imu(1'000'000 + k * 5000, 0, 0.1f, 0.2f, 0.3f);
  return b.bytes();
}

TEST(DataFlashStream, ChunksAndLimitsDoNotChangeWhatIsRead) {
  std::vector<std::pair<std::string, std::string>> inputs = {
      {"flight.bin", FlightFile(600).bytes()},
      {"disordered.bin", DisorderedFile()},
      {"batches.bin", BatchFile()}};
  // Cut and damaged copies, as RandomDamageGivesErrorOrPartialResult makes them.
  std::mt19937_64 rng(15);
  for (size_t i = 0, n = inputs.size(); i < n; ++i) {
    const std::string bytes = inputs[i].second;
    std::uniform_int_distribution<size_t> where(0, bytes.size() - 1);
    for (int trial = 0; trial < 6; ++trial) {
      std::string copy = bytes.substr(0, where(rng));
      for (int k = 0; k < trial * 3 && !copy.empty(); ++k)
        copy[where(rng) % copy.size()] = static_cast<char>(rng() & 0xff);
      inputs.push_back({"copy_" + std::to_string(i) + "_" + std::to_string(trial), copy});
    }
  }
  size_t redone = 0;
  for (const auto& [name, bytes] : inputs) {
    const Outcome whole = Whole(bytes, name);
    for (size_t chunk : {1, 7, 1000}) {
      for (internal::CandidateLimits limits :
           {internal::CandidateLimits{}, internal::CandidateLimits{8, 4}}) {
        const Outcome streamed = Streamed(bytes, name, chunk, limits);
        redone += test::AnyWarningContains(streamed.log.warnings, "held in memory whole");
        ExpectSameOutcome(streamed, whole,
                          name + " chunk " + std::to_string(chunk) + " reorder limit " +
                              std::to_string(limits.reorder_samples));
        if (HasFailure()) return;
      }
    }
  }
  EXPECT_GT(redone, 3u);  // small limits do send some logs the way without limits
  // The disordered stream is read sorted, all of it, with the disorder said.
  const FlightLog log = ParseDataFlash(DisorderedFile(), "disordered.bin");
  EXPECT_EQ(log.gyro.size(), 1200u);
  // (Counted where the times step back: after the late run, and at the run stamped early.)
  EXPECT_TRUE(
      test::AnyWarningContains(log, "GYR: 2 samples were out of time order and were sorted"))
      << test::JoinedWarnings(log.warnings);
}

TEST(DataFlashStream, AFileIsReadTheSameWayAsBytesInMemory) {
  test::TempDir dir;
  const std::string path = dir / "batches.bin";
  const std::string bytes = BatchFile();
  WriteFileAtomically(path, bytes);
  DataFlashStream stream = OpenDataFlash(path, 5);
  Outcome from_file;
  from_file.log = std::move(stream.log);
  from_file.log.gyro = ReadAllSamples(stream.samples.get());
  ExpectSameOutcome(from_file, Whole(bytes, path), "file");
  EXPECT_EQ(from_file.log.gyro_source, "ISBD");
  EXPECT_EQ(from_file.log.gyro.size(), 19u * 100 + 64);
}

TEST(DataFlashStream, AFileChangedBetweenThePassesIsRefusedInOneLine) {
  test::TempDir dir;
  const std::string path = dir / "recording.bin";
  const std::string bytes = FlightFile(300).bytes();
  for (const char* change : {"grown", "cut"}) {
    WriteFileAtomically(path, bytes);
    DataFlashStream stream = OpenDataFlash(path, 16);
    if (std::string(change) == "grown") {
      std::ofstream(path, std::ios::app | std::ios::binary) << bytes.substr(0, 100);
    } else {
      std::filesystem::resize_file(path, bytes.size() / 2);
    }
    try {
      ReadAllSamples(stream.samples.get());
      FAIL() << change << ": a changed file must be refused";
    } catch (const IoError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(path + ": changed while it was read in passes"), std::string::npos)
          << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  }
}

TEST(DataFlashStream, RealLogsStreamedInSmallChunksAreReadAsWhole) {
  for (const char* relative :
       {"incoming/ardupilot_log171/log171.bin", "incoming/ardupilot_isb_80k/backend_log_80k.bin",
        "incoming/ardupilot_pymavlink_test/test.BIN"}) {
    SHUTTERLAB_REAL_DATA(path, relative);
    const std::string bytes = ReadFileToString(path);
    DataFlashStream stream = OpenDataFlash(path, 13);
    Outcome streamed;
    streamed.log = std::move(stream.log);
    streamed.log.gyro = ReadAllSamples(stream.samples.get());
    ExpectSameOutcome(Streamed(bytes, path, 1 << 14, internal::CandidateLimits{16, 16}), streamed,
                      relative);
    EXPECT_GE(streamed.log.gyro.size(), 2u) << relative;
  }
}

}  // namespace
}  // namespace shutterlab
