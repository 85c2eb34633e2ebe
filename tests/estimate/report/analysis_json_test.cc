// The paper's analyses as docs/FORMATS.md's JSON: every key the contract names, with the values
// the typed results hold.
#include "estimate/report/analysis_json.h"

#include "tests/estimate/loop/effect_fixtures.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace shutterlab {
namespace {

constexpr int64_t kDtNs = 1'000'000;  // 1 kHz
constexpr double kStillS = 4.0;       // a still lead-in: the bias segment

// Still for kStillS, then a constant rate about (1, 1, 1) until total_s.
GyroTrace ConstantRateTrace(double rate_rad_s, double total_s) {
  std::vector<GyroSample> samples;
  const int64_t n = static_cast<int64_t>(total_s * 1e9) / kDtNs + 1;
  const int64_t still_n = static_cast<int64_t>(kStillS * 1e9) / kDtNs;
  const Eigen::Vector3d axis = Eigen::Vector3d::Ones().normalized();
  for (int64_t k = 0; k < n; ++k) {
    const Eigen::Vector3d rate =
        k <= still_n ? Eigen::Vector3d::Zero() : Eigen::Vector3d(rate_rad_s * axis);
    samples.push_back({k * kDtNs, rate});
  }
  return GyroTrace(std::move(samples));
}

TEST(AnalysisJson, FlightHasTheContractsKeys) {
  FlightOptions options;
  options.bias = {0.0, 2.0};
  const FlightResult r = Flight(ConstantRateTrace(0.1, 8.0), options);
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
  const nlohmann::json no_vector = FlightToJson(Flight(ConstantRateTrace(0.1, 8.0), options));
  EXPECT_TRUE(no_vector["rows"][0]["flagged_percent_vector"].is_null());
}

TEST(AnalysisJson, AnalyzeHasTheContractsKeysAndOneEntryPerImage) {
  FlightLog log;
  log.gyro = ConstantRateTrace(0.05, 12.0);
  log.format = "test";
  log.gyro_source = "constant";
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

}  // namespace
}  // namespace shutterlab
