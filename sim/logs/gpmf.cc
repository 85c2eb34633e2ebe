#include "sim/logs/gpmf.h"

#include "sim/check.h"

#include <cctype>
#include <cmath>
#include <cstring>

namespace shutterlab {
namespace {

constexpr int kMaxDepth = 8;  // DEVC > STRM > data is depth 3; a corrupted type byte stops here

[[noreturn]] void Fail(const std::string& path, uint64_t offset, const std::string& problem) {
  throw IoError(IoMessage(path, -1, "offset " + std::to_string(offset) + ": GPMF " + problem));
}

uint64_t BigEndian(const char* p, int bytes) {
  uint64_t value = 0;
  for (int i = 0; i < bytes; ++i) value = (value << 8) | static_cast<uint8_t>(p[i]);
  return value;
}

void ParseLevel(std::string_view buf, uint64_t file_offset, const std::string& path, int depth,
                std::vector<GpmfKlv>* out) {
  if (depth > kMaxDepth)
    Fail(path, file_offset, "nested deeper than " + std::to_string(kMaxDepth) + " levels");
  size_t at = 0;
  while (at < buf.size()) {
    const size_t left = buf.size() - at;
    if (left >= 4 && std::memcmp(buf.data() + at, "\0\0\0\0", 4) == 0) return;  // zero padding
    if (left < 8)
      Fail(path, file_offset + at, "KLV header truncated (" + std::to_string(left) + " bytes)");
    GpmfKlv klv;
    klv.key.assign(buf.data() + at, 4);
    for (char c : klv.key)
      if (!std::isprint(static_cast<unsigned char>(c)))
        Fail(path, file_offset + at, "key is not a FourCC (corrupted?)");
    klv.type = buf[at + 4];
    klv.struct_size = static_cast<uint8_t>(buf[at + 5]);
    klv.repeat = static_cast<uint16_t>(BigEndian(buf.data() + at + 6, 2));
    klv.file_offset = file_offset + at;
    const size_t bytes = static_cast<size_t>(klv.struct_size) * klv.repeat;
    if (bytes > left - 8)
      Fail(path, file_offset + at,
           "'" + klv.key + "' holds " + std::to_string(bytes) + " bytes, " +
               std::to_string(left - 8) + " left (truncated?)");
    klv.data = buf.substr(at + 8, bytes);
    if (klv.type == 0) ParseLevel(klv.data, file_offset + at + 8, path, depth + 1, &klv.children);
    out->push_back(std::move(klv));
    at += 8 + std::min((bytes + 3) / 4 * 4, left - 8);  // data is padded to 4 bytes
  }
}

int TypeSize(char type) {
  switch (type) {
    case 'b':
    case 'B':
    case 'c':
      return 1;
    case 's':
    case 'S':
      return 2;
    case 'l':
    case 'L':
    case 'f':
    case 'q':
    case 'F':
      return 4;
    case 'j':
    case 'J':
    case 'd':
    case 'Q':
      return 8;
    default:
      return 0;
  }
}

double Decode(char type, const char* p) {
  switch (type) {
    case 'b':
      return static_cast<int8_t>(p[0]);
    case 'B':
      return static_cast<uint8_t>(p[0]);
    case 's':
      return static_cast<int16_t>(BigEndian(p, 2));
    case 'S':
      return static_cast<uint16_t>(BigEndian(p, 2));
    case 'l':
      return static_cast<int32_t>(BigEndian(p, 4));
    case 'L':
      return static_cast<uint32_t>(BigEndian(p, 4));
    case 'j':
      return static_cast<double>(static_cast<int64_t>(BigEndian(p, 8)));
    case 'J':
      return static_cast<double>(BigEndian(p, 8));
    case 'q':
      return static_cast<int32_t>(BigEndian(p, 4)) / 65536.0;
    case 'Q':
      return static_cast<double>(static_cast<int64_t>(BigEndian(p, 8))) / 4294967296.0;
    case 'f': {
      const uint32_t bits = static_cast<uint32_t>(BigEndian(p, 4));
      float value;
      std::memcpy(&value, &bits, 4);
      return value;
    }
    case 'd': {
      const uint64_t bits = BigEndian(p, 8);
      double value;
      std::memcpy(&value, &bits, 8);
      return value;
    }
  }
  return 0.0;
}

bool Numeric(char type) { return TypeSize(type) > 0 && type != 'c' && type != 'F'; }

}  // namespace

std::vector<GpmfKlv> ParseGpmf(std::string_view payload, uint64_t file_offset,
                               const std::string& path) {
  std::vector<GpmfKlv> out;
  ParseLevel(payload, file_offset, path, 0, &out);
  return out;
}

size_t GpmfElements(const GpmfKlv& klv, const std::string& path) {
  const int size = TypeSize(klv.type);
  if (!Numeric(klv.type))
    Fail(path, klv.file_offset,
         "'" + klv.key + "' has type '" + std::string(1, klv.type) + "', not a number");
  if (klv.struct_size == 0 || klv.struct_size % size != 0)
    Fail(path, klv.file_offset,
         "'" + klv.key + "' structure size " + std::to_string(klv.struct_size) +
             " is not a whole number of '" + std::string(1, klv.type) + "' values");
  return klv.struct_size / size;
}

std::vector<double> GpmfValues(const GpmfKlv& klv, const std::string& path) {
  const size_t elements = GpmfElements(klv, path);
  const int size = TypeSize(klv.type);
  std::vector<double> values(elements * klv.repeat);
  for (size_t i = 0; i < values.size(); ++i)
    values[i] = Decode(klv.type, klv.data.data() + i * size);
  for (double v : values)
    if (!std::isfinite(v))
      Fail(path, klv.file_offset, "'" + klv.key + "' holds a non-finite value");
  return values;
}

std::string GpmfString(const GpmfKlv& klv) {
  std::string text(klv.data);
  while (!text.empty() && text.back() == '\0') text.pop_back();
  return text;
}

std::vector<GpmfStreamData> FindGpmfStreams(const std::vector<GpmfKlv>& payload,
                                            const std::string& key, const std::string& path) {
  std::vector<GpmfStreamData> found;
  for (const GpmfKlv& devc : payload) {
    if (devc.key != "DEVC" || devc.type != 0) continue;
    std::string device;
    for (const GpmfKlv& strm : devc.children) {
      if (strm.key == "DVNM" && strm.type == 'c') device = GpmfString(strm);
      if (strm.key != "STRM" || strm.type != 0) continue;
      GpmfStreamData stream;
      stream.device = device;
      for (const GpmfKlv& item : strm.children) {
        if (item.key == "STNM" && item.type == 'c')
          stream.name = GpmfString(item);
        else if ((item.key == "SIUN" || item.key == "UNIT") && item.type == 'c')
          stream.units = GpmfString(item);
        else if (item.key == "ORIN" && item.type == 'c')
          stream.orientation = GpmfString(item);
        else if (item.key == "ORIO" && item.type == 'c')
          stream.orientation_out = GpmfString(item);
        else if (item.key == "MTRX")
          stream.matrix = GpmfValues(item, path);
        else if (item.key == "SCAL")
          stream.scale = GpmfValues(item, path);
        else if (item.key == key) {
          stream.elements = GpmfElements(item, path);
          stream.values = GpmfValues(item, path);
          if (!stream.scale.empty()) {
            if (stream.scale.size() != 1 && stream.scale.size() != stream.elements)
              Fail(path, item.file_offset,
                   "'" + key + "' has " + std::to_string(stream.elements) + " elements but SCAL " +
                       std::to_string(stream.scale.size()) + " values");
            for (double s : stream.scale)
              if (s == 0) Fail(path, item.file_offset, "'" + key + "' SCAL is 0");
            for (size_t i = 0; i < stream.values.size(); ++i)
              stream.values[i] /=
                  stream.scale.size() == 1 ? stream.scale[0] : stream.scale[i % stream.elements];
          }
          found.push_back(stream);
        }
      }
    }
  }
  return found;
}

namespace {

// ORIO and MTRX (see AxisOrder): the output row of each axis, the matrix checked or taken.
void ReadOutputOrientation(const GpmfStreamData& stream, const std::string& path,
                           AxisOrder* order) {
  std::array<int, 3> row_of_axis{0, 1, 2};  // output row of axis a
  if (!stream.orientation_out.empty()) {
    const std::string& out = stream.orientation_out;
    std::array<bool, 3> seen{false, false, false};
    for (size_t y = 0; y < out.size() && y < 3; ++y) {
      const int axis = out[y] - 'X';
      if (axis < 0 || axis > 2 || seen[axis]) break;
      seen[axis] = true;
      row_of_axis[axis] = static_cast<int>(y);
    }
    if (out.size() != 3 || !(seen[0] && seen[1] && seen[2]))
      throw IoError(IoMessage(path, -1, "ORIO '" + out + "' is not a permutation of X, Y, Z"));
    order->source += ", ORIO '" + out + "'";
  }
  if (stream.matrix.empty()) return;
  if (stream.matrix.size() != 9)
    throw IoError(IoMessage(
        path, -1,
        "MTRX has " + std::to_string(stream.matrix.size()) + " values, not a 3x3 matrix"));
  Eigen::Matrix3d m;  // rows: output channels (ORIO's order); columns: stored channels
  bool signed_permutation = true;
  for (int i = 0; i < 9; ++i) {
    const double v = stream.matrix[i];
    m(i / 3, i % 3) = v;
    signed_permutation = signed_permutation && (v == 0 || v == 1 || v == -1);
  }
  Eigen::Matrix3d xyz_from_stored;
  for (int a = 0; a < 3; ++a) xyz_from_stored.row(a) = m.row(row_of_axis[a]);
  if (!signed_permutation) {
    order->calibration = xyz_from_stored;
    order->source += ", MTRX (a calibration, applied)";
    return;
  }
  Eigen::Matrix3d expected = Eigen::Matrix3d::Zero();
  for (int a = 0; a < 3; ++a) expected(a, order->column[a]) = order->sign[a];
  // As gpmf-parser: a matrix of 0 and +-1 is the channels' orientation, which ORIN and ORIO give.
  order->source += xyz_from_stored == expected ? ", MTRX agrees" : ", MTRX disagrees (not used)";
}

}  // namespace

AxisOrder GpmfAxisOrder(const GpmfStreamData& stream, const std::string& path) {
  AxisOrder order;
  std::string letters;  // three of x/y/z, upper or lower case
  std::array<int, 3> sign{1, 1, 1};
  if (!stream.orientation.empty()) {
    letters = stream.orientation;
    order.source = "ORIN '" + stream.orientation + "'";
    for (int j = 0; j < 3 && j < static_cast<int>(letters.size()); ++j)
      sign[j] = std::islower(static_cast<unsigned char>(letters[j])) ? -1 : 1;
  } else {
    const size_t open = stream.name.find('(');
    const size_t close = stream.name.find(')', open == std::string::npos ? 0 : open);
    if (open != std::string::npos && close != std::string::npos) {
      int j = 0;
      for (size_t i = open + 1; i < close; ++i) {
        const char c = stream.name[i];
        if (c == '-' && j < 3)
          sign[j] = -1;
        else if (std::isalpha(static_cast<unsigned char>(c))) {
          letters += c;
          ++j;
        }
      }
      order.source = "STNM '" + stream.name + "'";
    }
  }
  if (letters.empty()) {
    order.source = "default x,y,z";
    ReadOutputOrientation(stream, path, &order);
    return order;
  }
  std::array<bool, 3> seen{false, false, false};
  if (letters.size() != 3)
    throw IoError(IoMessage(path, -1, "axis order " + order.source + " does not name 3 axes"));
  for (int j = 0; j < 3; ++j) {
    const int axis = std::tolower(static_cast<unsigned char>(letters[j])) - 'x';
    if (axis < 0 || axis > 2 || seen[axis])
      throw IoError(
          IoMessage(path, -1, "axis order " + order.source + " is not a permutation of x, y, z"));
    seen[axis] = true;
    order.column[axis] = j;
    order.sign[axis] = sign[j];
  }
  ReadOutputOrientation(stream, path, &order);
  return order;
}

GpmfTrackStream ReadGpmfTrackStream(Mp4File& mp4, const Mp4Track& track, const std::string& key) {
  const std::string& path = mp4.path();
  GpmfTrackStream out;
  out.key = key;
  std::vector<double> starts_s, before;  // payload start time, samples before it
  bool have = false;
  for (size_t k = 0; k < track.size(); ++k) {
    const std::string payload = mp4.ReadSample(track, k);
    const std::vector<GpmfKlv> klvs = ParseGpmf(payload, track.offsets[k], path);
    starts_s.push_back(track.DecodeTimeS(k));
    before.push_back(static_cast<double>(out.samples()));
    size_t count = 0;
    for (const GpmfStreamData& stream : FindGpmfStreams(klvs, key, path)) {
      if (!have) {
        out.first = stream;
        out.elements = stream.elements;
        have = true;
      } else if (stream.elements != out.elements) {
        Fail(path, track.offsets[k],
             "'" + key + "' has " + std::to_string(stream.elements) + " elements in payload " +
                 std::to_string(k) + ", " + std::to_string(out.elements) + " before");
      }
      out.values.insert(out.values.end(), stream.values.begin(), stream.values.end());
      count += stream.samples();
    }
    out.payload_samples.push_back(count);
  }
  if (!have || out.samples() == 0)
    throw IoError(IoMessage(path, -1, "the gpmd track holds no '" + key + "' samples"));
  if (track.size() == 1) {  // one payload: its end is the only other time known
    starts_s.push_back(track.DecodeTimeS(0) +
                       static_cast<double>(track.durations[0]) / track.timescale);
    before.push_back(static_cast<double>(out.samples()));
  }
  // Least-squares line t = a + b * n through (samples before, payload start).
  const size_t m = starts_s.size();
  double mean_n = 0, mean_t = 0;
  for (size_t k = 0; k < m; ++k) {
    mean_n += before[k] / m;
    mean_t += starts_s[k] / m;
  }
  double snn = 0, snt = 0;
  for (size_t k = 0; k < m; ++k) {
    snn += (before[k] - mean_n) * (before[k] - mean_n);
    snt += (before[k] - mean_n) * (starts_s[k] - mean_t);
  }
  if (!(snn > 0) || !(snt > 0))
    throw IoError(IoMessage(
        path, -1, "cannot time '" + key + "': its payloads do not advance in samples and time"));
  const double b = snt / snn;
  out.rate_hz = 1.0 / b;
  out.t0_s = mean_t - b * mean_n;
  for (size_t k = 0; k < m; ++k)
    out.fit_max_residual_s =
        std::max(out.fit_max_residual_s, std::abs(starts_s[k] - out.t0_s - b * before[k]));
  return out;
}

}  // namespace shutterlab
