#include "model/reported_model.h"

#include "model/effect_io.h"
#include "sim/check.h"
#include "sim/text_file.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace shutterlab {

using nlohmann::json;

namespace {

// A JSON array of arrays of numbers (null: NaN) as a matrix; an empty one when absent.
Eigen::MatrixXd MatrixFromJson(const json& j, const std::string& where) {
  if (j.is_null()) return {};
  if (!j.is_array()) throw std::invalid_argument(where + ": expected an array of rows");
  Eigen::MatrixXd m(static_cast<int>(j.size()), j.empty() ? 0 : static_cast<int>(j[0].size()));
  for (size_t r = 0; r < j.size(); ++r) {
    if (!j[r].is_array() || static_cast<int>(j[r].size()) != m.cols()) {
      throw std::invalid_argument(where + ": rows of different lengths");
    }
    for (size_t c = 0; c < j[r].size(); ++c) {
      const json& x = j[r][c];
      if (!x.is_number() && !x.is_null()) throw std::invalid_argument(where + ": not a number");
      m(static_cast<int>(r), static_cast<int>(c)) = x.is_null() ? NAN : x.get<double>();
    }
  }
  return m;
}

// validate's "claims": the strings each claim has; an entry that is not an object, or a field that
// is not a string, is refused.
std::vector<ReportedClaim> ClaimsFromJson(const json& j) {
  std::vector<ReportedClaim> claims;
  if (!j.contains("claims")) return claims;
  if (!j["claims"].is_array()) throw std::invalid_argument("claims: expected an array");
  for (size_t i = 0; i < j["claims"].size(); ++i) {
    const json& c = j["claims"][i];
    const std::string where = "claims[" + std::to_string(i) + "]";
    if (!c.is_object()) throw std::invalid_argument(where + ": expected an object");
    ReportedClaim claim;
    for (auto [key, field] :
         {std::pair{"claim", &claim.claim}, std::pair{"effect", &claim.effect},
          std::pair{"status", &claim.status}, std::pair{"verdict", &claim.verdict}}) {
      if (!c.contains(key)) continue;
      if (!c[key].is_string())
        throw std::invalid_argument(where + "." + key + ": expected a string");
      *field = c[key].get<std::string>();
    }
    claims.push_back(std::move(claim));
  }
  return claims;
}

ReportedModel ReportedModelFromJson(const json& j) {
  if (!j.is_object() || j.value("format", "") != "validation/1") {
    throw std::invalid_argument("not a validation report (format validation/1)");
  }
  ReportedModel out;
  out.noise_px = j.value("noise_px", 0.0);
  out.unexplained = j.value("unexplained", false);
  if (j.contains("after") && j["after"].is_object()) {
    out.after_rms_px = j["after"].value("rms_px", 0.0);
    out.after_max_px = j["after"].value("max_px", 0.0);
  }
  if (!j.contains("effects") || !j["effects"].is_array()) {
    throw std::invalid_argument("effects: expected an array");
  }
  for (size_t i = 0; i < j["effects"].size(); ++i) {
    const json& e = j["effects"][i];
    const std::string where = "effects[" + std::to_string(i) + "]";
    if (!e.is_object() || !e.contains("name") || !e["name"].is_string()) {
      throw std::invalid_argument(where + ": expected an object with a name");
    }
    ReportedEffect effect;
    effect.effect = RequireEffect(e["name"].get<std::string>(), where);
    effect.value = EffectValueFromJson(effect.effect, e.at("value"), where + ".value");
    if (e.contains("parameters") && e.contains("covariance")) {
      const Eigen::MatrixXd p =
          MatrixFromJson(json::array({e["parameters"]}), where + ".parameters");
      effect.parameters = p.rows() == 1 ? Eigen::VectorXd(p.row(0).transpose()) : Eigen::VectorXd();
      effect.covariance = MatrixFromJson(e["covariance"], where + ".covariance");
      const int n = Spec(effect.effect).parameter_count;
      if (effect.parameters.size() != n || effect.covariance.rows() != n ||
          effect.covariance.cols() != n) {
        throw std::invalid_argument(where + ": " + std::to_string(n) +
                                    " parameters and an n x n covariance expected");
      }
    }
    out.effects.push_back(std::move(effect));
  }
  if (j.contains("fitted_model")) out.fitted = TrueModelFromJson(j["fitted_model"], "fitted_model");
  out.claims = ClaimsFromJson(j);
  return out;
}

}  // namespace

ReportedModel ReadValidationReport(const std::string& path) {
  const std::string text = ReadFileToString(path);
  try {
    return ReportedModelFromJson(json::parse(text));
  } catch (const json::exception& e) {
    throw IoError(IoMessage(path, 0, std::string("invalid JSON: ") + e.what()));
  } catch (const std::invalid_argument& e) {
    throw IoError(IoMessage(path, 0, e.what()));
  }
}

}  // namespace shutterlab
