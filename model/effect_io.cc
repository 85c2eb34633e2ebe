#include "model/effect_io.h"

#include "sim/text_file.h"
#include "sim/units.h"

#include <array>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string_view>
#include <vector>

namespace shutterlab {

namespace {

using nlohmann::json;

// `--inject` VALUE as JSON when it parses, else comma-separated numbers, else a bare word.
json ParseValueText(const std::string& text) {
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

// An effect with a unit takes quantities: "5ms", "0.5deg/s,0,-0.2deg/s" (0 needs no unit), in
// the effect's docs/FORMATS.md unit; a bare number is refused with what it probably meant.
json QuantityListText(const std::string& text, Effect effect, const std::string& where) {
  const std::string& unit = Spec(effect).unit;
  // The unit a person most likely typed a bare number in.
  const char* bare_means = unit == "s" ? "ms" : unit == "rad/s" ? "deg/s" : unit.c_str();
  std::vector<std::string_view> fields;
  SplitFields(text, ',', &fields);
  json numbers = json::array();
  for (std::string_view f : fields) numbers.push_back(ParseQuantity(f, unit, where, bare_means));
  return numbers.size() == 1 ? numbers[0] : numbers;
}

double Scalar(const json& j, const std::string& where) {
  if (!j.is_number() || !std::isfinite(j.get<double>())) {
    throw std::invalid_argument(where + ": expected a number, got " + j.dump());
  }
  return j.get<double>();
}

// Exactly n numbers, given flat or nested one level ([[1,2,3],[4,5,6],[7,8,9]]).
std::vector<double> Numbers(const json& j, size_t n, const std::string& where) {
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
    throw std::invalid_argument(where + ": expected " + std::to_string(n) + " numbers, got " +
                                j.dump());
  }
  std::vector<double> out;
  for (const json& x : flat) out.push_back(Scalar(x, where));
  return out;
}

// A lens value: a JSON object as camera.json's "distortion" (its "model" says which, brown when
// absent), or a list of numbers in the declared model's order (`--inject` only; Brown-Conrady when
// no camera is known): k1[,k2[,p1,p2[,k3]]] or, for a fisheye, k1[,k2[,k3[,k4]]].
LensDistortion LensFromJson(const json& j, const std::string& where,
                            const LensDistortion* declared) {
  if (j.is_object()) {
    for (const auto& [key, x] : j.items()) {
      if (key != "model") Scalar(x, where);  // finite numbers only
    }
    try {
      return DistortionFromJson(j);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(where + ": " + e.what());
    }
  }
  const bool fisheye = declared && std::holds_alternative<Fisheye>(*declared);
  const size_t most = fisheye ? 4 : 5;
  const json list = j.is_array() ? j : json::array({j});
  if (list.empty() || list.size() > most) {
    throw std::invalid_argument(where +
                                (fisheye ? ": expected k1[,k2[,k3[,k4]]] (fisheye), got "
                                         : ": expected k1[,k2[,p1,p2[,k3]]], got ") +
                                j.dump());
  }
  std::array<double, 5> c{};
  for (size_t i = 0; i < list.size(); ++i) c[i] = Scalar(list[i], where);
  if (fisheye) return Fisheye({c[0], c[1], c[2], c[3]});
  return BrownConrady{c};
}

ReadoutDirection DirectionFromJson(const json& j, const std::string& where) {
  const std::string word = j.is_string() ? j.get<std::string>() : j.dump();
  const std::optional<ReadoutDirection> parsed = ParseReadoutDirection(word);
  if (!parsed || !IsRowReadout(*parsed)) {
    throw std::invalid_argument(where + ": '" + word + "' is not top_to_bottom or bottom_to_top");
  }
  return *parsed;
}

// docs/FORMATS.md's own shape, which EffectValueFromJson requires before reading the value as
// `--inject` does (which also takes numbers nested otherwise and a list of lens coefficients).
bool HasFormatsShape(EffectShape shape, const json& j) {
  const auto numbers = [](const json& list, size_t n) {
    if (!list.is_array() || list.size() != n) return false;
    for (const json& x : list) {
      if (!x.is_number()) return false;
    }
    return true;
  };
  switch (shape) {
    case EffectShape::kNumber:
      return j.is_number();
    case EffectShape::kVector3:
      return numbers(j, 3);
    case EffectShape::kMatrix3:
      return j.is_array() && j.size() == 3 && numbers(j[0], 3) && numbers(j[1], 3) &&
             numbers(j[2], 3);
    case EffectShape::kLens:
      return j.is_object();
    case EffectShape::kDirection:
      return j.is_string();
  }
  return false;
}

// The value as `--inject` reads it (effect_io.h ParseInjection); declared: the camera's lens, which
// sets the order of a list of lens coefficients (nullptr: Brown-Conrady).
EffectValue InjectionValue(Effect effect, const json& j, const std::string& where,
                           const LensDistortion* declared = nullptr) {
  switch (Spec(effect).shape) {
    case EffectShape::kNumber:
      return Scalar(j, where);
    case EffectShape::kVector3: {
      const std::vector<double> v = Numbers(j, 3, where);
      return Eigen::Vector3d(v[0], v[1], v[2]);
    }
    case EffectShape::kMatrix3: {
      const std::vector<double> e = Numbers(j, 9, where);
      Eigen::Matrix3d m;
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) m(r, c) = e[3 * r + c];
      }
      return m;
    }
    case EffectShape::kLens:
      return LensFromJson(j, where, declared);
    case EffectShape::kDirection:
      return DirectionFromJson(j, where);
  }
  throw std::logic_error("unhandled shape of " + Spec(effect).name);
}

struct ToJson {
  json operator()(std::monostate) const { return nullptr; }
  json operator()(double x) const { return x; }
  json operator()(const Eigen::Vector3d& v) const { return json::array({v.x(), v.y(), v.z()}); }
  json operator()(const Eigen::Matrix3d& m) const { return MatrixJson(m); }
  json operator()(const LensDistortion& lens) const {
    json out = DistortionJson(lens);
    // Brown-Conrady: k1 and k2 always, p1, p2 and k3 only where set (the fit holds k1 and k2).
    if (std::holds_alternative<BrownConrady>(lens)) {
      for (const char* key : {"p1", "p2", "k3"}) {
        if (out[key].get<double>() == 0.0) out.erase(key);
      }
    }
    return out;
  }
  json operator()(ReadoutDirection d) const { return ReadoutDirectionName(d); }
};

}  // namespace

json EffectValueToJson(const EffectValue& value) { return std::visit(ToJson{}, value); }

std::string EffectValueText(const EffectValue& value) { return EffectValueToJson(value).dump(); }

EffectValue EffectValueFromJson(Effect effect, const json& j, const std::string& where) {
  const EffectShape shape = Spec(effect).shape;
  if (!HasFormatsShape(shape, j)) {
    throw std::invalid_argument(where + ": expected " + EffectShapeWords(shape) + ", got " +
                                j.dump());
  }
  return InjectionValue(effect, j, where);
}

Injection ParseInjection(const std::string& name_equals_value) {
  const size_t eq = name_equals_value.find('=');
  if (eq == std::string::npos) {
    throw std::invalid_argument("--inject '" + name_equals_value + "': expected NAME=VALUE");
  }
  const Effect effect =
      RequireEffect(std::string_view(name_equals_value).substr(0, eq), "--inject");
  const std::string where = "--inject " + Spec(effect).name;
  const std::string text = name_equals_value.substr(eq + 1);
  const json value =
      Spec(effect).unit.empty() ? ParseValueText(text) : QuantityListText(text, effect, where);
  return Injection{effect, InjectionValue(effect, value, where)};
}

json TrueModelToJson(const TrueModel& model) {
  return {{"camera", RigModelToJson(model.rig)},
          {"gyro_scale", EffectValueToJson(model.gyro_scale)},
          {"gyro_bias_rad_s", EffectValueToJson(model.gyro_bias_rad_s)},
          {"clock_rate_ppm", model.clock_rate_ppm}};
}

TrueModel TrueModelFromJson(const json& j, const std::string& where) {
  if (!j.is_object() || !j.contains("camera")) {
    throw std::invalid_argument(where + ": expected an object with \"camera\"");
  }
  TrueModel model;
  try {
    model.rig = RigModelFromJson(j.at("camera"));
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(where + ".camera: " + e.what());
  }
  const auto vector = [&](const char* key, Eigen::Vector3d fallback) {
    if (!j.contains(key)) return fallback;
    const std::vector<double> v = Numbers(j.at(key), 3, where + "." + key);
    return Eigen::Vector3d(v[0], v[1], v[2]);
  };
  model.gyro_scale = vector("gyro_scale", Eigen::Vector3d::Ones());
  model.gyro_bias_rad_s = vector("gyro_bias_rad_s", Eigen::Vector3d::Zero());
  if (j.contains("clock_rate_ppm")) {
    model.clock_rate_ppm = Scalar(j.at("clock_rate_ppm"), where + ".clock_rate_ppm");
  }
  try {
    model.Check();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(where + ": " + e.what());
  }
  return model;
}

Injection ApplyInjection(const std::string& name_equals_value, TrueModel* model) {
  Injection injection = ParseInjection(name_equals_value);
  if (injection.effect == Effect::kLensDistortion) {
    // A list of coefficients is in the declared camera's model.
    const size_t eq = name_equals_value.find('=');
    injection.value =
        InjectionValue(Effect::kLensDistortion, ParseValueText(name_equals_value.substr(eq + 1)),
                       "--inject lens_distortion", &model->rig.camera.distortion);
  }
  injection.value = ApplyInjection(injection, model);
  return injection;
}

}  // namespace shutterlab
