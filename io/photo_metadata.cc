#include "io/photo_metadata.h"

#include "io/exiv2_setup.h"
#include "sim/check.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <Eigen/Geometry>

// exiv2 0.27's headers use std::auto_ptr, deprecated in C++11 and still in libstdc++'s C++17.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-declarations"
#include <exiv2/exiv2.hpp>
#pragma GCC diagnostic pop

#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

namespace shutterlab {
namespace {

constexpr char kDjiXmpNamespace[] = "http://www.dji.com/drone-dji/1.0/";

std::string TrimText(std::string s) {
  while (!s.empty() && (s.back() == ' ' || s.back() == '\0')) s.pop_back();
  size_t start = 0;
  while (start < s.size() && s[start] == ' ') ++start;
  return s.substr(start);
}

const Exiv2::Exifdatum* FindExif(const Exiv2::ExifData& exif, const char* key) {
  const auto it = exif.findKey(Exiv2::ExifKey(key));
  return it == exif.end() ? nullptr : &*it;
}

std::string ExifText(const Exiv2::ExifData& exif, const char* key) {
  const Exiv2::Exifdatum* d = FindExif(exif, key);
  return d ? TrimText(d->toString()) : std::string();
}

// The n-th component of a numeric tag as a double (rationals exactly); nullopt when absent, not a
// number, or a rational with a zero denominator.
std::optional<double> ExifNumber(const Exiv2::Exifdatum* d, long n = 0) {
  if (!d || d->count() <= n) return std::nullopt;
  const Exiv2::TypeId type = d->typeId();
  if (type == Exiv2::unsignedRational || type == Exiv2::signedRational) {
    const Exiv2::Rational r = d->toRational(n);
    if (r.second == 0) return std::nullopt;
    return static_cast<double>(r.first) / r.second;
  }
  if (type == Exiv2::asciiString || type == Exiv2::undefined) return ParseDouble(d->toString());
  const double v = static_cast<double>(d->toFloat(n));
  return std::isfinite(v) ? std::optional<double>(v) : std::nullopt;
}

std::optional<double> ExifNumber(const Exiv2::ExifData& exif, const char* key) {
  return ExifNumber(FindExif(exif, key));
}

// EXIF GPS degrees, minutes, seconds and a reference letter (S and W negative).
std::optional<double> GpsDegrees(const Exiv2::ExifData& exif, const char* key,
                                 const char* ref_key) {
  const Exiv2::Exifdatum* d = FindExif(exif, key);
  const auto deg = ExifNumber(d, 0), min = ExifNumber(d, 1), sec = ExifNumber(d, 2);
  if (!deg || !min || !sec) return std::nullopt;
  const double value = *deg + *min / 60.0 + *sec / 3600.0;
  const std::string ref = ExifText(exif, ref_key);
  return (ref == "S" || ref == "W") ? -value : value;
}

// The capture time: DateTimeOriginal with its sub-second and offset tags, else DateTime with its.
void ReadCaptureTime(const Exiv2::ExifData& exif, PhotoMetadata* out) {
  struct Tags {
    const char *date, *sub, *offset;
  };
  for (const Tags& tags :
       {Tags{"Exif.Photo.DateTimeOriginal", "Exif.Photo.SubSecTimeOriginal",
             "Exif.Photo.OffsetTimeOriginal"},
        Tags{"Exif.Image.DateTime", "Exif.Photo.SubSecTime", "Exif.Photo.OffsetTime"}}) {
    const std::string date = ExifText(exif, tags.date);
    if (date.empty()) continue;
    out->capture_time_text = date;
    out->capture_time = ParseExifDateTime(date, ExifText(exif, tags.sub),
                                          ExifText(exif, tags.offset), &out->capture_time_problem);
    return;
  }
}

void ReadExif(const Exiv2::ExifData& exif, PhotoMetadata* out) {
  out->make = ExifText(exif, "Exif.Image.Make");
  out->model = ExifText(exif, "Exif.Image.Model");
  out->exif_width = static_cast<int>(ExifNumber(exif, "Exif.Photo.PixelXDimension").value_or(0));
  out->exif_height = static_cast<int>(ExifNumber(exif, "Exif.Photo.PixelYDimension").value_or(0));
  out->focal_length_mm = ExifNumber(exif, "Exif.Photo.FocalLength");
  if (out->focal_length_mm && *out->focal_length_mm <= 0) out->focal_length_mm.reset();
  out->focal_length_35mm = ExifNumber(exif, "Exif.Photo.FocalLengthIn35mmFilm");
  if (out->focal_length_35mm && *out->focal_length_35mm <= 0) out->focal_length_35mm.reset();
  const auto plane_res = ExifNumber(exif, "Exif.Photo.FocalPlaneXResolution");
  const int unit =
      static_cast<int>(ExifNumber(exif, "Exif.Photo.FocalPlaneResolutionUnit").value_or(2));
  const double mm_per_unit = unit == 3 ? 10.0 : unit == 4 ? 1.0 : unit == 5 ? 1e-3 : 25.4;
  if (plane_res && *plane_res > 0 && unit >= 2)
    out->focal_plane_px_per_mm = *plane_res / mm_per_unit;
  out->exposure_s = ExifNumber(exif, "Exif.Photo.ExposureTime");
  if (out->exposure_s && *out->exposure_s <= 0) out->exposure_s.reset();
  ReadCaptureTime(exif, out);
  const auto lat = GpsDegrees(exif, "Exif.GPSInfo.GPSLatitude", "Exif.GPSInfo.GPSLatitudeRef");
  const auto lon = GpsDegrees(exif, "Exif.GPSInfo.GPSLongitude", "Exif.GPSInfo.GPSLongitudeRef");
  // 0,0 (or a few arcseconds from it, as the SIYI ZR10 writes) means "no fix".
  if (lat && lon && (std::abs(*lat) > 1e-2 || std::abs(*lon) > 1e-2)) {
    out->latitude_deg = lat;
    out->longitude_deg = lon;
    const auto altitude = ExifNumber(exif, "Exif.GPSInfo.GPSAltitude");
    const auto below = ExifNumber(exif, "Exif.GPSInfo.GPSAltitudeRef");
    if (altitude) out->gps_altitude_m = below && *below == 1 ? -*altitude : *altitude;
  }
}

// DJI's maker note (Phantom 3/4, Inspire 1): one IFD in the EXIF byte order whose entries are all
// FLOAT (type 11) or a 4-byte string held inline. Tags after ExifTool's DJI table: 3..5 SpeedX/Y/Z
// (m/s), 6..8 Pitch/Yaw/Roll, 9..11 CameraPitch/Yaw/Roll (degrees). Returns false when the bytes
// are not such an IFD.
bool DecodeDjiMakerNote(const std::vector<uint8_t>& note, PhotoMetadata* out) {
  if (note.size() < 2) return false;
  for (const bool little : {true, false}) {
    auto u16 = [&](size_t at) {
      return little ? static_cast<unsigned>(note[at] | note[at + 1] << 8)
                    : static_cast<unsigned>(note[at] << 8 | note[at + 1]);
    };
    auto u32 = [&](size_t at) {
      return little ? static_cast<uint32_t>(note[at] | note[at + 1] << 8 | note[at + 2] << 16 |
                                            static_cast<uint32_t>(note[at + 3]) << 24)
                    : static_cast<uint32_t>(static_cast<uint32_t>(note[at]) << 24 |
                                            note[at + 1] << 16 | note[at + 2] << 8 | note[at + 3]);
    };
    const unsigned count = u16(0);
    if (count == 0 || count > 64 || 2 + 12 * static_cast<size_t>(count) > note.size()) continue;
    if (u16(2) != 1) continue;  // the first entry is Make
    double value[12];
    bool have[12] = {};
    for (unsigned i = 0; i < count; ++i) {
      const size_t at = 2 + 12 * static_cast<size_t>(i);
      const unsigned tag = u16(at), type = u16(at + 2);
      if (tag < 3 || tag > 11 || type != 11 || u32(at + 4) != 1) continue;
      const uint32_t bits = u32(at + 8);
      float f;
      std::memcpy(&f, &bits, sizeof f);
      if (!std::isfinite(f)) continue;
      value[tag] = f;
      have[tag] = true;
    }
    if (have[3] && have[4] && have[5])
      out->speed_m_s = Eigen::Vector3d(value[3], value[4], value[5]);
    if (have[6] && have[7] && have[8]) out->flight = AttitudeDeg{value[8], value[6], value[7]};
    if (have[9] && have[10] && have[11]) out->gimbal = AttitudeDeg{value[11], value[9], value[10]};
    return out->speed_m_s || out->flight || out->gimbal;
  }
  return false;
}

void ReadDjiMakerNote(const Exiv2::ExifData& exif, PhotoMetadata* out) {
  const Exiv2::Exifdatum* d = FindExif(exif, "Exif.Photo.MakerNote");
  if (!d || ToLower(out->make) != "dji" || d->size() < 2) return;
  std::vector<uint8_t> note(d->size());
  d->copy(note.data(), Exiv2::littleEndian);  // undefined bytes: the order is not applied
  if (DecodeDjiMakerNote(note, out)) out->flight_state_source = "DJI maker note";
}

// drone-dji values, by tag name, whatever prefix the file bound the namespace to.
void ReadDjiXmp(const Exiv2::XmpData& xmp, PhotoMetadata* out) {
  std::optional<double> v[14];
  static const char* kNames[14] = {"RelativeAltitude",  "AbsoluteAltitude", "GimbalRollDegree",
                                   "GimbalPitchDegree", "GimbalYawDegree",  "FlightRollDegree",
                                   "FlightPitchDegree", "FlightYawDegree",  "FlightXSpeed",
                                   "FlightYSpeed",      "FlightZSpeed",     "CalibratedFocalLength",
                                   "GpsLatitude",       "GpsLongitude"};
  bool any = false;
  for (const Exiv2::Xmpdatum& d : xmp) {
    std::string ns;
    try {
      ns = Exiv2::XmpProperties::ns(d.groupName());
    } catch (const std::exception&) {
      continue;
    }
    if (ns != kDjiXmpNamespace) continue;
    const std::string name = d.tagName();
    for (int i = 0; i < 14; ++i) {
      if (name == kNames[i]) {
        v[i] = ParseDouble(TrimText(d.toString()));
        any = any || v[i].has_value();
      }
    }
  }
  if (!any) return;
  auto both = [](const std::optional<double>& a, const std::optional<double>& b,
                 const std::optional<double>& c) { return a && b && c; };
  if (v[0]) out->relative_altitude_m = v[0];
  if (v[1]) out->absolute_altitude_m = v[1];
  if (both(v[2], v[3], v[4])) out->gimbal = AttitudeDeg{*v[2], *v[3], *v[4]};
  if (both(v[5], v[6], v[7])) out->flight = AttitudeDeg{*v[5], *v[6], *v[7]};
  if (both(v[8], v[9], v[10])) out->speed_m_s = Eigen::Vector3d(*v[8], *v[9], *v[10]);
  if (v[11] && *v[11] > 0) out->calibrated_focal_px = v[11];
  if (!out->latitude_deg && v[12] && v[13]) {
    out->latitude_deg = v[12];
    out->longitude_deg = v[13];
  }
  out->flight_state_source = "XMP drone-dji";
}

}  // namespace

Eigen::Matrix3d NedFromGimbal(const AttitudeDeg& attitude) {
  return (Eigen::AngleAxisd(attitude.yaw_deg * kRadPerDeg, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(attitude.pitch_deg * kRadPerDeg, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(attitude.roll_deg * kRadPerDeg, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

PhotoMetadata ReadPhotoMetadata(const std::string& path) {
  internal::InitialiseExiv2();
  PhotoMetadata out;
  try {
    auto image = Exiv2::ImageFactory::open(path);
    SHUTTERLAB_CHECK(image.get() != nullptr) << "exiv2 returned no image";
    image->readMetadata();
    out.width = image->pixelWidth();
    out.height = image->pixelHeight();
    ReadExif(image->exifData(), &out);
    ReadDjiMakerNote(image->exifData(), &out);
    // XMP last: where both are written, drone-dji is the newer and fuller record.
    ReadDjiXmp(image->xmpData(), &out);
  } catch (const IoError&) {
    throw;
  } catch (const std::exception& e) {
    std::string message = e.what();
    for (char& c : message) {
      if (c == '\n') c = ' ';
    }
    throw IoError(IoMessage(path, 0, "cannot read the photo's metadata: " + message));
  }
  return out;
}

}  // namespace shutterlab
