#include "sim/logs/ulog.h"

#include "sim/check.h"
#include "sim/text_file.h"
#include "tests/sim/logs/same_log.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <optional>
#include <random>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

using test::ExpectSameLog;

// Writes a ULog file message by message, as PX4's logger lays it out.
class ULogBuilder {
 public:
  explicit ULogBuilder(uint8_t version = 1) {
    bytes_.append("ULog\x01\x12\x35", 7);
    test::PutLittleEndian<uint8_t>(&bytes_, version);
    test::PutLittleEndian<uint64_t>(&bytes_, 1'000'000);
  }
  void Message(char type, const std::string& payload) {
    test::PutLittleEndian<uint16_t>(&bytes_, static_cast<uint16_t>(payload.size()));
    bytes_.push_back(type);
    bytes_ += payload;
  }
  void FlagBits(uint8_t incompat0, uint64_t appended_offset = 0, uint8_t incompat1 = 0) {
    std::string p(8, '\0');  // compat flags
    p.push_back(static_cast<char>(incompat0));
    p.push_back(static_cast<char>(incompat1));
    p.append(6, '\0');
    test::PutLittleEndian<uint64_t>(&p, appended_offset);
    test::PutLittleEndian<uint64_t>(&p, 0);
    test::PutLittleEndian<uint64_t>(&p, 0);
    Message('B', p);
  }
  void Format(const std::string& text) { Message('F', text); }
  void AddLogged(uint8_t multi_id, uint16_t msg_id, const std::string& topic) {
    std::string p;
    test::PutLittleEndian<uint8_t>(&p, multi_id);
    test::PutLittleEndian<uint16_t>(&p, msg_id);
    Message('A', p + topic);
  }
  void Data(uint16_t msg_id, const std::string& fields) {
    std::string p;
    test::PutLittleEndian<uint16_t>(&p, msg_id);
    Message('D', p + fields);
  }
  void Dropout(uint16_t ms) {
    std::string p;
    test::PutLittleEndian<uint16_t>(&p, ms);
    Message('O', p);
  }
  std::string& bytes() { return bytes_; }

 private:
  std::string bytes_;
};

constexpr char kFifoFormat[] =
    "sensor_gyro_fifo:uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;float dt;"
    "float scale;uint8_t samples;int16_t[32] x;int16_t[32] y;int16_t[32] z;uint8_t[1] _padding0;";
constexpr char kCombinedFormat[] =
    "sensor_combined:uint64_t timestamp;float[3] gyro_rad;uint32_t gyro_integral_dt;"
    "int32_t accelerometer_timestamp_relative;float[3] accelerometer_m_s2;uint8_t[4] _padding0;";

std::string FifoRecord(uint64_t t_us, uint64_t t_sample_us, float dt_us, float scale, uint8_t n,
                       const std::vector<int16_t>& x, const std::vector<int16_t>& y,
                       const std::vector<int16_t>& z) {
  std::string r;
  test::PutLittleEndian<uint64_t>(&r, t_us);
  test::PutLittleEndian<uint64_t>(&r, t_sample_us);
  test::PutLittleEndian<uint32_t>(&r, 42);
  test::PutLittleEndian<float>(&r, dt_us);
  test::PutLittleEndian<float>(&r, scale);
  test::PutLittleEndian<uint8_t>(&r, n);
  for (const auto* axis : {&x, &y, &z}) {
    for (size_t i = 0; i < 32; ++i)
      test::PutLittleEndian<int16_t>(&r, i < axis->size() ? (*axis)[i] : int16_t{0});
  }
  return r;  // trailing _padding0 left out, as PX4 does
}

std::string CombinedRecord(uint64_t t_us, float gx, float gy, float gz) {
  std::string r;
  test::PutLittleEndian<uint64_t>(&r, t_us);
  test::PutLittleEndian<float>(&r, gx);
  test::PutLittleEndian<float>(&r, gy);
  test::PutLittleEndian<float>(&r, gz);
  test::PutLittleEndian<uint32_t>(&r, 4000);
  test::PutLittleEndian<int32_t>(&r, 0);
  for (int i = 0; i < 3; ++i) test::PutLittleEndian<float>(&r, 9.81f);
  return r;
}

std::string SamplePath(const std::string& name) {
  return test::RealDataPath("gyro/px4_ulog/" + name);
}

double PeakRate(const GyroTrace& trace) {
  double peak = 0.0;
  for (const GyroSample& s : trace.samples()) peak = std::max(peak, s.omega_rad_s.norm());
  return peak;
}

// ------------------------------------------------------------------------------ real files

TEST(ULog, SampleV0MatchesItsDocumentedContents) {
  SHUTTERLAB_NEED_REAL_DATA();
  const std::string bytes = ReadFileToString(SamplePath("sample.ulg"));
  ASSERT_TRUE(LooksLikeULog(bytes));
  EXPECT_EQ(bytes[7], 0) << "sample.ulg is a version-0 file";
  const FlightLog log = ReadULog(SamplePath("sample.ulg"));
  EXPECT_EQ(log.format, "ulog");
  EXPECT_EQ(log.gyro_source, "sensor_combined.gyro_rad");
  ASSERT_EQ(log.gyro.size(), 17070u);
  constexpr double kDurationTolS = 0.05;  // SOURCES.md gives 68.9 s to one decimal
  EXPECT_NEAR(log.gyro.DurationS(), 68.9, kDurationTolS);
  const double mean_rate_hz = (log.gyro.size() - 1) / log.gyro.DurationS();
  constexpr double kRateTolHz = 1.0;  // "~248 Hz" is the mean rate
  EXPECT_NEAR(mean_rate_hz, 248.0, kRateTolHz);
  EXPECT_EQ(log.gyro.sampling().median_interval_ns, 4'000'000) << "median dt 4.0 ms";
  constexpr double kPeakTol = 0.005;  // SOURCES.md gives 3.29 rad/s to two decimals
  EXPECT_NEAR(PeakRate(log.gyro), 3.29, kPeakTol);
  EXPECT_TRUE(test::AnyWarningContains(log, "4 logging dropouts totalling 119 ms"))
      << log.warnings.size();
  EXPECT_FALSE(log.gyro.sampling().gap_indices.empty()) << "the 62 ms dropout must show as a gap";
  EXPECT_TRUE(log.camera_events.empty());
  EXPECT_EQ(log.records_skipped, 0u);
  // vehicle_local_position.z stays near 0.1 m and dist_bottom near 0: never airborne by the log.
  EXPECT_FALSE(log.altitude_above_ground_m.has_value());
}

TEST(ULog, SampleSmallV1MatchesItsDocumentedContents) {
  SHUTTERLAB_NEED_REAL_DATA();
  const std::string bytes = ReadFileToString(SamplePath("sample_log_small.ulg"));
  EXPECT_EQ(bytes[7], 1) << "sample_log_small.ulg is a version-1 file";
  const FlightLog log = ParseULog(bytes, "sample_log_small.ulg");
  EXPECT_EQ(log.gyro_source, "vehicle_angular_velocity.xyz");
  ASSERT_EQ(log.gyro.size(), 1812u);
  const double mean_rate_hz = (log.gyro.size() - 1) / log.gyro.DurationS();
  constexpr double kRateTolHz = 3.0;  // "~280 Hz" is the mean rate
  EXPECT_NEAR(mean_rate_hz, 280.0, kRateTolHz);
  // Publications alternate ~2.4 ms and ~4.9 ms apart; the median interval is the short one.
  EXPECT_EQ(log.gyro.sampling().median_interval_ns, 2'445'000);
  EXPECT_TRUE(test::AnyWarningContains(log, "1 logging dropouts totalling 30 ms"));
  ASSERT_GE(log.gyro_sources_available.size(), 3u);
  EXPECT_EQ(log.gyro_sources_available[0].rfind("vehicle_angular_velocity.xyz (", 0), 0u);
  EXPECT_TRUE(std::any_of(
      log.gyro_sources_available.begin(), log.gyro_sources_available.end(),
      [](const std::string& s) { return s.rfind("sensor_combined.gyro_rad (", 0) == 0; }));
  EXPECT_TRUE(std::any_of(
      log.gyro_sources_available.begin(), log.gyro_sources_available.end(),
      [](const std::string& s) { return s.rfind("sensor_gyro/2.x,y,z (1.0 Hz", 0) == 0; }))
      << "three sensor_gyro instances at 1 Hz";
  constexpr double kStationaryPeak = 0.1;  // rad/s; a vehicle on the bench
  EXPECT_LT(PeakRate(log.gyro), kStationaryPeak);
  EXPECT_TRUE(log.camera_events.empty());
}

// Renames the subscription ('A' message) of a topic so that the reader no longer sees it.
std::string HideSubscription(std::string bytes, const std::string& topic) {
  size_t at = 0;
  while ((at = bytes.find(topic, at)) != std::string::npos) {
    // An 'A' payload is multi_id(1) msg_id(2) name: the type byte sits 4 bytes before the name.
    if (at >= 6 && bytes[at - 4] == 'A' && at + topic.size() <= bytes.size()) {
      bytes[at] = 'X';
    }
    at += topic.size();
  }
  return bytes;
}

TEST(ULog, SampleSmallSensorCombinedIsStationary) {
  SHUTTERLAB_NEED_REAL_DATA();
  const std::string bytes = HideSubscription(ReadFileToString(SamplePath("sample_log_small.ulg")),
                                             "vehicle_angular_velocity");
  const FlightLog log = ParseULog(bytes, "sample_log_small.ulg");
  EXPECT_EQ(log.gyro_source, "sensor_combined.gyro_rad");
  EXPECT_EQ(log.gyro.size(), 1298u);
  constexpr double kPeakTol = 0.0005;  // SOURCES.md gives 0.016 rad/s
  EXPECT_NEAR(PeakRate(log.gyro), 0.016, kPeakTol);
}

// ------------------------------------------------------------------------------ synthetic files

TEST(ULog, UnpacksSensorGyroFifoWithScaleAndDt) {
  ULogBuilder b;
  b.FlagBits(0);
  b.Format(kFifoFormat);
  b.Format(kCombinedFormat);
  b.AddLogged(0, 0, "sensor_gyro_fifo");
  b.AddLogged(1, 1, "sensor_gyro_fifo");
  b.AddLogged(0, 2, "sensor_combined");
  const float scale = 0.0010652644f;  // 2000 deg/s over int16, as a ICM-42688 reports it
  const float dt_us = 125.0f;         // 8 kHz
  std::vector<int64_t> expected_t_ns;
  std::vector<double> expected_x;
  for (int m = 0; m < 50; ++m) {
    const uint64_t newest_us = 2'000'000 + m * 1000;  // 8 samples per ms
    std::vector<int16_t> x, y, z;
    for (int i = 0; i < 8; ++i) {
      x.push_back(static_cast<int16_t>(m * 8 + i));
      y.push_back(static_cast<int16_t>(-100 - i));
      z.push_back(static_cast<int16_t>(7));
      expected_t_ns.push_back(static_cast<int64_t>(newest_us) * 1000 - (7 - i) * 125'000);
      expected_x.push_back((m * 8 + i) * static_cast<double>(scale));
    }
    b.Data(0, FifoRecord(newest_us + 50, newest_us, dt_us, scale, 8, x, y, z));
    if (m % 10 == 0) b.Data(1, FifoRecord(newest_us, newest_us, 1000.0f, scale, 1, {1}, {1}, {1}));
    if (m % 4 == 0) b.Data(2, CombinedRecord(newest_us, 0.1f, 0.2f, 0.3f));
  }
  const FlightLog log = ParseULog(b.bytes(), "fifo.ulg");
  EXPECT_EQ(log.gyro_source, "sensor_gyro_fifo.x,y,z");
  ASSERT_EQ(log.gyro.size(), expected_t_ns.size());
  for (size_t k = 0; k < expected_t_ns.size(); ++k) {
    EXPECT_EQ(log.gyro[k].t_ns, expected_t_ns[k]) << k;
    EXPECT_EQ(log.gyro[k].omega_rad_s.x(), expected_x[k]) << k;
  }
  EXPECT_EQ(log.gyro[3].omega_rad_s.y(), -103 * static_cast<double>(scale));
  EXPECT_EQ(log.gyro.sampling().median_interval_ns, 125'000);
  ASSERT_EQ(log.gyro_sources_available.size(), 3u);
  EXPECT_EQ(log.gyro_sources_available[0], "sensor_gyro_fifo.x,y,z (8000.0 Hz, 400 samples)");
  EXPECT_EQ(log.gyro_sources_available[1], "sensor_combined.gyro_rad (250.0 Hz, 13 samples)");
  EXPECT_EQ(log.gyro_sources_available[2], "sensor_gyro_fifo/1.x,y,z (100.0 Hz, 5 samples)");
  EXPECT_EQ(log.records_skipped, 0u);
}

TEST(ULog, ReadsNestedTypesAndOmittedTrailingPadding) {
  ULogBuilder b(0);  // version 0: no flag bits message
  b.Format("meta:uint16_t a;float b;");
  b.Format(
      "vehicle_angular_velocity:uint64_t timestamp;meta[2] m;uint64_t timestamp_sample;float[3] "
      "xyz;"
      "uint8_t[4] _padding0;");
  b.AddLogged(0, 7, "vehicle_angular_velocity");
  for (int k = 0; k < 20; ++k) {
    std::string r;
    test::PutLittleEndian<uint64_t>(&r, 5'000'000 + k * 2000 + 300);
    for (int j = 0; j < 2; ++j) {
      test::PutLittleEndian<uint16_t>(&r, 0xFFFF);
      test::PutLittleEndian<float>(&r, -1.0f);
    }
    test::PutLittleEndian<uint64_t>(&r, 5'000'000 + k * 2000);
    test::PutLittleEndian<float>(&r, 0.5f * k);
    test::PutLittleEndian<float>(&r, -0.25f);
    test::PutLittleEndian<float>(&r, 2.0f);
    if (k % 2 == 1) r.append(4, '\0');  // some writers keep the padding; both are valid
    b.Data(7, r);
  }
  const FlightLog log = ParseULog(b.bytes(), "nested.ulg");
  EXPECT_EQ(log.gyro_source, "vehicle_angular_velocity.xyz");
  ASSERT_EQ(log.gyro.size(), 20u);
  for (int k = 0; k < 20; ++k) {
    EXPECT_EQ(log.gyro[k].t_ns, (5'000'000 + k * 2000) * int64_t{1000})
        << "timestamp_sample, not timestamp";
    EXPECT_EQ(log.gyro[k].omega_rad_s, Eigen::Vector3d(0.5 * k, -0.25, 2.0));
  }
  EXPECT_EQ(log.records_skipped, 0u);
}

TEST(ULog, SurvivesHostileFormats) {
  ULogBuilder b;
  b.FlagBits(0);
  b.Format(kCombinedFormat);
  b.Format("empty:");
  b.Format("loop:uint8_t a;loop[2] again;");
  b.Format("vehicle_angular_velocity:uint64_t timestamp;empty[65535] e;float[3] xyz;");
  b.Format("sensor_gyro:uint64_t timestamp;loop inner;float x;float y;float z;");
  b.Format("sensor_gyro_fifo:uint64_t timestamp;uint8_t[65535] big;uint8_t[65535] bigger;");
  b.Format("broken format without a colon");
  b.AddLogged(0, 0, "sensor_combined");
  b.AddLogged(0, 1, "vehicle_angular_velocity");
  b.AddLogged(0, 2, "sensor_gyro");
  b.AddLogged(0, 3, "sensor_gyro_fifo");
  for (int k = 0; k < 10; ++k) b.Data(0, CombinedRecord(1'000'000 + k * 4000, 0, 0, 0));
  const FlightLog log = ParseULog(b.bytes(), "hostile.ulg");
  EXPECT_EQ(log.gyro_source, "sensor_combined.gyro_rad");
  EXPECT_TRUE(test::AnyWarningContains(log, "nested type 'empty' has no bytes"));
  EXPECT_TRUE(test::AnyWarningContains(log, "nesting deeper than"));
  EXPECT_TRUE(test::AnyWarningContains(log, "larger than a ULog message can be"));
  EXPECT_TRUE(test::AnyWarningContains(log, "malformed format definition"));
}

TEST(ULog, ReadsAppendedDataAfterACutMessage) {
  ULogBuilder b;
  b.FlagBits(1, 0);  // offset patched below
  const size_t flag_offsets_at = 16 + 3 + 16;
  b.Format(kCombinedFormat);
  b.AddLogged(0, 3, "sensor_combined");
  for (int k = 0; k < 10; ++k) b.Data(3, CombinedRecord(1'000'000 + k * 4000, 0.01f * k, 0, 0));
  // The logger stopped in the middle of a message and later appended data at a known offset.
  std::string cut;
  test::PutLittleEndian<uint16_t>(&cut, 2 + 44);
  cut.push_back('D');
  cut += "\x03\x00partial";
  b.bytes() += cut;
  const uint64_t appended_at = b.bytes().size();
  std::memcpy(&b.bytes()[flag_offsets_at], &appended_at, 8);
  for (int k = 10; k < 15; ++k) b.Data(3, CombinedRecord(1'000'000 + k * 4000, 0.01f * k, 0, 0));
  const FlightLog log = ParseULog(b.bytes(), "appended.ulg");
  ASSERT_EQ(log.gyro.size(), 15u);
  for (int k = 0; k < 15; ++k) EXPECT_FLOAT_EQ(log.gyro[k].omega_rad_s.x(), 0.01f * k);
  EXPECT_EQ(log.records_skipped, 0u);
}

TEST(ULog, RefusesUnknownIncompatibleFlags) {
  ULogBuilder b;
  b.FlagBits(0, 0, /*incompat1=*/4);
  b.Format(kCombinedFormat);
  EXPECT_THROW(ParseULog(b.bytes(), "flags.ulg"), IoError);
  ULogBuilder c;
  c.FlagBits(2);
  EXPECT_THROW(ParseULog(c.bytes(), "flags.ulg"), IoError);
}

TEST(ULog, ReportsDropoutsAsGapsAndWarnings) {
  ULogBuilder b;
  b.FlagBits(0);
  b.Format(kCombinedFormat);
  b.AddLogged(0, 0, "sensor_combined");
  for (int k = 0; k < 100; ++k) {
    if (k == 50) b.Dropout(40);
    const int64_t t_us = 1'000'000 + k * 4000 + (k >= 50 ? 40'000 : 0);
    b.Data(0, CombinedRecord(t_us, 0, 0, 0));
  }
  const FlightLog log = ParseULog(b.bytes(), "dropout.ulg");
  EXPECT_TRUE(
      test::AnyWarningContains(log, "1 logging dropouts totalling 40 ms (40 ms at 1.196 s)"));
  ASSERT_EQ(log.gyro.sampling().gap_indices.size(), 1u);
  EXPECT_EQ(log.gyro.sampling().gap_indices[0], 49u);
}

TEST(ULog, ChoosesRawerSourceOnlyAtSimilarRate) {
  const std::string sensor_gyro_format =
      "sensor_gyro:uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;float x;float y;"
      "float z;float temperature;uint32_t error_count;";
  const std::string vav_format =
      "vehicle_angular_velocity:uint64_t timestamp;uint64_t timestamp_sample;float[3] xyz;";
  auto gyro_record = [](uint64_t t_us) {
    std::string r;
    test::PutLittleEndian<uint64_t>(&r, t_us);
    test::PutLittleEndian<uint64_t>(&r, t_us);
    test::PutLittleEndian<uint32_t>(&r, 1);
    for (int i = 0; i < 4; ++i) test::PutLittleEndian<float>(&r, 0.0f);
    test::PutLittleEndian<uint32_t>(&r, 0);
    return r;
  };
  auto vav_record = [](uint64_t t_us) {
    std::string r;
    test::PutLittleEndian<uint64_t>(&r, t_us);
    test::PutLittleEndian<uint64_t>(&r, t_us);
    for (int i = 0; i < 3; ++i) test::PutLittleEndian<float>(&r, 0.0f);
    return r;
  };
  for (const int gyro_period_us : {2000, 1'000'000}) {
    ULogBuilder b;
    b.FlagBits(0);
    b.Format(sensor_gyro_format);
    b.Format(vav_format);
    b.AddLogged(0, 0, "sensor_gyro");
    b.AddLogged(0, 1, "vehicle_angular_velocity");
    for (int64_t t_us = 1'000'000; t_us < 4'000'000; t_us += 1900) b.Data(1, vav_record(t_us));
    for (int64_t t_us = 1'000'000; t_us < 4'000'000; t_us += gyro_period_us)
      b.Data(0, gyro_record(t_us));
    const FlightLog log = ParseULog(b.bytes(), "choice.ulg");
    // 500 Hz raw sensor_gyro is within 10% of 526 Hz vehicle_angular_velocity: the raw one wins;
    // at 1 Hz it does not.
    EXPECT_EQ(log.gyro_source,
              gyro_period_us == 2000 ? "sensor_gyro.x,y,z" : "vehicle_angular_velocity.xyz")
        << gyro_period_us;
    EXPECT_EQ(log.gyro_sources_available.size(), 2u);
  }
}

TEST(ULog, ReadsCameraEventsAndAltitude) {
  ULogBuilder b;
  b.FlagBits(0);
  b.Format(kCombinedFormat);
  b.Format(
      "camera_trigger:uint64_t timestamp;uint64_t timestamp_utc;uint32_t seq;bool "
      "feedback;uint8_t[3] _padding0;");
  b.Format(
      "camera_capture:uint64_t timestamp;uint64_t timestamp_utc;int32_t seq;double lat;double "
      "lon;float alt;"
      "float ground_distance;float[4] q;int8_t result;uint8_t[3] _padding0;");
  b.Format(
      "vehicle_local_position:uint64_t timestamp;bool xy_valid;bool z_valid;uint8_t[2] "
      "_padding0;float x;"
      "float y;float z;float dist_bottom;bool dist_bottom_valid;uint8_t[7] _padding1;");
  b.AddLogged(0, 0, "sensor_combined");
  b.AddLogged(0, 1, "camera_trigger");
  b.AddLogged(0, 2, "camera_capture");
  b.AddLogged(0, 3, "vehicle_local_position");
  for (int k = 0; k < 400; ++k) b.Data(0, CombinedRecord(1'000'000 + k * 4000, 0, 0, 0));
  for (uint32_t seq = 0; seq < 3; ++seq) {
    std::string r;
    test::PutLittleEndian<uint64_t>(&r, 1'200'000 + seq * 100'000);
    test::PutLittleEndian<uint64_t>(&r, 0);
    test::PutLittleEndian<uint32_t>(&r, seq + 10);
    test::PutLittleEndian<uint8_t>(&r, 1);
    b.Data(1, r);
  }
  {
    std::string r;
    test::PutLittleEndian<uint64_t>(&r, 1'250'000);
    test::PutLittleEndian<uint64_t>(&r, 0);
    test::PutLittleEndian<int32_t>(&r, 7);
    test::PutLittleEndian<double>(&r, 47.0);
    test::PutLittleEndian<double>(&r, 8.0);
    for (int i = 0; i < 6; ++i) test::PutLittleEndian<float>(&r, 0.0f);
    test::PutLittleEndian<int8_t>(&r, 1);
    b.Data(2, r);
  }
  // On the ground (dist 0.1 m, invalid), then at 30, 31, 32, 33 m with a valid range finder.
  auto position = [](uint64_t t_us, float z, float dist, bool dist_valid) {
    std::string r;
    test::PutLittleEndian<uint64_t>(&r, t_us);
    test::PutLittleEndian<uint8_t>(&r, 1);
    test::PutLittleEndian<uint8_t>(&r, 1);
    test::PutLittleEndian<uint16_t>(&r, 0);
    test::PutLittleEndian<float>(&r, 0.0f);
    test::PutLittleEndian<float>(&r, 0.0f);
    test::PutLittleEndian<float>(&r, z);
    test::PutLittleEndian<float>(&r, dist);
    test::PutLittleEndian<uint8_t>(&r, dist_valid);
    return r;
  };
  const float heights[] = {0.1f, 0.2f, 30.0f, 31.0f, 32.0f, 33.0f};
  for (int i = 0; i < 6; ++i)
    b.Data(3, position(1'000'000 + i * 10'000, 2.0f - heights[i], heights[i], i >= 2));
  const FlightLog log = ParseULog(b.bytes(), "camera.ulg");
  // Both kinds: the camera's feedback (camera_capture) is kept, the 3 commands are counted.
  ASSERT_EQ(log.camera_events.size(), 1u);
  EXPECT_EQ(log.camera_events[0].kind, "camera_capture");
  EXPECT_EQ(log.camera_events[0].t_ns, 1'250'000'000);
  EXPECT_EQ(log.camera_events[0].sequence, 7);
  EXPECT_TRUE(test::AnyWarningContains(log.warnings,
                                       "camera events: used the 1 camera_capture events; 3 "
                                       "camera_trigger not used"))
      << test::JoinedWarnings(log.warnings);
  ASSERT_TRUE(log.altitude_above_ground_m.has_value());
  EXPECT_DOUBLE_EQ(*log.altitude_above_ground_m, 31.5);
  EXPECT_NE(log.altitude_source.find("dist_bottom"), std::string::npos) << log.altitude_source;

  // Without a valid range finder: -(z - z_home), z_home the first local z (2 - 0.1 = 1.9).
  ULogBuilder c;
  c.FlagBits(0);
  c.Format(kCombinedFormat);
  c.Format(
      "vehicle_local_position:uint64_t timestamp;bool xy_valid;bool z_valid;uint8_t[2] "
      "_padding0;float x;"
      "float y;float z;float dist_bottom;bool dist_bottom_valid;uint8_t[7] _padding1;");
  c.AddLogged(0, 0, "sensor_combined");
  c.AddLogged(0, 3, "vehicle_local_position");
  for (int k = 0; k < 400; ++k) c.Data(0, CombinedRecord(1'000'000 + k * 4000, 0, 0, 0));
  for (int i = 0; i < 6; ++i)
    c.Data(3, position(1'000'000 + i * 10'000, 2.0f - heights[i], 0.0f, false));
  const FlightLog fallback = ParseULog(c.bytes(), "z.ulg");
  ASSERT_TRUE(fallback.altitude_above_ground_m.has_value());
  constexpr double kFloatTol = 1e-5;  // heights pass through float32
  EXPECT_NEAR(*fallback.altitude_above_ground_m, 31.4, kFloatTol);
  EXPECT_NE(fallback.altitude_source.find("first local z"), std::string::npos)
      << fallback.altitude_source;
}

TEST(ULog, SkipsCorruptStretchAndReadsOn) {
  ULogBuilder b;
  b.FlagBits(0);
  b.Format(kCombinedFormat);
  b.AddLogged(0, 0, "sensor_combined");
  for (int k = 0; k < 50; ++k) b.Data(0, CombinedRecord(1'000'000 + k * 4000, 0, 0, 0));
  b.bytes() += std::string("\x00\x00\xee garbage \xff\xff", 15);
  for (int k = 50; k < 100; ++k) b.Data(0, CombinedRecord(1'000'000 + k * 4000, 0, 0, 0));
  const FlightLog log = ParseULog(b.bytes(), "corrupt.ulg");
  EXPECT_EQ(log.gyro.size(), 100u);
  EXPECT_EQ(log.records_skipped, 1u);
  EXPECT_TRUE(test::AnyWarningContains(log, "15 corrupt bytes skipped in total"));
}

TEST(ULog, RejectsWhatIsNotULog) {
  SHUTTERLAB_NEED_REAL_DATA();
  EXPECT_FALSE(LooksLikeULog("ULog"));
  EXPECT_FALSE(LooksLikeULog(std::string("\xA3\x95\x80\x80\x59", 5)));
  EXPECT_TRUE(LooksLikeULog(std::string("ULog\x01\x12\x35\x01", 8)));
  EXPECT_THROW(ParseULog("not a log at all, but long enough", "x.ulg"), IoError);
  EXPECT_THROW(ParseULog(std::string("ULog\x01\x12\x35\x01", 8), "short.ulg"), IoError);
  ULogBuilder b;
  b.FlagBits(0);
  b.Format(kCombinedFormat);
  try {
    ParseULog(b.bytes(), "empty.ulg");
    FAIL() << "a log without gyro data must throw";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("empty.ulg: no usable gyro data"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(ReadULog(SamplePath("does_not_exist.ulg")), IoError);
}

// A damaged file gives a clear IoError or a partial result that says what was skipped. A result
// may lose at most max_lost samples: resynchronisation must not silently swallow good messages.
void ExpectGracefulOn(const std::string& bytes, size_t full_samples, size_t max_lost,
                      const std::string& what) {
  try {
    const FlightLog log = ParseULog(bytes, what);
    EXPECT_LE(log.gyro.size(), full_samples) << what;
    EXPECT_GE(log.gyro.size() + max_lost, full_samples) << what;
    if (log.gyro.size() < full_samples) {
      EXPECT_FALSE(log.warnings.empty()) << what;
    }
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
  }
}

TEST(ULog, TruncatedCopiesGiveErrorOrPartialResult) {
  SHUTTERLAB_NEED_REAL_DATA();
  const std::string bytes = ReadFileToString(SamplePath("sample_log_small.ulg"));
  const FlightLog full = ParseULog(bytes, "full");
  std::mt19937_64 rng(20261122);
  std::uniform_int_distribution<size_t> cut(0, bytes.size() - 1);
  for (int trial = 0; trial < 12; ++trial) {
    const size_t at = cut(rng);
    const std::string name = "cut_at_" + std::to_string(at);
    ExpectGracefulOn(bytes.substr(0, at), full.gyro.size(), full.gyro.size(), name);
    if (at > bytes.size() / 2) {
      const FlightLog log = ParseULog(bytes.substr(0, at), name);
      EXPECT_TRUE(test::AnyWarningContains(log, "truncated") || log.gyro.size() == full.gyro.size())
          << name;
    }
  }
  // A cut right inside the header and right inside the definitions.
  for (size_t at : {size_t{5}, size_t{16}, size_t{17}, size_t{300}}) {
    ExpectGracefulOn(bytes.substr(0, at), full.gyro.size(), full.gyro.size(),
                     "cut_at_" + std::to_string(at));
  }
}

TEST(ULog, ByteFlippedCopiesGiveErrorOrPartialResult) {
  SHUTTERLAB_NEED_REAL_DATA();
  const std::string bytes = ReadFileToString(SamplePath("sample_log_small.ulg"));
  const size_t full_samples = ParseULog(bytes, "full").gyro.size();
  // A damaged byte may cost the gyro message it falls in (or one whose time it bent); the reader
  // must not lose good messages around it.
  constexpr size_t kMaxLostPerFlip = 1;
  constexpr int kFlips = 64;
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<size_t> where(0, bytes.size() - 1);
  std::uniform_int_distribution<int> value(0, 255);
  size_t partial_results = 0;
  for (int trial = 0; trial < 12; ++trial) {
    std::string copy = bytes;
    for (int k = 0; k < kFlips; ++k) {
      const size_t at = where(rng);
      copy[at] = static_cast<char>(value(rng));
    }
    const std::string name = "flipped_" + std::to_string(trial);
    ExpectGracefulOn(copy, full_samples, kFlips * kMaxLostPerFlip, name);
    try {
      if (ParseULog(copy, name).records_skipped > 0) ++partial_results;
    } catch (const IoError&) {
    }
  }
  EXPECT_GE(partial_results, 6u) << "most damaged copies should be read past the damage";
  // Damage concentrated in the definitions section, where formats live: a topic may be lost whole,
  // so only a graceful outcome is asked for.
  std::uniform_int_distribution<size_t> early(16, 60'000);
  for (int trial = 0; trial < 6; ++trial) {
    std::string copy = bytes;
    for (int k = 0; k < 32; ++k) {
      const size_t at = early(rng);
      copy[at] = static_cast<char>(value(rng));
    }
    ExpectGracefulOn(copy, full_samples, full_samples, "early_flipped_" + std::to_string(trial));
  }
}

// ------------------------------------------------------------------------------ streamed

constexpr char kGyroFormat[] =
    "sensor_gyro:uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;float x;float y;"
    "float z;";

std::string GyroRecord(uint64_t t_us, float x, float y, float z) {
  std::string r;
  test::PutLittleEndian<uint64_t>(&r, t_us);
  test::PutLittleEndian<uint64_t>(&r, t_us);
  test::PutLittleEndian<uint32_t>(&r, 1);
  for (float v : {x, y, z}) test::PutLittleEndian<float>(&r, v);
  return r;
}

// A log with every kind of gyro stream and trouble the cleaning handles, drawn from rng: a
// sensor_gyro_fifo instance with partial batches, two sensor_gyro instances and sensor_combined
// whose times are now and then zero, bent back or forward, or far ahead, NaN rates, a dropout,
// camera events, and sensor_gyro instance 0 removed and added again under another msg_id.
std::string RandomULog(std::mt19937_64& rng) {
  ULogBuilder b;
  b.FlagBits(0);
  b.Format(kFifoFormat);
  b.Format(kCombinedFormat);
  b.Format(kGyroFormat);
  b.Format("camera_capture:uint64_t timestamp;uint32_t seq;");
  b.AddLogged(0, 0, "sensor_gyro_fifo");
  b.AddLogged(0, 1, "sensor_gyro");
  b.AddLogged(1, 2, "sensor_gyro");
  b.AddLogged(0, 3, "sensor_combined");
  b.AddLogged(0, 4, "camera_capture");
  std::uniform_int_distribution<int> trouble(0, 60);
  auto bent = [&](uint64_t t_us) -> uint64_t {
    switch (trouble(rng)) {
      case 0:
        return 0;
      case 1:
        return t_us + 100'000'000;  // 100 s ahead
      case 2:
        return t_us - 3000;
      case 3:
        return t_us + 1500;
      default:
        return t_us;
    }
  };
  uint16_t gyro0_id = 1;
  uint64_t t_us = 1'000'000;
  const int messages = 200 + static_cast<int>(rng() % 300);
  for (int m = 0; m < messages; ++m) {
    t_us += 1000 + rng() % 3;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    b.Data(gyro0_id, GyroRecord(bent(t_us), 0.01f * m, trouble(rng) == 0 ? nan : 0.2f, -0.1f));
    if (m % 2 == 0) b.Data(2, GyroRecord(bent(t_us), 0.0f, 0.1f, 0.2f));
    if (m % 4 == 0) b.Data(3, CombinedRecord(bent(t_us), 0.3f, 0.2f, 0.1f));
    if (m % 8 == 0) {
      const uint8_t n = static_cast<uint8_t>(rng() % 33);
      std::vector<int16_t> x(n), y(n, -5), z(n, 9);
      for (uint8_t i = 0; i < n; ++i) x[i] = static_cast<int16_t>(m + i);
      b.Data(0, FifoRecord(t_us, bent(t_us), 250.0f, 0.001f, n, x, y, z));
    }
    if (m % 50 == 7) {
      std::string r;
      test::PutLittleEndian<uint64_t>(&r, t_us + 10);
      test::PutLittleEndian<uint32_t>(&r, static_cast<uint32_t>(m));
      b.Data(4, r);
    }
    if (m == messages / 3) b.Dropout(25);
    if (m == messages / 2) {
      b.Message('R', std::string("\x01\x00", 2));
      gyro0_id = 5;
      b.AddLogged(0, gyro0_id, "sensor_gyro");
    }
  }
  return b.bytes();
}

// The stream read chunk by chunk (each at most chunk_samples, Fraction rising to 1), as a log.
FlightLog ReadInChunks(ULogStream stream, size_t chunk_samples, const std::string& what) {
  std::vector<GyroSample> samples;
  double fraction = 0.0;
  for (GyroChunk chunk = stream.gyro->Next(); !chunk.empty(); chunk = stream.gyro->Next()) {
    EXPECT_LE(chunk.size, chunk_samples) << what;
    samples.insert(samples.end(), chunk.begin(), chunk.end());
    EXPECT_GE(stream.gyro->Fraction(), fraction) << what;
    fraction = stream.gyro->Fraction();
  }
  EXPECT_EQ(stream.gyro->Fraction(), 1.0) << what;
  FlightLog log = std::move(stream.log);
  log.gyro = GyroTrace(std::move(samples));
  return log;
}

// What reading `bytes` whole gives (or the error it throws) and what the stream gives in chunks of
// 1 and 7 samples, with the default limits and with limits so small that most topic instances
// take the fallback: the same, but for the fallback's one warning.
void ExpectStreamedAsWhole(const std::string& bytes, const std::string& what) {
  std::optional<FlightLog> whole;
  std::string error;
  try {
    whole = ParseULog(bytes, what);
  } catch (const IoError& e) {
    error = e.what();
  }
  const internal::CandidateLimits tiny{2, 2};
  for (const auto& limits : {internal::CandidateLimits{}, tiny}) {
    for (size_t chunk : {size_t{1}, size_t{7}}) {
      const std::string how = what + " chunk " + std::to_string(chunk) +
                              (limits.reorder_samples == 2 ? " tiny limits" : "");
      try {
        FlightLog log =
            ReadInChunks(internal::OpenULogBytes(bytes, what, chunk, limits), chunk, how);
        ASSERT_TRUE(whole.has_value()) << how << ": streamed read, whole threw " << error;
        auto memory = std::find_if(log.warnings.begin(), log.warnings.end(),
                                   [](const LogWarning& w) { return w.kind == "memory"; });
        if (memory != log.warnings.end()) {
          EXPECT_EQ(limits.reorder_samples, 2u) << how << ": " << memory->message;
          log.warnings.erase(memory);
        }
        ExpectSameLog(log, *whole, how);
      } catch (const IoError& e) {
        EXPECT_EQ(std::string(e.what()), error) << how;
      }
    }
  }
}

TEST(ULogStream, RandomLogsReadInTinyChunksAsWhole) {
  std::mt19937_64 rng(20261126);
  size_t fallbacks = 0;
  for (int trial = 0; trial < 30; ++trial) {
    const std::string bytes = RandomULog(rng);
    ExpectStreamedAsWhole(bytes, "random_" + std::to_string(trial));
    ULogStream tiny = internal::OpenULogBytes(bytes, "tiny", 64, {2, 2});
    for (const LogWarning& w : tiny.log.warnings) fallbacks += w.kind == "memory";
  }
  EXPECT_GE(fallbacks, 20u) << "tiny limits should make most logs take the fallback";
}

TEST(ULogStream, RealLogsAndDamagedCopiesReadInTinyChunksAsWhole) {
  SHUTTERLAB_NEED_REAL_DATA();
  const std::string bytes = ReadFileToString(SamplePath("sample_log_small.ulg"));
  ExpectStreamedAsWhole(bytes, "sample_log_small");
  std::mt19937_64 rng(17);
  std::uniform_int_distribution<size_t> where(16, bytes.size() - 1);
  for (int trial = 0; trial < 3; ++trial) {
    const size_t cut = where(rng);
    ExpectStreamedAsWhole(bytes.substr(0, cut), "cut_at_" + std::to_string(cut));
    std::string copy = bytes;
    for (int k = 0; k < 40; ++k) copy[where(rng)] = static_cast<char>(rng());
    ExpectStreamedAsWhole(copy, "flipped_" + std::to_string(trial));
  }
}

TEST(ULogStream, InterleavedSubscriptionsOfOneInstanceAreCleanedOneAfterTheOther) {
  // Two subscriptions of sensor_gyro instance 0 whose messages alternate: the candidate is the
  // first subscription's samples, then the second's (the order the reader always took), so one
  // sample is out of time order and the sort merges them.
  ULogBuilder b;
  b.FlagBits(0);
  b.Format(kGyroFormat);
  b.AddLogged(0, 0, "sensor_gyro");
  b.AddLogged(0, 1, "sensor_gyro");
  std::vector<int64_t> expected_t_ns;
  for (int k = 0; k < 40; ++k) {
    const uint64_t t_us = 1'000'000 + k * 1000;
    b.Data(static_cast<uint16_t>(k % 2), GyroRecord(t_us, static_cast<float>(k), 0.0f, 0.0f));
    expected_t_ns.push_back(static_cast<int64_t>(t_us) * 1000);
  }
  ExpectStreamedAsWhole(b.bytes(), "interleaved");
  const FlightLog log = ParseULog(b.bytes(), "interleaved");
  ASSERT_EQ(log.gyro.size(), expected_t_ns.size());
  for (size_t k = 0; k < expected_t_ns.size(); ++k) {
    EXPECT_EQ(log.gyro[k].t_ns, expected_t_ns[k]) << k;
    EXPECT_EQ(log.gyro[k].omega_rad_s.x(), static_cast<double>(k)) << k;
  }
  EXPECT_TRUE(test::AnyWarningContains(log, "sensor_gyro.x,y,z: 1 samples were out of time order"));
}

TEST(ULogStream, AFileThatChangesBetweenThePassesIsRefusedInOneLine) {
  test::TempDir dir;
  const std::string path = dir / "growing.ulg";
  ULogBuilder b;
  b.FlagBits(0);
  b.Format(kGyroFormat);
  b.AddLogged(0, 0, "sensor_gyro");
  for (int k = 0; k < 100; ++k) b.Data(0, GyroRecord(1'000'000 + k * 1000, 0.1f, 0.2f, 0.3f));
  WriteFileAtomically(path, b.bytes());
  EXPECT_EQ(ReadAllSamples(OpenULog(path).gyro.get()).size(), 100u);
  ULogStream stream = OpenULog(path, 8);
  // Still being recorded: a message appended in place.
  const size_t size = b.bytes().size();
  b.Data(0, GyroRecord(1'100'000, 0.1f, 0.2f, 0.3f));
  std::ofstream(path, std::ios::app | std::ios::binary) << b.bytes().substr(size);
  try {
    stream.gyro->Next();
    ADD_FAILURE() << "a file that grew between the passes was read";
  } catch (const IoError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(path), std::string::npos) << message;
    EXPECT_NE(message.find("changed while it was read"), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}

}  // namespace
}  // namespace shutterlab
