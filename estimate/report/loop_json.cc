#include "estimate/report/loop_json.h"

#include "model/effect_io.h"
#include "sim/check.h"
#include "sim/text_file.h"

#include <string>
#include <utility>
#include <vector>

namespace shutterlab {

using nlohmann::json;

json LoopToJson(const LoopResult& result, size_t frame_count) {
  auto stats = [](const ResidualStats& s) {
    return json{{"rms_px", s.rms_px}, {"max_px", s.max_px}};
  };
  json effects = json::array();
  for (const IdentifiedEffect& e : result.effects) {
    const EffectSpec& spec = Spec(e.effect);
    json j = {{"name", spec.name},
              {"value", EffectValueToJson(e.value)},
              {"stderr", EffectValueToJson(e.stderr_value)},
              {"unit", spec.unit}};
    if (!e.ambiguous_with.empty()) {
      std::vector<std::string> names;
      for (Effect a : e.ambiguous_with) names.push_back(Spec(a).name);
      j["ambiguous_with"] = names;
    }
    // Beyond docs/FORMATS.md: whether a real device can have the value (model/effects.h
    // OutOfBounds).
    j["within_bounds"] = e.out_of_bounds.empty();
    if (!e.out_of_bounds.empty()) j["out_of_bounds"] = e.out_of_bounds;
    j["after"] = stats(e.after);
    // Beyond docs/FORMATS.md: the fitted parameters and their covariance, which the value's
    // standard errors leave out (clock_rate's companion offset, correlations): `correct` draws
    // the model's uncertainty from them.
    j["parameters"] =
        std::vector<double>(e.parameters.data(), e.parameters.data() + e.parameters.size());
    json covariance = json::array();
    for (int r = 0; r < e.covariance.rows(); ++r) {
      std::vector<double> row(static_cast<size_t>(e.covariance.cols()));
      for (int c = 0; c < e.covariance.cols(); ++c) row[c] = e.covariance(r, c);
      covariance.push_back(row);
    }
    j["covariance"] = std::move(covariance);
    // Every estimator's standard error of the effect's parameters (EffectSpec's parameter units),
    // beside the one "stderr" holds (the loop's "covariance").
    const auto numbers = [](const Eigen::VectorXd& v) {
      std::vector<double> out(v.data(), v.data() + v.size());
      return out;
    };
    j["parameter_stderr"] = {{"model", numbers(e.parameter_stderr_model)},
                             {"cluster_sandwich", numbers(e.parameter_stderr_sandwich)},
                             {"cluster_jackknife", numbers(e.parameter_stderr_jackknife)},
                             {"clusters", e.clusters}};
    j["stderr_from"] = CovarianceKindName(e.stderr_from);
    if (!e.stderr_withheld.empty()) j["stderr_withheld"] = e.stderr_withheld;
    effects.push_back(std::move(j));
  }
  json out{{"format", "validation/1"},
           {"frames", frame_count},
           {"before", stats(result.before)},
           {"effects", std::move(effects)},
           {"after", stats(result.after)},
           {"noise_px", result.noise_px},
           {"unexplained", result.unexplained},
           {"log", result.log},
           {"covariance", CovarianceKindName(result.covariance)}};
  // Beyond docs/FORMATS.md: with pair_translation the residual is one component (the distance
  // across the epipolar line), to be read against noise_px / sqrt(2), not noise_px.
  if (result.residual_components != 2) out["residual_components"] = result.residual_components;
  out["fitted_model"] = TrueModelToJson(result.model);
  return out;
}

json MeasureToJson(const MeasureReport& report) {
  const DisplacementMeasurement& m = report.measurement;
  json j = {
      {"format", "measure/1"}, {"width", m.field.cols}, {"height", m.field.rows}, {"D_px", m.d_px}};
  if (report.ground_m_per_px) j["D_m"] = m.d_px * *report.ground_m_per_px;
  j["noise_px"] = m.noise_px;
  j["measured_fraction"] = m.measured_fraction;
  j["points"] = m.points.size();
  if (report.truth) {
    j["truth"] = {{"rms_px", report.truth->rms_px},
                  {"max_px", report.truth->max_px},
                  {"pixels", report.truth->pixels}};
  }
  return j;
}

nlohmann::json Rounded(const nlohmann::json& value) {
  if (value.is_number_float()) return std::stod(FormatNumber("%.4g", value.get<double>()));
  if (!value.is_structured()) return value;
  nlohmann::json out = value;
  for (auto& item : out.items()) item.value() = Rounded(item.value());
  return out;
}

}  // namespace shutterlab
