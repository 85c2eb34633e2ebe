#include "estimate/loop/validate_video.h"
#include "estimate/report/loop_json.h"
#include "estimate/report/validate_report.h"
#include "model/effect_io.h"
#include "sim/check.h"
#include "sim/text_file.h"

#include <cmath>
#include <sstream>

namespace shutterlab {
namespace {

using nlohmann::json;

json StatsJson(const ResidualStats& s) {
  return json{{"rms_px", s.rms_px}, {"max_px", s.max_px}, {"points", s.points}};
}

}  // namespace

json VideoValidationToJson(const ValidationResult& result) {
  const bool translation = result.preferred == "translation";
  const LoopResult& preferred = translation ? result.translation_loop : result.loop;
  json out = LoopToJson(preferred, result.frames.size());
  // A stabiliser's rendering holds no rolling-shutter effect of the sensor's: the report names
  // none, whatever the loops fitted (kept under their own keys).
  if (ReRenderedByStabiliser(result)) {
    out["effects"] = json::array();
    out["unexplained"] = true;
  }
  out["model"] = result.preferred;
  out["video"] = true;
  out["dataset"] = result.dataset;
  out["rotation_only"] = LoopToJson(result.loop, result.frames.size());
  json trans = LoopToJson(result.translation_loop, result.frames.size());
  trans["explains_share"] = result.translation_explains;
  trans["inherits"] = result.translation_inherits;
  trans["mean_square_per_component_px2"] = {
      {"rotation_only", result.rotation_mean_sq_px2},
      {"translation", result.translation_mean_sq_px2},
      {"noise", result.loop.noise_px * result.loop.noise_px / 2.0}};
  out["translation"] = trans;
  json pairs = json::array();
  for (const FrameValidation& f : result.frames) {
    pairs.push_back({{"frame", f.frame},
                     {"previous", f.previous ? json(*f.previous) : json()},
                     {"image", f.image},
                     {"t_gyro_s", f.t_gyro_s},
                     {"points", f.points},
                     {"measured_fraction", f.measured_fraction},
                     {"noise_px", f.noise_px},
                     {"before", StatsJson(f.before)},
                     {"after", StatsJson(f.after)},
                     {"translation_after", StatsJson(f.translation_after)},
                     {"left_out",
                      {{"camera_fixed", f.camera_fixed},
                       {"moving", f.moving},
                       {"off_epipolar", f.off_epipolar}}},
                     {"translation_dir",
                      {f.translation_dir.x(), f.translation_dir.y(), f.translation_dir.z()}}});
  }
  out["pairs"] = pairs;
  json halves = json::array();
  for (const HalfCheck& h : result.halves) {
    json effects = json::array();
    for (const HalfAgreement& a : h.effects) {
      effects.push_back({{"name", Spec(a.effect).name},
                         {"first", EffectValueToJson(a.first)},
                         {"first_stderr", EffectValueToJson(a.first_stderr)},
                         {"second", EffectValueToJson(a.second)},
                         {"second_stderr", EffectValueToJson(a.second_stderr)},
                         {"distance", std::isfinite(a.distance) ? json(a.distance) : json()},
                         {"agree", a.agree},
                         {"determined", a.determined}});
    }
    halves.push_back({{"model", h.model},
                      {"first_pairs", h.first_pairs},
                      {"second_pairs", h.second_pairs},
                      {"first_after", StatsJson(h.first_after)},
                      {"second_after", StatsJson(h.second_after)},
                      {"effects", effects}});
  }
  out["halves"] = halves;
  json claims = json::array();
  for (const ClaimCheck& c : result.claims) {
    claims.push_back({{"claim", c.claim},
                      {"effect", Spec(c.effect).name},
                      {"status", c.status},
                      {"claimed", EffectValueToJson(c.claimed)},
                      {"found", EffectValueToJson(c.found)},
                      {"found_stderr", EffectValueToJson(c.found_stderr)},
                      {"difference", std::isfinite(c.difference) ? json(c.difference) : json()},
                      {"verdict", c.verdict}});
  }
  out["claims"] = claims;
  out["skipped"] = result.skipped;
  out["screening"] = ScreeningToJson(result);
  if (result.image_orientation.present) {
    const ImageOrientationCheck& o = result.image_orientation;
    out["image_orientation"] = {
        {"pairs_tested", o.pairs_tested},
        {"share", o.share},
        {"gain", o.gain},
        {"holds", o.holds},
        {"gain_gyro_alone", std::isfinite(o.raw_gain) ? json(o.raw_gain) : json()},
        {"gain_applied", std::isfinite(o.applied_gain) ? json(o.applied_gain) : json()},
        {"pairs_applied", o.applied_pairs},
        {"axes", MatrixJson(o.axes)},
        {"inverse", o.inverse},
        {"verdict", o.verdict}};
  }
  out["timing_s"] = {
      {"read", result.read_s}, {"measure", result.measure_s}, {"loop", result.loop_s}};
  return out;
}

std::string VideoValidationReport(const ValidationResult& result) {
  std::ostringstream out;
  const RigModel& rig = result.declared;
  out << "video dataset " << result.dataset << ": " << result.frames.size() << " pairs, "
      << rig.camera.width << "x" << rig.camera.height << ", f "
      << FormatNumber("%.1f", 0.5 * (rig.camera.fx + rig.camera.fy)) << " px, readout "
      << FormatNumber("%.2f", rig.shutter.readout_s * 1e3) << " ms declared\n"
      << LensProfileLines(result);
  for (const std::string& s : result.skipped) out << "  left out: " << s << "\n";
  out << "\n  pair          points  noise |  rms before | rotation only | with translation\n";
  out << "                          px  |  px (declared) |   after, px   |  after, px (across)\n";
  for (const FrameValidation& f : result.frames) {
    char line[200];
    std::snprintf(line, sizeof(line), "%6lld -> %-6lld %6zu %6.3f | %10.3f  | %12.3f  | %10.3f\n",
                  static_cast<long long>(f.previous.value_or(-1)), static_cast<long long>(f.frame),
                  f.points, f.noise_px, f.before.rms_px, f.after.rms_px,
                  f.translation_after.rms_px);
    out << line;
  }
  const double noise = result.loop.noise_px;
  out << "\n";
  WriteScreeningSummary(result, out);
  if (result.image_orientation.present) {
    out << "the stabiliser's rotation (image_orientation.csv): " << result.image_orientation.verdict
        << "\n";
  }
  out << "standard errors: " << CovarianceKindName(result.loop.covariance) << " over the pairs\n";
  out << "\nrotation only (docs/FORMATS.md's video model), " << result.loop.before.points
      << " points, noise " << FormatNumber("%.3f", noise) << " px:\n";
  WriteLoopSummary(result.loop, out);
  out << "with each pair's translation as an unknown direction (distance across the epipolar "
         "line)";
  if (!result.translation_inherits.empty()) {
    out << ", the gyro's calibration from the rotation-only fit (";
    for (size_t i = 0; i < result.translation_inherits.size(); ++i) {
      out << (i ? ", " : "") << result.translation_inherits[i];
    }
    out << ")";
  }
  out << ":\n";
  WriteLoopSummary(result.translation_loop, out);
  out << "  mean square per residual component over the same points (largest "
      << FormatNumber("%.0f", 100 * kCompareTrimShare) << " % of either left out): rotation only "
      << FormatNumber("%.4f", result.rotation_mean_sq_px2) << " px^2, with translation "
      << FormatNumber("%.4f", result.translation_mean_sq_px2) << " px^2, noise "
      << FormatNumber("%.4f", noise * noise / 2) << " px^2\n";
  if (result.loop.unexplained) {
    out << "  translation explains " << FormatNumber("%.0f", 100 * result.translation_explains)
        << " % of the rotation-only residual's excess over the noise";
  } else {
    out << "  rotation alone leaves the noise: nothing for translation to explain";
  }
  out << "; preferred model: " << result.preferred << "\n";
  for (const HalfCheck& h : result.halves) {
    out << "\nstability: " << h.model << " effects on pairs 1-" << h.first_pairs << " and "
        << h.first_pairs + 1 << "-" << h.first_pairs + h.second_pairs << ":\n";
    for (const HalfAgreement& a : h.effects) {
      out << "  " << Spec(a.effect).name << ": " << Rounded(EffectValueToJson(a.first)).dump()
          << " +- " << Rounded(EffectValueToJson(a.first_stderr)).dump() << " | "
          << Rounded(EffectValueToJson(a.second)).dump() << " +- "
          << Rounded(EffectValueToJson(a.second_stderr)).dump() << " -> ";
      if (!a.determined) {
        out << "not determined (a half has no standard error)\n";
        continue;
      }
      out << (std::isfinite(a.distance) ? FormatNumber("%.2f", a.distance) : std::string("inf"))
          << " (Mahalanobis), " << (a.agree ? "agree" : "DISAGREE") << "\n";
    }
  }
  if (!result.claims.empty()) out << "\nthe source's claims (import.json) against the data:\n";
  for (const ClaimCheck& c : result.claims) {
    out << "  " << c.claim << " (" << c.status << "): " << c.verdict << "\n";
  }
  out << "\ntime: read " << FormatNumber("%.2f", result.read_s) << " s, measure "
      << FormatNumber("%.2f", result.measure_s) << " s, loop "
      << FormatNumber("%.2f", result.loop_s) << " s\n";
  return out.str();
}

}  // namespace shutterlab
