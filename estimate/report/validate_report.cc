#include "estimate/report/validate_report.h"

#include "estimate/paper/analyze.h"
#include "estimate/report/analysis_json.h"
#include "estimate/report/html_report.h"
#include "estimate/report/loop_json.h"
#include "estimate/report/validate_verdict.h"
#include "io/frames_csv.h"
#include "io/image_io.h"
#include "model/effect_io.h"
#include "render/pictures.h"
#include "render/rs_warp.h"
#include "sim/check.h"
#include "sim/gyro_trace.h"
#include "sim/text_file.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <sstream>
#include <utility>

namespace shutterlab {
namespace {

namespace fs = std::filesystem;

}  // namespace

void WriteLoopSummary(const LoopResult& loop, std::ostream& out) {
  out << "  before: rms " << FormatNumber("%.3f", loop.before.rms_px) << " px, max "
      << FormatNumber("%.3f", loop.before.max_px) << " px\n";
  for (const IdentifiedEffect& e : loop.effects) {
    out << "  + " << Spec(e.effect).name << " = " << Rounded(EffectValueToJson(e.value)).dump()
        << (e.stderr_withheld.empty() ? " +- " + Rounded(EffectValueToJson(e.stderr_value)).dump() +
                                            " " + Spec(e.effect).unit
                                      : " " + Spec(e.effect).unit + ", with no standard error (" +
                                            e.stderr_withheld + ")")
        << " -> rms " << FormatNumber("%.3f", e.after.rms_px) << " px, max "
        << FormatNumber("%.3f", e.after.max_px) << " px";
    if (!e.ambiguous_with.empty()) {
      out << " (ambiguous with";
      for (Effect other : e.ambiguous_with) out << " " << Spec(other).name;
      out << ")";
    }
    out << "\n";
  }
  if (loop.effects.empty()) out << "  no effect added\n";
  out << "  after: rms " << FormatNumber("%.3f", loop.after.rms_px) << " px, max "
      << FormatNumber("%.3f", loop.after.max_px)
      << " px ("
      // The noise of the residual's own components (1 of 2 across an epipolar line).
      << FormatNumber("%.2f", loop.noise_px > 0 ? loop.after.rms_px / loop.noise_px /
                                                      std::sqrt(loop.residual_components / 2.0)
                                                : 0.0)
      << "x noise); " << (loop.unexplained ? "UNEXPLAINED residual remains" : "explained") << "\n";
}

namespace {

nlohmann::json GyroFollowToJson(const GyroFollowCheck& g) {
  nlohmann::json axes = nlohmann::json::object();
  for (int a = 0; a < 3; ++a) {
    const AxisFollow& f = g.axes[a];
    // NaN (not determined) is null in JSON.
    const auto number = [](bool determined, double v) {
      return determined && std::isfinite(v) ? nlohmann::json(v) : nlohmann::json();
    };
    axes[kAxisNames[a]] = {
        {"determined", f.determined},
        {"gain", number(f.determined, f.gain)},
        {"row_norm", number(f.determined, f.row_norm)},
        {"row_norm_stderr", number(f.determined, f.row_norm_stderr)},
        {"fast_determined", f.fast_determined},
        {"fast_row_norm", number(f.fast_determined, f.fast_row_norm)},
        {"fast_row_norm_stderr", number(f.fast_determined, f.fast_row_norm_stderr)},
        {"follows", f.follows},
        {"clearly_follows", f.clearly_follows}};
  }
  return {{"determined", g.determined},
          {"follows", g.follows},
          {"gain", g.gain},
          {"pairs_tested", g.pairs_tested},
          {"verdict", g.verdict},
          {"frames", g.frames},
          {"gyro_rate_rad_s", g.gyro_rate_rad_s},
          {"image_rate_rad_s", g.image_rate_rad_s},
          {"axes", axes}};
}

}  // namespace

nlohmann::json ScreeningToJson(const ValidationResult& result) {
  const PointScreen& screen = result.screen;
  const CameraFixedRegion& region = screen.region;
  nlohmann::json out;
  out["mask"] = result.mask.empty() ? nlohmann::json() : nlohmann::json(result.mask_description);
  out["camera_fixed"] = {{"share_of_points", screen.camera_fixed_share},
                         {"cells", region.cells_fixed},
                         {"cells_testable", region.cells_testable},
                         {"cell_px", region.step_px},
                         {"whole_image", region.whole_image}};
  out["moving_share"] = screen.moving_share;
  if (result.video) {
    out["off_epipolar_share"] = screen.off_epipolar_share;
    out["gyro_follow"] = GyroFollowToJson(screen.gyro_follow);
    // A stabiliser on some axes: the first screening's check, before the image's own rotation
    // about them was given to the pairs.
    if (result.axes_not_following) {
      nlohmann::json& j = out["axes_not_following"] = GyroFollowToJson(*result.axes_not_following);
      j["not_following"] = nlohmann::json::array();
      for (int a : result.axes_not_following->AxesNotFollowing()) {
        j["not_following"].push_back(kAxisNames[a]);
      }
    }
  }
  return out;
}

void WriteScreeningSummary(const ValidationResult& result, std::ostream& out) {
  const PointScreen& screen = result.screen;
  const CameraFixedRegion& region = screen.region;
  const auto percent = [](double share) { return FormatNumber("%.1f", 100 * share) + " %"; };
  out << "left out before the loop:";
  if (!result.mask.empty()) out << " the pixels " << result.mask_description << " masks;";
  out << " " << percent(screen.camera_fixed_share)
      << " of the points in a region that moves with the camera (" << region.cells_fixed << " of "
      << region.cells_testable << " cells of " << region.step_px << " px)";
  if (region.whole_image) out << " [none: the whole image stays, see below]";
  out << ", " << percent(screen.moving_share) << " that no single camera motion of their "
      << (result.video ? "pair" : "frame") << " explains";
  if (result.video) {
    out << "; with pair translation, " << percent(screen.off_epipolar_share)
        << " off their pair's epipolar geometry";
  }
  out << "\n";
  if (result.axes_not_following) {
    out << "image against gyro, per axis: " << result.axes_not_following->verdict << "\n";
  }
  if (result.video) out << "image against gyro: " << screen.gyro_follow.verdict << "\n";
}

namespace {

nlohmann::json StillValidationToJson(const ValidationResult& result) {
  nlohmann::json json = LoopToJson(result.loop, result.frames.size());
  json["dataset"] = result.dataset;
  json["limits_m"] = result.limits_m;
  nlohmann::json frames = nlohmann::json::array();
  for (const FrameValidation& f : result.frames) {
    nlohmann::json flags = nlohmann::json::object();
    for (size_t l = 0; l < result.limits_m.size(); ++l) {
      flags[LimitKey(result.limits_m[l])] = {{"measured", bool(f.flag_meas[l])},
                                             {"full", bool(f.flag_full[l])},
                                             {"paper", bool(f.flag_paper[l])}};
    }
    frames.push_back({{"frame", f.frame},
                      {"image", f.image},
                      {"t_gyro_s", f.t_gyro_s},
                      {"points", f.points},
                      {"measured_fraction", f.measured_fraction},
                      {"noise_px", f.noise_px},
                      {"D_meas_px", f.d_meas_px},
                      {"D_meas_m", f.d_meas_m},
                      {"D_full_px", f.d_full_px},
                      {"D_full_m", f.d_full_m},
                      {"D_paper_m", f.d_paper_m},
                      {"D_vector_m", f.d_vector_m},
                      {"D_centre_px", f.d_centre_px},
                      {"range_arcsec", f.range_arcsec},
                      {"dominant_axis", kAxisNames[f.dominant_axis]},
                      {"flagged", flags},
                      {"before", {{"rms_px", f.before.rms_px}, {"max_px", f.before.max_px}}},
                      {"after", {{"rms_px", f.after.rms_px}, {"max_px", f.after.max_px}}}});
  }
  json["frames_detail"] = frames;
  nlohmann::json confusion = nlohmann::json::array();
  for (size_t l = 0; l < result.confusion_paper.size(); ++l) {
    for (const auto& [model, c] : {std::pair{"paper", result.confusion_paper[l]},
                                   std::pair{"full", result.confusion_full[l]}}) {
      confusion.push_back({{"model", model},
                           {"limit_m", c.limit_m},
                           {"true_positive", c.true_positive},
                           {"false_positive", c.false_positive},
                           {"false_negative", c.false_negative},
                           {"true_negative", c.true_negative}});
    }
  }
  json["confusion"] = confusion;
  nlohmann::json ratios = nlohmann::json::array();
  for (const RatioGroup& g : result.ratios) {
    ratios.push_back({{"dominant_axis", g.axis < 3 ? kAxisNames[g.axis] : "all"},
                      {"frames", g.frames},
                      {"paper_over_measured_min", g.paper_min},
                      {"paper_over_measured_median", g.paper_median},
                      {"paper_over_measured_max", g.paper_max},
                      {"vector_over_measured_median", g.vector_median},
                      {"full_over_measured_median", g.full_median},
                      {"centre_column_over_full_median", g.centre_median}});
  }
  json["ratios"] = ratios;
  json["screening"] = ScreeningToJson(result);
  json["timing_s"] = {{"read", result.read_s},
                      {"measure", result.measure_s},
                      {"predict", result.predict_s},
                      {"loop", result.loop_s}};
  json["log"] = result.loop.log;
  return json;
}

}  // namespace

nlohmann::json ValidationToJson(const ValidationResult& result) {
  nlohmann::json json =
      result.video ? VideoValidationToJson(result) : StillValidationToJson(result);
  json["warnings"] = WarningsToJson(result.warnings);
  json["verdict"] = VerdictToJson(MakeVerdict(result));
  if (result.lens_profile) json["lens_profile"] = LensProfileUseJson(*result.lens_profile);
  return json;
}

std::string LensProfileLines(const ValidationResult& result) {
  std::string out;
  if (result.lens_profile) {
    for (const std::string& note : result.lens_profile->notes) out += "  " + note + "\n";
  }
  return out;
}

std::string ValidationReport(const ValidationResult& result) {
  if (result.video) return VideoValidationReport(result) + "\n" + VerdictText(MakeVerdict(result));
  std::ostringstream out;
  const auto& limits = result.limits_m;
  out << "dataset " << result.dataset << ": " << result.frames.size() << " frames, "
      << result.declared.camera.width << "x" << result.declared.camera.height << ", f "
      << FormatNumber("%.1f", 0.5 * (result.declared.camera.fx + result.declared.camera.fy))
      << " px, readout " << FormatNumber("%.2f", result.declared.shutter.readout_s * 1e3) << " ms, "
      << FormatNumber("%g", result.declared.altitude_m) << " m\n"
      << LensProfileLines(result) << "\n";
  out << "frame  points  noise |  D_meas        |  D_full        | D_paper | D_vector | axis |"
         " flags M F P at";
  for (double l : limits) out << " " << FormatNumber("%g", l * 100) << "cm";
  out << "\n";
  out << "                  px |    px      cm  |    px      cm  |    cm   |    cm    |      |\n";
  for (const FrameValidation& f : result.frames) {
    char line[256];
    std::snprintf(line, sizeof(line),
                  "%5lld %7zu %6.3f | %6.2f %7.2f | %6.2f %7.2f | %7.2f | %8.2f |  %s   |",
                  static_cast<long long>(f.frame), f.points, f.noise_px, f.d_meas_px,
                  f.d_meas_m * 100, f.d_full_px, f.d_full_m * 100, f.d_paper_m * 100,
                  f.d_vector_m * 100, kAxisNames[f.dominant_axis]);
    out << line;
    for (size_t l = 0; l < limits.size(); ++l) {
      out << " " << (f.flag_meas[l] ? 'M' : '.') << (f.flag_full[l] ? 'F' : '.')
          << (f.flag_paper[l] ? 'P' : '.');
    }
    out << "\n";
  }
  out << "(M measured, F full model, P paper's model: D over the limit)\n\n";

  out << "paper's flags against the measured D (true pos / false pos / false neg / true neg):\n";
  for (size_t l = 0; l < limits.size(); ++l) {
    const Confusion& p = result.confusion_paper[l];
    const Confusion& f = result.confusion_full[l];
    char line[256];
    std::snprintf(
        line, sizeof(line), "  %5g cm: paper %d / %d / %d / %d   full model %d / %d / %d / %d\n",
        limits[l] * 100, p.true_positive, p.false_positive, p.false_negative, p.true_negative,
        f.true_positive, f.false_positive, f.false_negative, f.true_negative);
    out << line;
  }
  out << "\nD_model / D_meas by dominant axis (frames with D_meas >= " << kMinRatioDPx
      << " px; > 1: conservative):\n";
  for (const RatioGroup& g : result.ratios) {
    if (g.frames == 0) continue;
    const std::string name = g.axis == 0   ? "about x (image rows shift up/down)"
                             : g.axis == 1 ? "about y (image rows shift sideways)"
                             : g.axis == 2 ? "about z (yaw about the optical axis)"
                                           : "all frames";
    char line[320];
    std::snprintf(line, sizeof(line),
                  "  %-36s %2d frames: paper %.2f (%.2f-%.2f)  vector %.2f  full %.2f;"
                  " nadir column holds %.0f%% of D\n",
                  name.c_str(), g.frames, g.paper_median, g.paper_min, g.paper_max, g.vector_median,
                  g.full_median, 100 * g.centre_median);
    out << line;
  }
  const RatioGroup& all = result.ratios.back();
  if (all.frames > 0) {
    out << "  -> the paper's per-axis model is "
        << (all.paper_max < 1.0    ? "NOT conservative on any frame"
            : all.paper_min >= 1.0 ? "conservative on every frame"
                                   : "conservative on some frames only")
        << "; the vector angle gives " << FormatNumber("%.2f", all.vector_median / all.paper_median)
        << "x the per-axis D (median)\n";
  }

  const LoopResult& loop = result.loop;
  out << "\n";
  WriteScreeningSummary(result, out);
  out << "closing the loop over " << loop.before.points << " points (noise "
      << FormatNumber("%.3f", loop.noise_px)
      << " px; standard errors: " << CovarianceKindName(loop.covariance) << " over the frames):\n";
  WriteLoopSummary(loop, out);
  out << "\ntime: read " << FormatNumber("%.2f", result.read_s) << " s, measure "
      << FormatNumber("%.2f", result.measure_s) << " s, predict "
      << FormatNumber("%.2f", result.predict_s) << " s, loop "
      << FormatNumber("%.2f", result.loop_s) << " s\n\n";
  out << VerdictText(MakeVerdict(result));
  return out.str();
}

}  // namespace shutterlab
