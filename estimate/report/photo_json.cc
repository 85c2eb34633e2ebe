#include "estimate/report/photo_json.h"

#include "estimate/paper/analyze.h"
#include "model/camera.h"
#include "sim/civil_time.h"

#include <optional>

namespace shutterlab {
namespace {

nlohmann::json Optional(const std::optional<double>& v) {
  return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
}

nlohmann::json Attitude(const std::optional<AttitudeDeg>& a) {
  if (!a) return nullptr;
  return {{"roll", a->roll_deg}, {"pitch", a->pitch_deg}, {"yaw", a->yaw_deg}};
}

nlohmann::json CaptureTime(const PhotoMetadata& m) {
  if (!m.capture_time) {
    return m.capture_time_problem.empty() ? nlohmann::json(nullptr)
                                          : nlohmann::json{{"problem", m.capture_time_problem}};
  }
  const ClockFace& c = *m.capture_time;
  nlohmann::json j;
  j["written"] = m.capture_time_text;
  j["camera_clock"] = UtcText(c.face_ns);
  j["utc_offset"] =
      c.utc_offset_s ? nlohmann::json(UtcOffsetText(*c.utc_offset_s)) : nlohmann::json(nullptr);
  j["utc"] = c.UtcNs() ? nlohmann::json(UtcText(*c.UtcNs())) : nlohmann::json(nullptr);
  j["resolution_s"] = c.resolution_s;
  return j;
}

nlohmann::json PhotoJson(const PhotoRecord& r, const PhotoResult& p, const PhotoAnalysis& a) {
  nlohmann::json j;
  j["name"] = r.name;
  j["path"] = r.path;
  if (!r.ok()) {
    j["error"] = r.error;
    return j;
  }
  const PhotoMetadata& m = r.metadata;
  j["make"] = m.make;
  j["model"] = m.model;
  j["width"] = m.width;
  j["height"] = m.height;
  j["capture_megapixels"] = r.CaptureMegapixels();
  j["capture_time"] = CaptureTime(m);
  j["focal_px"] = Optional(r.focal_px);
  j["focal_mm"] = Optional(m.focal_length_mm);
  j["focal_plane_px_per_mm"] = Optional(m.focal_plane_px_per_mm);
  j["focal_source"] = r.focal_source;
  if (r.camera) {
    j["camera"] = {{"fx", r.camera->fx},
                   {"fy", r.camera->fy},
                   {"cx", r.camera->cx},
                   {"cy", r.camera->cy},
                   {"distortion", DistortionJson(r.camera->distortion)}};
  }
  j["readout_s"] = Optional(r.readout_s);
  j["readout_origin"] = ReadoutOriginName(r.readout_origin);
  j["readout_source"] = r.readout_source;
  j["altitude_m"] = Optional(r.altitude_m);
  j["altitude_source"] = r.altitude_source;
  j["speed_m_s"] = Optional(r.ground_speed_m_s);
  j["course_deg"] = Optional(r.course_deg);
  j["velocity_m_s"] = m.speed_m_s
                          ? nlohmann::json{m.speed_m_s->x(), m.speed_m_s->y(), m.speed_m_s->z()}
                          : nlohmann::json(nullptr);
  j["speed_source"] = r.speed_source;
  j["exposure_s"] = Optional(m.exposure_s);
  j["gimbal_deg"] = Attitude(m.gimbal);
  j["flight_deg"] = Attitude(m.flight);
  j["D_translation_px"] = Optional(p.d_translation_px);
  j["D_translation_m"] = Optional(p.d_translation_m);
  j["along_readout_px"] = Optional(p.along_readout_px);
  j["across_readout_px"] = Optional(p.across_readout_px);
  j["blur_px"] = Optional(p.blur_px);
  if (a.with_log) {
    j["t"] = p.placement.t_ns ? nlohmann::json(*p.placement.t_ns * 1e-9) : nlohmann::json(nullptr);
    j["placement"] =
        p.placement.t_ns ? nlohmann::json(p.placement.method) : nlohmann::json(nullptr);
    j["placement_problem"] = p.placement.problem;
    j["residual_s"] = Optional(p.placement.residual_s);
    j["D_rotation_m"] = Optional(p.d_rotation_m);
    j["D_rotation_px"] = Optional(p.d_rotation_px);
    j["D_paper_m"] = Optional(p.d_paper_m);
  }
  nlohmann::json flagged = nlohmann::json::object();
  for (size_t l = 0; l < a.limits_m.size(); ++l) {
    flagged[LimitKey(a.limits_m[l])] = l < p.flagged.size() && p.flagged[l]
                                           ? nlohmann::json(*p.flagged[l])
                                           : nlohmann::json(nullptr);
  }
  j["flagged"] = flagged;
  j["missing"] = r.missing;
  j["notes"] = p.notes;
  return j;
}

}  // namespace

nlohmann::json PhotoAnalysisToJson(const PhotoSet& set, const PhotoAnalysis& a) {
  nlohmann::json j;
  j["source"] = a.source;
  j["model"] = a.with_log ? "rotation (log) + translation (recorded speed)"
                          : "translation only (recorded speed)";
  j["limits_m"] = a.limits_m;
  if (a.with_log) {
    j["placement"] = {{"method", a.placement_method},
                      {"placed", a.placed},
                      {"clock_offset_s", Optional(a.clock_offset_s)},
                      {"clock_offset_to", a.clock_offset_s ? nlohmann::json(a.clock_offset_to)
                                                           : nlohmann::json(nullptr)},
                      {"residual_rms_s", Optional(a.residual_rms_s)},
                      {"residual_max_s", Optional(a.residual_max_s)}};
  }
  nlohmann::json photos = nlohmann::json::array();
  for (size_t i = 0; i < a.photos.size(); ++i)
    photos.push_back(PhotoJson(set.photos[i], a.photos[i], a));
  j["photos"] = std::move(photos);
  j["summary"] = {{"files", a.photos.size()},   {"read", a.read},
                  {"predicted", a.predicted},   {"readout_from_table", a.readout_from_table},
                  {"flagged", a.flagged_count}, {"line", a.verdict}};
  return j;
}

}  // namespace shutterlab
