#pragma once
// GoPro Metadata Format (GPMF, github.com/gopro/gpmf-parser): the key-length-value telemetry that
// GoPro cameras store as the samples of an MP4 'gpmd' track, one payload per ~1 s.
//
// A KLV is an 8-byte header (FourCC key; type char; structure size in bytes; repeat count,
// big-endian uint16) followed by size * repeat bytes of big-endian data padded to a multiple of 4.
// Type 0 nests KLVs (DEVC device > STRM stream > properties and data). Properties before a stream's
// data apply to it: STNM name, SIUN/UNIT units, SCAL divisor (one value, or one per element),
// ORIN axis order. Every length is checked: a truncated or corrupted payload throws
// IoError("PATH: offset N: problem") naming the file offset.

#include "sim/logs/mp4.h"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace shutterlab {

struct GpmfKlv {
  std::string key;  // FourCC, e.g. "DEVC", "GYRO"
  char type = 0;    // 'b','B','s','S','l','L','j','J','f','d','q','Q','c','F','?', ...; 0 nested
  uint8_t struct_size = 0;        // bytes per sample
  uint16_t repeat = 0;            // samples
  uint64_t file_offset = 0;       // of the KLV header, for messages
  std::string_view data;          // struct_size * repeat bytes (no padding)
  std::vector<GpmfKlv> children;  // type 0 only
};

// Parses a payload into its KLV tree; the KLVs' data are views into payload, which must outlive
// them. file_offset is the file offset of payload[0]. Four zero
// bytes where a key should be end a level (payloads may be zero-padded). Throws IoError.
std::vector<GpmfKlv> ParseGpmf(std::string_view payload, uint64_t file_offset,
                               const std::string& path);

// Values of a numeric KLV as doubles, row-major (repeat rows of struct_size / type size
// elements): b B s S l L j J f d, and the fixed-point q (Q15.16) and Q (Q31.32). Throws IoError for
// other types or a structure size that is not a whole number of elements.
std::vector<double> GpmfValues(const GpmfKlv& klv, const std::string& path);
// Elements per sample of a numeric KLV (struct_size / type size).
size_t GpmfElements(const GpmfKlv& klv, const std::string& path);
// A 'c' KLV as text, trailing NULs removed.
std::string GpmfString(const GpmfKlv& klv);

// One stream's data in one payload, with its sticky properties, already divided by SCAL.
struct GpmfStreamData {
  std::string device;           // DVNM of the enclosing DEVC
  std::string name;             // STNM
  std::string units;            // SIUN (or UNIT)
  std::string orientation;      // ORIN ("" when absent)
  std::vector<double> scale;    // SCAL as found (empty: 1)
  size_t elements = 0;          // values per sample
  std::vector<double> values;   // samples * elements
  std::string orientation_out;  // ORIO ("" when absent): the output channels' axis letters
  std::vector<double> matrix;   // MTRX, row-major (empty when absent)
  size_t samples() const { return elements ? values.size() / elements : 0; }
};

// Every stream (DEVC > STRM) of a parsed payload whose data key is `key`, in order.
std::vector<GpmfStreamData> FindGpmfStreams(const std::vector<GpmfKlv>& payload,
                                            const std::string& key, const std::string& path);

// Which stored column holds the camera's x, y and z (GoPro's own axis labels), and with which sign.
// From ORIN when present ("XzY": the stored channels are the camera's X, -Z and Y; lowercase =
// negated, GPMF_common.h), else from a "(z,x,y)" list in the stream name (HERO5: "Gyroscope
// (z,x,y)"), else x,y,z. ORIO (the output order, "ZXY") and MTRX (the stored-to-output matrix,
// rows in ORIO's order) are read as gpmf-parser's GPMF_ScaledData reads them: a matrix of 0 and
// +-1 only is the same mapping as ORIN and ORIO and is checked against them; any other MTRX is a
// calibration and is applied as it is (`calibration`). Throws IoError when ORIN or ORIO names no
// permutation or MTRX is not 3x3.
struct AxisOrder {
  std::array<int, 3> column{0, 1, 2};  // column[a]: stored column of axis a (0 = x)
  std::array<int, 3> sign{1, 1, 1};
  // A calibration MTRX: axis a = sum over columns j of calibration(a, j) * stored j; nullopt when
  // the mapping is the signed permutation above.
  std::optional<Eigen::Matrix3d> calibration;
  // "ORIN 'XzY', ORIO 'ZXY', MTRX agrees", "STNM 'Gyroscope (z,x,y)'" or "default x,y,z"
  std::string source;
};
AxisOrder GpmfAxisOrder(const GpmfStreamData& stream, const std::string& path);

// One stream read from every payload of a gpmd track and timed by one straight line: sample i is at
// t0_s + i / rate_hz on the movie timeline. The line is the least-squares fit of each payload's
// start time (the track's sample table) against the number of samples before it; payloads hold
// uneven counts (the HERO5's 392 or 399, a short last one), so spreading each payload's samples
// evenly over its own duration would bend the time axis by several milliseconds.
struct GpmfTrackStream {
  std::string key;
  GpmfStreamData first;  // properties (and the first payload's data) of the stream
  size_t elements = 0;
  std::vector<double> values;           // every payload's values, concatenated
  std::vector<size_t> payload_samples;  // per payload (0 where a payload lacks the stream)
  double t0_s = 0.0;
  double rate_hz = 0.0;
  double fit_max_residual_s = 0.0;  // largest |payload start - line| over the fitted payloads
  size_t samples() const { return elements ? values.size() / elements : 0; }
  double TimeS(size_t i) const { return t0_s + static_cast<double>(i) / rate_hz; }
};

// Reads stream `key` ("GYRO", "SHUT", ...) from every payload of `track`. Throws IoError when a
// payload is unreadable, the stream is absent from every payload, or its element count changes.
GpmfTrackStream ReadGpmfTrackStream(Mp4File& mp4, const Mp4Track& track, const std::string& key);

}  // namespace shutterlab
