#include "estimate/report/validate_verdict.h"

#include "estimate/report/loop_json.h"
#include "model/effect_io.h"
#include "sim/gyro_trace.h"
#include "sim/text_file.h"

#include <nlohmann/json.hpp>

#include <cctype>
#include <cmath>
#include <sstream>

namespace shutterlab {
namespace {

// Share of the points the screening left out beyond which the verdict asks to look at the region.
constexpr double kManyLeftOut = 0.3;

std::string Percent(double share) { return FormatNumber("%.0f", 100 * share) + " %"; }

// A value with its standard error for a person: seconds as ms, numbers at 4 digits, else JSON.
std::string ValueText(const EffectSpec& spec, const EffectValue& value, const EffectValue& se) {
  const double* v = std::get_if<double>(&value);
  const double* s = std::get_if<double>(&se);
  if (v != nullptr && spec.unit == "s") {
    return FormatNumber("%.3f", *v * 1e3) +
           (s && std::isfinite(*s) ? " ± " + FormatNumber("%.3f", *s * 1e3) : "") + " ms";
  }
  std::string text = EffectValueText(value);
  if (!std::holds_alternative<std::monostate>(se)) text += " ± " + EffectValueText(se);
  return text + (spec.unit.empty() ? "" : " " + spec.unit);
}

// The loop whose effects the report gives (video: the preferred model's).
const LoopResult& PreferredLoop(const ValidationResult& result) {
  return result.video && result.preferred == "translation" ? result.translation_loop : result.loop;
}

double NoiseRatio(const LoopResult& loop) {
  return loop.noise_px > 0
             ? loop.after.rms_px / loop.noise_px / std::sqrt(loop.residual_components / 2.0)
             : 0.0;
}

// "readout_time = 23.47 ± 0.59 ms (declared 33.31 ms)" for each effect.
std::vector<std::string> EffectLines(const ValidationResult& result, const LoopResult& loop) {
  TrueModel declared;
  declared.rig = result.declared;
  std::vector<std::string> lines;
  for (const IdentifiedEffect& e : loop.effects) {
    const EffectSpec& spec = Spec(e.effect);
    const EffectValue se = e.stderr_withheld.empty() ? e.stderr_value : EffectValue{};
    const std::string declared_text = ValueText(spec, spec.value(declared), std::monostate{});
    lines.push_back(spec.name + " = " + ValueText(spec, e.value, se) +
                    (e.stderr_withheld.empty() ? " (declared " + declared_text + ")"
                                               : ", with no standard error (" + e.stderr_withheld +
                                                     "; declared " + declared_text + ")"));
  }
  return lines;
}

std::string Joined(const std::vector<std::string>& parts, const std::string& last_separator) {
  std::string out;
  for (size_t i = 0; i < parts.size(); ++i) {
    out += (i == 0 ? "" : i + 1 == parts.size() ? last_separator : ", ") + parts[i];
  }
  return out;
}

// How sure: the standard errors' kind and clusters, the halves, what was left out.
std::string Certainty(const ValidationResult& result, const LoopResult& loop) {
  std::ostringstream out;
  const std::string unit = result.video ? "pairs" : "frames";
  if (!loop.effects.empty()) {
    const IdentifiedEffect& e = loop.effects.front();
    out << "Standard errors: " << CovarianceKindName(e.stderr_from) << " over " << e.clusters << " "
        << unit
        << (e.stderr_from == CovarianceKind::kClusterJackknife
                ? " (each refit without one of them; scaled to a t interval)"
                : "")
        << ". ";
  }
  for (const HalfCheck& h : result.halves) {
    bool agree = true, determined = true;
    for (const HalfAgreement& a : h.effects) {
      agree = agree && a.agree;
      determined = determined && a.determined;
    }
    out << "The two halves of the clip "
        << (!determined ? "do not both determine the effects"
            : agree     ? "agree within their standard errors"
                        : "DISAGREE beyond their standard errors")
        << ". ";
  }
  const PointScreen& s = result.screen;
  out << "Residual after the fit: " << FormatNumber("%.2f", NoiseRatio(loop))
      << "x the measurement noise over " << loop.after.points
      << " points; left out before the fit: " << Percent(s.camera_fixed_share)
      << " in a region that moves with the camera, " << Percent(s.moving_share)
      << " moving on their own"
      << (result.video ? ", " + Percent(s.off_epipolar_share) + " off their epipolar lines" : "")
      << (result.mask.empty() ? "" : ", and the masked pixels") << ".";
  return out.str();
}

std::string ConfigLine(const LoopResult& loop) {
  std::vector<std::string> parts;
  for (const IdentifiedEffect& e : loop.effects) {
    parts.push_back(Spec(e.effect).name + " = " + Rounded(EffectValueToJson(e.value)).dump());
  }
  return Joined(parts, " and ");
}

}  // namespace

const char* VerdictLevelName(ValidationVerdict::Level level) {
  switch (level) {
    case ValidationVerdict::Level::kOk:
      return "ok";
    case ValidationVerdict::Level::kAttention:
      return "attention";
    case ValidationVerdict::Level::kProblem:
      return "problem";
  }
  return "?";
}

namespace {

// The fitted effects no real device can have, each "NAME = VALUE: why" (empty when none).
std::vector<std::string> OutOfBoundsLines(const LoopResult& loop) {
  std::vector<std::string> lines;
  for (const IdentifiedEffect& e : loop.effects) {
    if (e.out_of_bounds.empty()) continue;
    lines.push_back(Spec(e.effect).name + " " + e.out_of_bounds);
  }
  return lines;
}

// What to trust less: many points left out, halves of a clip that disagree.
void AddCautions(const ValidationResult& result, ValidationVerdict* v) {
  const PointScreen& s = result.screen;
  if (s.camera_fixed_share + s.moving_share > kManyLeftOut) {
    v->actions.push_back(Percent(s.camera_fixed_share + s.moving_share) +
                         " of the points were left out before the fit: check the region drawn "
                         "below, and give --mask where it is wrong.");
  }
  for (const HalfCheck& h : result.halves) {
    for (const HalfAgreement& a : h.effects) {
      if (a.determined && !a.agree) {
        v->actions.push_back("The halves disagree on " + Spec(a.effect).name +
                             ": the value may change during the clip; trust it less than its "
                             "standard error says.");
      }
    }
  }
}

// A stabiliser on some camera axes only (ValidationResult::axes_not_following): which axes, how
// fast the image turns about them against the gyro, and that the loop ran on the others. The
// headline when the loop found the declared model right on those; a finding otherwise.
void AddAxesNotFollowing(const ValidationResult& result, ValidationVerdict* v) {
  if (!result.axes_not_following) return;
  const GyroFollowCheck& check = *result.axes_not_following;
  std::vector<std::string> off, off_gains, on, on_gains;
  bool roll = false;
  for (int a = 0; a < 3; ++a) {
    const AxisFollow& f = check.axes[a];
    if (!f.follows) {
      const bool whole = f.determined && f.row_norm < kMinGain;
      roll = roll || a == 2;
      off.push_back(kAxisNames[a]);
      off_gains.push_back(FormatNumber("%.2fx", whole ? f.row_norm : f.fast_row_norm) +
                          (whole ? "" : " in the fast part of the motion") + " about " +
                          kAxisNames[a]);
    } else {
      on.push_back(kAxisNames[a]);
      on_gains.push_back(f.determined ? FormatNumber("%.2fx", f.row_norm) : "not determined");
    }
  }
  const bool one = off.size() == 1;
  const std::string off_axes = Joined(off, " and "), on_axes = Joined(on, " and ");
  const std::string sentence =
      "A stabiliser re-renders the image about camera " + std::string(one ? "axis " : "axes ") +
      off_axes + (roll && one ? ", the optical axis (roll, as horizon levelling does)" : "") +
      ": the image turns " + Joined(off_gains, " and ") +
      " as fast as the gyro says, while about " + on_axes + " it follows (" +
      Joined(on_gains, ", ") + "). The loop took the image's own rotation about " + off_axes +
      " and the gyro's about " + on_axes + ".";
  if (v->level == ValidationVerdict::Level::kOk) {
    v->level = ValidationVerdict::Level::kAttention;
    std::string rest = v->headline;
    if (!rest.empty())
      rest[0] = static_cast<char>(std::tolower(static_cast<unsigned char>(rest[0])));
    v->headline = sentence + " About " + on_axes + ", " + rest;
    v->actions.push_back(
        "To test the sensor about every axis, record with the stabiliser (horizon levelling) off.");
  } else {
    v->findings.insert(v->findings.begin(), sentence);
  }
}

}  // namespace

ValidationVerdict MakeVerdict(const ValidationResult& result) {
  ValidationVerdict v;
  const LoopResult& loop = PreferredLoop(result);
  const std::vector<std::string> impossible = OutOfBoundsLines(loop);
  const std::vector<std::string> effects = EffectLines(result, loop);
  const GyroFollowCheck& follow = result.screen.gyro_follow;
  const std::string noise = FormatNumber("%.2f", NoiseRatio(loop)) + "x the measurement noise";
  if (result.video && result.image_orientation.holds) {
    const ImageOrientationCheck& o = result.image_orientation;
    v.level = ValidationVerdict::Level::kProblem;
    v.headline =
        "A stabiliser re-rendered the image: it follows the gyro only turned by the stabiliser's "
        "own per-frame rotation (IORI; " +
        FormatNumber("%.2f", o.applied_gain) + "x as fast, where the gyro alone gives " +
        FormatNumber("%.2f", o.raw_gain) +
        "x). The images are its output, not the sensor's rows, so no rolling-shutter effect of "
        "the sensor can be read from them.";
    v.actions.push_back(
        "Record with the stabiliser off (GoPro: HyperSmooth / EIS off), or validate the camera's "
        "unstabilised footage.");
  } else if (result.video && follow.determined && !follow.follows) {
    v.level = ValidationVerdict::Level::kProblem;
    v.headline = "The image does not follow the gyro: it turns " +
                 FormatNumber("%.2f", follow.gain) + "x as fast as the gyro says (median over " +
                 std::to_string(follow.pairs_tested) +
                 " pairs). A stabiliser re-rendered it, in the camera or afterwards, so no "
                 "rolling-shutter effect of the sensor can be read from this footage.";
    v.actions.push_back(
        "Record with the stabiliser off (GoPro: HyperSmooth / EIS off; phones: video "
        "stabilisation off), or validate the camera's unstabilised footage.");
  } else if (!impossible.empty()) {
    // The fit explains the residual only with a value no sensor has: naming it as the fix would
    // hide what really moves the image.
    v.level = ValidationVerdict::Level::kProblem;
    v.headline = "No effect of the sensor explains this: the fit needs " +
                 Joined(impossible, "; and ") +
                 ". That points elsewhere: a stabiliser or re-rendering that turns the image on "
                 "its own, a wrong axis mapping (gyro_to_camera), or the wrong camera in "
                 "camera.json.";
    v.actions.push_back(
        "Check camera.json's gyro_to_camera and intrinsics against the camera, record with any "
        "stabiliser off, and validate again; do not put these values into camera.json.");
  } else if (loop.unexplained) {
    v.level = ValidationVerdict::Level::kProblem;
    v.headline = "Something the model lacks moves the image: " +
                 (effects.empty() ? "no effect explains the residual, which stays at " + noise
                                  : "even with " + Joined(effects, " and ") +
                                        " the residual stays at " + noise) +
                 ".";
    v.actions.push_back(
        "Look at the residual pictures below: a part of the frame that moves with the camera and "
        "was not found (mask it with --mask), a lens that camera.json does not declare, or "
        "motion the model does not hold.");
  } else if (!effects.empty()) {
    v.level = ValidationVerdict::Level::kAttention;
    v.headline =
        "The declared camera model is off: the data show " + Joined(effects, " and ") + ".";
    v.actions.push_back("Put " + ConfigLine(loop) +
                        " into camera.json (docs/FORMATS.md names and units) and validate again.");
  } else {
    v.headline = "The declared camera model explains the measured motion to the noise level (" +
                 noise + "): there is nothing to correct.";
  }
  if (result.image_orientation.present) {
    v.findings.push_back(
        "The stabiliser's own rotation (IORI): " + result.image_orientation.verdict + ".");
  }
  if (result.video && result.preferred == "translation" && !ReRenderedByStabiliser(result)) {
    v.findings.push_back("The camera moved between frames: each pair's translation explains " +
                         Percent(result.translation_explains) +
                         " of what rotation alone leaves (parallax), so the fit uses it.");
  }
  for (const std::string& e : effects) v.findings.push_back(e);
  if (!result.video && !result.ratios.empty() && result.ratios.back().frames > 0) {
    const RatioGroup& all = result.ratios.back();
    v.findings.push_back("The paper's per-axis threshold model gives " +
                         FormatNumber("%.2f", all.paper_median) +
                         "x the measured distortion D (median over " + std::to_string(all.frames) +
                         " frames; below 1 it misses distortion).");
  }
  bool contradicted = false;
  for (const ClaimCheck& c : result.claims) {
    v.findings.push_back("The source's " + c.claim + " (" + c.status + "): " + c.verdict);
    contradicted = contradicted || c.verdict.rfind("claim contradicted", 0) == 0;
  }
  if (contradicted) {
    v.actions.push_back("Where the source's claim is contradicted, use the fitted value instead.");
  }
  v.certainty = Certainty(result, loop);
  AddCautions(result, &v);
  AddAxesNotFollowing(result, &v);
  return v;
}

nlohmann::json VerdictToJson(const ValidationVerdict& verdict) {
  return {{"level", VerdictLevelName(verdict.level)},
          {"headline", verdict.headline},
          {"findings", verdict.findings},
          {"certainty", verdict.certainty},
          {"actions", verdict.actions}};
}

std::string VerdictText(const ValidationVerdict& verdict) {
  std::string text =
      "VERDICT (" + std::string(VerdictLevelName(verdict.level)) + "): " + verdict.headline + "\n";
  for (const std::string& f : verdict.findings) text += "  - " + f + "\n";
  text += "  how sure: " + verdict.certainty + "\n";
  for (const std::string& a : verdict.actions) text += "  to do: " + a + "\n";
  return text;
}

}  // namespace shutterlab
