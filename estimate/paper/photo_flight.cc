#include "estimate/paper/photo_flight.h"

#include "sim/check.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <tuple>

namespace shutterlab {

void CameraFromPhotos(const PhotoSet& set, bool readout_given, RigModel* rig, std::string* source) {
  using Key = std::tuple<int, int, int64_t, int64_t>;
  std::map<Key, size_t> counts;
  std::map<Key, const PhotoRecord*> example;
  for (const PhotoRecord& r : set.photos) {
    if (!r.ok() || !r.focal_px || r.metadata.width <= 0) continue;
    const Key key{r.metadata.width, r.metadata.height, std::llround(*r.focal_px * 10.0),
                  r.readout_s ? std::llround(*r.readout_s * 1e9) : -1};
    ++counts[key];
    example.emplace(key, &r);
  }
  if (counts.empty()) {
    *source =
        "no photo gives its image size and focal length: the camera of the flags (--size, "
        "--focal-px, --readout)";
    return;
  }
  const auto best = std::max_element(counts.begin(), counts.end(),
                                     [](auto& a, auto& b) { return a.second < b.second; });
  const PhotoRecord& r = *example[best->first];
  rig->camera.width = r.metadata.width;
  rig->camera.height = r.metadata.height;
  rig->camera.fx = rig->camera.fy = *r.focal_px;
  rig->camera.cx = 0.5 * (r.metadata.width - 1);
  rig->camera.cy = 0.5 * (r.metadata.height - 1);
  *source = "the photos' " + r.metadata.make + " " + r.metadata.model + " (" +
            std::to_string(best->second) + " of " + std::to_string(set.photos.size()) +
            " photos), " + std::to_string(r.metadata.width) + "x" +
            std::to_string(r.metadata.height) + FormatNumber(", f %.0f px", *r.focal_px);
  if (readout_given) {
    *source += FormatNumber(", readout %g ms (--readout)", rig->shutter.readout_s * 1e3);
  } else if (r.readout_s) {
    rig->shutter.readout_s = *r.readout_s;
    *source += FormatNumber(", readout %g ms (", *r.readout_s * 1e3) + r.readout_source + ")";
  } else {
    *source += FormatNumber(", readout unknown: %g ms assumed (give --readout)",
                            rig->shutter.readout_s * 1e3);
  }
  if (counts.size() > 1) *source += "; other cameras in the folder are analysed as this one";
}

void PhotoFlightOptions::Check() const {
  analyze.Check();
  photos.Check();
  clock.Check();
}

namespace {

// Each placed photo that records no flight speed takes the log's horizontal velocity at its time
// (over one differentiated from the photos' positions).
void SpeedsFromLog(const FlightLog& log, const PhotoClock& clock, PhotoSet* set) {
  for (size_t i = 0; i < set->photos.size(); ++i) {
    PhotoRecord& r = set->photos[i];
    const std::optional<int64_t>& t_ns = clock.placements[i].t_ns;
    if (!r.ok() || (r.ground_speed_m_s && !r.speed_from_positions) || !t_ns) continue;
    const std::optional<Eigen::Vector3d> v = VelocityAt(log.velocity, *t_ns);
    if (!v) continue;
    r.ground_speed_m_s = v->head<2>().norm();
    if (*r.ground_speed_m_s > 0) r.course_deg = CourseDeg(v->x(), v->y());
    r.speed_source = "the log's " + log.velocity_source + " at the photo's time";
    r.speed_from_positions = false;
    r.missing.erase(std::remove(r.missing.begin(), r.missing.end(), "flight speed"),
                    r.missing.end());
  }
}

// The photos placed on the log (its camera events and GPS fixes: never its samples), the camera
// and the options analyze is given, and once analyze has run on them (analyze), each photo's
// rotation beside its translation.
PhotoFlightResult PhotoFlight(const PhotoSet& set, const FlightLog& log,
                              const TriggerFile* triggers, const PhotoFlightOptions& options,
                              const std::function<AnalyzeResult(const AnalyzeOptions&)>& analyze) {
  options.Check();
  PhotoFlightResult out;
  out.clock = PlacePhotos(set, log, triggers, options.clock);
  out.set = set;
  SpeedsFromLog(log, out.clock, &out.set);

  AnalyzeOptions a = options.analyze;
  if (options.rig_given) {
    out.camera_source = "camera.json";
  } else {
    CameraFromPhotos(set, options.readout_given, &a.rig, &out.camera_source);
  }
  if (options.lens_profile) {
    out.lens = ScaleLensProfile(*options.lens_profile, a.rig.camera.width, a.rig.camera.height);
    ApplyLensProfile(&*out.lens, &a.rig, options.readout_given);
    out.camera_source += "; its lens from the lens profile " + out.lens->name;
  }
  if (!options.altitude_given && !options.rig_given) {
    a.use_log_altitude = true;
    std::vector<double> heights;
    for (const PhotoRecord& r : set.photos) {
      if (r.ok() && r.altitude_m) heights.push_back(*r.altitude_m);
    }
    if (!heights.empty()) {
      a.rig.altitude_m = Median(std::move(heights));
      a.altitude_is_default = false;
    }
  }
  a.triggers.clear();
  for (size_t i = 0; i < set.photos.size(); ++i) {
    const PhotoPlacement& p = out.clock.placements[i];
    if (p.t_ns) a.triggers.push_back({set.photos[i].name, *p.t_ns});
  }
  a.triggers_source = "photos: " + out.clock.method;
  a.every_s = 0.0;
  a.log_events = false;
  out.log = analyze(a);
  out.analyzed = std::move(a);

  PhotoAnalysisOptions photo_options = options.photos;
  photo_options.limits_m = out.analyzed.limits_m;
  photo_options.rotation_at_each_photo_altitude = !options.altitude_given && !options.rig_given;
  out.photos = AnalyzePhotosWithLog(out.set, photo_options, out.clock.placements, out.log);
  out.photos.placement_method = out.clock.method;
  out.photos.clock_offset_s = out.clock.clock_offset_s;
  out.photos.clock_offset_to = out.clock.clock_offset_to;
  out.photos.residual_rms_s = out.clock.residual_rms_s;
  out.photos.residual_max_s = out.clock.residual_max_s;
  return out;
}

}  // namespace

PhotoFlightResult AnalyzePhotoFlight(const PhotoSet& set, const FlightLog& log,
                                     const TriggerFile* triggers,
                                     const PhotoFlightOptions& options) {
  return PhotoFlight(set, log, triggers, options,
                     [&log](const AnalyzeOptions& a) { return Analyze(log, a); });
}

PhotoFlightResult AnalyzePhotoFlightStream(const PhotoSet& set, const FlightLog& metadata,
                                           const AnalyzeLogSource& source,
                                           const TriggerFile* triggers,
                                           const PhotoFlightOptions& options) {
  return PhotoFlight(set, metadata, triggers, options,
                     [&source](const AnalyzeOptions& a) { return AnalyzeStream(source, a); });
}

}  // namespace shutterlab
