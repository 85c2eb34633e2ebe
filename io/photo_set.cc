#include "io/photo_set.h"

#include "io/image_check.h"
#include "model/readout_table.h"
#include "sim/check.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <Eigen/Core>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>

namespace shutterlab {
namespace {

namespace fs = std::filesystem;

std::optional<int64_t> TrailingNumber(const std::string& name) {
  const std::string stem = fs::path(name).stem().string();
  size_t end = stem.size();
  while (end > 0 && !std::isdigit(static_cast<unsigned char>(stem[end - 1]))) --end;
  size_t start = end;
  while (start > 0 && std::isdigit(static_cast<unsigned char>(stem[start - 1]))) --start;
  if (start == end || end - start > 15) return std::nullopt;
  return ParseInt(std::string_view(stem).substr(start, end - start));
}

// The camera's own image width when the file was downscaled: pixel values written for the camera's
// image (calibrated focal, focal-plane resolution) are scaled by width / exif_width.
double FileScale(const PhotoMetadata& m) {
  return (m.exif_width > 0 && m.width > 0) ? static_cast<double>(std::max(m.width, m.height)) /
                                                 std::max(m.exif_width, m.exif_height)
                                           : 1.0;
}

// The lens profile scaled to the photo, when one is given and the photo has a size.
std::optional<LensProfileUse> ProfileFor(const PhotoSetOptions& options, const PhotoMetadata& m) {
  if (!options.lens_profile || m.width <= 0 || m.height <= 0) return std::nullopt;
  return ScaleLensProfile(*options.lens_profile, m.width, m.height);
}

void ChooseFocal(const PhotoSetOptions& options, PhotoRecord* r) {
  const PhotoMetadata& m = r->metadata;
  if (options.focal_px) {
    r->focal_px = options.focal_px;
    r->focal_source = options.focal_text.empty() ? "--focal-px" : options.focal_text;
    if (options.camera && options.camera->width == m.width && options.camera->height == m.height)
      r->camera = options.camera;
  } else if (const auto use = ProfileFor(options, m)) {
    r->focal_px = 0.5 * (use->camera.fx + use->camera.fy);
    r->focal_source = "lens profile " + use->name;
    r->camera = use->camera;
  } else if (m.calibrated_focal_px) {
    r->focal_px = *m.calibrated_focal_px * FileScale(m);
    r->focal_source = "XMP drone-dji:CalibratedFocalLength";
  } else if (m.focal_length_35mm && m.width > 0 && m.height > 0) {
    r->focal_px = FocalPxFrom35mm(*m.focal_length_35mm, m.width, m.height);
    r->focal_source =
        FormatNumber("EXIF FocalLengthIn35mmFilm %g mm on the diagonal", *m.focal_length_35mm);
  } else if (m.focal_length_mm && m.focal_plane_px_per_mm) {
    r->focal_px = *m.focal_length_mm * *m.focal_plane_px_per_mm * FileScale(m);
    r->focal_source = "EXIF FocalLength x FocalPlaneXResolution";
  }
}

void ChooseReadout(const PhotoSetOptions& options, PhotoRecord* r) {
  if (options.readout_s) {
    r->readout_s = options.readout_s;
    r->readout_origin = options.readout_origin;
    r->readout_source = options.readout_text.empty() ? "--readout" : options.readout_text;
    return;
  }
  const PhotoMetadata& m = r->metadata;
  if (const auto use = ProfileFor(options, m); use && use->readout && use->readout->readout_s) {
    r->readout_s = use->readout->readout_s;
    r->readout_origin = ReadoutOrigin::kLensProfile;
    r->readout_source = "lens profile " + use->name;
  } else if (const auto hit = LookUpReadout(m.make, m.model, r->CaptureMegapixels())) {
    r->readout_s = hit->readout_s;
    r->readout_origin = ReadoutOrigin::kTable;
    r->readout_source = hit->Citation();
  } else {
    r->readout_origin = ReadoutOrigin::kNone;
    r->readout_source = "'" + ReadoutTableKey(m.make, m.model) + "' is not in the readout table";
  }
}

void ChooseFlightState(const PhotoSetOptions& options, PhotoRecord* r) {
  const PhotoMetadata& m = r->metadata;
  if (options.altitude_m) {
    r->altitude_m = options.altitude_m;
    r->altitude_source = "--altitude";
  } else if (m.relative_altitude_m && *m.relative_altitude_m > 0) {
    r->altitude_m = m.relative_altitude_m;
    r->altitude_source = "XMP drone-dji:RelativeAltitude (above take-off)";
  } else if (options.ground_elevation_m && (m.absolute_altitude_m || m.gps_altitude_m)) {
    const bool xmp = m.absolute_altitude_m.has_value();
    const double absolute = xmp ? *m.absolute_altitude_m : *m.gps_altitude_m;
    const double above = absolute - *options.ground_elevation_m;
    const std::string how =
        FormatNumber("derived: %.1f m, ", above) +
        (xmp ? "XMP drone-dji:AbsoluteAltitude" : "EXIF GPSAltitude") +
        FormatNumber(" %.1f m", absolute) +
        FormatNumber(" minus --ground-elevation %.1f m", *options.ground_elevation_m);
    if (above > 0) {
      r->altitude_m = above;
      r->altitude_source = how;
    } else {
      r->altitude_source = how + ": not above the ground (check --ground-elevation's datum)";
    }
  }
  if (m.speed_m_s) {
    r->ground_speed_m_s = std::hypot(m.speed_m_s->x(), m.speed_m_s->y());
    if (*r->ground_speed_m_s > 0) r->course_deg = CourseDeg(m.speed_m_s->x(), m.speed_m_s->y());
    r->speed_source = m.flight_state_source == "DJI maker note"
                          ? "DJI maker note SpeedX/SpeedY"
                          : "XMP drone-dji:FlightXSpeed/FlightYSpeed";
  }
  if (options.speed_m_s) {
    r->ground_speed_m_s = options.speed_m_s;
    if (*options.speed_m_s == 0) r->course_deg.reset();
    r->speed_source = "--speed";
  }
}

}  // namespace

double FocalPxFrom35mm(double focal_35mm, int width, int height) {
  SHUTTERLAB_CHECK(focal_35mm > 0 && width > 0 && height > 0)
      << "35 mm-equivalent focal length and image size must be positive";
  return focal_35mm / kFullFrameDiagonalMm * std::hypot(width, height);
}

const char* ReadoutOriginName(ReadoutOrigin origin) {
  switch (origin) {
    case ReadoutOrigin::kUser:
      return "user";
    case ReadoutOrigin::kCameraFile:
      return "camera.json";
    case ReadoutOrigin::kLensProfile:
      return "lens profile";
    case ReadoutOrigin::kPhoto:
      return "photo";
    case ReadoutOrigin::kTable:
      return "table";
    case ReadoutOrigin::kNone:
      return "none";
  }
  return "none";
}

void PhotoSetOptions::Check() const {
  SHUTTERLAB_CHECK(!readout_s || (std::isfinite(*readout_s) && *readout_s >= 0))
      << "readout must be finite and not negative";
  SHUTTERLAB_CHECK(!focal_px || (std::isfinite(*focal_px) && *focal_px > 0))
      << "focal length must be positive";
  SHUTTERLAB_CHECK(!altitude_m || (std::isfinite(*altitude_m) && *altitude_m > 0))
      << "altitude must be positive";
  SHUTTERLAB_CHECK(!ground_elevation_m || std::isfinite(*ground_elevation_m))
      << "--ground-elevation must be a finite height";
  SHUTTERLAB_CHECK(!speed_m_s || (std::isfinite(*speed_m_s) && *speed_m_s >= 0 && *speed_m_s < 200))
      << "--speed must be 0 to 200 m/s";
  SHUTTERLAB_CHECK(readout_origin == ReadoutOrigin::kUser ||
                   readout_origin == ReadoutOrigin::kCameraFile ||
                   readout_origin == ReadoutOrigin::kLensProfile)
      << "a given readout comes from the user, a camera file or a lens profile";
}

double PhotoRecord::CaptureMegapixels() const {
  const PhotoMetadata& m = metadata;
  const bool exif = m.exif_width > 0 && m.exif_height > 0;
  return exif ? m.exif_width * 1e-6 * m.exif_height : m.width * 1e-6 * m.height;
}

bool IsPhotoFileName(const std::string& name) {
  const std::string ext = ToLower(fs::path(name).extension().string());
  return ext == ".jpg" || ext == ".jpeg" || ext == ".tif" || ext == ".tiff" || ext == ".dng";
}

PhotoRecord MakePhotoRecord(const std::string& path, const PhotoMetadata& metadata,
                            const PhotoSetOptions& options) {
  PhotoRecord r;
  r.path = path;
  r.name = fs::path(path).filename().string();
  r.number = TrailingNumber(r.name);
  r.metadata = metadata;
  ChooseFocal(options, &r);
  ChooseReadout(options, &r);
  ChooseFlightState(options, &r);
  if (metadata.width <= 0 || metadata.height <= 0) r.missing.push_back("image size");
  if (!r.focal_px) r.missing.push_back("focal length");
  if (!r.readout_s) r.missing.push_back("readout");
  if (!r.altitude_m) r.missing.push_back("altitude");
  if (!r.ground_speed_m_s) r.missing.push_back("flight speed");
  if (!metadata.capture_time) r.missing.push_back("capture time");
  return r;
}

namespace {

// A photo's place on the ground and its capture time on its camera clock.
struct GroundFix {
  size_t photo = 0;  // index into the set
  double t_s = 0, resolution_s = 0;
  Eigen::Vector2d north_east_m = Eigen::Vector2d::Zero();  // from the first photo with a position
};

std::vector<GroundFix> GroundFixesByTime(const PhotoSet& set) {
  std::vector<GroundFix> fixes;
  std::optional<double> lat0_deg, lon0_deg;
  for (size_t i = 0; i < set.photos.size(); ++i) {
    const PhotoMetadata& m = set.photos[i].metadata;
    if (!set.photos[i].ok() || !m.latitude_deg || !m.longitude_deg || !m.capture_time) continue;
    if (!lat0_deg) {
      lat0_deg = m.latitude_deg;
      lon0_deg = m.longitude_deg;
    }
    GroundFix f;
    f.photo = i;
    f.t_s = m.capture_time->face_ns * 1e-9;
    f.resolution_s = m.capture_time->resolution_s;
    f.north_east_m = {
        (*m.latitude_deg - *lat0_deg) * kMetresPerDegree,
        (*m.longitude_deg - *lon0_deg) * kMetresPerDegree * std::cos(*lat0_deg * kRadPerDeg)};
    fixes.push_back(f);
  }
  std::stable_sort(fixes.begin(), fixes.end(),
                   [](const GroundFix& a, const GroundFix& b) { return a.t_s < b.t_s; });
  return fixes;
}

// Whether every step between fixes a and b (of at least a metre: GPS noise turns shorter ones
// anywhere) keeps within kMaxSpeedBendDeg of the chord from a to b.
bool StraightBetween(const std::vector<GroundFix>& fixes, size_t a, size_t b) {
  const Eigen::Vector2d chord = fixes[b].north_east_m - fixes[a].north_east_m;
  if (chord.norm() < 1.0) return true;  // hovering: no course to keep
  for (size_t j = a; j < b; ++j) {
    const Eigen::Vector2d step = fixes[j + 1].north_east_m - fixes[j].north_east_m;
    if (step.norm() < 1.0) continue;
    const double cos_bend = step.dot(chord) / (step.norm() * chord.norm());
    if (cos_bend < std::cos(kMaxSpeedBendDeg * kRadPerDeg)) return false;
  }
  return true;
}

// The photos on either side of fix k that a speed is taken between: a window of three (k's
// neighbours, the two before it, or the two after it), widened on its open sides until their times
// are kSpeedSpanResolutions resolutions apart; nullopt when none is straight within kMaxSpeedSpanS.
std::optional<std::pair<size_t, size_t>> SpeedWindow(const std::vector<GroundFix>& fixes,
                                                     size_t k) {
  const size_t last = fixes.size() - 1;
  struct Window {
    size_t a, b;
    bool widen_a, widen_b;
  };
  std::vector<Window> windows;  // best first: centred, then one side, then the other
  if (k >= 1 && k + 1 <= last) windows.push_back({k - 1, k + 1, true, true});
  if (k >= 2) windows.push_back({k - 2, k, true, false});
  if (k + 2 <= last) windows.push_back({k, k + 2, false, true});
  for (Window w : windows) {
    const auto span = [&] { return fixes[w.b].t_s - fixes[w.a].t_s; };
    const auto needed = [&] {
      return kSpeedSpanResolutions * std::max(fixes[w.a].resolution_s, fixes[w.b].resolution_s);
    };
    while (span() < needed() && span() <= kMaxSpeedSpanS) {
      const bool can_a = w.widen_a && w.a > 0, can_b = w.widen_b && w.b < last;
      if (!can_a && !can_b) break;
      if (can_a) --w.a;
      if (can_b) ++w.b;
    }
    if (span() >= needed() && span() <= kMaxSpeedSpanS && StraightBetween(fixes, w.a, w.b))
      return std::make_pair(w.a, w.b);
  }
  return std::nullopt;
}

}  // namespace

void SpeedsFromPositions(PhotoSet* set) {
  const std::vector<GroundFix> fixes = GroundFixesByTime(*set);
  for (size_t k = 0; k < fixes.size(); ++k) {
    PhotoRecord& r = set->photos[fixes[k].photo];
    if (r.ground_speed_m_s) continue;
    const auto window = SpeedWindow(fixes, k);
    if (!window) continue;
    const auto [a, b] = *window;
    const double span_s = fixes[b].t_s - fixes[a].t_s;
    const Eigen::Vector2d chord = fixes[b].north_east_m - fixes[a].north_east_m;
    r.ground_speed_m_s = chord.norm() / span_s;
    if (*r.ground_speed_m_s > 0) r.course_deg = CourseDeg(chord.x(), chord.y());
    r.speed_source = "the GPS positions of " + set->photos[fixes[a].photo].name + " and " +
                     set->photos[fixes[b].photo].name + FormatNumber(": %.1f m in ", chord.norm()) +
                     FormatNumber("%.2f s", span_s);
    r.speed_from_positions = true;
    r.missing.erase(std::remove(r.missing.begin(), r.missing.end(), "flight speed"),
                    r.missing.end());
  }
}

PhotoSet ReadPhotoSet(const std::string& dir, const PhotoSetOptions& options) {
  options.Check();
  PhotoSet set;
  set.source = dir;
  std::vector<std::string> paths;
  std::error_code ec;
  if (fs::is_regular_file(dir, ec)) {
    paths.push_back(dir);
  } else {
    if (!fs::is_directory(dir, ec)) throw IoError(IoMessage(dir, 0, "no such folder"));
    // Subfolders are always walked: unread, their photos are counted, so that a card's DCIM
    // folder is not "no photo files".
    for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
      if (!it->is_regular_file() || !IsPhotoFileName(it->path().filename().string())) continue;
      if (it.depth() == 0 || options.recursive) {
        paths.push_back(it->path().string());
      } else {
        ++set.in_subfolders;
      }
    }
    if (ec) throw IoError(IoMessage(dir, 0, "cannot list the folder: " + ec.message()));
    std::sort(paths.begin(), paths.end());
  }
  if (paths.empty() && set.in_subfolders > 0) {
    throw IoError(IoMessage(dir, 0,
                            "no photo files here, but its subfolders hold " +
                                std::to_string(set.in_subfolders) +
                                " (a card's DCIM/100MEDIA?): give --recursive to read them"));
  }
  if (paths.empty())
    throw IoError(IoMessage(dir, 0, "no photo files (.jpg, .jpeg, .tif, .tiff, .dng)"));
  for (size_t i = 0; i < paths.size(); ++i) {
    try {
      PhotoRecord record = MakePhotoRecord(paths[i], ReadPhotoMetadata(paths[i]), options);
      // Metadata survives a cut: the pixels are what a photogrammetry tool will use.
      const std::string problem = options.check_image_data ? ImageDataProblem(paths[i]) : "";
      if (!problem.empty()) record.error = IoMessage(paths[i], 0, UndecodableImageText(problem));
      if (options.recursive) record.name = fs::relative(paths[i], dir).generic_string();
      set.photos.push_back(std::move(record));
    } catch (const IoError& e) {
      PhotoRecord bad;
      bad.path = paths[i];
      bad.name = fs::path(paths[i]).filename().string();
      bad.number = TrailingNumber(bad.name);
      bad.error = e.what();
      set.photos.push_back(std::move(bad));
    }
    if (options.progress) options.progress(static_cast<double>(i + 1) / paths.size());
  }
  SpeedsFromPositions(&set);
  return set;
}

std::vector<std::string> LensProfileNotes(const PhotoSet& set, const LensProfile& profile) {
  for (const PhotoRecord& r : set.photos) {
    if (!r.ok() || r.metadata.width <= 0 || r.metadata.height <= 0) continue;
    return ScaleLensProfile(profile, r.metadata.width, r.metadata.height).notes;
  }
  return {};
}

}  // namespace shutterlab
