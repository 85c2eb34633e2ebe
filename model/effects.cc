#include "model/effects.h"

#include "sim/check.h"
#include "sim/so3.h"
#include "sim/text_file.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace shutterlab {

namespace {

double Sd(double variance) {
  return variance >= 0 ? std::sqrt(variance) : std::numeric_limits<double>::quiet_NaN();
}

// --- the shapes most effects share

// Steps of 1e-5 and 1e-4 in the parameter's own unit.
double Step1e5(int, double) { return 1e-5; }
double Step1e4(int, double) { return 1e-4; }
EffectValue FirstSd(const TrueModel&, const Eigen::MatrixXd&, const Eigen::VectorXd& sd) {
  return sd[0];
}
EffectValue ThreeSd(const TrueModel&, const Eigen::MatrixXd&, const Eigen::VectorXd& sd) {
  return Eigen::Vector3d(sd[0], sd[1], sd[2]);
}

// --- physical bounds: what a real device can have (docs/FORMATS.md "Physical bounds")

// "V UNIT, outside LO ... HI UNIT: why" for v outside [lo, hi] (in the value's unit; `scale`
// turns it into the message's unit), else "".
std::string Outside(double v, double lo, double hi, double scale, const std::string& unit,
                    const std::string& why) {
  if (v >= lo && v <= hi) return "";
  const std::string u = unit.empty() ? "" : " " + unit;
  return FormatNumber("%.5g", v * scale) + u + ", outside " + FormatNumber("%g", lo * scale) +
         " ... " + FormatNumber("%g", hi * scale) + u + ": " + why;
}

// --- the table, one function per effect in docs/FORMATS.md's order

// Steps: small enough that the model is linear over them (the displacements move by ~1e-3 px)
// and large enough that rounding (~1e-13 px) is far below the differences.

EffectSpec TimeOffsetSpec() {
  EffectSpec s;
  s.effect = Effect::kTimeOffset;
  s.name = "time_offset";
  s.unit = "s";
  s.shape = EffectShape::kNumber;
  s.parameter_count = 1;
  s.step = Step1e5;  // s
  s.apply_delta = [](const double* x, TrueModel* m) { m->rig.time_offset_s += x[0]; };
  s.inject = [](const EffectValue& v, TrueModel* m) -> EffectValue {
    m->rig.time_offset_s = std::get<double>(v);
    return m->rig.time_offset_s;
  };
  s.value = [](const TrueModel& m) -> EffectValue { return m.rig.time_offset_s; };
  s.stderr_value = FirstSd;
  s.claim = "time_offset_s";
  s.bounds = PhysicalBounds{-1.0, 1.0, 1e3, "ms",
                            "a camera and a gyro on clocks that were set together at all differ by "
                            "milliseconds; over a second the log is not of these frames' time"};
  return s;
}

EffectSpec ReadoutTimeSpec() {
  EffectSpec s;
  s.effect = Effect::kReadoutTime;
  s.name = "readout_time";
  s.unit = "s";
  s.shape = EffectShape::kNumber;
  s.parameter_count = 1;
  s.step = Step1e5;  // s
  s.apply_delta = [](const double* x, TrueModel* m) { m->rig.shutter.readout_s += x[0]; };
  s.inject = [](const EffectValue& v, TrueModel* m) -> EffectValue {
    m->rig.shutter.readout_s = std::get<double>(v);
    SHUTTERLAB_CHECK(m->rig.shutter.readout_s > 0) << "--inject readout_time must be positive";
    return m->rig.shutter.readout_s;
  };
  s.value = [](const TrueModel& m) -> EffectValue { return m.rig.shutter.readout_s; };
  s.stderr_value = FirstSd;
  s.claim = "readout_s";
  s.bounds = PhysicalBounds{1e-4, 0.1, 1e3, "ms",
                            "sensors read a frame in 1 to 60 ms (the readout table's cameras, "
                            "model/readout_table.h)"};
  return s;
}

EffectSpec GyroToCameraSpec() {
  EffectSpec s;
  s.effect = Effect::kGyroToCamera;
  s.name = "gyro_to_camera";
  s.shape = EffectShape::kMatrix3;
  s.parameter_count = 3;
  s.step = Step1e4;  // rad
  s.apply_delta = [](const double* x, TrueModel* m) {
    m->rig.cam_from_gyro =
        ExpSO3(Eigen::Vector3d(x[0], x[1], x[2])).toRotationMatrix() * m->rig.cam_from_gyro;
  };
  s.inject = [](const EffectValue& v, TrueModel* m) -> EffectValue {
    m->rig.cam_from_gyro = std::get<Eigen::Matrix3d>(v);
    SHUTTERLAB_CHECK(IsRotationMatrix(m->rig.cam_from_gyro, 1e-6))
        << "--inject gyro_to_camera is not a rotation";
    return m->rig.cam_from_gyro;
  };
  s.value = [](const TrueModel& m) -> EffectValue { return m.rig.cam_from_gyro; };
  s.stderr_value = [](const TrueModel& m, const Eigen::MatrixXd& covariance,
                      const Eigen::VectorXd&) -> EffectValue {
    // R = Exp(x) R_0 with x near 0: dR/dx_k = Hat(e_k) R (first order), entry by entry.
    const Eigen::Matrix3d& r = m.rig.cam_from_gyro;
    Eigen::Matrix<double, 9, 3> d_entries_d_x;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Matrix3d d = Hat(Eigen::Vector3d::Unit(k)) * r;
      for (int i = 0; i < 9; ++i) d_entries_d_x(i, k) = d(i / 3, i % 3);
    }
    const Eigen::Matrix<double, 9, 9> cov = d_entries_d_x * covariance * d_entries_d_x.transpose();
    Eigen::Matrix3d out;
    for (int i = 0; i < 9; ++i) out(i / 3, i % 3) = Sd(cov(i, i));
    return out;
  };
  s.identifiable_with_pair_translation = false;
  s.claim = "gyro_to_camera";
  return s;
}

EffectSpec GyroScaleSpec() {
  EffectSpec s;
  s.effect = Effect::kGyroScale;
  s.name = "gyro_scale";
  s.shape = EffectShape::kVector3;
  s.parameter_count = 3;
  s.step = Step1e4;
  s.apply_delta = [](const double* x, TrueModel* m) {
    m->gyro_scale += Eigen::Vector3d(x[0], x[1], x[2]);
  };
  s.inject = [](const EffectValue& v, TrueModel* m) -> EffectValue {
    m->gyro_scale = std::get<Eigen::Vector3d>(v);
    return m->gyro_scale;
  };
  s.value = [](const TrueModel& m) -> EffectValue { return m.gyro_scale; };
  s.stderr_value = ThreeSd;
  s.identifiable_with_pair_translation = false;
  s.bounds =
      PhysicalBounds{0.9, 1.1, 1.0, "",
                     "a MEMS gyro's sensitivity is within 3 % of nominal (MPU-9250 datasheet, "
                     "sensitivity scale factor tolerance), 10 % allowed"};
  return s;
}

EffectSpec GyroBiasSpec() {
  EffectSpec s;
  s.effect = Effect::kGyroBias;
  s.name = "gyro_bias";
  s.unit = "rad/s";
  s.shape = EffectShape::kVector3;
  s.parameter_count = 3;
  s.step = Step1e4;  // rad/s
  s.apply_delta = [](const double* x, TrueModel* m) {
    m->gyro_bias_rad_s += Eigen::Vector3d(x[0], x[1], x[2]);
  };
  s.inject = [](const EffectValue& v, TrueModel* m) -> EffectValue {
    m->gyro_bias_rad_s = std::get<Eigen::Vector3d>(v);
    return m->gyro_bias_rad_s;
  };
  s.value = [](const TrueModel& m) -> EffectValue { return m.gyro_bias_rad_s; };
  s.stderr_value = ThreeSd;
  s.identifiable_with_pair_translation = false;
  s.bounds = PhysicalBounds{-10.0 * M_PI / 180.0, 10.0 * M_PI / 180.0, 180.0 / M_PI, "deg/s",
                            "a MEMS gyro's zero-rate output is within 5 deg/s at turn-on (MPU-9250 "
                            "datasheet, initial ZRO tolerance), 10 deg/s allowed"};
  return s;
}

EffectSpec VelocitySpec() {
  EffectSpec s;
  s.effect = Effect::kVelocity;
  s.name = "velocity";
  s.unit = "m/s";
  s.shape = EffectShape::kVector3;
  s.parameter_count = 3;
  s.step = [](int, double) { return 1e-2; };  // m/s
  s.apply_delta = [](const double* x, TrueModel* m) {
    m->rig.velocity_mps += Eigen::Vector3d(x[0], x[1], x[2]);
  };
  s.inject = [](const EffectValue& v, TrueModel* m) -> EffectValue {
    m->rig.velocity_mps = std::get<Eigen::Vector3d>(v);
    return m->rig.velocity_mps;
  };
  s.value = [](const TrueModel& m) -> EffectValue { return m.rig.velocity_mps; };
  s.stderr_value = ThreeSd;
  s.bounds = PhysicalBounds{-100.0, 100.0, 1.0, "m/s",
                            "no mapping drone, FPV quad or car films at over 100 m/s"};
  // The pair translation replaces it (and video's rotation-only model has none).
  s.identifiable_with_pair_translation = false;
  // Stills: 92 of 117 parameters within 2 standard errors (79 %), |z| up to 4.7.
  s.stderr_fails_in = {FitModel::kStill};
  return s;
}

EffectSpec LensDistortionSpec() {
  EffectSpec s;
  s.effect = Effect::kLensDistortion;
  s.name = "lens_distortion";
  s.shape = EffectShape::kLens;
  s.parameter_count = 2;
  s.step = Step1e4;
  s.apply_delta = [](const double* x, TrueModel* m) {
    AddToK1K2(x[0], x[1], &m->rig.camera.distortion);
  };
  s.inject = [](const EffectValue& v, TrueModel* m) -> EffectValue {
    const LensDistortion& lens = std::get<LensDistortion>(v);
    const LensDistortion& declared = m->rig.camera.distortion;
    if (lens.index() != declared.index()) {
      // docs/FORMATS.md: the true distortion in the declared camera's model. Another model is not
      // an effect that a fit of the declared one could find.
      throw std::invalid_argument(std::string("--inject lens_distortion: a ") +
                                  LensModelName(lens) + " lens for a camera declared " +
                                  LensModelName(declared) + " (give the declared model's " +
                                  "coefficients, or declare the other model in camera.json)");
    }
    m->rig.camera.distortion = lens;
    return lens;
  };
  s.value = [](const TrueModel& m) -> EffectValue {
    const LensDistortion& lens = m.rig.camera.distortion;
    if (const auto* brown = std::get_if<BrownConrady>(&lens)) {
      return LensDistortion(BrownConrady{{brown->coeffs[0], brown->coeffs[1], 0, 0, 0}});
    }
    return lens;
  };
  s.stderr_value = [](const TrueModel& m, const Eigen::MatrixXd&,
                      const Eigen::VectorXd& sd) -> EffectValue {
    if (std::holds_alternative<BrownConrady>(m.rig.camera.distortion)) {
      return LensDistortion(BrownConrady{{sd[0], sd[1], 0, 0, 0}});
    }
    constexpr double kHeld = std::numeric_limits<double>::quiet_NaN();  // k3, k4: not fitted
    return LensDistortion(Fisheye({sd[0], sd[1], kHeld, kHeld}));
  };
  // Pair translation: 2 of 4 covered, |z| up to 13. Rotation-only: 51 of 66 parameters (77 %),
  // |z| up to 6.8; stills: 25 of 32 (78 %), up to 4.2 (k1 and k2 are nearly one direction on a
  // 16-frame clip or 8 stills).
  s.stderr_fails_in = {FitModel::kStill, FitModel::kRotationOnly, FitModel::kPairTranslation};
  return s;
}

EffectSpec ReadoutDirectionSpec() {
  EffectSpec s;
  s.effect = Effect::kReadoutDirection;
  s.name = "readout_direction";
  s.shape = EffectShape::kDirection;
  s.parameter_count = 0;
  s.step = [](int, double) { return 1.0; };  // no parameter to step
  s.apply_delta = [](const double*, TrueModel* m) {
    m->rig.shutter.direction = m->rig.shutter.direction == ReadoutDirection::kTopToBottom
                                   ? ReadoutDirection::kBottomToTop
                                   : ReadoutDirection::kTopToBottom;
  };
  s.inject = [](const EffectValue& v, TrueModel* m) -> EffectValue {
    const ReadoutDirection direction = std::get<ReadoutDirection>(v);
    if (!IsRowReadout(direction)) {
      throw std::invalid_argument(std::string("--inject readout_direction: '") +
                                  ReadoutDirectionName(direction) +
                                  "' is not top_to_bottom or bottom_to_top");
    }
    m->rig.shutter.direction = direction;
    return direction;
  };
  s.value = [](const TrueModel& m) -> EffectValue { return m.rig.shutter.direction; };
  s.stderr_value = [](const TrueModel&, const Eigen::MatrixXd&,
                      const Eigen::VectorXd&) -> EffectValue { return std::monostate(); };
  s.claim = "direction";
  return s;
}

EffectSpec ClockRateSpec() {
  EffectSpec s;
  s.effect = Effect::kClockRate;
  s.name = "clock_rate";
  s.unit = "ppm";
  // A clock rate is only defined together with an offset: docs/FORMATS.md counts it from camera
  // time 0, which a log's clock may have passed long ago (frames at t = 1000 s: 3 ppm is 3 ms).
  s.shape = EffectShape::kNumber;
  s.parameter_count = 2;  // ppm, s
  s.step = [](int i, double frames_span_s) {
    return i == 0 ? 1e-5 / std::max(frames_span_s, 1.0) * 1e6 : 1e-5;  // ppm, s
  };
  s.apply_delta = [](const double* x, TrueModel* m) {
    m->clock_rate_ppm += x[0];
    m->rig.time_offset_s += x[1];
  };
  s.inject = [](const EffectValue& v, TrueModel* m) -> EffectValue {
    m->clock_rate_ppm = std::get<double>(v);
    return m->clock_rate_ppm;
  };
  s.value = [](const TrueModel& m) -> EffectValue { return m.clock_rate_ppm; };
  s.stderr_value = FirstSd;  // the rate's, not the offset's
  s.bounds =
      PhysicalBounds{-2e4, 2e4, 1.0, "ppm",
                     "a crystal keeps within 100 ppm and a MEMS part's own oscillator within "
                     "about 1 %, 2 % allowed"};
  s.stderr_fails_in = {FitModel::kPairTranslation};  // 1 of 4 covered, |z| up to 29
  return s;
}

std::vector<EffectSpec> MakeTable() {
  std::vector<EffectSpec> table = {
      TimeOffsetSpec(),     ReadoutTimeSpec(),      GyroToCameraSpec(),
      GyroScaleSpec(),      GyroBiasSpec(),         VelocitySpec(),
      LensDistortionSpec(), ReadoutDirectionSpec(), ClockRateSpec(),
  };
  for (size_t i = 0; i < table.size(); ++i) {
    SHUTTERLAB_CHECK(table[i].effect == static_cast<Effect>(i))
        << "the effect table is not in the enum's order at " << table[i].name;
  }
  return table;
}

}  // namespace

const char* EffectShapeWords(EffectShape shape) {
  switch (shape) {
    case EffectShape::kNumber:
      return "a number";
    case EffectShape::kVector3:
      return "3 numbers";
    case EffectShape::kMatrix3:
      return "a 3x3 matrix";
    case EffectShape::kLens:
      return "lens coefficients";
    case EffectShape::kDirection:
      return "a readout direction";
  }
  return "a value";
}

bool HasShape(const EffectValue& value, EffectShape shape) {
  switch (shape) {
    case EffectShape::kNumber:
      return std::holds_alternative<double>(value);
    case EffectShape::kVector3:
      return std::holds_alternative<Eigen::Vector3d>(value);
    case EffectShape::kMatrix3:
      return std::holds_alternative<Eigen::Matrix3d>(value);
    case EffectShape::kLens:
      return std::holds_alternative<LensDistortion>(value);
    case EffectShape::kDirection:
      return std::holds_alternative<ReadoutDirection>(value);
  }
  return false;
}

const std::vector<EffectSpec>& AllEffects() {
  static const std::vector<EffectSpec> table = MakeTable();
  return table;
}

const EffectSpec& Spec(Effect effect) { return AllEffects().at(static_cast<size_t>(effect)); }

const char* FitModelName(FitModel model) {
  switch (model) {
    case FitModel::kStill:
      return "still";
    case FitModel::kRotationOnly:
      return "rotation-only";
    case FitModel::kPairTranslation:
      return "pair-translation";
  }
  return "still";
}

std::string BoundedEffectNames() {
  std::string names;
  for (const EffectSpec& spec : AllEffects()) {
    if (spec.bounds) names += (names.empty() ? "" : ", ") + spec.name;
  }
  return names;
}

std::string OutOfBounds(Effect effect, const EffectValue& value, const RigModel* rig) {
  const EffectSpec& spec = Spec(effect);
  if (!spec.bounds) return "";
  PhysicalBounds b = *spec.bounds;
  std::string why = b.why;
  if (rig != nullptr) {
    const auto given = rig->bounds.find(spec.name);
    if (given != rig->bounds.end()) {
      b.lo = given->second[0];
      b.hi = given->second[1];
      why = "camera.json's bounds for " + spec.name;
    }
  }
  if (const double* v = std::get_if<double>(&value)) {
    return Outside(*v, b.lo, b.hi, b.scale, b.unit, why);
  }
  const Eigen::Vector3d& v = std::get<Eigen::Vector3d>(value);
  for (int a = 0; a < 3; ++a) {
    const std::string outside = Outside(v[a], b.lo, b.hi, b.scale, b.unit, why);
    if (!outside.empty()) return std::string("axis ") + "xyz"[a] + " at " + outside;
  }
  return "";
}

std::optional<Effect> ParseEffect(std::string_view name) {
  for (const EffectSpec& s : AllEffects()) {
    if (s.name == name) return s.effect;
  }
  return std::nullopt;
}

Effect RequireEffect(std::string_view name, const std::string& where) {
  if (const std::optional<Effect> effect = ParseEffect(name)) return *effect;
  std::string known;
  for (const EffectSpec& s : AllEffects()) known += (known.empty() ? "" : ", ") + s.name;
  throw std::invalid_argument(where + ": unknown effect '" + std::string(name) +
                              "' (known: " + known + ")");
}

EffectValue ApplyInjection(const Injection& injection, TrueModel* model) {
  const EffectSpec& spec = Spec(injection.effect);
  if (!HasShape(injection.value, spec.shape)) {
    throw std::invalid_argument("--inject " + spec.name + ": expected " +
                                EffectShapeWords(spec.shape));
  }
  // On a copy, so that a rejected value leaves *model as it was.
  TrueModel injected = *model;
  EffectValue recorded = spec.inject(injection.value, &injected);
  injected.Check();
  *model = injected;
  return recorded;
}

EffectValue EffectStderr(Effect effect, const TrueModel& model, const Eigen::MatrixXd& covariance) {
  const EffectSpec& spec = Spec(effect);
  const int n = spec.parameter_count;
  if (n == 0) return std::monostate();
  SHUTTERLAB_CHECK(covariance.rows() == n && covariance.cols() == n)
      << spec.name << ": covariance is " << covariance.rows() << "x" << covariance.cols();
  // A negative or NaN variance is an undetermined parameter: NaN (null in JSON), not 0.
  const Eigen::VectorXd sd = covariance.diagonal().unaryExpr([](double v) { return Sd(v); });
  return spec.stderr_value(model, covariance, sd);
}

}  // namespace shutterlab
