// The paper's analyses as docs/FORMATS.md's JSON: every key the contract names, with the values
// the typed results hold.
#include "estimate/report/analysis_json.h"

#include "tests/estimate/paper/paper_fixtures.h"
#include "tests/render/render_fixtures.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

// Still for 4 s, then a constant rate about (1, 1, 1) until total_s.
FlightLog DiagonalRateLog(double rate_rad_s, double total_s) {
  return test::ConstantRateLog(rate_rad_s * Eigen::Vector3d::Ones().normalized(), total_s);
}

TEST(AnalysisJson, FlightHasTheContractsKeys) {
  FlightOptions options;
  options.bias = {0.0, 2.0};
  const FlightResult r = Flight(DiagonalRateLog(0.1, 8.0).gyro, options);
  const nlohmann::json j = FlightToJson(r);
  EXPECT_EQ(j.at("altitude_m"), 50.0);
  EXPECT_EQ(j.at("noise_allowance_arcsec"), 20.0);
  EXPECT_EQ(j.at("windows_total"), r.windows_total);
  EXPECT_EQ(j.at("samples"), r.samples);
  ASSERT_EQ(j.at("rows").size(), r.rows.size());
  for (size_t i = 0; i < r.rows.size(); ++i) {
    for (const char* key : {"limit_m", "window_s", "threshold_arcsec", "flagged_percent",
                            "flagged_percent_vector", "flagged_percent_axis"}) {
      EXPECT_TRUE(j["rows"][i].contains(key)) << key;
    }
    EXPECT_EQ(j["rows"][i]["window_s"], r.rows[i].window_s);
    EXPECT_EQ(j["rows"][i]["flagged_percent"], r.rows[i].flagged_percent);
  }
  // Without the vector criterion its column is null, not a made-up number.
  options.vector_criterion = false;
  const nlohmann::json no_vector = FlightToJson(Flight(DiagonalRateLog(0.1, 8.0).gyro, options));
  EXPECT_TRUE(no_vector["rows"][0]["flagged_percent_vector"].is_null());
}

TEST(AnalysisJson, AnalyzeHasTheContractsKeysAndOneEntryPerImage) {
  const FlightLog log = DiagonalRateLog(0.05, 12.0);
  AnalyzeOptions options;
  options.rig = test::MappingRig();  // 1280x960, f 1100 px, 30 ms, 50 m
  options.every_s = 2.0;
  const AnalyzeResult result = Analyze(log, options);
  const nlohmann::json json = AnalyzeToJson(result);
  EXPECT_EQ(json["source"]["format"], "test");
  EXPECT_EQ(json["camera"]["altitude_m"], 50.0);
  ASSERT_EQ(json["images"].size(), result.images.size());
  ASSERT_FALSE(result.images.empty());
  for (size_t i = 0; i < result.images.size(); ++i) {
    EXPECT_EQ(json["images"][i]["name"], result.images[i].name);
    EXPECT_TRUE(json["images"][i]["flagged"].contains("0.05"));
    EXPECT_TRUE(json["images"][i]["flagged"].contains("0.1"));
  }
  EXPECT_TRUE(json.contains("verdict"));
  EXPECT_TRUE(json.contains("flight"));
}

// The keys of a JSON object, in the order they are written.
std::vector<std::string> Keys(const nlohmann::ordered_json& object) {
  std::vector<std::string> keys;
  for (const auto& item : object.items()) keys.push_back(item.key());
  return keys;
}

TEST(AnalysisJson, NoiseHasTheContractsKeysInOrderWithTheResultsValues) {
  NoiseResult r;
  r.window_samples = 120;
  r.windows = 881;
  r.samples_analysed = 1000;
  r.rate_hz = 3000.0;
  r.bias.bias_rad_s = Eigen::Vector3d(1e-3, -2e-3, 3e-3);
  for (int a = 0; a < 3; ++a) {
    // Distinct values per field and axis, so that a key bound to the wrong field shows.
    r.axes[a].sigma_mean_arcsec = 1.0 + 10 * a;
    r.axes[a].sigma_max_arcsec = 2.0 + 10 * a;
    r.axes[a].sigma_rms_arcsec = 3.0 + 10 * a;
    r.axes[a].range_mean_arcsec = 4.0 + 10 * a;
    r.axes[a].range_max_arcsec = 5.0 + 10 * a;
  }
  const nlohmann::ordered_json no_allan = NoiseToJson(r);
  EXPECT_EQ(Keys(no_allan),
            (std::vector<std::string>{"window_samples", "windows", "samples", "rate_hz", "axes"}));
  EXPECT_EQ(no_allan["window_samples"], 120);
  EXPECT_EQ(no_allan["windows"], 881u);
  EXPECT_EQ(no_allan["samples"], 1000u);
  EXPECT_EQ(no_allan["rate_hz"], 3000.0);
  EXPECT_EQ(Keys(no_allan["axes"]), (std::vector<std::string>{"x", "y", "z"}));
  const std::vector<std::string> axis_keys = {"sigma_mean_arcsec", "sigma_max_arcsec",
                                              "range_mean_arcsec", "range_max_arcsec",
                                              "sigma_rms_arcsec",  "bias_rad_s"};
  for (int a = 0; a < 3; ++a) {
    const nlohmann::ordered_json& axis = no_allan["axes"][std::string(1, "xyz"[a])];
    EXPECT_EQ(Keys(axis), axis_keys) << "without the Allan coefficients, axis " << a;
    EXPECT_EQ(axis["sigma_mean_arcsec"], r.axes[a].sigma_mean_arcsec);
    EXPECT_EQ(axis["sigma_max_arcsec"], r.axes[a].sigma_max_arcsec);
    EXPECT_EQ(axis["sigma_rms_arcsec"], r.axes[a].sigma_rms_arcsec);
    EXPECT_EQ(axis["range_mean_arcsec"], r.axes[a].range_mean_arcsec);
    EXPECT_EQ(axis["range_max_arcsec"], r.axes[a].range_max_arcsec);
    EXPECT_EQ(axis["bias_rad_s"], r.bias.bias_rad_s[a]);
  }

  r.allan.tau_s = {0.001, 0.01};
  for (int a = 0; a < 3; ++a) {
    r.allan.axes[a].arw_deg_sqrt_h = 0.1 + a;
    r.allan.axes[a].arw_rad_s_sqrt_hz = 0.2 + a;
    r.allan.axes[a].bias_instability_deg_h = 0.3 + a;
    r.allan.axes[a].bias_instability_tau_s = 0.4 + a;
    r.allan.axes[a].bias_instability_upper_bound = a == 1;
  }
  const nlohmann::ordered_json with_allan = NoiseToJson(r);
  std::vector<std::string> allan_keys = axis_keys;
  allan_keys.insert(allan_keys.end(),
                    {"arw_deg_sqrt_h", "arw_rad_s_sqrt_hz", "bias_instability_deg_h",
                     "bias_instability_tau_s", "bias_instability_upper_bound"});
  for (int a = 0; a < 3; ++a) {
    const nlohmann::ordered_json& axis = with_allan["axes"][std::string(1, "xyz"[a])];
    EXPECT_EQ(Keys(axis), allan_keys) << "axis " << a;
    const AllanCoefficients& c = r.allan.axes[a];
    EXPECT_EQ(axis["arw_deg_sqrt_h"], c.arw_deg_sqrt_h);
    EXPECT_EQ(axis["arw_rad_s_sqrt_hz"], c.arw_rad_s_sqrt_hz);
    EXPECT_EQ(axis["bias_instability_deg_h"], c.bias_instability_deg_h);
    EXPECT_EQ(axis["bias_instability_tau_s"], c.bias_instability_tau_s);
    EXPECT_EQ(axis["bias_instability_upper_bound"], c.bias_instability_upper_bound);
  }
}

TEST(AnalysisJson, AccuracyHasTheContractsKeysInOrderWithTheResultsValues) {
  AccuracyResult r;
  r.reference_deg = 1.0;
  r.average_samples = 100;
  r.noise_level_rad_s = 1e-4;
  r.enter_rad_s = 8e-4;
  r.exit_rad_s = 3e-4;
  r.skipped_t_s = {42.5};
  r.difference_mean_arcsec = 7.5;
  r.difference_std_arcsec = 2.5;
  for (int i = 0; i < 2; ++i) {
    DetectedRotation turn;
    turn.t_start_s = 10.0 + i;
    turn.t_end_s = 10.5 + i;
    turn.before_arcsec = Eigen::Vector3d(-51, -41, -23) * (i + 1);
    turn.after_arcsec = Eigen::Vector3d(3433, -340, 757) * (i + 1);
    turn.theta_arcsec = 3605.0 + 5 * i;
    turn.difference_arcsec = 5.0 + 5 * i;
    turn.theta_vector_arcsec = 3601.0 + i;
    turn.theta_so3_arcsec = 3602.0 + i;
    r.rotations.push_back(turn);
  }
  const nlohmann::ordered_json j = AccuracyToJson(r);
  EXPECT_EQ(Keys(j), (std::vector<std::string>{"reference_deg", "rotations", "average_samples",
                                               "difference_mean_arcsec", "difference_std_arcsec",
                                               "noise_level_rad_s", "enter_rad_s", "exit_rad_s",
                                               "skipped_t_s"}));
  EXPECT_EQ(j["reference_deg"], 1.0);
  EXPECT_EQ(j["average_samples"], 100);
  EXPECT_EQ(j["difference_mean_arcsec"], 7.5);
  EXPECT_EQ(j["difference_std_arcsec"], 2.5);
  EXPECT_EQ(j["noise_level_rad_s"], 1e-4);
  EXPECT_EQ(j["enter_rad_s"], 8e-4);
  EXPECT_EQ(j["exit_rad_s"], 3e-4);
  EXPECT_EQ(j["skipped_t_s"], nlohmann::ordered_json::array({42.5}));
  ASSERT_EQ(j["rotations"].size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    const nlohmann::ordered_json& turn = j["rotations"][i];
    const DetectedRotation& want = r.rotations[i];
    EXPECT_EQ(Keys(turn), (std::vector<std::string>{"before_arcsec", "after_arcsec", "theta_arcsec",
                                                    "difference_arcsec", "theta_vector_arcsec",
                                                    "theta_so3_arcsec", "t_start_s", "t_end_s"}));
    for (int a = 0; a < 3; ++a) {
      EXPECT_EQ(turn["before_arcsec"][a], want.before_arcsec[a]);
      EXPECT_EQ(turn["after_arcsec"][a], want.after_arcsec[a]);
    }
    EXPECT_EQ(turn["theta_arcsec"], want.theta_arcsec);
    EXPECT_EQ(turn["difference_arcsec"], want.difference_arcsec);
    EXPECT_EQ(turn["theta_vector_arcsec"], want.theta_vector_arcsec);
    EXPECT_EQ(turn["theta_so3_arcsec"], want.theta_so3_arcsec);
    EXPECT_EQ(turn["t_start_s"], want.t_start_s);
    EXPECT_EQ(turn["t_end_s"], want.t_end_s);
  }
}

}  // namespace
}  // namespace shutterlab
