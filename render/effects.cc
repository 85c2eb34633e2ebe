#include "render/effects.h"

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

using nlohmann::json;

// --- reading `--inject` values

// VALUE as JSON when it parses, else comma-separated numbers, else a bare word.
json ParseValue(const std::string& text) {
  json j = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (!j.is_discarded()) return j;
  std::vector<std::string_view> fields;
  SplitFields(text, ',', &fields);
  json numbers = json::array();
  for (std::string_view f : fields) {
    const std::optional<double> x = ParseDouble(f);
    if (!x) return json(text);
    numbers.push_back(*x);
  }
  return numbers.size() == 1 ? numbers[0] : numbers;
}

double Scalar(const json& j, Effect effect) {
  if (!j.is_number() || !std::isfinite(j.get<double>())) {
    throw std::invalid_argument("--inject " + Spec(effect).name + ": expected a number, got " +
                                j.dump());
  }
  return j.get<double>();
}

std::vector<double> Numbers(const json& j, Effect effect, size_t n) {
  json flat = json::array();
  if (j.is_array()) {
    for (const json& e : j) {
      if (e.is_array()) {
        for (const json& x : e) flat.push_back(x);
      } else {
        flat.push_back(e);
      }
    }
  }
  if (flat.size() != n) {
    throw std::invalid_argument("--inject " + Spec(effect).name + ": expected " +
                                std::to_string(n) + " numbers, got " + j.dump());
  }
  std::vector<double> out;
  for (const json& x : flat) out.push_back(Scalar(x, effect));
  return out;
}

Eigen::Vector3d Vector3(const json& j, Effect effect) {
  const std::vector<double> v = Numbers(j, effect, 3);
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

json Array3(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }

double Sd(double variance) {
  return variance >= 0 ? std::sqrt(variance) : std::numeric_limits<double>::quiet_NaN();
}

// --- the shapes most effects share

// Steps of 1e-5 and 1e-4 in the parameter's own unit.
double Step1e5(int, double) { return 1e-5; }
double Step1e4(int, double) { return 1e-4; }
json FirstSd(const TrueModel&, const Eigen::MatrixXd&, const Eigen::VectorXd& sd) { return sd[0]; }
json ThreeSd(const TrueModel&, const Eigen::MatrixXd&, const Eigen::VectorXd& sd) {
  return json::array({sd[0], sd[1], sd[2]});
}

// --- the table, one function per effect in docs/FORMATS.md's order

// Steps: small enough that the model is linear over them (the displacements move by ~1e-3 px)
// and large enough that rounding (~1e-13 px) is far below the differences.

EffectSpec TimeOffsetSpec() {
  EffectSpec s;
  s.effect = Effect::kTimeOffset;
  s.name = "time_offset";
  s.unit = "s";
  s.parameter_count = 1;
  s.step = Step1e5;  // s
  s.apply_delta = [](const double* x, TrueModel* m) { m->rig.time_offset_s += x[0]; };
  s.inject = [](const json& v, TrueModel* m) -> json {
    m->rig.time_offset_s = Scalar(v, Effect::kTimeOffset);
    return m->rig.time_offset_s;
  };
  s.value = [](const TrueModel& m) -> json { return m.rig.time_offset_s; };
  s.stderr_value = FirstSd;
  s.claim = "time_offset_s";
  return s;
}

EffectSpec ReadoutTimeSpec() {
  EffectSpec s;
  s.effect = Effect::kReadoutTime;
  s.name = "readout_time";
  s.unit = "s";
  s.parameter_count = 1;
  s.step = Step1e5;  // s
  s.apply_delta = [](const double* x, TrueModel* m) { m->rig.shutter.readout_s += x[0]; };
  s.inject = [](const json& v, TrueModel* m) -> json {
    m->rig.shutter.readout_s = Scalar(v, Effect::kReadoutTime);
    SHUTTERLAB_CHECK(m->rig.shutter.readout_s > 0) << "--inject readout_time must be positive";
    return m->rig.shutter.readout_s;
  };
  s.value = [](const TrueModel& m) -> json { return m.rig.shutter.readout_s; };
  s.stderr_value = FirstSd;
  s.claim = "readout_s";
  return s;
}

EffectSpec GyroToCameraSpec() {
  EffectSpec s;
  s.effect = Effect::kGyroToCamera;
  s.name = "gyro_to_camera";
  s.parameter_count = 3;
  s.step = Step1e4;  // rad
  s.apply_delta = [](const double* x, TrueModel* m) {
    m->rig.cam_from_gyro =
        ExpSO3(Eigen::Vector3d(x[0], x[1], x[2])).toRotationMatrix() * m->rig.cam_from_gyro;
  };
  s.inject = [](const json& v, TrueModel* m) -> json {
    const std::vector<double> e = Numbers(v, Effect::kGyroToCamera, 9);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) m->rig.cam_from_gyro(r, c) = e[3 * r + c];
    }
    SHUTTERLAB_CHECK(IsRotationMatrix(m->rig.cam_from_gyro, 1e-6))
        << "--inject gyro_to_camera is not a rotation";
    json recorded = json::array();
    for (int r = 0; r < 3; ++r) recorded.push_back({e[3 * r], e[3 * r + 1], e[3 * r + 2]});
    return recorded;
  };
  s.value = [](const TrueModel& m) -> json { return MatrixJson(m.rig.cam_from_gyro); };
  s.stderr_value = [](const TrueModel& m, const Eigen::MatrixXd& covariance,
                      const Eigen::VectorXd&) -> json {
    // R = Exp(x) R_0 with x near 0: dR/dx_k = Hat(e_k) R (first order), entry by entry.
    const Eigen::Matrix3d& r = m.rig.cam_from_gyro;
    Eigen::Matrix<double, 9, 3> d_entries_d_x;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Matrix3d d = Hat(Eigen::Vector3d::Unit(k)) * r;
      for (int i = 0; i < 9; ++i) d_entries_d_x(i, k) = d(i / 3, i % 3);
    }
    const Eigen::Matrix<double, 9, 9> cov = d_entries_d_x * covariance * d_entries_d_x.transpose();
    json out = json::array();
    for (int row = 0; row < 3; ++row) {
      json line = json::array();
      for (int col = 0; col < 3; ++col) line.push_back(Sd(cov(3 * row + col, 3 * row + col)));
      out.push_back(line);
    }
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
  s.parameter_count = 3;
  s.step = Step1e4;
  s.apply_delta = [](const double* x, TrueModel* m) {
    m->gyro_scale += Eigen::Vector3d(x[0], x[1], x[2]);
  };
  s.inject = [](const json& v, TrueModel* m) -> json {
    m->gyro_scale = Vector3(v, Effect::kGyroScale);
    return Array3(m->gyro_scale);
  };
  s.value = [](const TrueModel& m) -> json { return Array3(m.gyro_scale); };
  s.stderr_value = ThreeSd;
  s.identifiable_with_pair_translation = false;
  return s;
}

EffectSpec GyroBiasSpec() {
  EffectSpec s;
  s.effect = Effect::kGyroBias;
  s.name = "gyro_bias";
  s.unit = "rad/s";
  s.parameter_count = 3;
  s.step = Step1e4;  // rad/s
  s.apply_delta = [](const double* x, TrueModel* m) {
    m->gyro_bias_rad_s += Eigen::Vector3d(x[0], x[1], x[2]);
  };
  s.inject = [](const json& v, TrueModel* m) -> json {
    m->gyro_bias_rad_s = Vector3(v, Effect::kGyroBias);
    return Array3(m->gyro_bias_rad_s);
  };
  s.value = [](const TrueModel& m) -> json { return Array3(m.gyro_bias_rad_s); };
  s.stderr_value = ThreeSd;
  s.identifiable_with_pair_translation = false;
  return s;
}

EffectSpec VelocitySpec() {
  EffectSpec s;
  s.effect = Effect::kVelocity;
  s.name = "velocity";
  s.unit = "m/s";
  s.parameter_count = 3;
  s.step = [](int, double) { return 1e-2; };  // m/s
  s.apply_delta = [](const double* x, TrueModel* m) {
    m->rig.velocity_mps += Eigen::Vector3d(x[0], x[1], x[2]);
  };
  s.inject = [](const json& v, TrueModel* m) -> json {
    m->rig.velocity_mps = Vector3(v, Effect::kVelocity);
    return Array3(m->rig.velocity_mps);
  };
  s.value = [](const TrueModel& m) -> json { return Array3(m.rig.velocity_mps); };
  s.stderr_value = ThreeSd;
  // The pair translation replaces it (and video's rotation-only model has none).
  s.identifiable_with_pair_translation = false;
  return s;
}

EffectSpec LensDistortionSpec() {
  EffectSpec s;
  s.effect = Effect::kLensDistortion;
  s.name = "lens_distortion";
  s.parameter_count = 2;
  s.step = Step1e4;
  s.apply_delta = [](const double* x, TrueModel* m) {
    m->rig.camera.dist[0] += x[0];
    m->rig.camera.dist[1] += x[1];
  };
  s.inject = [](const json& v, TrueModel* m) -> json {
    static const char* kNames[5] = {"k1", "k2", "p1", "p2", "k3"};
    std::array<double, 5>& dist = m->rig.camera.dist;
    dist.fill(0.0);
    if (v.is_object()) {
      for (const auto& [key, x] : v.items()) {
        int i = 0;
        while (i < 5 && key != kNames[i]) ++i;
        if (i == 5) {
          throw std::invalid_argument("--inject lens_distortion: unknown coefficient '" + key +
                                      "'");
        }
        dist[i] = Scalar(x, Effect::kLensDistortion);
      }
    } else {
      const json list = v.is_array() ? v : json::array({v});
      if (list.empty() || list.size() > 5) {
        throw std::invalid_argument(
            "--inject lens_distortion: expected k1[,k2[,p1,p2[,k3]]], got " + v.dump());
      }
      for (size_t i = 0; i < list.size(); ++i) dist[i] = Scalar(list[i], Effect::kLensDistortion);
    }
    json recorded = json::object();
    for (int i = 0; i < 5; ++i) {
      if (i < 2 || dist[i] != 0.0) recorded[kNames[i]] = dist[i];
    }
    return recorded;
  };
  s.value = [](const TrueModel& m) -> json {
    return {{"k1", m.rig.camera.dist[0]}, {"k2", m.rig.camera.dist[1]}};
  };
  s.stderr_value = [](const TrueModel&, const Eigen::MatrixXd&, const Eigen::VectorXd& sd) -> json {
    return {{"k1", sd[0]}, {"k2", sd[1]}};
  };
  return s;
}

EffectSpec ReadoutDirectionSpec() {
  EffectSpec s;
  s.effect = Effect::kReadoutDirection;
  s.name = "readout_direction";
  s.parameter_count = 0;
  s.step = [](int, double) { return 1.0; };  // no parameter to step
  s.apply_delta = [](const double*, TrueModel* m) {
    m->rig.shutter.direction = m->rig.shutter.direction == ReadoutDirection::kTopToBottom
                                   ? ReadoutDirection::kBottomToTop
                                   : ReadoutDirection::kTopToBottom;
  };
  s.inject = [](const json& v, TrueModel* m) -> json {
    const std::string word = v.is_string() ? v.get<std::string>() : v.dump();
    const std::optional<ReadoutDirection> parsed = ParseReadoutDirection(word);
    if (!parsed || !IsRowReadout(*parsed)) {
      throw std::invalid_argument("--inject readout_direction: '" + word +
                                  "' is not top_to_bottom or bottom_to_top");
    }
    m->rig.shutter.direction = *parsed;
    return word;
  };
  s.value = [](const TrueModel& m) -> json {
    return ReadoutDirectionName(m.rig.shutter.direction);
  };
  s.stderr_value = [](const TrueModel&, const Eigen::MatrixXd&, const Eigen::VectorXd&) -> json {
    return nullptr;
  };
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
  s.parameter_count = 2;  // ppm, s
  s.step = [](int i, double frames_span_s) {
    return i == 0 ? 1e-5 / std::max(frames_span_s, 1.0) * 1e6 : 1e-5;  // ppm, s
  };
  s.apply_delta = [](const double* x, TrueModel* m) {
    m->clock_rate_ppm += x[0];
    m->rig.time_offset_s += x[1];
  };
  s.inject = [](const json& v, TrueModel* m) -> json {
    m->clock_rate_ppm = Scalar(v, Effect::kClockRate);
    return m->clock_rate_ppm;
  };
  s.value = [](const TrueModel& m) -> json { return m.clock_rate_ppm; };
  s.stderr_value = FirstSd;  // the rate's, not the offset's
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

const std::vector<EffectSpec>& AllEffects() {
  static const std::vector<EffectSpec> table = MakeTable();
  return table;
}

const EffectSpec& Spec(Effect effect) { return AllEffects().at(static_cast<size_t>(effect)); }

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

json ApplyInjection(const std::string& name_equals_value, TrueModel* model) {
  const size_t eq = name_equals_value.find('=');
  if (eq == std::string::npos) {
    throw std::invalid_argument("--inject '" + name_equals_value + "': expected NAME=VALUE");
  }
  const json value = ParseValue(name_equals_value.substr(eq + 1));
  const Effect effect =
      RequireEffect(std::string_view(name_equals_value).substr(0, eq), "--inject");
  const json recorded = Spec(effect).inject(value, model);
  model->Check();
  return recorded;
}

json EffectStderr(Effect effect, const TrueModel& model, const Eigen::MatrixXd& covariance) {
  const EffectSpec& spec = Spec(effect);
  const int n = spec.parameter_count;
  if (n == 0) return nullptr;
  SHUTTERLAB_CHECK(covariance.rows() == n && covariance.cols() == n)
      << spec.name << ": covariance is " << covariance.rows() << "x" << covariance.cols();
  // A negative or NaN variance is an undetermined parameter: NaN (null in JSON), not 0.
  const Eigen::VectorXd sd = covariance.diagonal().unaryExpr([](double v) { return Sd(v); });
  return spec.stderr_value(model, covariance, sd);
}

}  // namespace shutterlab
