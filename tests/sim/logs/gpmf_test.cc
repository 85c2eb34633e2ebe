#include "sim/logs/gpmf.h"

#include "sim/check.h"
#include "tests/test_util.h"

#include <cmath>
#include <cstring>
#include <random>

namespace shutterlab {
namespace {

// Big-endian KLV builders.
template <typename T>
std::string BigEndianBytes(T value) {
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  return std::string(std::rbegin(raw), std::rend(raw));  // little-endian host
}
std::string Klv(const std::string& key, char type, uint8_t size, uint16_t repeat,
                std::string data) {
  std::string out = key + std::string(1, type) + static_cast<char>(size) +
                    static_cast<char>(repeat >> 8) + static_cast<char>(repeat & 0xFF);
  data.resize(static_cast<size_t>(size) * repeat, '\0');
  out += data;
  out.resize((out.size() + 3) / 4 * 4, '\0');  // 4-byte alignment
  return out;
}
std::string Nest(const std::string& key, const std::string& body) {
  return Klv(key, 0, 1, static_cast<uint16_t>(body.size()), body);
}

// A 3-element stream with only a name and an ORIN.
GpmfStreamData Stream(const std::string& name, const std::string& orin) {
  GpmfStreamData stream;
  stream.name = name;
  stream.orientation = orin;
  stream.elements = 3;
  return stream;
}

// A payload with known values: a gyro stream in z,x,y order with one SCAL, a stream with one SCAL
// per element, and one value of each numeric type.
std::string KnownPayload() {
  std::string gyro_data;
  for (int16_t v : {100, 200, 300, -100, -200, -300}) gyro_data += BigEndianBytes(v);
  const std::string gyro =
      Nest("STRM", Klv("STNM", 'c', 1, 17, "Gyroscope (z,x,y)") +  // 17 chars: padded
                       Klv("SIUN", 'c', 5, 1, "rad/s") +
                       Klv("SCAL", 's', 2, 1, BigEndianBytes(int16_t{100})) +
                       Klv("GYRO", 's', 6, 2, gyro_data));
  std::string scal;
  for (int32_t v : {10, 1000}) scal += BigEndianBytes(v);
  std::string pair;
  for (int32_t v : {25, -3000}) pair += BigEndianBytes(v);
  const std::string per_axis =
      Nest("STRM", Klv("SCAL", 'l', 4, 2, scal) + Klv("ORIN", 'c', 1, 3, "yXz") +
                       Klv("PAIR", 'l', 8, 1, pair));
  const std::string types = Nest(
      "STRM", Klv("TB__", 'b', 1, 1, BigEndianBytes(int8_t{-5})) +
                  Klv("TBU_", 'B', 1, 1, BigEndianBytes(uint8_t{250})) +
                  Klv("TSU_", 'S', 2, 1, BigEndianBytes(uint16_t{65000})) +
                  Klv("TLU_", 'L', 4, 1, BigEndianBytes(uint32_t{4000000000u})) +
                  Klv("TF__", 'f', 4, 1, BigEndianBytes(0.25f)) +
                  Klv("TD__", 'd', 8, 1, BigEndianBytes(-1.5)) +
                  Klv("TJ__", 'j', 8, 1, BigEndianBytes(int64_t{-7})) +
                  Klv("TQ__", 'q', 4, 1, BigEndianBytes(int32_t{3 * 65536 + 32768})) +
                  Klv("SHUT", 'f', 4, 3,
                      BigEndianBytes(0.004f) + BigEndianBytes(0.005f) + BigEndianBytes(0.006f)));
  return Nest("DEVC", Klv("DVNM", 'c', 1, 6, "Camera") + gyro + per_axis + types) +
         std::string(8, '\0');
}

TEST(Gpmf, KnownPayloadDecodes) {
  const std::string payload = KnownPayload();
  const std::vector<GpmfKlv> klvs = ParseGpmf(payload, 1000, "known");
  ASSERT_EQ(klvs.size(), 1u);  // trailing zero padding ends the level
  EXPECT_EQ(klvs[0].key, "DEVC");
  ASSERT_EQ(klvs[0].children.size(), 4u);
  EXPECT_EQ(klvs[0].children[1].children[0].file_offset,
            1000u + 8 + 16 + 8);  // DEVC header, DVNM (padded to 16), STRM header

  const auto gyro = FindGpmfStreams(klvs, "GYRO", "known");
  ASSERT_EQ(gyro.size(), 1u);
  EXPECT_EQ(gyro[0].device, "Camera");
  EXPECT_EQ(gyro[0].name, "Gyroscope (z,x,y)");
  EXPECT_EQ(gyro[0].units, "rad/s");
  EXPECT_EQ(gyro[0].elements, 3u);
  EXPECT_EQ(gyro[0].samples(), 2u);
  EXPECT_EQ(gyro[0].values, (std::vector<double>{1, 2, 3, -1, -2, -3}));
  const AxisOrder order = GpmfAxisOrder(gyro[0], "known");
  EXPECT_EQ(order.column, (std::array<int, 3>{1, 2, 0}));  // x is stored second, y third, z first
  EXPECT_EQ(order.sign, (std::array<int, 3>{1, 1, 1}));

  const auto pair = FindGpmfStreams(klvs, "PAIR", "known");
  ASSERT_EQ(pair.size(), 1u);
  EXPECT_EQ(pair[0].values, (std::vector<double>{2.5, -3.0}));  // SCAL per element
  const AxisOrder orin = GpmfAxisOrder(Stream("", "yXz"), "known");
  EXPECT_EQ(orin.column, (std::array<int, 3>{1, 0, 2}));
  EXPECT_EQ(orin.sign, (std::array<int, 3>{1, -1, -1}));  // lowercase = negated

  auto one = [&](const std::string& key) {
    const auto streams = FindGpmfStreams(klvs, key, "known");
    EXPECT_EQ(streams.size(), 1u) << key;
    return streams.empty() || streams[0].values.empty() ? NAN : streams[0].values[0];
  };
  EXPECT_EQ(one("TB__"), -5);
  EXPECT_EQ(one("TBU_"), 250);
  EXPECT_EQ(one("TSU_"), 65000);
  EXPECT_EQ(one("TLU_"), 4000000000.0);
  EXPECT_EQ(one("TF__"), 0.25);
  EXPECT_EQ(one("TD__"), -1.5);
  EXPECT_EQ(one("TJ__"), -7);
  EXPECT_EQ(one("TQ__"), 3.5);
  const auto shut = FindGpmfStreams(klvs, "SHUT", "known");
  ASSERT_EQ(shut.size(), 1u);
  ASSERT_EQ(shut[0].samples(), 3u);
  EXPECT_FLOAT_EQ(static_cast<float>(shut[0].values[2]), 0.006f);
}

// The GoPro MAX's gyro keys: ORIN "XzY" (stored channels X, -Z, Y), ORIO "ZXY" (output order) and
// MTRX, the same mapping as a matrix with rows in ORIO's order; gpmf-parser takes a matrix of 0 and
// +-1 as that orientation and any other as a calibration.
TEST(Gpmf, OutputOrientationAndMatrixAsGpmfParserReadsThem) {
  GpmfStreamData max;
  max.orientation = "XzY";
  max.orientation_out = "ZXY";
  max.matrix = {0, -1, 0, 1, 0, 0, 0, 0, 1};
  const AxisOrder order = GpmfAxisOrder(max, "max");
  EXPECT_EQ(order.column, (std::array<int, 3>{0, 2, 1}));  // X stored first, Y third, Z second
  EXPECT_EQ(order.sign, (std::array<int, 3>{1, 1, -1}));
  EXPECT_FALSE(order.calibration.has_value());
  EXPECT_EQ(order.source, "ORIN 'XzY', ORIO 'ZXY', MTRX agrees");
  // A +-1 matrix that says otherwise is not used (the orientation keys are).
  GpmfStreamData other = max;
  other.matrix = {0, 1, 0, 1, 0, 0, 0, 0, 1};
  EXPECT_EQ(GpmfAxisOrder(other, "max").source,
            "ORIN 'XzY', ORIO 'ZXY', MTRX disagrees (not used)");
  EXPECT_EQ(GpmfAxisOrder(other, "max").column, order.column);
  // A calibration: each camera axis a row of it, in ORIO's order (Z is the first row).
  GpmfStreamData calibrated = max;
  calibrated.matrix = {0.01, -0.99, 0, 1.01, 0, 0.02, 0, 0, 1};
  const AxisOrder cal = GpmfAxisOrder(calibrated, "max");
  ASSERT_TRUE(cal.calibration.has_value());
  EXPECT_EQ(cal.calibration->row(0), Eigen::RowVector3d(1.01, 0, 0.02));   // X
  EXPECT_EQ(cal.calibration->row(1), Eigen::RowVector3d(0, 0, 1));         // Y
  EXPECT_EQ(cal.calibration->row(2), Eigen::RowVector3d(0.01, -0.99, 0));  // Z
  GpmfStreamData bad = max;
  bad.orientation_out = "ZXX";
  EXPECT_THROW(GpmfAxisOrder(bad, "p"), IoError);
  bad = max;
  bad.matrix = {1, 0, 0, 1};
  EXPECT_THROW(GpmfAxisOrder(bad, "p"), IoError);
}

TEST(Gpmf, BadScaleAndAxisOrderAreErrors) {
  const std::string bad_scal =
      Nest("DEVC", Nest("STRM", Klv("SCAL", 's', 2, 2, std::string(4, '\1')) +
                                    Klv("GYRO", 's', 6, 1, std::string(6, '\0'))));
  EXPECT_THROW(FindGpmfStreams(ParseGpmf(bad_scal, 0, "p"), "GYRO", "p"),
               IoError);  // 2 SCAL for 3 elements
  const std::string odd_size =
      Nest("DEVC", Nest("STRM", Klv("GYRO", 's', 5, 1, std::string(5, '\0'))));
  EXPECT_THROW(FindGpmfStreams(ParseGpmf(odd_size, 0, "p"), "GYRO", "p"), IoError);
  EXPECT_THROW(GpmfAxisOrder(Stream("Gyroscope (z,x,x)", ""), "p"), IoError);
  EXPECT_EQ(GpmfAxisOrder(Stream("Gyroscope", ""), "p").source, "default x,y,z");
}

TEST(Gpmf, EveryTruncationAndByteValueIsAnErrorOrAResult) {
  const std::string payload = KnownPayload();
  for (size_t cut = 0; cut <= payload.size(); ++cut) {
    try {
      const std::string truncated = payload.substr(0, cut);  // the KLVs view into it
      const auto klvs = ParseGpmf(truncated, 0, "cut");
      FindGpmfStreams(klvs, "GYRO", "cut");
    } catch (const IoError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("cut: offset ", 0), 0u) << e.what();
    }
  }
  for (size_t i = 0; i < payload.size(); ++i) {
    for (char value : {'\0', '\x01', '\x7f', '\xff'}) {
      std::string flipped = payload;
      flipped[i] = value;
      try {
        const auto klvs = ParseGpmf(flipped, 0, "flip");
        for (const auto& stream : FindGpmfStreams(klvs, "GYRO", "flip"))
          EXPECT_EQ(stream.values.size(), stream.samples() * stream.elements);
      } catch (const IoError&) {
      }
    }
  }
}

TEST(Gpmf, KarmaGyroAndShutter) {
  SHUTTERLAB_NEED_REAL_DATA();
  Mp4File mp4(test::KarmaClipPath());
  const Mp4Track* track = mp4.FindTrack("meta", "gpmd");
  ASSERT_NE(track, nullptr);
  const GpmfTrackStream gyro = ReadGpmfTrackStream(mp4, *track, "GYRO");
  EXPECT_EQ(gyro.first.name, "Gyroscope (z,x,y)");
  EXPECT_EQ(gyro.first.units, "rad/s");
  EXPECT_EQ(gyro.first.device, "Camera");
  EXPECT_EQ(gyro.first.scale, std::vector<double>{3755});
  EXPECT_EQ(gyro.elements, 3u);
  EXPECT_EQ(gyro.samples(), 4795u);
  EXPECT_EQ(gyro.payload_samples,
            (std::vector<size_t>{392, 399, 399, 399, 392, 399, 399, 399, 399, 399, 392, 399, 28}));
  // One line over the track: the 12 full payloads span 12.012 s.
  EXPECT_NEAR(gyro.rate_hz, 397.18, 0.05);
  EXPECT_NEAR(gyro.t0_s, 0.0083, 0.001);
  // Uneven payloads leave up to ~9 ms between a payload's start and the line.
  EXPECT_GT(gyro.fit_max_residual_s, 0.005);
  EXPECT_LT(gyro.fit_max_residual_s, 0.010);
  double peak = 0;
  for (size_t i = 0; i < gyro.samples(); ++i)
    peak = std::max(peak,
                    std::hypot(gyro.values[3 * i], gyro.values[3 * i + 1], gyro.values[3 * i + 2]));
  EXPECT_NEAR(peak, 0.83, 0.01);
  const AxisOrder order = GpmfAxisOrder(gyro.first, test::KarmaClipPath());
  EXPECT_EQ(order.column, (std::array<int, 3>{1, 2, 0}));

  const GpmfTrackStream shut = ReadGpmfTrackStream(mp4, *track, "SHUT");
  EXPECT_EQ(shut.samples(), 361u);
  EXPECT_NEAR(shut.values.front(), 0.00487, 0.00001);
  EXPECT_NEAR(shut.rate_hz, 29.97, 0.1);
  EXPECT_THROW(ReadGpmfTrackStream(mp4, *track, "NONE"), IoError);
}

TEST(Gpmf, KarmaPayloadByteFlipsNeverCrash) {
  SHUTTERLAB_NEED_REAL_DATA();
  Mp4File mp4(test::KarmaClipPath());
  const Mp4Track* track = mp4.FindTrack("meta", "gpmd");
  ASSERT_NE(track, nullptr);
  std::mt19937 rng(6);
  int errors = 0;
  for (size_t k = 0; k < track->size(); ++k) {
    const std::string payload = mp4.ReadSample(*track, k);
    std::uniform_int_distribution<size_t> where(0, payload.size() - 1);
    for (int trial = 0; trial < 60; ++trial) {
      std::string flipped = payload;
      flipped[where(rng)] = static_cast<char>(rng());
      try {
        FindGpmfStreams(ParseGpmf(flipped, track->offsets[k], test::KarmaClipPath()), "GYRO",
                        test::KarmaClipPath());
      } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("offset "), std::string::npos);
        ++errors;
      }
    }
    // A truncated payload: an error, never a read past the end.
    EXPECT_THROW(ParseGpmf(payload.substr(0, payload.size() / 2 + 1), 0, test::KarmaClipPath()),
                 IoError);
  }
  EXPECT_GT(errors, 0);
}

}  // namespace
}  // namespace shutterlab
