#include "estimate/paper/photo_analysis.h"

#include "sim/check.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>

namespace shutterlab {
namespace {

// Translation only, from the recorded speed (the header's equations).
void PredictTranslation(const PhotoRecord& r, const PhotoAnalysisOptions& options,
                        PhotoResult* out) {
  const PhotoMetadata& m = r.metadata;
  // With a nadir gimbal, its attitude splits the motion along and across the readout.
  Eigen::Matrix3d ned_from_gimbal = Eigen::Matrix3d::Identity();
  bool nadir = false;
  if (m.gimbal) {
    ned_from_gimbal = NedFromGimbal(*m.gimbal);
    const double off_nadir_deg =
        std::acos(std::clamp(ned_from_gimbal.col(0).z(), -1.0, 1.0)) * kDegPerRad;
    nadir = off_nadir_deg <= options.nadir_tolerance_deg;
    if (!nadir) {
      out->notes.push_back(
          FormatNumber("oblique (%.1f deg from nadir", off_nadir_deg) +
          FormatNumber(", gimbal pitch %.1f deg): the model assumes nadir", m.gimbal->pitch_deg));
    }
  }
  if (!r.ground_speed_m_s || !r.readout_s || !r.focal_px || !r.altitude_m) return;
  const double px_per_m = *r.focal_px / *r.altitude_m;
  out->d_translation_m = *r.ground_speed_m_s * *r.readout_s;
  out->d_translation_px = *out->d_translation_m * px_per_m;
  if (m.exposure_s) out->blur_px = *r.ground_speed_m_s * *m.exposure_s * px_per_m;
  // A course is known for the photo's own speed or the log's (estimate/paper/photo_flight.h), not
  // for --speed's alone.
  if (nadir && (r.course_deg || *r.ground_speed_m_s == 0)) {
    // The ground moves against the camera: -v along each image axis (horizontal motion only).
    const double course = r.course_deg.value_or(0.0) * kRadPerDeg;
    const Eigen::Vector3d v =
        *r.ground_speed_m_s * Eigen::Vector3d(std::cos(course), std::sin(course), 0.0);
    const double scale = *r.readout_s * px_per_m;
    out->along_readout_px = -v.dot(ned_from_gimbal.col(2)) * scale;
    out->across_readout_px = -v.dot(ned_from_gimbal.col(1)) * scale;
  }
}

void Flag(const std::vector<double>& limits_m, std::optional<double> d_m, PhotoResult* out) {
  out->flagged.assign(limits_m.size(), std::nullopt);
  if (!d_m) return;
  for (size_t l = 0; l < limits_m.size(); ++l) out->flagged[l] = *d_m > limits_m[l];
}

// When exclude.txt would drop more than half of the photos: how many are unreadable, how large the
// others' shifts are in pixels at their ground sampling, so that a person sees whether a limit of a
// pixel or so is what they want, and what the photogrammetry tool can do instead (said only where
// a shift dropped a photo: no limit keeps an unreadable one).
std::string ExcludedMostText(const PhotoSet& set, PhotoAnalysis* a) {
  std::vector<double> d_px, gsd_m;
  size_t unreadable = 0, shifted = 0;
  for (size_t i = 0; i < a->photos.size(); ++i) {
    const PhotoRecord& r = set.photos[i];
    const PhotoResult& p = a->photos[i];
    if (!r.ok()) {
      ++unreadable;
      continue;
    }
    if (!p.AnyFlagged()) continue;
    ++shifted;
    if (!r.altitude_m || !r.focal_px) continue;
    const double gsd = *r.altitude_m / *r.focal_px;
    gsd_m.push_back(gsd);
    d_px.push_back((p.d_rotation_m.value_or(0.0) + p.d_translation_m.value_or(0.0)) / gsd);
  }
  a->excluded = unreadable + shifted;
  if (2 * a->excluded <= a->photos.size() || a->limits_m.empty()) return "";
  std::string text = "; exclude.txt drops " + std::to_string(a->excluded) + " of " +
                     std::to_string(a->photos.size()) + " photos";
  if (unreadable > 0) text += " (" + std::to_string(unreadable) + " unreadable)";
  if (shifted == 0) return text;
  if (!d_px.empty()) {
    const double gsd = Median(gsd_m);
    const std::string lo = FormatNumber("%.2g", *std::min_element(d_px.begin(), d_px.end()));
    const std::string hi = FormatNumber("%.2g", *std::max_element(d_px.begin(), d_px.end()));
    text += (unreadable > 0 ? ": the others' shifts are " : ": their shifts are ") +
            (lo == hi ? lo : lo + "-" + hi) + " px at " + FormatNumber("%.2g", gsd * 100.0) +
            " cm/px, where " + LengthText(a->limits_m[0]) + " is " +
            FormatNumber("%.2g", a->limits_m[0] / gsd) + " px";
  }
  return text +
         "; a larger --limit keeps more, and a photogrammetry tool's own rolling-shutter "
         "option (ODM --rolling-shutter) removes the translation part";
}

void Summarise(const PhotoSet& set, PhotoAnalysis* a) {
  a->flagged_count.assign(a->limits_m.size(), 0);
  size_t predicted_count = 0;
  for (size_t i = 0; i < a->photos.size(); ++i) {
    const PhotoRecord& r = set.photos[i];
    const PhotoResult& p = a->photos[i];
    a->read += r.ok();
    a->predicted += p.d_translation_m.has_value();
    a->readout_from_table += r.ok() && r.readout_origin == ReadoutOrigin::kTable;
    a->placed += p.placement.t_ns.has_value();
    predicted_count += !p.flagged.empty() && p.flagged[0].has_value();
    for (size_t l = 0; l < a->limits_m.size(); ++l)
      a->flagged_count[l] += l < p.flagged.size() && p.flagged[l].value_or(false);
  }
  std::string line;
  if (predicted_count == 0) {
    line = "no photo could be predicted: see what is missing above";
  } else {
    line = std::to_string(predicted_count) + " of " + std::to_string(a->photos.size()) +
           " photos predicted: ";
    for (size_t l = 0; l < a->limits_m.size(); ++l) {
      line += (l ? ", " : "") + std::to_string(a->flagged_count[l]) + " over " +
              LengthText(a->limits_m[l]);
    }
    if (!a->with_log) {
      line += " (translation only, from the recorded speed; the rotation needs a flight log)";
    } else if (a->placed == 0) {
      line += " (translation only: no photo could be placed on the log)";
    } else {
      line += " (rotation from the log for the " + std::to_string(a->placed) +
              " placed photo(s) + translation from the recorded speed)";
    }
  }
  // What would let the other photos be predicted, once each.
  std::vector<std::string> hints;
  for (size_t i = 0; i < a->photos.size(); ++i) {
    if (!set.photos[i].ok() || a->photos[i].d_translation_m) continue;
    // --ground-elevation only helps a photo that records an absolute altitude.
    const PhotoMetadata& m = set.photos[i].metadata;
    const bool absolute = m.absolute_altitude_m || m.gps_altitude_m;
    for (const std::string& what : set.photos[i].missing) {
      const char* hint = what == "altitude" && absolute
                             ? "--altitude M (height above the ground), or --ground-elevation M "
                               "(with the photos' GPS altitude)"
                         : what == "altitude"     ? "--altitude M (height above the ground)"
                         : what == "readout"      ? "--readout T (your camera's readout)"
                         : what == "focal length" ? "--focal-px F"
                                                  : nullptr;
      if (hint && std::find(hints.begin(), hints.end(), hint) == hints.end()) hints.push_back(hint);
    }
  }
  if (!hints.empty()) {
    line += predicted_count == 0 ? "; to predict them give" : "; to predict the others give";
    for (size_t h = 0; h < hints.size(); ++h) line += (h ? ", " : " ") + hints[h];
  }
  if (a->readout_from_table > 0) {
    line += "; readout from OpenDroneMap's table for " + std::to_string(a->readout_from_table) +
            " photo(s): give --readout if you know yours";
  }
  line += ExcludedMostText(set, a);
  a->verdict = line;
}

PhotoAnalysis AnalyzeEach(const PhotoSet& set, const PhotoAnalysisOptions& options) {
  options.Check();
  PhotoAnalysis a;
  a.source = set.source;
  a.limits_m = options.limits_m;
  for (const PhotoRecord& r : set.photos) {
    PhotoResult p;
    p.name = r.name;
    p.error = r.error;
    if (r.ok()) PredictTranslation(r, options, &p);
    a.photos.push_back(std::move(p));
  }
  return a;
}

std::string Cell(std::optional<double> v, const char* format, double scale = 1.0) {
  return v ? FormatNumber(format, *v * scale) : "-";
}

// One line per distinct camera: make, model, size, focal with its source, readout with its source.
std::string CameraLines(const PhotoSet& set) {
  std::map<std::string, size_t> lines;
  std::vector<std::string> order;
  for (const PhotoRecord& r : set.photos) {
    if (!r.ok()) continue;
    const PhotoMetadata& m = r.metadata;
    std::string line =
        "camera: " + (m.make.empty() ? std::string("(no make)") : m.make) + " " +
        (m.model.empty() ? std::string("(no model)") : m.model) + ", " + std::to_string(m.width) +
        "x" + std::to_string(m.height) + ", f " +
        (r.focal_px ? FormatNumber("%.0f px", *r.focal_px) + " (" + r.focal_source + ")"
                    : std::string("unknown")) +
        "\n  readout " + (r.readout_s ? FormatNumber("%g ms", *r.readout_s * 1e3) : "unknown") +
        " (" + r.readout_source + ")";
    if (lines[line]++ == 0) order.push_back(line);
  }
  std::string text;
  for (const std::string& line : order) {
    const size_t n = lines[line];
    text +=
        line +
        (lines.size() > 1 ? "  [" + std::to_string(n) + (n == 1 ? " photo]" : " photos]") : "") +
        "\n";
  }
  return text;
}

std::string FlagText(const PhotoAnalysis& a, const PhotoResult& p) {
  std::string text;
  for (size_t l = 0; l < p.flagged.size(); ++l) {
    if (p.flagged[l].value_or(false))
      text += (text.empty() ? ">" : ",>") + LengthText(a.limits_m[l]);
  }
  return text;
}

}  // namespace

void PhotoAnalysisOptions::Check() const {
  SHUTTERLAB_CHECK(!limits_m.empty()) << "give at least one ground limit";
  for (double limit : limits_m) {
    SHUTTERLAB_CHECK(std::isfinite(limit) && limit > 0)
        << "ground limit must be positive (got " << limit << " m)";
  }
  SHUTTERLAB_CHECK(std::isfinite(nadir_tolerance_deg) && nadir_tolerance_deg >= 0 &&
                   nadir_tolerance_deg <= 90)
      << "nadir tolerance must be within 0..90 deg";
}

bool PhotoResult::AnyFlagged() const {
  return std::any_of(flagged.begin(), flagged.end(),
                     [](const std::optional<bool>& f) { return f.value_or(false); });
}

PhotoAnalysis AnalyzePhotos(const PhotoSet& set, const PhotoAnalysisOptions& options) {
  PhotoAnalysis a = AnalyzeEach(set, options);
  for (PhotoResult& p : a.photos) Flag(a.limits_m, p.d_translation_m, &p);
  Summarise(set, &a);
  return a;
}

PhotoAnalysis AnalyzePhotosWithLog(const PhotoSet& set, const PhotoAnalysisOptions& options,
                                   const std::vector<PhotoPlacement>& placements,
                                   const AnalyzeResult& log_result) {
  SHUTTERLAB_CHECK(placements.size() == set.photos.size()) << "one placement per photo";
  PhotoAnalysis a = AnalyzeEach(set, options);
  a.with_log = true;
  std::map<std::string, const ImageResult*> by_name;
  for (const ImageResult& image : log_result.images) by_name[image.name] = &image;
  for (size_t i = 0; i < a.photos.size(); ++i) {
    PhotoResult& p = a.photos[i];
    p.placement = placements[i];
    const auto it = by_name.find(p.name);
    if (it != by_name.end() && it->second->in_trace) {
      p.d_rotation_m = it->second->d_full_m;
      p.d_rotation_px = it->second->d_full_px;
      p.d_paper_m = it->second->d_paper_m;
      // The same image angle covers ground in proportion to the height: a folder flown at 41 m
      // and 118 m is not one altitude.
      // A log's own height above ground stands (a photo's is above take-off).
      const std::optional<double>& altitude_m = set.photos[i].altitude_m;
      if (options.rotation_at_each_photo_altitude && altitude_m && log_result.altitude_m > 0 &&
          log_result.altitude_source != "log") {
        const double scale = *altitude_m / log_result.altitude_m;
        *p.d_rotation_m *= scale;
        if (p.d_paper_m) *p.d_paper_m *= scale;
      }
    } else if (p.placement.t_ns) {
      p.notes.push_back("its readout is outside the log's gyro trace");
    } else if (p.error.empty()) {
      p.notes.push_back("not placed on the log: " + p.placement.problem);
    }
    std::optional<double> total_m;
    if (p.d_rotation_m || p.d_translation_m)
      total_m = p.d_rotation_m.value_or(0.0) + p.d_translation_m.value_or(0.0);
    if (p.d_rotation_m && !p.d_translation_m && p.error.empty())
      p.notes.push_back("translation unknown: flagged on the rotation alone");
    Flag(a.limits_m, total_m, &p);
  }
  Summarise(set, &a);
  return a;
}

std::string PhotoAnalysisReport(const PhotoSet& set, const PhotoAnalysis& a) {
  std::ostringstream out;
  out << "photos: " << a.source << " (" << a.photos.size()
      << (a.photos.size() == 1 ? " file, " : " files, ") << a.read << " read)\n"
      << CameraLines(set);
  out << "model: "
      << (a.with_log ? "rotation from the log's gyro (analyze's full model) + translation from "
                       "the recorded speed, D = speed x readout x f / altitude"
                     : "translation only: D = speed x readout x f / altitude (nadir camera, flat "
                       "ground); the rotation needs a flight log")
      << "\n";
  if (a.with_log) {
    out << "placement: " << a.placement_method << "; " << a.placed << " of " << a.photos.size()
        << " placed";
    if (a.clock_offset_s)
      out << ", camera clock - " << a.clock_offset_to << FormatNumber(" %.3f s", *a.clock_offset_s);
    if (a.residual_rms_s) {
      out << FormatNumber(", residual rms %.3f s", *a.residual_rms_s)
          << FormatNumber(" (max %.3f s)", *a.residual_max_s);
    }
    out << "\n";
  }
  out << "\n";
  char line[512];
  if (a.with_log) {
    std::snprintf(line, sizeof line, "%-22s %10s %9s %7s %7s %9s %9s %9s  %s\n", "photo",
                  "t log (s)", "resid ms", "v m/s", "alt m", "rot cm", "trans cm", "trans px",
                  "flagged");
  } else {
    std::snprintf(line, sizeof line, "%-22s %-19s %7s %7s %9s %8s %8s %13s %7s  %s\n", "photo",
                  "capture (camera)", "v m/s", "alt m", "readout", "D px", "D cm", "along/across",
                  "blur px", "flagged");
  }
  out << line;
  for (size_t i = 0; i < a.photos.size(); ++i) {
    const PhotoRecord& r = set.photos[i];
    const PhotoResult& p = a.photos[i];
    if (!r.ok()) {
      std::snprintf(line, sizeof line, "%-22s unreadable\n", p.name.c_str());
      out << line;
      continue;
    }
    const std::string readout = r.readout_s
                                    ? FormatNumber("%g ms", *r.readout_s * 1e3) +
                                          (r.readout_origin == ReadoutOrigin::kTable ? "*" : "")
                                    : "-";
    const std::string parts = p.along_readout_px ? FormatNumber("%+.2f", *p.along_readout_px) +
                                                       FormatNumber("/%+.2f", *p.across_readout_px)
                                                 : "-";
    if (a.with_log) {
      const std::string t = p.placement.t_ns ? FormatNumber("%.3f", *p.placement.t_ns * 1e-9) : "-";
      std::snprintf(line, sizeof line, "%-22s %10s %9s %7s %7s %9s %9s %9s  %s\n", p.name.c_str(),
                    t.c_str(), Cell(p.placement.residual_s, "%+.1f", 1e3).c_str(),
                    Cell(r.ground_speed_m_s, "%.1f").c_str(), Cell(r.altitude_m, "%.1f").c_str(),
                    Cell(p.d_rotation_m, "%.2f", 100.0).c_str(),
                    Cell(p.d_translation_m, "%.2f", 100.0).c_str(),
                    Cell(p.d_translation_px, "%.2f").c_str(), FlagText(a, p).c_str());
    } else {
      const std::string when =
          r.metadata.capture_time ? UtcText(r.metadata.capture_time->face_ns).substr(0, 19) : "-";
      std::snprintf(line, sizeof line, "%-22s %-19s %7s %7s %9s %8s %8s %13s %7s  %s\n",
                    p.name.c_str(), when.c_str(), Cell(r.ground_speed_m_s, "%.1f").c_str(),
                    Cell(r.altitude_m, "%.1f").c_str(), readout.c_str(),
                    Cell(p.d_translation_px, "%.2f").c_str(),
                    Cell(p.d_translation_m, "%.2f", 100.0).c_str(), parts.c_str(),
                    Cell(p.blur_px, "%.2f").c_str(), FlagText(a, p).c_str());
    }
    out << line;
  }
  if (a.readout_from_table > 0) {
    out << "* readout from OpenDroneMap's rolling-shutter database (community-measured, not this "
           "camera's own): --readout overrides\n";
  }
  if (!a.with_log) {
    out << "along/across: the ground's motion during the readout along it (+ stretches the photo) "
           "and across it (+ to the right), px\n";
  }
  bool header = false;
  for (size_t i = 0; i < a.photos.size(); ++i) {
    const PhotoRecord& r = set.photos[i];
    const PhotoResult& p = a.photos[i];
    std::string what;
    if (!r.ok()) what = "unreadable: " + r.error;
    for (const std::string& m : r.missing) what += (what.empty() ? "no " : ", no ") + m;
    for (const std::string& n : p.notes) what += (what.empty() ? "" : "; ") + n;
    if (what.empty()) continue;
    if (!header) out << "\nper photo:\n";
    header = true;
    out << "  " << p.name << ": " << what << "\n";
  }
  out << "\n" << a.verdict << "\n";
  return out.str();
}

void WritePhotoOutputs(const std::string& dir, const PhotoSet& set, const PhotoAnalysis& a) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw IoError(IoMessage(dir, 0, "cannot create folder: " + ec.message()));
  std::string csv =
      "name,make,model,width,height,focal_px,readout_s,readout_origin,altitude_m,speed_m_s,"
      "t_log,residual_s,D_rotation_m,D_translation_m,D_translation_px,along_readout_px,"
      "across_readout_px,blur_px";
  for (double limit : a.limits_m) csv += ",flag_" + LimitKey(limit);
  csv += ",missing\n";
  auto number = [&csv](std::optional<double> v) {
    csv += ",";
    if (v) AppendDouble(*v, &csv);
  };
  std::string exclude, image_list, colmap_list;
  for (size_t i = 0; i < a.photos.size(); ++i) {
    const PhotoRecord& r = set.photos[i];
    const PhotoResult& p = a.photos[i];
    const PhotoMetadata& m = r.metadata;
    csv += p.name + "," + m.make + "," + m.model + "," + std::to_string(m.width) + "," +
           std::to_string(m.height);
    number(r.focal_px);
    number(r.readout_s);
    csv += std::string(",") + ReadoutOriginName(r.readout_origin);
    number(r.altitude_m);
    number(r.ground_speed_m_s);
    number(p.placement.t_ns ? std::optional<double>(*p.placement.t_ns * 1e-9) : std::nullopt);
    number(p.placement.residual_s);
    number(p.d_rotation_m);
    number(p.d_translation_m);
    number(p.d_translation_px);
    number(p.along_readout_px);
    number(p.across_readout_px);
    number(p.blur_px);
    for (const std::optional<bool>& f : p.flagged) csv += f ? (*f ? ",1" : ",0") : ",";
    std::string missing = r.ok() ? "" : "unreadable";
    for (const std::string& what : r.missing) missing += (missing.empty() ? "" : ";") + what;
    csv += "," + missing + "\n";
    if (!r.ok() || p.AnyFlagged()) {
      exclude += p.name + "\n";
    } else {
      image_list += fs::absolute(r.path).lexically_normal().string() + "\n";
      colmap_list += p.name + "\n";
    }
  }
  WriteFileAtomically(dir + "/photos.csv", csv);
  WriteFileAtomically(dir + "/exclude.txt", exclude);
  WriteFileAtomically(dir + "/image_list.txt", image_list);
  WriteFileAtomically(dir + "/colmap_image_list.txt", colmap_list);
}

}  // namespace shutterlab
