#pragma once
// Photos for the metadata tests: a JPEG whose EXIF APP1 segment (a little-endian TIFF structure:
// IFD0 and the EXIF IFD) and optional XMP APP1 segment are written byte by byte here, not by the
// library under test, so that the reader is checked against the EXIF 2.32 and XMP layouts
// themselves; the image data after them (tables, frame header, a grey scan) is OpenCV's encoder's,
// so that the photo decodes as a real one does (io/image_check.h).

#include "io/codecs.h"
#include "io/photo_metadata.h"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace shutterlab::test {

struct FixturePhoto {
  int width = 64, height = 48;  // SOF0
  std::string make = "DJI", model = "FC8482";
  std::string date_time_original;  // "YYYY:MM:DD HH:MM:SS"; empty: not written
  std::string sub_sec_time_original, offset_time_original;
  std::optional<std::pair<uint32_t, uint32_t>> focal_length_mm;  // rational
  std::optional<uint16_t> focal_length_35mm;
  std::optional<std::pair<uint32_t, uint32_t>> exposure_s;  // rational
  uint32_t exif_width = 0, exif_height = 0;                 // 0: not written
  std::string maker_note;                                   // raw bytes; empty: not written
  std::string xmp;                                          // a whole XMP packet; empty: none
  cv::Mat pixels;  // the image (8-bit, its size over width and height); empty: a grey one
};

namespace photo_fixture_detail {

enum : uint16_t { kAscii = 2, kShort = 3, kLong = 4, kRational = 5, kUndefined = 7 };

struct Entry {
  uint16_t tag, type;
  uint32_t count;
  std::string bytes;  // the value, little-endian
};

inline void Put16(std::string* out, uint16_t v) {
  out->push_back(static_cast<char>(v & 0xff));
  out->push_back(static_cast<char>(v >> 8));
}
inline void Put32(std::string* out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out->push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}
inline Entry Ascii(uint16_t tag, const std::string& text) {
  return {tag, kAscii, static_cast<uint32_t>(text.size() + 1), text + std::string(1, '\0')};
}
inline Entry Short(uint16_t tag, uint16_t v) {
  std::string b;
  Put16(&b, v);
  return {tag, kShort, 1, b};
}
inline Entry Long(uint16_t tag, uint32_t v) {
  std::string b;
  Put32(&b, v);
  return {tag, kLong, 1, b};
}
inline Entry Rational(uint16_t tag, std::pair<uint32_t, uint32_t> v) {
  std::string b;
  Put32(&b, v.first);
  Put32(&b, v.second);
  return {tag, kRational, 1, b};
}

// One IFD at `offset` (from the TIFF header): entries sorted by tag, values over 4 bytes after the
// IFD, next-IFD offset 0.
inline std::string Ifd(std::vector<Entry> entries, uint32_t offset) {
  std::sort(entries.begin(), entries.end(),
            [](const Entry& a, const Entry& b) { return a.tag < b.tag; });
  std::string ifd, data;
  const uint32_t data_start = offset + 2 + 12 * static_cast<uint32_t>(entries.size()) + 4;
  Put16(&ifd, static_cast<uint16_t>(entries.size()));
  for (const Entry& e : entries) {
    Put16(&ifd, e.tag);
    Put16(&ifd, e.type);
    Put32(&ifd, e.count);
    if (e.bytes.size() <= 4) {
      ifd += e.bytes + std::string(4 - e.bytes.size(), '\0');
    } else {
      Put32(&ifd, data_start + static_cast<uint32_t>(data.size()));
      data += e.bytes;
      if (data.size() % 2) data.push_back('\0');  // word alignment
    }
  }
  Put32(&ifd, 0);
  return ifd + data;
}

inline std::string Segment(uint8_t marker, const std::string& payload) {
  std::string s = {'\xff', static_cast<char>(marker)};
  const size_t length = payload.size() + 2;
  s.push_back(static_cast<char>(length >> 8));
  s.push_back(static_cast<char>(length & 0xff));
  return s + payload;
}

}  // namespace photo_fixture_detail

// The JPEG bytes of a FixturePhoto.
inline std::string JpegWithMetadata(const FixturePhoto& p) {
  using namespace photo_fixture_detail;
  std::vector<Entry> exif;
  if (p.exposure_s) exif.push_back(Rational(0x829A, *p.exposure_s));
  if (!p.date_time_original.empty()) exif.push_back(Ascii(0x9003, p.date_time_original));
  if (!p.offset_time_original.empty()) exif.push_back(Ascii(0x9011, p.offset_time_original));
  if (p.focal_length_mm) exif.push_back(Rational(0x920A, *p.focal_length_mm));
  if (!p.maker_note.empty())
    exif.push_back({0x927C, kUndefined, static_cast<uint32_t>(p.maker_note.size()), p.maker_note});
  if (!p.sub_sec_time_original.empty()) exif.push_back(Ascii(0x9291, p.sub_sec_time_original));
  if (p.exif_width) exif.push_back(Long(0xA002, p.exif_width));
  if (p.exif_height) exif.push_back(Long(0xA003, p.exif_height));
  if (p.focal_length_35mm) exif.push_back(Short(0xA405, *p.focal_length_35mm));
  std::vector<Entry> ifd0 = {Ascii(0x010F, p.make), Ascii(0x0110, p.model), Long(0x8769, 0)};
  const uint32_t exif_offset = 8 + static_cast<uint32_t>(Ifd(ifd0, 8).size());
  ifd0.back() = Long(0x8769, exif_offset);
  std::string tiff = "II";
  Put16(&tiff, 42);
  Put32(&tiff, 8);
  tiff += Ifd(ifd0, 8) + Ifd(exif, exif_offset);

  std::string jpeg = "\xff\xd8";
  jpeg += Segment(0xE1, std::string("Exif\0\0", 6) + tiff);
  if (!p.xmp.empty())
    jpeg += Segment(0xE1, std::string("http://ns.adobe.com/xap/1.0/\0", 29) + p.xmp);
  // The encoder's own file from its first segment that is not APPn (JFIF): tables, SOF0 with the
  // size, the scan and EOI.
  const std::vector<uchar> encoded = EncodeImage(
      ".jpg",
      !p.pixels.empty() ? p.pixels : cv::Mat(p.height, p.width, CV_8UC3, cv::Scalar(90, 128, 160)));
  size_t at = 2;  // after SOI
  while (at + 4 <= encoded.size() && encoded[at] == 0xFF && encoded[at + 1] >= 0xE0 &&
         encoded[at + 1] <= 0xEF) {
    at += 2 + (static_cast<size_t>(encoded[at + 2]) << 8 | encoded[at + 3]);
  }
  jpeg.append(reinterpret_cast<const char*>(encoded.data()) + at, encoded.size() - at);
  return jpeg;
}

// An XMP packet with one rdf:Description holding `values` in the drone-dji namespace (bound to
// `prefix`), as attributes (DJI's own form) or as elements (what ExifTool writes back).
inline std::string DjiXmp(const std::map<std::string, std::string>& values, bool as_elements,
                          const std::string& prefix = "drone-dji") {
  std::string x =
      "<?xpacket begin=\"\xef\xbb\xbf\" id=\"W5M0MpCehiHzreSzNTczkc9d\"?>\n"
      "<x:xmpmeta xmlns:x=\"adobe:ns:meta/\">\n"
      " <rdf:RDF xmlns:rdf=\"http://www.w3.org/1999/02/22-rdf-syntax-ns#\">\n"
      "  <rdf:Description rdf:about=\"DJI Meta Data\"\n"
      "    xmlns:tiff=\"http://ns.adobe.com/tiff/1.0/\"\n"
      "    xmlns:" +
      prefix + "=\"http://www.dji.com/drone-dji/1.0/\"\n    tiff:Make=\"XMP-Make\"";
  if (as_elements) {
    x += ">\n";
    for (const auto& [k, v] : values)
      x += "   <" + prefix + ":" + k + ">" + v + "</" + prefix + ":" + k + ">\n";
    x += "  </rdf:Description>\n";
  } else {
    for (const auto& [k, v] : values) x += "\n    " + prefix + ":" + k + "=\"" + v + "\"";
    x += "/>\n";
  }
  x += " </rdf:RDF>\n</x:xmpmeta>\n<?xpacket end=\"w\"?>";
  return x;
}

// DJI's Phantom maker note: one little-endian IFD, entry 1 Make "DJI", then FLOAT entries with the
// given tags (3..11) and values.
inline std::string DjiMakerNote(const std::vector<std::pair<uint16_t, float>>& floats) {
  using namespace photo_fixture_detail;
  std::string note;
  Put16(&note, static_cast<uint16_t>(1 + floats.size()));
  Put16(&note, 1);
  Put16(&note, kAscii);
  Put32(&note, 4);
  note += std::string("DJI\0", 4);
  for (const auto& [tag, value] : floats) {
    Put16(&note, tag);
    Put16(&note, 11);
    Put32(&note, 1);
    uint32_t bits;
    std::memcpy(&bits, &value, sizeof bits);
    Put32(&note, bits);
  }
  Put32(&note, 0);
  return note;
}

// What the metadata reader gives for a SIYI ZR10 photo (2560x1440): a camera the readout table does
// not know, no focal length, no flight state.
inline PhotoMetadata SiyiZr10Metadata() {
  PhotoMetadata m;
  m.make = "SIYIKEJI";
  m.model = "ZR10";
  m.width = 2560;
  m.height = 1440;
  return m;
}

// What the metadata reader gives for a DJI Mini 3 photo (FC8482, 4032x2268, 24 mm equivalent):
// the camera the readout table knows, with the flight state DJI writes in its XMP.
inline PhotoMetadata DjiMini3Metadata(double relative_altitude_m,
                                      const Eigen::Vector3d& speed_m_s) {
  PhotoMetadata m;
  m.make = "DJI";
  m.model = "FC8482";
  m.width = 4032;
  m.height = 2268;
  m.focal_length_35mm = 24.0;
  m.relative_altitude_m = relative_altitude_m;
  m.speed_m_s = speed_m_s;
  m.flight_state_source = "XMP drone-dji";
  return m;
}

}  // namespace shutterlab::test
