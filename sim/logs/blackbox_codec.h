#pragma once
// Byte-level decoders of the Betaflight / Cleanflight / INAV blackbox format: variable-byte
// integers and the tagged group encodings. Header-only so that the frame decoder inlines them
// (decoding speed is a requirement: no per-byte virtual calls, no per-byte bounds exceptions).
//
// Bit layouts follow the firmware's writers (betaflight src/main/blackbox/blackbox_encoding.c:
// blackboxWriteUnsignedVB, blackboxWriteTag2_3S32, blackboxWriteTag2_3SVariable,
// blackboxWriteTag8_4S16, blackboxWriteTag8_8SVB) and the readers of betaflight/blackbox-tools
// (src/stream.c, src/decoders.c) and blackbox-log-viewer (src/decoders.js).

#include <cstddef>
#include <cstdint>

namespace shutterlab::blackbox {

// Field encodings as numbered in "H Field X encoding:" header lines (firmware
// blackbox_fielddefs.h).
enum Encoding : int {
  kSignedVb = 0,
  kUnsignedVb = 1,
  kNeg14Bit = 3,
  kTag8_8Svb = 6,
  kTag2_3S32 = 7,
  kTag8_4S16 = 8,
  kNull = 9,
  kTag2_3SVariable = 10,
};

// Field predictors as numbered in "H Field X predictor:" header lines.
enum Predictor : int {
  kPredictZero = 0,
  kPredictPrevious = 1,
  kPredictStraightLine = 2,
  kPredictAverage2 = 3,
  kPredictMinThrottle = 4,
  kPredictMotor0 = 5,
  kPredictIncrement = 6,
  kPredictHomeCoord = 7,
  kPredict1500 = 8,
  kPredictVbatRef = 9,
  kPredictLastMainFrameTime = 10,
  kPredictMinMotor = 11,
  // Not in any file: the decoder's name for the second coordinate of a HOME_COORD pair
  // (blackbox-tools rewrites the pair the same way, as FLIGHT_LOG_FIELD_PREDICTOR_HOME_COORD_1).
  kPredictHomeCoord1 = 256,
};

// Sign-extends the low `bits` bits of value.
inline int32_t SignExtend(uint32_t value, int bits) {
  const uint32_t mask = bits >= 32 ? 0xFFFFFFFFu : ((1u << bits) - 1u);
  const uint32_t sign = 1u << (bits - 1);
  return static_cast<int32_t>(((value & mask) ^ sign) - sign);
}

// A bounded cursor over a byte buffer. Reading past `end` yields 0 and sets eof, as the
// reference reader's EOF does; the caller checks eof once per frame instead of per byte, and
// every loop over the input advances pos or stops, so no input can make it loop forever.
struct ByteReader {
  const uint8_t* data = nullptr;
  size_t pos = 0;
  size_t end = 0;
  bool eof = false;

  uint8_t ReadByte() {
    if (pos < end) return data[pos++];
    eof = true;
    return 0;
  }

  // Little-endian base-128, at most 5 bytes for 32 bits; an over-long or truncated value reads as
  // 0, as in blackbox-tools' streamReadUnsignedVB.
  uint32_t ReadUnsignedVb() {
    uint32_t result = 0;
    for (int i = 0, shift = 0; i < 5; ++i, shift += 7) {
      if (pos >= end) {
        eof = true;
        return 0;
      }
      const uint8_t c = data[pos++];
      result |= static_cast<uint32_t>(c & 0x7F) << shift;
      if (c < 0x80) return result;
    }
    return 0;
  }

  // ZigZag on top of the unsigned encoding.
  int32_t ReadSignedVb() {
    const uint32_t u = ReadUnsignedVb();
    return static_cast<int32_t>((u >> 1) ^ (0u - (u & 1u)));
  }

  // Encoding 3: the firmware negates a 14-bit value before writing it unsigned.
  int32_t ReadNeg14Bit() { return -SignExtend(ReadUnsignedVb(), 14); }

  // Shared by TAG2_3S32 and TAG2_3SVARIABLE selector 3: each of the three values takes 1..4
  // little-endian bytes, the byte count of value i in bits 2i..2i+1 of the lead byte.
  void ReadTag2_3SBytes(uint8_t lead, int32_t* values) {
    for (int i = 0; i < 3; ++i, lead >>= 2) {
      const int count = (lead & 0x03) + 1;
      uint32_t v = 0;
      for (int b = 0; b < count; ++b) v |= static_cast<uint32_t>(ReadByte()) << (8 * b);
      values[i] = SignExtend(v, 8 * count);
    }
  }

  // Encoding 7: 2-bit selector, then three values of 2, 4, 6 bits or 1..4 bytes each.
  void ReadTag2_3S32(int32_t* values) {
    const uint8_t lead = ReadByte();
    switch (lead >> 6) {
      case 0:
        values[0] = SignExtend(lead >> 4, 2);
        values[1] = SignExtend(lead >> 2, 2);
        values[2] = SignExtend(lead, 2);
        break;
      case 1: {
        values[0] = SignExtend(lead, 4);
        const uint8_t b = ReadByte();
        values[1] = SignExtend(b >> 4, 4);
        values[2] = SignExtend(b, 4);
        break;
      }
      case 2:
        values[0] = SignExtend(lead, 6);
        values[1] = SignExtend(ReadByte(), 6);
        values[2] = SignExtend(ReadByte(), 6);
        break;
      default:
        ReadTag2_3SBytes(lead, values);
        break;
    }
  }

  // Encoding 10: like TAG2_3S32 but with 2/2/2, 5/5/4, 8/7/7 bit packings.
  void ReadTag2_3SVariable(int32_t* values) {
    const uint8_t lead = ReadByte();
    switch (lead >> 6) {
      case 0:
        values[0] = SignExtend(lead >> 4, 2);
        values[1] = SignExtend(lead >> 2, 2);
        values[2] = SignExtend(lead, 2);
        break;
      case 1: {  // ss11 1112 2222 3333
        const uint8_t b = ReadByte();
        values[0] = SignExtend((lead & 0x3E) >> 1, 5);
        values[1] = SignExtend(((lead & 0x01) << 4) | (b >> 4), 5);
        values[2] = SignExtend(b, 4);
        break;
      }
      case 2: {  // ss11 1111 1122 2222 2333 3333
        const uint8_t b2 = ReadByte();
        const uint8_t b3 = ReadByte();
        values[0] = SignExtend(((lead & 0x3F) << 2) | (b2 >> 6), 8);
        values[1] = SignExtend(((b2 & 0x3F) << 1) | (b3 >> 7), 7);
        values[2] = SignExtend(b3, 7);
        break;
      }
      default:
        ReadTag2_3SBytes(lead, values);
        break;
    }
  }

  // Encoding 8, data version 2: a selector byte (2 bits per value: zero, 4, 8 or 16 bits), then the
  // values packed big-endian on nibble boundaries.
  void ReadTag8_4S16V2(int32_t* values) {
    uint8_t selector = ReadByte();
    bool half = false;  // a low nibble of `buffer` is still unread
    uint8_t buffer = 0;
    for (int i = 0; i < 4; ++i, selector >>= 2) {
      switch (selector & 0x03) {
        case 0:
          values[i] = 0;
          break;
        case 1:
          if (!half) {
            buffer = ReadByte();
            values[i] = SignExtend(buffer >> 4, 4);
          } else {
            values[i] = SignExtend(buffer, 4);
          }
          half = !half;
          break;
        case 2:
          if (!half) {
            values[i] = SignExtend(ReadByte(), 8);
          } else {
            const uint8_t high = static_cast<uint8_t>(buffer << 4);
            buffer = ReadByte();
            values[i] = SignExtend(high | (buffer >> 4), 8);
          }
          break;
        default:
          if (!half) {
            const uint8_t b1 = ReadByte();
            const uint8_t b2 = ReadByte();
            values[i] = SignExtend((static_cast<uint32_t>(b1) << 8) | b2, 16);
          } else {
            const uint8_t b1 = ReadByte();
            const uint8_t b2 = ReadByte();
            values[i] = SignExtend((static_cast<uint32_t>(buffer & 0x0F) << 12) |
                                       (static_cast<uint32_t>(b1) << 4) | (b2 >> 4),
                                   16);
            buffer = b2;
          }
          break;
      }
    }
  }

  // Encoding 8, data version 1: 4-bit values come in pairs sharing one byte (low nibble first),
  // 16-bit values are little-endian.
  void ReadTag8_4S16V1(int32_t* values) {
    uint8_t selector = ReadByte();
    for (int i = 0; i < 4; ++i, selector >>= 2) {
      switch (selector & 0x03) {
        case 0:
          values[i] = 0;
          break;
        case 1: {
          const uint8_t b = ReadByte();
          values[i] = SignExtend(b, 4);
          if (i + 1 < 4) {
            ++i;
            selector >>= 2;
            values[i] = SignExtend(b >> 4, 4);
          }
          break;
        }
        case 2:
          values[i] = SignExtend(ReadByte(), 8);
          break;
        default: {
          const uint8_t b1 = ReadByte();
          const uint8_t b2 = ReadByte();
          values[i] = SignExtend(b1 | (static_cast<uint32_t>(b2) << 8), 16);
          break;
        }
      }
    }
  }

  // Encoding 6 for a run of `count` (1..8) consecutive fields: a header byte flags the non-zero
  // values (first value in bit 0), each then written as signed VB. A run of one has no header.
  void ReadTag8_8Svb(int32_t* values, int count) {
    if (count == 1) {
      values[0] = ReadSignedVb();
      return;
    }
    uint8_t header = ReadByte();
    for (int i = 0; i < count; ++i, header >>= 1) values[i] = (header & 1) ? ReadSignedVb() : 0;
  }
};

}  // namespace shutterlab::blackbox
