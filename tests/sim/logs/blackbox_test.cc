#include "sim/logs/blackbox.h"

#include "sim/check.h"
#include "sim/logs/blackbox_codec.h"
#include "sim/text_file.h"
#include "sim/units.h"
#include "tests/sim/logs/same_log.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <random>
#include <string>
#include <string_view>
#include <vector>

namespace shutterlab {
namespace {

using test::ExpectSameLog;

// Rates are integer counts times one double factor: the reader must reproduce them to rounding.
constexpr double kRateTolRadS = 1e-12;
// Durations and rates quoted in SOURCES.md / PROVENANCE.md to four decimals.
constexpr double kDurationTolS = 1e-4;

// ---- A port of the firmware's writers (betaflight src/main/blackbox/blackbox_encoding.c) ----

class Writer {
 public:
  void Byte(uint32_t b) { out_.push_back(static_cast<char>(static_cast<uint8_t>(b))); }
  void Text(const std::string& s) { out_ += s; }
  void UnsignedVb(uint32_t value) {
    while (value > 127) {
      Byte(value | 0x80);
      value >>= 7;
    }
    Byte(value);
  }
  void SignedVb(int32_t value) {
    UnsignedVb((static_cast<uint32_t>(value) << 1) ^ static_cast<uint32_t>(value >> 31));
  }
  void Tag2_3S32(const int32_t* v) {
    int selector = 0;
    for (int x = 0; x < 3; ++x) {
      if (v[x] >= 32 || v[x] < -32) {
        selector = 3;
        break;
      }
      if (v[x] >= 8 || v[x] < -8) {
        selector = std::max(selector, 2);
      } else if (v[x] >= 2 || v[x] < -2) {
        selector = std::max(selector, 1);
      }
    }
    const auto u = [&](int x) { return static_cast<uint32_t>(v[x]); };
    switch (selector) {
      case 0:
        Byte((0u << 6) | ((u(0) & 3) << 4) | ((u(1) & 3) << 2) | (u(2) & 3));
        break;
      case 1:
        Byte((1u << 6) | (u(0) & 0x0F));
        Byte((u(1) << 4) | (u(2) & 0x0F));
        break;
      case 2:
        Byte((2u << 6) | (u(0) & 0x3F));
        Byte(u(1));
        Byte(u(2));
        break;
      default:
        WriteBytesGroup(v);
        break;
    }
  }
  void Tag2_3SVariable(const int32_t* v) {
    const auto u = [&](int x) { return static_cast<uint32_t>(v[x]); };
    if (v[0] >= 256 || v[0] < -256 || v[1] >= 128 || v[1] < -128 || v[2] >= 128 || v[2] < -128) {
      WriteBytesGroup(v);
    } else if (v[0] >= 16 || v[0] < -16 || v[1] >= 16 || v[1] < -16 || v[2] >= 8 || v[2] < -8) {
      Byte((2u << 6) | ((u(0) & 0xFF) >> 2));
      Byte(((u(0) & 0x03) << 6) | ((u(1) & 0x7F) >> 1));
      Byte(((u(1) & 0x01) << 7) | (u(2) & 0x7F));
    } else if (v[0] >= 2 || v[0] < -2 || v[1] >= 2 || v[1] < -2 || v[2] >= 2 || v[2] < -2) {
      Byte((1u << 6) | ((u(0) & 0x1F) << 1) | ((u(1) & 0x1F) >> 4));
      Byte(((u(1) & 0x0F) << 4) | (u(2) & 0x0F));
    } else {
      Byte(((u(0) & 3) << 4) | ((u(1) & 3) << 2) | (u(2) & 3));
    }
  }
  void Tag8_4S16(const int32_t* v) {
    uint32_t selector = 0;
    for (int x = 3; x >= 0; --x) {
      selector <<= 2;
      if (v[x] == 0) {
      } else if (v[x] < 8 && v[x] >= -8) {
        selector |= 1;
      } else if (v[x] < 128 && v[x] >= -128) {
        selector |= 2;
      } else {
        selector |= 3;
      }
    }
    Byte(selector);
    bool half = false;
    uint32_t buffer = 0;
    for (int x = 0; x < 4; ++x, selector >>= 2) {
      const uint32_t value = static_cast<uint32_t>(v[x]);
      switch (selector & 3) {
        case 0:
          break;
        case 1:
          if (!half) {
            buffer = value << 4;
          } else {
            Byte(buffer | (value & 0x0F));
          }
          half = !half;
          break;
        case 2:
          if (!half) {
            Byte(value);
          } else {
            Byte(buffer | ((value >> 4) & 0x0F));
            buffer = value << 4;
          }
          break;
        default:
          if (!half) {
            Byte(value >> 8);
            Byte(value);
          } else {
            Byte(buffer | ((value >> 12) & 0x0F));
            Byte(value >> 4);
            buffer = value << 4;
          }
          break;
      }
    }
    if (half) Byte(buffer);
  }
  void Tag8_8Svb(const int32_t* v, int count) {
    if (count == 1) {
      SignedVb(v[0]);
      return;
    }
    uint32_t header = 0;
    for (int i = count - 1; i >= 0; --i) header = (header << 1) | (v[i] != 0 ? 1 : 0);
    Byte(header);
    for (int i = 0; i < count; ++i) {
      if (v[i] != 0) SignedVb(v[i]);
    }
  }
  const std::string& bytes() const { return out_; }
  std::string& bytes() { return out_; }

 private:
  void WriteBytesGroup(const int32_t* v) {
    uint32_t selector2 = 0;
    for (int x = 2; x >= 0; --x) {
      selector2 <<= 2;
      if (v[x] < 128 && v[x] >= -128) {
      } else if (v[x] < 32768 && v[x] >= -32768) {
        selector2 |= 1;
      } else if (v[x] < 8388608 && v[x] >= -8388608) {
        selector2 |= 2;
      } else {
        selector2 |= 3;
      }
    }
    Byte((3u << 6) | selector2);
    for (int x = 0; x < 3; ++x, selector2 >>= 2) {
      const uint32_t value = static_cast<uint32_t>(v[x]);
      for (uint32_t b = 0; b <= (selector2 & 3); ++b) Byte(value >> (8 * b));
    }
  }
  std::string out_;
};

// The reader borrows the bytes: pass literals or strings that outlive it.
blackbox::ByteReader ReaderOf(std::string_view bytes) {
  return blackbox::ByteReader{reinterpret_cast<const uint8_t*>(bytes.data()), 0, bytes.size(),
                              false};
}

// Values that hit every size class of the tagged encodings, plus uniform random ones.
std::vector<int32_t> InterestingValues(std::mt19937_64& rng, int count) {
  std::vector<int32_t> v = {0,
                            1,
                            -1,
                            2,
                            -2,
                            7,
                            -8,
                            8,
                            -9,
                            15,
                            -16,
                            16,
                            -17,
                            31,
                            -32,
                            32,
                            -33,
                            63,
                            -64,
                            127,
                            -128,
                            128,
                            -129,
                            255,
                            -256,
                            256,
                            -257,
                            32767,
                            -32768,
                            32768,
                            -32769,
                            8388607,
                            -8388608,
                            8388608,
                            -8388609,
                            2147483647,
                            -2147483647 - 1};
  std::uniform_int_distribution<int> bits(1, 31);
  while (static_cast<int>(v.size()) < count) {
    const int b = bits(rng);
    std::uniform_int_distribution<int64_t> value(-(int64_t{1} << (b - 1)),
                                                 (int64_t{1} << (b - 1)) - 1);
    v.push_back(static_cast<int32_t>(value(rng)));
  }
  return v;
}

TEST(BlackboxCodec, VariableByteKnownAnswers) {
  // 300 = 0b10_0101100: low 7 bits first with the continuation bit set.
  EXPECT_EQ(ReaderOf("\xAC\x02").ReadUnsignedVb(), 300u);
  EXPECT_EQ(ReaderOf(std::string_view("\x00", 1)).ReadUnsignedVb(), 0u);
  EXPECT_EQ(ReaderOf("\xFF\xFF\xFF\xFF\x0F").ReadUnsignedVb(), 0xFFFFFFFFu);
  // ZigZag: 1 -> -1, 2 -> 1, 3 -> -2.
  EXPECT_EQ(ReaderOf("\x01").ReadSignedVb(), -1);
  EXPECT_EQ(ReaderOf("\x02").ReadSignedVb(), 1);
  EXPECT_EQ(ReaderOf("\x03").ReadSignedVb(), -2);
  // NEG_14BIT: the firmware writes (ref - value) & 0x3FFF; 0x3FFF is -1 in 14 bits, negated +1.
  EXPECT_EQ(ReaderOf("\xFF\x7F").ReadNeg14Bit(), 1);
  EXPECT_EQ(ReaderOf("\x05").ReadNeg14Bit(), -5);
}

TEST(BlackboxCodec, TruncatedAndOverlongVariableBytesReadAsZeroWithoutOverrun) {
  auto r = ReaderOf("\x80\x80");
  EXPECT_EQ(r.ReadUnsignedVb(), 0u);
  EXPECT_TRUE(r.eof);
  EXPECT_EQ(r.pos, 2u);
  auto overlong = ReaderOf("\x80\x80\x80\x80\x80\x01");
  EXPECT_EQ(overlong.ReadUnsignedVb(), 0u);  // more than 5 bytes is not a 32-bit value
  EXPECT_EQ(overlong.pos, 5u);
  auto empty = ReaderOf("");
  int32_t values[4];
  empty.ReadTag8_4S16V2(values);
  EXPECT_TRUE(empty.eof);
  EXPECT_EQ(empty.pos, 0u);
}

TEST(BlackboxCodec, FirmwareTestVectorsForTag2_3SVariable) {
  // betaflight src/test/unit/blackbox_encoding_unittest.cc, TestWriteTag2_3SVariable_BITS*.
  struct Vector {
    int32_t v[3];
    std::string bytes;
  };
  const Vector vectors[] = {
      {{1, 1, 1}, "\x15"},
      {{-2, -2, -2}, "\x2A"},
      {{15, 15, 7}, "\x5E\xF7"},
      {{-16, -16, -8}, "\x61\x08"},
      {{7, 8, 5}, "\x4E\x85"},
      {{127, 63, 63}, "\x9F\xDF\xBF"},
      {{-128, -64, -64}, std::string("\xA0\x20\x40", 3)},
  };
  for (const Vector& vec : vectors) {
    Writer w;
    w.Tag2_3SVariable(vec.v);
    ASSERT_EQ(w.bytes(), vec.bytes) << vec.v[0];
    int32_t out[3];
    auto r = ReaderOf(w.bytes());
    r.ReadTag2_3SVariable(out);
    EXPECT_EQ(out[0], vec.v[0]);
    EXPECT_EQ(out[1], vec.v[1]);
    EXPECT_EQ(out[2], vec.v[2]);
    EXPECT_EQ(r.pos, vec.bytes.size());
  }
}

// The firmware picks the 8/7/7-bit packing for |v0| < 256 and |v1|, |v2| < 128 although those
// fields hold only 8 and 7 signed bits (its own unit test documents [-128, 127] and [-64, 63]):
// values in between are truncated when written. Round trips use only representable triples.
bool Tag2_3SVariableRepresentable(const int32_t* v) {
  const bool wide =
      v[0] >= 256 || v[0] < -256 || v[1] >= 128 || v[1] < -128 || v[2] >= 128 || v[2] < -128;
  return wide ||
         (v[0] >= -128 && v[0] < 128 && v[1] >= -64 && v[1] < 64 && v[2] >= -64 && v[2] < 64);
}

TEST(BlackboxCodec, TaggedGroupsRoundTripThroughTheFirmwareEncoders) {
  std::mt19937_64 rng(20261122);
  const std::vector<int32_t> pool = InterestingValues(rng, 3000);
  std::uniform_int_distribution<size_t> pick(0, pool.size() - 1);
  for (int trial = 0; trial < 2000; ++trial) {
    int32_t v[8];
    for (int32_t& x : v) x = pool[pick(rng)];
    while (!Tag2_3SVariableRepresentable(v + 3)) v[4] = pool[pick(rng)];
    int32_t v16[4];
    for (int k = 0; k < 4; ++k) v16[k] = static_cast<int16_t>(v[k]);  // TAG8_4S16 holds 16 bits
    const int run = 1 + trial % 8;
    Writer w;
    w.Tag2_3S32(v);
    w.Tag2_3SVariable(v + 3);
    w.Tag8_4S16(v16);
    w.Tag8_8Svb(v, run);
    w.SignedVb(v[5]);
    w.UnsignedVb(static_cast<uint32_t>(v[6]));
    auto r = ReaderOf(w.bytes());
    int32_t a[3], b[3], c[4], d[8];
    r.ReadTag2_3S32(a);
    r.ReadTag2_3SVariable(b);
    r.ReadTag8_4S16V2(c);
    r.ReadTag8_8Svb(d, run);
    const int32_t e = r.ReadSignedVb();
    const uint32_t f = r.ReadUnsignedVb();
    ASSERT_FALSE(r.eof);
    ASSERT_EQ(r.pos, w.bytes().size()) << "trial " << trial;
    for (int k = 0; k < 3; ++k) ASSERT_EQ(a[k], v[k]) << "TAG2_3S32 trial " << trial;
    for (int k = 0; k < 3; ++k) ASSERT_EQ(b[k], v[3 + k]) << "TAG2_3SVARIABLE trial " << trial;
    for (int k = 0; k < 4; ++k) ASSERT_EQ(c[k], v16[k]) << "TAG8_4S16 trial " << trial;
    for (int k = 0; k < run; ++k) ASSERT_EQ(d[k], v[k]) << "TAG8_8SVB trial " << trial;
    ASSERT_EQ(e, v[5]);
    ASSERT_EQ(f, static_cast<uint32_t>(v[6]));
  }
}

TEST(BlackboxCodec, Tag8_4S16Version1PairsNibblesLowFirst) {
  // Selector 0b01'01'10'11: field 0 16-bit LE, field 1 8-bit, fields 2 and 3 4-bit sharing a byte.
  const std::string bytes = "\x5B\x34\x12\xF0\x9A";
  auto r = ReaderOf(bytes);
  int32_t v[4];
  r.ReadTag8_4S16V1(v);
  EXPECT_EQ(v[0], 0x1234);
  EXPECT_EQ(v[1], -16);
  EXPECT_EQ(v[2], -6);  // low nibble 0xA
  EXPECT_EQ(v[3], -7);  // high nibble 0x9
  EXPECT_EQ(r.pos, bytes.size());
}

// ---- Synthetic logs with exact ground truth ----

struct FieldSpec {
  const char* name;
  int is_signed;
  int i_predictor, i_encoding, p_predictor, p_encoding;
  int lo, hi;  // range of the random values
};

// Betaflight-like layout covering every predictor a main frame uses and every encoding.
const FieldSpec kFields[] = {
    {"loopIteration", 0, 0, 1, 6, 9, 0, 0},     {"time", 0, 0, 1, 2, 0, 0, 0},
    {"axisP[0]", 1, 0, 0, 1, 7, -40000, 40000}, {"axisP[1]", 1, 0, 0, 1, 7, -300, 300},
    {"axisP[2]", 1, 0, 0, 1, 7, -5, 5},         {"rcCommand[0]", 1, 0, 0, 1, 10, -500, 500},
    {"rcCommand[1]", 1, 0, 0, 1, 10, -20, 20},  {"rcCommand[2]", 1, 0, 0, 1, 10, -3, 3},
    {"vbatLatest", 0, 9, 3, 1, 6, 350, 430},    {"amperageLatest", 1, 0, 0, 1, 6, -10, 3000},
    {"gyroADC[0]", 1, 0, 0, 3, 0, -2000, 2000}, {"gyroADC[1]", 1, 0, 0, 3, 0, -700, 700},
    {"gyroADC[2]", 1, 0, 0, 2, 0, -100, 100},   {"motor[0]", 0, 11, 1, 3, 8, 158, 2047},
    {"motor[1]", 0, 5, 0, 3, 8, 158, 2047},     {"motor[2]", 0, 5, 0, 1, 8, 158, 2047},
    {"motor[3]", 0, 5, 0, 1, 8, 158, 2047},
};
constexpr int kNumFields = sizeof(kFields) / sizeof(kFields[0]);
constexpr int kGyroField = 10;
constexpr int64_t kVbatRef = 420;
constexpr int64_t kMotorLow = 158;
constexpr int64_t kLoopUs = 125;

struct SyntheticOptions {
  int i_interval = 64;
  int p_denom = 4;
  bool slash_p_interval = false;  // "1/4" (old firmware) rather than "4" (Betaflight 4)
  int frames = 500;               // main frames before the resume
  int frames_after_resume = 100;  // 0: no LOGGING_RESUME event
  int64_t t0_us = 1000000;
  bool log_end = true;
  std::string firmware_type = "Cleanflight";
  uint32_t gyro_scale_bits = 0x3f800000;  // 1.0f
  uint64_t seed = 7;
};

struct Synthetic {
  std::string bytes;
  std::vector<int64_t> t_us;                 // expected sample times (unwrapped)
  std::vector<std::array<int64_t, 3>> gyro;  // expected raw gyroADC
};

std::string JoinInts(int column) {
  std::string s;
  for (int i = 0; i < kNumFields; ++i) {
    const FieldSpec& f = kFields[i];
    const int v = column == 0   ? f.is_signed
                  : column == 1 ? f.i_predictor
                  : column == 2 ? f.i_encoding
                  : column == 3 ? f.p_predictor
                                : f.p_encoding;
    s += (i ? "," : "") + std::to_string(v);
  }
  return s;
}

std::string SyntheticHeader(const SyntheticOptions& o) {
  std::string names;
  for (int i = 0; i < kNumFields; ++i) names += std::string(i ? "," : "") + kFields[i].name;
  char scale[32];
  std::snprintf(scale, sizeof(scale), "0x%08x", o.gyro_scale_bits);
  return "H Product:Blackbox flight data recorder by Nicholas Sherlock\n"
         "H Data version:2\n"
         "H Field I name:" +
         names +
         "\n"
         "H Field I signed:" +
         JoinInts(0) +
         "\n"
         "H Field I predictor:" +
         JoinInts(1) +
         "\n"
         "H Field I encoding:" +
         JoinInts(2) +
         "\n"
         "H Field P predictor:" +
         JoinInts(3) +
         "\n"
         "H Field P encoding:" +
         JoinInts(4) +
         "\n"
         "H Field S name:flightModeFlags,stateFlags\n"
         "H Field S signed:0,0\n"
         "H Field S predictor:0,0\n"
         "H Field S encoding:1,1\n"
         "H Firmware type:" +
         o.firmware_type +
         "\n"
         "H Firmware revision:Synthetic 1.0\n"
         "H I interval:" +
         std::to_string(o.i_interval) + "\n" +
         (o.slash_p_interval ? "H P interval:1/" + std::to_string(o.p_denom) + "\n"
                             : "H P interval:" + std::to_string(o.p_denom) + "\n") +
         "H minthrottle:1070\n"
         "H gyro_scale:" +
         scale +
         "\n"
         "H motorOutput:" +
         std::to_string(kMotorLow) +
         ",2047\n"
         "H vbatref:" +
         std::to_string(kVbatRef) + "\n";
}

// Encodes frames as the firmware does: residual = value - prediction from the previous frames.
Synthetic MakeSyntheticLog(const SyntheticOptions& o) {
  std::mt19937_64 rng(o.seed);
  std::uniform_int_distribution<int64_t> jitter(-3, 3);
  Synthetic s;
  Writer w;
  w.Text(SyntheticHeader(o));
  w.Text("E");  // SYNC_BEEP
  w.Byte(0);
  w.UnsignedVb(static_cast<uint32_t>(o.t0_us));

  std::vector<int64_t> prev, prev2;  // empty: no history (start, or after a resume)
  int64_t iteration = 0;
  bool wrote_slow = false;
  const int total = o.frames + o.frames_after_resume;
  for (int k = 0; k < total; ++k) {
    if (k == o.frames) {
      // Logging paused for 4000 iterations (0.5 s), then resumed at an I-frame boundary.
      iteration += 4000;
      iteration = (iteration / o.i_interval + 1) * o.i_interval;
      w.Text("E");
      w.Byte(14);
      w.UnsignedVb(static_cast<uint32_t>(iteration));
      w.UnsignedVb(static_cast<uint32_t>(o.t0_us + iteration * kLoopUs));
      prev.clear();
      prev2.clear();
    }
    std::vector<int64_t> v(kNumFields);
    v[0] = iteration;
    v[1] = o.t0_us + iteration * kLoopUs + jitter(rng);
    for (int i = 2; i < kNumFields; ++i) {
      std::uniform_int_distribution<int64_t> value(kFields[i].lo, kFields[i].hi);
      v[i] = value(rng);
    }
    const bool intra = iteration % o.i_interval == 0 || prev.empty();
    if (!intra && prev.empty()) ADD_FAILURE() << "the test schedule must start at an I frame";
    if (intra) {
      w.Text("I");
      w.UnsignedVb(static_cast<uint32_t>(v[0]));
      w.UnsignedVb(static_cast<uint32_t>(v[1]));
      for (int i = 2; i < kNumFields; ++i) {
        const FieldSpec& f = kFields[i];
        int64_t pred = 0;
        if (f.i_predictor == 9) pred = kVbatRef;
        if (f.i_predictor == 11) pred = kMotorLow;
        if (f.i_predictor == 5) pred = v[13];
        const int64_t r = v[i] - pred;
        if (f.i_encoding == 0) w.SignedVb(static_cast<int32_t>(r));
        if (f.i_encoding == 1) w.UnsignedVb(static_cast<uint32_t>(r));
        if (f.i_encoding == 3) w.UnsignedVb(static_cast<uint32_t>(-r) & 0x3FFF);
      }
      prev = v;
      prev2 = v;
    } else {
      w.Text("P");
      std::vector<int32_t> r(kNumFields);
      for (int i = 1; i < kNumFields; ++i) {
        int64_t pred = 0;
        switch (kFields[i].p_predictor) {
          case 1:
            pred = prev[i];
            break;
          case 2:
            pred = 2 * prev[i] - prev2[i];
            break;
          case 3:
            pred = (prev[i] + prev2[i]) / 2;
            break;
        }
        // 32-bit arithmetic as in the firmware (the time field wraps).
        r[i] = static_cast<int32_t>(static_cast<uint32_t>(v[i]) - static_cast<uint32_t>(pred));
      }
      w.SignedVb(r[1]);
      w.Tag2_3S32(&r[2]);
      w.Tag2_3SVariable(&r[5]);
      w.Tag8_8Svb(&r[8], 2);
      for (int i = 10; i < 13; ++i) w.SignedVb(r[i]);
      w.Tag8_4S16(&r[13]);
      prev2 = prev;
      prev = v;
    }
    if (!wrote_slow) {
      w.Text("S");
      w.UnsignedVb(3);
      w.UnsignedVb(1);
      wrote_slow = true;
    }
    s.t_us.push_back(v[1]);
    s.gyro.push_back({v[kGyroField], v[kGyroField + 1], v[kGyroField + 2]});
    iteration += o.p_denom;
  }
  if (o.log_end) {
    w.Text("E");
    w.Byte(255);
    w.bytes().append("End of log", 11);  // with its NUL
  }
  s.bytes = w.bytes();
  return s;
}

void ExpectMatchesSynthetic(const FlightLog& log, const Synthetic& s, double rad_per_count) {
  ASSERT_EQ(log.gyro.size(), s.t_us.size());
  for (size_t k = 0; k < s.t_us.size(); ++k) {
    ASSERT_EQ(log.gyro[k].t_ns, s.t_us[k] * 1000) << "sample " << k;
    for (int axis = 0; axis < 3; ++axis) {
      ASSERT_NEAR(log.gyro[k].omega_rad_s[axis], s.gyro[k][axis] * rad_per_count, kRateTolRadS)
          << "sample " << k << " axis " << axis;
    }
  }
}

TEST(Blackbox, DecodesEveryEncodingAndPredictorOfASyntheticLogExactly) {
  const Synthetic s = MakeSyntheticLog({});
  const FlightLog log = DecodeBlackbox(s.bytes, "synthetic.bbl");
  ExpectMatchesSynthetic(log, s, kRadPerDeg);
  EXPECT_EQ(log.format, "betaflight");
  EXPECT_EQ(log.gyro_source, "gyroADC");
  EXPECT_EQ(log.records_skipped, 0u);
  // The LOGGING_RESUME pause is the only gap.
  EXPECT_EQ(log.gyro.sampling().gap_indices.size(), 1u);
  // The P interval of 4 loops, up to the ±3 µs timing jitter the synthetic log adds.
  EXPECT_NEAR(log.gyro.sampling().median_interval_ns, 4 * kLoopUs * 1000, 6000);
}

TEST(Blackbox, OldSlashPIntervalSyntaxMeansTheSame) {
  SyntheticOptions o;
  o.slash_p_interval = true;
  o.p_denom = 8;
  const Synthetic s = MakeSyntheticLog(o);
  ExpectMatchesSynthetic(DecodeBlackbox(s.bytes, "slash.bbl"), s, kRadPerDeg);
}

TEST(Blackbox, UndoesThe32BitMicrosecondRollover) {
  SyntheticOptions o;
  o.t0_us = (int64_t{1} << 32) - 30000;  // the clock wraps 30 ms into the log
  o.frames_after_resume = 0;
  const Synthetic s = MakeSyntheticLog(o);
  ASSERT_GT(s.t_us.back(), int64_t{1} << 32);
  const FlightLog log = DecodeBlackbox(s.bytes, "rollover.bbl");
  ExpectMatchesSynthetic(log, s, kRadPerDeg);
}

TEST(Blackbox, GyroScaleFollowsBlackboxToolsRule) {
  // Cleanflight family: deg/s per count.
  SyntheticOptions half;
  half.gyro_scale_bits = 0x3f000000;  // 0.5f
  half.frames_after_resume = 0;
  const Synthetic a = MakeSyntheticLog(half);
  ExpectMatchesSynthetic(DecodeBlackbox(a.bytes, "half.bbl"), a, 0.5 * kRadPerDeg);
  // Baseflight: rad/µs per count.
  SyntheticOptions base = half;
  const float scale = 1.0642251e-9f;  // an MPU6050's 2000 deg/s range: 1/16.4 deg/s in rad/µs
  std::memcpy(&base.gyro_scale_bits, &scale, sizeof(scale));
  base.firmware_type = "Baseflight";
  const Synthetic b = MakeSyntheticLog(base);
  ExpectMatchesSynthetic(DecodeBlackbox(b.bytes, "base.bbl"), b, static_cast<double>(scale) * 1e6);
}

TEST(Blackbox, ChoosesTheLongestLogOrTheOneAskedFor) {
  SyntheticOptions short_log;
  short_log.frames = 40;
  short_log.frames_after_resume = 0;
  short_log.seed = 1;
  SyntheticOptions long_log;
  long_log.frames = 300;
  long_log.frames_after_resume = 0;
  long_log.seed = 2;
  const Synthetic a = MakeSyntheticLog(short_log);
  const Synthetic b = MakeSyntheticLog(long_log);
  const std::string file = "\xFF\xFF" + a.bytes + b.bytes + a.bytes;
  const std::vector<BlackboxLogInfo> infos = ListBlackboxLogsInBuffer(file, "multi.bbl");
  ASSERT_EQ(infos.size(), 3u);
  EXPECT_EQ(infos[0].main_frames, 40u);
  EXPECT_EQ(infos[1].main_frames, 300u);
  EXPECT_EQ(infos[2].main_frames, 40u);
  EXPECT_EQ(infos[1].begin_byte, 2 + a.bytes.size());
  EXPECT_EQ(infos[1].size_bytes, b.bytes.size());
  EXPECT_TRUE(infos[1].ended_cleanly);
  EXPECT_EQ(infos[1].firmware, "Synthetic 1.0");
  EXPECT_NEAR(infos[1].rate_hz, 1e6 / (4 * kLoopUs), 30.0);  // ±3 µs jitter on 500 µs

  ExpectMatchesSynthetic(DecodeBlackbox(file, "multi.bbl"), b, kRadPerDeg);
  ExpectMatchesSynthetic(DecodeBlackbox(file, "multi.bbl", 2), a, kRadPerDeg);
  EXPECT_THROW(DecodeBlackbox(file, "multi.bbl", 3), IoError);
  EXPECT_THROW(DecodeBlackbox(file, "multi.bbl", -2), IoError);
  const FlightLog log = DecodeBlackbox(file, "multi.bbl");
  const bool says_which =
      std::any_of(log.warnings.begin(), log.warnings.end(), [](const LogWarning& w) {
        return w.message.find("3 logs") != std::string::npos &&
               w.message.find("log 1") != std::string::npos;
      });
  EXPECT_TRUE(says_which);
}

TEST(Blackbox, RejectsInputThatIsNotALogWithAMessageNamingThePath) {
  EXPECT_THROW(DecodeBlackbox("t,gx,gy,gz\n0,0,0,0\n", "gyro.csv"), IoError);
  try {
    DecodeBlackbox(
        "H Product:Blackbox flight data recorder by Nicholas Sherlock\nH Data version:2\n",
        "hdr.bbl");
    FAIL() << "a header without field definitions must not decode";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("hdr.bbl"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("log 0"), std::string::npos) << e.what();
  }
  // A header whose predictor list is shorter than its names.
  SyntheticOptions o;
  std::string bad = MakeSyntheticLog(o).bytes;
  const size_t at = bad.find("H Field P predictor:6,");
  bad.replace(at, std::strlen("H Field P predictor:6,"), "H Field P predictor:");
  EXPECT_THROW(DecodeBlackbox(bad, "bad.bbl"), IoError);
  // An unknown encoding number.
  std::string unknown = MakeSyntheticLog(o).bytes;
  const size_t enc = unknown.find("H Field I encoding:1,");
  unknown.replace(enc, std::strlen("H Field I encoding:1,"), "H Field I encoding:42,");
  EXPECT_THROW(DecodeBlackbox(unknown, "unknown.bbl"), IoError);
}

// Regression (fuzz/flight_log_fuzz on 2a2eb04, 169,291 executions): only the first field of an
// encoded group had its predictor checked, so a later member predicted from motor[0] read the
// frame before motor[0] was decoded, and with no motor[0] field at all, before the ring buffer
// (a heap overflow under ASan). Every member is checked now.
TEST(Blackbox, AGroupMemberPredictedFromMotor0DecodedAfterItIsRefused) {
  SyntheticOptions o;
  std::string bad = MakeSyntheticLog(o).bytes;
  // axisP[0..2] are one Tag2_3S32 group in P frames; axisP[1] now predicts from motor[0].
  const std::string line = "H Field P predictor:6,2,1,1,1,";
  const size_t at = bad.find(line);
  ASSERT_NE(at, std::string::npos);
  bad.replace(at, line.size(), "H Field P predictor:6,2,1,5,1,");  // 5: motor[0]
  try {
    DecodeBlackbox(bad, "group.bbl");
    FAIL() << "a group member predicted from a later motor[0] must not decode";
  } catch (const IoError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("axisP[1] is predicted from motor[0], which is not decoded before it"),
              std::string::npos)
        << what;
  }
}

TEST(Blackbox, RandomBodiesAfterAValidHeaderNeverCrashOrHang) {
  SyntheticOptions o;
  const std::string header = SyntheticHeader(o);
  std::mt19937_64 rng(99);
  std::uniform_int_distribution<int> byte(0, 255);
  const std::string markers = "IPESGH";
  for (int trial = 0; trial < 20; ++trial) {
    std::string file = header;
    for (int k = 0; k < 20000; ++k) {
      // Bias towards frame markers so that many frames start and fail.
      file.push_back(k % 7 == 0 ? markers[byte(rng) % markers.size()]
                                : static_cast<char>(byte(rng)));
    }
    try {
      const FlightLog log = DecodeBlackbox(file, "random.bbl");
      EXPECT_GT(log.records_skipped, 0u);
    } catch (const IoError&) {
      // No main frame survived: a clear error is the right answer.
    }
  }
}

TEST(Blackbox, FloodsOfFrameMarkersAreBoundedPerFrame) {
  // Every byte starts a frame attempt; each attempt reads at most one maximal frame, so these
  // finish in linear time. Only that they finish and do not crash is checked.
  const std::string header = SyntheticHeader(SyntheticOptions{});
  for (const char marker : std::string("IPEGHS")) {
    const std::string file = header + std::string(200000, marker);
    try {
      DecodeBlackbox(file, "flood.bbl");
    } catch (const IoError&) {
    }
  }
  // A P frame can never start the main stream: P frames before any I frame are dropped.
  Synthetic s = MakeSyntheticLog(SyntheticOptions{});
  const size_t first_p = s.bytes.find('P', SyntheticHeader(SyntheticOptions{}).size());
  std::string p_first = SyntheticHeader(SyntheticOptions{}) + s.bytes.substr(first_p);
  const FlightLog log = DecodeBlackbox(p_first, "pfirst.bbl");
  EXPECT_LT(log.gyro.size(), s.t_us.size());
  EXPECT_GT(log.records_skipped, 0u);
}

TEST(Blackbox, AHeaderThatRunsIntoTheNextLogsMarkerReadsAsAnEmptyLog) {
  // Regression (found by fuzzing): log 0's last header line is a bare "H " directly followed by
  // log 1's "H Product:" marker, so log 0 ends where that line's text would begin and its header
  // scan stops one byte past its end. Its data then began after its end: the decoder reserved a
  // wrapped-around size and threw std::length_error instead of reading log 0 as empty.
  SyntheticOptions o;
  o.frames = 60;
  o.frames_after_resume = 0;
  const Synthetic next = MakeSyntheticLog(o);
  const std::string file = SyntheticHeader(o) + "H " + next.bytes;
  std::vector<BlackboxLogInfo> infos;
  ASSERT_NO_THROW(infos = ListBlackboxLogsInBuffer(file, "cut.bbl"));
  ASSERT_EQ(infos.size(), 2u);
  EXPECT_EQ(infos[0].size_bytes, SyntheticHeader(o).size() + 2);
  EXPECT_EQ(infos[0].main_frames, 0u);
  EXPECT_EQ(infos[1].main_frames, 60u);
  // The longest log is read whole; log 0 itself is a clear error, not a crash.
  ExpectMatchesSynthetic(DecodeBlackbox(file, "cut.bbl"), next, kRadPerDeg);
  EXPECT_THROW(DecodeBlackbox(file, "cut.bbl", 0), IoError);
}

// ---- The real logs ----

std::string DataPath(const std::string& leaf) {
  return test::RealDataPath("gyro/betaflight_blackbox/" + leaf);
}

Eigen::Vector3d PeakDegS(const FlightLog& log) {
  Eigen::Vector3d peak = Eigen::Vector3d::Zero();
  for (const GyroSample& s : log.gyro.samples()) peak = peak.cwiseMax(s.omega_rad_s.cwiseAbs());
  return peak / kRadPerDeg;
}

void ExpectPeakDegS(const FlightLog& log, double x, double y, double z) {
  const Eigen::Vector3d peak = PeakDegS(log);
  // gyroADC is in whole deg/s; the peak must be that integer up to the deg->rad->deg round trip.
  constexpr double kTol = 1e-9;
  EXPECT_NEAR(peak.x(), x, kTol);
  EXPECT_NEAR(peak.y(), y, kTol);
  EXPECT_NEAR(peak.z(), z, kTol);
}

TEST(BlackboxRealLogs, Btfl002HoldsOneAcroFlightAt500Hz) {
  SHUTTERLAB_NEED_REAL_DATA();
  const FlightLog log = ReadBlackbox(DataPath("btfl_002.bbl"));
  EXPECT_EQ(log.gyro.size(), 66640u);
  EXPECT_NEAR(log.gyro.DurationS(), 133.8383, kDurationTolS);
  EXPECT_EQ(log.gyro.sampling().median_interval_ns, 2000000);
  EXPECT_EQ(log.records_skipped, 0u);
  ExpectPeakDegS(log, 732, 234, 200);
  const std::vector<BlackboxLogInfo> infos = ListBlackboxLogs(DataPath("btfl_002.bbl"));
  ASSERT_EQ(infos.size(), 1u);
  EXPECT_EQ(infos[0].i_frames, 4165u);
  EXPECT_TRUE(infos[0].ended_cleanly);
  EXPECT_EQ(infos[0].firmware, "Betaflight 4.2.8 (101738d8e) STM32F7X2");
  EXPECT_EQ(infos[0].craft_name, "Gecko");
}

TEST(BlackboxRealLogs, Btfl001HoldsTwoLogsAndTheLongerIsTheDefault) {
  SHUTTERLAB_NEED_REAL_DATA();
  const std::vector<BlackboxLogInfo> infos = ListBlackboxLogs(DataPath("btfl_001.bbl"));
  ASSERT_EQ(infos.size(), 2u);
  EXPECT_EQ(infos[0].main_frames, 98u);
  EXPECT_NEAR(infos[0].duration_s, 0.1947, kDurationTolS);
  EXPECT_EQ(infos[1].main_frames, 24893u);
  EXPECT_NEAR(infos[1].duration_s, 49.9782, kDurationTolS);
  EXPECT_DOUBLE_EQ(infos[1].rate_hz, 500.0);
  EXPECT_EQ(infos[1].begin_byte, infos[0].size_bytes);
  const FlightLog log = ReadBlackbox(DataPath("btfl_001.bbl"));
  EXPECT_EQ(log.gyro.size(), 24893u);
  ExpectPeakDegS(log, 26, 23, 60);
  EXPECT_EQ(ReadBlackbox(DataPath("btfl_001.bbl"), 0).gyro.size(), 98u);
}

TEST(BlackboxRealLogs, Log00037Is1kHzFromAn8kHzLoop) {
  SHUTTERLAB_NEED_REAL_DATA();
  const FlightLog log = ReadBlackbox(DataPath("LOG00037.BFL"));
  EXPECT_EQ(log.gyro.size(), 16774u);
  EXPECT_NEAR(log.gyro.DurationS(), 17.0219, kDurationTolS);
  EXPECT_EQ(log.gyro.sampling().median_interval_ns, 1000000);
  EXPECT_TRUE(log.gyro.sampling().gap_indices.empty());
  ExpectPeakDegS(log, 37, 197, 43);
  EXPECT_EQ(ListBlackboxLogs(DataPath("LOG00037.BFL"))[0].i_frames, 525u);
}

TEST(BlackboxRealLogs, LooksLikeBlackboxRecognisesTheFiles) {
  SHUTTERLAB_NEED_REAL_DATA();
  const std::string bytes = ReadFileToString(DataPath("btfl_001.bbl"));
  EXPECT_TRUE(LooksLikeBlackbox(std::string_view(bytes).substr(0, 4096)));
  EXPECT_FALSE(LooksLikeBlackbox("t,gx,gy,gz\n0.0,0,0,0\n"));
  EXPECT_FALSE(LooksLikeBlackbox(""));
  EXPECT_TRUE(LooksLikeBlackbox(
      "loopIteration, time (us), axisP[0], gyroADC[0], gyroADC[1], gyroADC[2]\n"));
}

// Truncation at random offsets: a clear error inside the header, otherwise an exact prefix of the
// full decode (the cut frame is dropped), flagged as not ended cleanly.
TEST(BlackboxCorruption, TruncatedCopiesDecodeToAPrefix) {
  SHUTTERLAB_NEED_REAL_DATA();
  const std::string bytes = ReadFileToString(DataPath("LOG00037.BFL"));
  const FlightLog full = DecodeBlackbox(bytes, "full");
  std::mt19937_64 rng(5);
  std::uniform_int_distribution<size_t> cut(0, bytes.size() - 1);
  constexpr size_t kHeaderBytes = 4400;  // the header ends at byte 4046; the first frames follow
  for (int trial = 0; trial < 12; ++trial) {
    const size_t size = trial == 0 ? 3000 : cut(rng);
    const std::string prefix = bytes.substr(0, size);
    try {
      const FlightLog log = DecodeBlackbox(prefix, "cut");
      ASSERT_LE(log.gyro.size(), full.gyro.size());
      for (size_t k = 0; k + 1 < log.gyro.size(); ++k) {
        ASSERT_EQ(log.gyro[k].t_ns, full.gyro[k].t_ns) << "cut at " << size;
        ASSERT_EQ(log.gyro[k].omega_rad_s, full.gyro[k].omega_rad_s) << "cut at " << size;
      }
      // Most of what precedes the cut survives: at most one I interval is lost at the end.
      const double kept_fraction = static_cast<double>(log.gyro.size()) / full.gyro.size();
      EXPECT_GT(kept_fraction, static_cast<double>(size) / bytes.size() - 0.05)
          << "cut at " << size;
      EXPECT_TRUE(test::AnyWarningContains(log.warnings, "truncated: "));
      EXPECT_TRUE(test::AnyWarningContains(log.warnings, "LOG_END"));
    } catch (const IoError& e) {
      EXPECT_LT(size, kHeaderBytes) << e.what();
    }
  }
}

// Byte flips in the data: no crash, the damage is counted, and almost every frame survives intact.
TEST(BlackboxCorruption, ByteFlippedCopiesLoseOnlyTheDamagedFrames) {
  SHUTTERLAB_NEED_REAL_DATA();
  const std::string bytes = ReadFileToString(DataPath("LOG00037.BFL"));
  const FlightLog full = DecodeBlackbox(bytes, "full");
  std::map<int64_t, Eigen::Vector3d> truth;
  for (const GyroSample& s : full.gyro.samples()) truth[s.t_ns] = s.omega_rad_s;
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<size_t> where(8000, bytes.size() - 1);
  std::uniform_int_distribution<int> flip(1, 255);
  size_t skipped_total = 0;
  for (int trial = 0; trial < 6; ++trial) {
    std::string damaged = bytes;
    for (int k = 0; k < 20; ++k) damaged[where(rng)] ^= static_cast<char>(flip(rng));
    const FlightLog log = DecodeBlackbox(damaged, "flipped");
    skipped_total += log.records_skipped;
    size_t intact = 0;
    for (const GyroSample& s : log.gyro.samples()) {
      const auto it = truth.find(s.t_ns);
      if (it != truth.end() && it->second == s.omega_rad_s) ++intact;
    }
    // 20 flips damage about 20 I intervals (32 frames each); over 40 seeds at least 97.5% survived.
    EXPECT_GT(intact, full.gyro.size() * 95 / 100) << "trial " << trial;
  }
  EXPECT_GT(skipped_total, 0u);
}

TEST(BlackboxCorruption, FlipsAnywhereIncludingTheHeaderNeverCrash) {
  SHUTTERLAB_NEED_REAL_DATA();
  const std::string bytes = ReadFileToString(DataPath("btfl_001.bbl")).substr(0, 60000);
  std::mt19937_64 rng(13);
  std::uniform_int_distribution<size_t> where(0, bytes.size() - 1);
  for (int trial = 0; trial < 10; ++trial) {
    std::string damaged = bytes;
    for (int k = 0; k < 50; ++k) damaged[where(rng)] = static_cast<char>(rng());
    try {
      DecodeBlackbox(damaged, "flipped");
    } catch (const IoError&) {
    }
  }
}

// ---- CSV export ----

TEST(BlackboxCsv, ReadsTheBlackboxDecodeExport) {
  test::TempDir dir;
  const std::string path = dir / "LOG00001.01.csv";
  // blackbox_decode: ", "-separated names, " (us)" after time, "%3d"-padded integers.
  std::string csv =
      "loopIteration, time (us), axisP[0], axisP[1], axisP[2], gyroADC[0], gyroADC[1], gyroADC[2], "
      "motor[0]\n";
  for (int k = 0; k < 5; ++k) {
    char line[200];
    std::snprintf(line, sizeof(line), "%3d, %d, %3d, %3d, %3d, %3d, %3d, %3d, %3d\n", 16 * k,
                  17433272 + 2000 * k, 1, 2, 3, 10 * k - 7, -k, 732, 1200);
    csv += line;
  }
  WriteFileAtomically(path, csv);
  const FlightLog log = ReadBlackbox(path);
  ASSERT_EQ(log.gyro.size(), 5u);
  EXPECT_EQ(log.format, "betaflight_csv");
  for (int k = 0; k < 5; ++k) {
    EXPECT_EQ(log.gyro[k].t_ns, (17433272 + 2000 * k) * int64_t{1000});
    EXPECT_NEAR(log.gyro[k].omega_rad_s.x(), (10 * k - 7) * kRadPerDeg, kRateTolRadS);
    EXPECT_NEAR(log.gyro[k].omega_rad_s.y(), -k * kRadPerDeg, kRateTolRadS);
    EXPECT_NEAR(log.gyro[k].omega_rad_s.z(), 732 * kRadPerDeg, kRateTolRadS);
  }
  EXPECT_FALSE(log.warnings.empty()) << "the unit-less gyroADC assumption is stated";
  const std::vector<BlackboxLogInfo> infos = ListBlackboxLogs(path);
  ASSERT_EQ(infos.size(), 1u);
  EXPECT_EQ(infos[0].main_frames, 5u);
}

TEST(BlackboxCsv, HonoursUnitsInTheHeader) {
  test::TempDir dir;
  const std::string path = dir / "units.csv";
  WriteFileAtomically(path,
                      "\"loopIteration\",\"time (s)\",\"gyroADC[0] (rad/s)\",\"gyroADC[1] "
                      "(rad/s)\",\"gyroADC[2] (rad/s)\"\n"
                      "0,1.5,0.25,-0.5,1\n"
                      "1,1.502,0.5,-1,2\n");
  const FlightLog log = ReadBlackbox(path);
  ASSERT_EQ(log.gyro.size(), 2u);
  EXPECT_EQ(log.gyro[1].t_ns, 1502000000);
  EXPECT_NEAR(log.gyro[1].omega_rad_s.y(), -1.0, kRateTolRadS);
  EXPECT_TRUE(log.warnings.empty());
}

TEST(BlackboxCsv, BadRowsNameTheLine) {
  test::TempDir dir;
  const std::string path = dir / "bad.csv";
  WriteFileAtomically(path,
                      "loopIteration, time (us), gyroADC[0], gyroADC[1], gyroADC[2]\n"
                      "0, 100, 1, 2, 3\n"
                      "1, 200, 1, x, 3\n");
  try {
    ReadBlackbox(path);
    FAIL() << "a non-number must not read";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.csv:3"), std::string::npos) << e.what();
  }
  WriteFileAtomically(path,
                      "loopIteration, time (us), gyroADC[0], gyroADC[1], gyroADC[2]\n"
                      "0, 300, 1, 2, 3\n"
                      "1, 200, 1, 2, 3\n");
  EXPECT_THROW(ReadBlackbox(path), IoError);
  EXPECT_THROW(ReadBlackbox(path, 1), IoError);
}

// ---- Streaming: the samples decoded again a chunk at a time ----

// Everything a stream gives, read chunk by chunk: each chunk holds chunk_samples but the last.
struct Streamed {
  FlightLog log;  // with every sample and the samples' warnings after the log's own
  size_t chunks = 0;
};

Streamed ReadInChunks(BlackboxStream stream, size_t chunk_samples) {
  Streamed out;
  std::vector<GyroSample> samples;
  double fraction = 0.0;
  for (GyroChunk chunk = stream.samples->Next(); !chunk.empty(); chunk = stream.samples->Next()) {
    EXPECT_LE(chunk.size, chunk_samples);
    if (out.chunks > 0) {
      EXPECT_EQ(samples.size() % chunk_samples, 0u) << "only the last chunk is short";
    }
    samples.insert(samples.end(), chunk.begin(), chunk.end());
    ++out.chunks;
    EXPECT_GE(stream.samples->Fraction(), fraction);
    fraction = stream.samples->Fraction();
  }
  EXPECT_EQ(stream.samples->Fraction(), 1.0);
  out.log = std::move(stream.log);
  if (!samples.empty()) out.log.gyro = GyroTrace(std::move(samples));
  for (LogWarning& w : stream.samples->Warnings()) out.log.warnings.push_back(std::move(w));
  return out;
}

// The decoder pauses when a chunk is full and goes on where it stopped: at every chunk size the
// samples and what was lost equal one uninterrupted decode's (the twin: a chunk larger than the
// log), on clean, multi-log, cut and damaged inputs.
TEST(BlackboxStream, ChunksOfAnySizeGiveTheUninterruptedDecodeBitForBit) {
  SyntheticOptions a_options;
  a_options.frames = 70;
  a_options.frames_after_resume = 30;
  SyntheticOptions b_options;
  b_options.seed = 3;
  b_options.t0_us = (int64_t{1} << 32) - 30000;  // the clock wraps inside it
  const Synthetic a = MakeSyntheticLog(a_options);
  const Synthetic b = MakeSyntheticLog(b_options);
  std::vector<std::string> inputs = {a.bytes, "\xFF" + a.bytes + b.bytes + a.bytes,
                                     b.bytes.substr(0, b.bytes.size() * 3 / 5)};
  std::mt19937_64 rng(21);
  for (int trial = 0; trial < 4; ++trial) {
    std::string damaged = a.bytes + b.bytes;
    std::uniform_int_distribution<size_t> where(SyntheticHeader(a_options).size(),
                                                damaged.size() - 1);
    for (int k = 0; k < 12; ++k) damaged[where(rng)] = static_cast<char>(rng());
    inputs.push_back(damaged);
  }
  for (size_t i = 0; i < inputs.size(); ++i) {
    for (const int log_index : {-1, 0}) {
      const std::string what = "input " + std::to_string(i) + " log " + std::to_string(log_index);
      const Streamed whole = ReadInChunks(
          OpenBlackboxBuffer(inputs[i], "s.bbl", log_index, size_t{1} << 30), size_t{1} << 30);
      ASSERT_LE(whole.chunks, 1u) << what;
      ExpectSameLog(whole.log, DecodeBlackbox(inputs[i], "s.bbl", log_index), what);
      for (const size_t chunk : {1, 2, 3, 7, 64}) {
        const Streamed streamed =
            ReadInChunks(OpenBlackboxBuffer(inputs[i], "s.bbl", log_index, chunk), chunk);
        ExpectSameLog(streamed.log, whole.log, what + " chunk " + std::to_string(chunk));
      }
    }
  }
  // And against the exact truth (logs whose every frame decodes: the resumes above may lose the
  // I interval after them, whose first frame's jitter puts it before the resume's time).
  SyntheticOptions c_options = b_options;
  c_options.frames_after_resume = 0;
  const Synthetic c = MakeSyntheticLog(c_options);
  const Synthetic d = MakeSyntheticLog(SyntheticOptions{});
  const std::string file = d.bytes + c.bytes;
  ExpectMatchesSynthetic(ReadInChunks(OpenBlackboxBuffer(file, "s.bbl", -1, 5), 5).log, d,
                         kRadPerDeg);
  ExpectMatchesSynthetic(ReadInChunks(OpenBlackboxBuffer(file, "s.bbl", 1, 4), 4).log, c,
                         kRadPerDeg);
}

// A real file read from its mapping in small chunks, and cut and damaged copies of it read from
// memory, equal the uninterrupted decode.
TEST(BlackboxStream, RealLogsInSmallChunksEqualTheUninterruptedDecode) {
  SHUTTERLAB_NEED_REAL_DATA();
  for (const char* leaf : {"LOG00037.BFL", "btfl_001.bbl"}) {
    const std::string path = DataPath(leaf);
    const std::string bytes = ReadFileToString(path);
    const FlightLog whole = DecodeBlackbox(bytes, path);
    ExpectSameLog(ReadInChunks(OpenBlackbox(path, -1, 1000), 1000).log, whole, leaf);
    ExpectSameLog(ReadBlackbox(path), whole, leaf);
  }
  const std::string bytes = ReadFileToString(DataPath("LOG00037.BFL"));
  std::mt19937_64 rng(8);
  for (int trial = 0; trial < 4; ++trial) {
    std::string copy = bytes.substr(
        0, std::uniform_int_distribution<size_t>(bytes.size() / 4, bytes.size() - 1)(rng));
    for (int k = 0; k < 8 * trial; ++k)
      copy[std::uniform_int_distribution<size_t>(5000, copy.size() - 1)(rng)] ^= 0x5A;
    const size_t chunk = 1 + trial * 37;
    ExpectSameLog(ReadInChunks(OpenBlackboxBuffer(copy, "copy", -1, chunk), chunk).log,
                  DecodeBlackbox(copy, "copy"), "trial " + std::to_string(trial));
  }
}

TEST(BlackboxStream, OpeningKeepsNoSampleAndSaysWhatWasLost) {
  SyntheticOptions o;
  o.log_end = false;
  const Synthetic s = MakeSyntheticLog(o);
  BlackboxStream stream = OpenBlackboxBuffer(s.bytes, "open.bbl", -1, 16);
  EXPECT_TRUE(stream.log.gyro.empty());
  EXPECT_EQ(stream.samples->Fraction(), 0.0);
  // The warnings of the whole log are known before a sample is taken: the pause, the cut end.
  EXPECT_TRUE(test::AnyWarningContains(stream.log.warnings, "paused and resumed 1 time"));
  EXPECT_TRUE(test::AnyWarningContains(stream.log.warnings, "no LOG_END"));
  EXPECT_EQ(ReadInChunks(std::move(stream), 16).log.gyro.size(), s.t_us.size());
}

TEST(BlackboxStream, AFileThatChangesBetweenThePassesIsRefusedInOneLine) {
  test::TempDir dir;
  const std::string path = dir / "growing.bbl";
  SyntheticOptions o;
  o.log_end = false;
  const Synthetic s = MakeSyntheticLog(o);
  for (const bool grow : {true, false}) {
    WriteFileAtomically(path, s.bytes);
    BlackboxStream stream = OpenBlackbox(path, -1, 8);
    ASSERT_FALSE(stream.samples->Next().empty());
    {
      // Still being recorded: more frames appended in place; or cut short (a mapped page past
      // the new end would kill the process).
      std::ofstream out(
          path, grow ? std::ios::binary | std::ios::app : std::ios::binary | std::ios::trunc);
      out << (grow ? s.bytes.substr(s.bytes.size() / 2) : s.bytes.substr(0, 5000));
    }
    try {
      while (!stream.samples->Next().empty()) {
      }
      FAIL() << "a changed file must be refused";
    } catch (const IoError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(path), std::string::npos) << what;
      EXPECT_NE(what.find("changed while it was read"), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  }
}

TEST(BlackboxStream, CsvExportInTinyChunksEqualsTheWholeRead) {
  test::TempDir dir;
  const std::string path = dir / "export.csv";
  std::string csv = "loopIteration, time (us), gyroADC[0], gyroADC[1], gyroADC[2]\n";
  for (int k = 0; k < 40; ++k) {
    csv += std::to_string(k) + ", " + std::to_string(1000 + 500 * k) + ", " +
           std::to_string(k % 7 - 3) + ", " + std::to_string(-k) + ", 12\n";
    if (k == 20) csv += "\n";  // blank lines are skipped
  }
  csv += "40, 210";  // cut inside its last line
  WriteFileAtomically(path, csv);
  const FlightLog whole = ReadBlackbox(path);
  ASSERT_EQ(whole.gyro.size(), 40u);
  ASSERT_TRUE(test::AnyWarningContains(whole.warnings, "line 43"));
  for (const size_t chunk : {1, 3, 40, 1000}) {
    const Streamed streamed = ReadInChunks(OpenBlackbox(path, -1, chunk), chunk);
    ExpectSameLog(streamed.log, whole, "chunk " + std::to_string(chunk));
  }
  // On a pipe the bytes come whole and are read the same way.
  ExpectSameLog(ReadInChunks(OpenBlackboxBytes(csv, path, -1, 2), 2).log, whole, "pipe");
}

}  // namespace
}  // namespace shutterlab
