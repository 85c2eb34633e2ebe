#include "estimate/correct/correct_io.h"

#include "estimate/report/analysis_json.h"
#include "io/frames_csv.h"
#include "model/effect_io.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <algorithm>
#include <filesystem>
#include <sstream>

namespace shutterlab {

using nlohmann::json;
namespace fs = std::filesystem;

namespace {

json FrameJson(const CorrectedFrame& f, double m_per_px) {
  const ResidualPrediction& r = f.residual;
  json j = {{"frame", f.frame},
            {"image", f.image},
            {"source_image", f.source_image},
            {"mask", "masks/" + f.source_image + ".png"},
            {"velocity_mps", {f.velocity_mps.x(), f.velocity_mps.y(), f.velocity_mps.z()}},
            {"translation", f.translation},
            {"t_first_row_s", f.t_first_row_ns * 1e-9},
            {"t_reference_s", f.t_reference_ns * 1e-9},
            {"reference_row", f.reference_row},
            {"kept", f.kept},
            {"map", {{"cell_px", f.cell_px}, {"estimated_error_px", f.map_error_px}}},
            {"no_source_fraction", f.no_source_fraction},
            {"D_before_px", r.d_before_px},
            {"D_before_m", m_per_px > 0 ? json(r.d_before_px * m_per_px) : json()},
            {"D_after_px", f.predicted_d_after_px},
            {"D_after_m", m_per_px > 0 ? json(f.predicted_d_after_px * m_per_px) : json()},
            {"D_after_p90_px", f.predicted_d_after_p90_px},
            {"D_after_model_px", r.d_after_px},
            {"rms_after_px", r.rms_after_px},
            {"draws", r.draws}};
  if (f.truth) {
    j["truth"] = {{"rms_px", f.truth->rms_px},
                  {"max_px", f.truth->max_px},
                  {"D_px", f.truth->d_px},
                  {"D_before_px", f.truth->d_before_px},
                  {"pixels", f.truth->pixels}};
  }
  if (!f.notes.empty()) j["notes"] = f.notes;
  return j;
}

}  // namespace

json CorrectionToJson(const CorrectSummary& s) {
  json effects = json::array();
  for (Effect e : s.model.effects) effects.push_back(Spec(e).name);
  json frames = json::array();
  for (const CorrectedFrame& f : s.frames) frames.push_back(FrameJson(f, s.m_per_px));
  json skipped = json::array();
  for (const auto& [frame, why] : s.skipped) skipped.push_back({{"frame", frame}, {"why", why}});
  std::vector<std::string> notes = s.model.notes;
  notes.insert(notes.end(), s.notes.begin(), s.notes.end());
  return {{"format", "correction/1"},
          {"dataset", s.dataset},
          {"out", s.out_dir},
          {"kind", s.photos  ? "photos"
                   : s.video ? "video"
                             : "still"},
          {"reference", CorrectionReferenceName(s.setting.reference)},
          {"translation", s.translation},
          {"image_root", s.image_root},
          {"report", s.report_path.empty() ? json() : json(s.report_path)},
          {"effects", effects},
          {"model", TrueModelToJson(s.model.model)},
          {"gyro_noise",
           {{"rad_s_sqrt_hz", s.model.gyro_noise_rad_s_sqrt_hz},
            {"source", s.model.gyro_noise_source}}},
          {"m_per_px", s.m_per_px > 0 ? json(s.m_per_px) : json()},
          {"frames", frames},
          {"skipped", skipped},
          {"notes", notes},
          {"warnings", WarningsToJson(s.warnings)}};
}

std::string CorrectionTable(const CorrectSummary& s) {
  std::ostringstream out;
  const bool truth = std::any_of(s.frames.begin(), s.frames.end(),
                                 [](const CorrectedFrame& f) { return f.truth.has_value(); });
  // Frames by number; photos by name.
  size_t label_width = 5;
  for (const CorrectedFrame& f : s.frames) {
    label_width = std::max(label_width, s.photos ? f.source_image.size() : 0);
  }
  const auto label = [&](const std::string& text) {
    return std::string(label_width - std::min(label_width, text.size()), ' ') + text;
  };
  out << label(s.photos ? "photo" : "frame")
      << "   D before px      m   D after px (p90)      m   no source"
      << (truth ? "   truth after px (D, rms)" : "") << "\n";
  std::vector<double> before, after;
  // On the ground only where a plane gives the scale (not for rotation-only video).
  const auto metres = [&](const char* format, double px) {
    return s.m_per_px > 0 ? FormatNumber(format, px * s.m_per_px) : std::string("      -");
  };
  for (const CorrectedFrame& f : s.frames) {
    const ResidualPrediction& r = f.residual;
    out << label(s.photos ? f.source_image : std::to_string(f.frame))
        << FormatNumber(" %13.3f", r.d_before_px) << metres(" %6.3f", r.d_before_px)
        << FormatNumber(" %12.3f", f.predicted_d_after_px)
        << FormatNumber(" (%.3f)", f.predicted_d_after_p90_px)
        << metres(" %6.4f", f.predicted_d_after_px)
        << FormatNumber(" %10.1f%%", 100.0 * f.no_source_fraction);
    if (f.truth) {
      out << FormatNumber(" %12.3f", f.truth->d_px) << FormatNumber(", %.3f", f.truth->rms_px);
    }
    out << (f.kept ? "  (kept)" : "") << "\n";
    before.push_back(r.d_before_px);
    after.push_back(f.predicted_d_after_px);
  }
  for (const auto& [frame, why] : s.skipped) {
    out << (s.photos ? std::string() : "frame " + std::to_string(frame) + " ") << "skipped: " << why
        << "\n";
  }
  if (!s.frames.empty()) {
    out << "corrected " << s.frames.size() << (s.photos ? " photo(s) to " : " frame(s) to ")
        << (s.image_root.empty() ? s.out_dir : (fs::path(s.out_dir) / s.image_root).string())
        << " (" << CorrectionReferenceName(s.setting.reference) << ", " << s.translation
        << "): median D " << FormatNumber("%.3f", UpperMedian(before)) << " px before, "
        << FormatNumber("%.3f", UpperMedian(after)) << " px predicted after\n";
  }
  return out.str();
}

}  // namespace shutterlab
