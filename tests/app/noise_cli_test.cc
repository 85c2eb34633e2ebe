// CLI tests of `shutterlab noise` and `shutterlab accuracy`: output formats, exit codes, bad input.

#include "sim/logs/gyro_io.h"
#include "sim/text_file.h"
#include "tests/app/cli_test_util.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

namespace shutterlab {
namespace {

using test::RunShutterlab;

constexpr int64_t kPeriodNs = 1'000'000;  // 1 kHz keeps the files small
constexpr double kSigmaRadS = 0.002;

// still_s of white noise, then turns of 1 deg about z (sin^2 rate pulses of 0.25 s), 1.5 s apart.
void WriteSession(const std::string& path, double still_s, int turns) {
  std::mt19937_64 rng(9);
  std::normal_distribution<double> unit(0.0, 1.0);
  std::vector<double> z(static_cast<size_t>(still_s * 1000), 0.0);
  for (int i = 0; i < turns; ++i) {
    const double peak = 2.0 * M_PI / 180.0 / 0.25;
    for (int j = 0; j < 250; ++j) z.push_back(peak * std::pow(std::sin(M_PI * j / 250.0), 2));
    z.resize(z.size() + 1500, 0.0);
  }
  std::vector<GyroSample> samples(z.size());
  for (size_t k = 0; k < z.size(); ++k) {
    samples[k].t_ns = static_cast<int64_t>(k) * kPeriodNs;
    samples[k].omega_rad_s = Eigen::Vector3d(0.01 + kSigmaRadS * unit(rng), kSigmaRadS * unit(rng),
                                             z[k] + kSigmaRadS * unit(rng));
  }
  WriteGyroCsv(path, GyroTrace(std::move(samples)));
}

TEST(NoiseCli, PrintsJsonAndWritesTheAllanCsv) {
  test::TempDir dir;
  const std::string trace = dir / "still.csv", allan = dir / "allan.csv";
  WriteSession(trace, 8.0, 0);
  const auto result =
      RunShutterlab("noise " + trace + " --window-samples 40 --json --allan " + allan);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const nlohmann::json j = nlohmann::json::parse(result.out);
  EXPECT_EQ(j.at("window_samples").get<int>(), 40);
  EXPECT_EQ(j.at("samples").get<int>(), 3000);  // 8 s at 1 kHz after the default bias 0:5
  // Random walk of step s = sigma dt = 0.41" over 40 points: rms sigma = s sqrt((N^2-1)/(6N)) =
  // 1.06"; only ~75 independent windows here, so a wide band.
  const double sigma_x = j["axes"]["x"]["sigma_rms_arcsec"].get<double>();
  EXPECT_GT(sigma_x, 0.8);
  EXPECT_LT(sigma_x, 1.3);
  const std::string csv = ReadFileToString(allan);
  EXPECT_EQ(csv.rfind("tau_s,adev_x,adev_y,adev_z\n0.001,", 0), 0u) << csv.substr(0, 80);
  EXPECT_GT(test::LineCount(csv), 20u);
}

// A logger that stamps its samples in threes with one time, every 1 ms, for still_s of noise: a
// median interval of 0.
void WriteBurstStampedTrace(const std::string& path, double still_s) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0.0, kSigmaRadS);
  std::vector<GyroSample> samples(static_cast<size_t>(still_s * 3000));
  for (size_t k = 0; k < samples.size(); ++k) {
    samples[k].t_ns = static_cast<int64_t>(k / 3) * kPeriodNs;
    samples[k].omega_rad_s = Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
  }
  WriteGyroCsv(path, GyroTrace(std::move(samples)));
}

TEST(NoiseCli, SamplesStampedInBurstsHaveNoAllanAndSayWhy) {
  // The Allan deviation needs a sample period; with a median interval of 0 it is not computed,
  // and the command says why instead of stopping (it stopped with "Allan: the trace has no
  // positive sample interval"). The sampling itself is stated once, as duplicate_time.
  test::TempDir dir;
  const std::string trace = dir / "bursts.csv";
  WriteBurstStampedTrace(trace, 8.0);
  const auto json = RunShutterlab("noise " + trace + " --json");
  ASSERT_EQ(json.exit_code, 0) << json.output;
  const nlohmann::json j = nlohmann::json::parse(json.out);
  EXPECT_NE(j.at("allan_not_computed").get<std::string>().find("median sample interval is 0"),
            std::string::npos);
  EXPECT_FALSE(j["axes"]["x"].contains("arw_deg_sqrt_h"));
  // The samples' rate, 23,999 intervals over 7.999 s (it said 0).
  EXPECT_NEAR(j.at("rate_hz").get<double>(), 23999 / 7.999, 0.01);
  EXPECT_NE(json.err.find("duplicate_time"), std::string::npos) << json.err;
  EXPECT_EQ(json.err.find("rate_change"), std::string::npos) << json.err;
  const auto table = RunShutterlab("noise " + trace);
  ASSERT_EQ(table.exit_code, 0) << table.output;
  EXPECT_NE(table.out.find("Allan deviation: not computed: the median sample interval is 0"),
            std::string::npos)
      << table.out;
}

TEST(NoiseCli, TableHasOneRowPerAxis) {
  test::TempDir dir;
  const std::string trace = dir / "still.csv";
  WriteSession(trace, 6.0, 0);
  const auto result = RunShutterlab("noise " + trace);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("sigma mean"), std::string::npos);
  EXPECT_NE(result.output.find("\n  z "), std::string::npos);
  EXPECT_NE(result.output.find("ARW"), std::string::npos);
}

TEST(NoiseCli, WindowLongerThanTheTraceIsOneLineExit2AndNoFile) {
  test::TempDir dir;
  const std::string trace = dir / "still.csv", allan = dir / "allan.csv";
  WriteSession(trace, 6.0, 0);
  const auto result = RunShutterlab("noise " + trace + " --window-samples 5000 --allan " + allan);
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_EQ(test::LineCount(result.output), 1u) << result.output;
  EXPECT_EQ(result.output.rfind("error: " + trace + ": window of 5000 samples", 0), 0u)
      << result.output;
  EXPECT_FALSE(std::filesystem::exists(allan));
}

// --window is a duration, as in flight: 40 ms at 1 kHz is the 40-sample window; a bare number is
// refused with both readings (a duration in ms, or the count --window-samples takes); the two
// together are refused.
TEST(NoiseCli, WindowIsADurationAndTheCountHasItsOwnOption) {
  test::TempDir dir;
  const std::string trace = dir / "still.csv";
  WriteSession(trace, 8.0, 0);
  const auto by_duration = RunShutterlab("noise " + trace + " --window 40ms --json");
  ASSERT_EQ(by_duration.exit_code, 0) << by_duration.output;
  const auto by_count = RunShutterlab("noise " + trace + " --window-samples 40 --json");
  ASSERT_EQ(by_count.exit_code, 0) << by_count.output;
  EXPECT_EQ(nlohmann::json::parse(by_duration.out)["window_samples"], 40);
  EXPECT_EQ(by_duration.out, by_count.out);
  const auto bare = RunShutterlab("noise " + trace + " --window 120");
  EXPECT_EQ(bare.exit_code, 2);
  EXPECT_EQ(test::LineCount(bare.output), 1u) << bare.output;
  EXPECT_NE(bare.err.find("--window '120': a duration needs a unit: did you mean 120ms, or "
                          "--window-samples 120?"),
            std::string::npos)
      << bare.err;
  const auto decimal = RunShutterlab("noise " + trace + " --window 40.0");
  EXPECT_NE(decimal.err.find("did you mean 40.0ms, or --window-samples 40.0?"), std::string::npos)
      << decimal.err;
  const auto both = RunShutterlab("noise " + trace + " --window 40ms --window-samples 40");
  EXPECT_EQ(both.exit_code, 2);
  EXPECT_NE(both.err.find("excludes"), std::string::npos) << both.err;
  const auto too_short = RunShutterlab("noise " + trace + " --window 1ms");
  EXPECT_EQ(too_short.exit_code, 2);
  EXPECT_NE(too_short.err.find("a window of 1ms holds 1 sample(s) at 1000 Hz"), std::string::npos)
      << too_short.err;
}

TEST(NoiseCli, BadBiasSegmentIsExit2) {
  test::TempDir dir;
  const std::string trace = dir / "still.csv";
  WriteSession(trace, 6.0, 0);
  const auto result = RunShutterlab("noise " + trace + " --bias 3:1s");
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_EQ(test::LineCount(result.output), 1u) << result.output;
}

TEST(AccuracyCli, FindsEachTurnAndPrintsJson) {
  test::TempDir dir;
  const std::string trace = dir / "station.csv";
  WriteSession(trace, 5.5, 3);
  const auto result = RunShutterlab("accuracy " + trace + " --reference-deg 1 --average 50 --json");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const nlohmann::json j = nlohmann::json::parse(result.out);
  EXPECT_DOUBLE_EQ(j.at("reference_deg").get<double>(), 1.0);
  ASSERT_EQ(j.at("rotations").size(), 3u);
  for (const auto& rot : j["rotations"]) {
    // Noise 2e-3 rad/s at 1 kHz: ~7.5" random walk between the averaging windows (fixed seed).
    EXPECT_NEAR(rot.at("theta_arcsec").get<double>(), 3600.0, 20.0);
    EXPECT_NEAR(rot.at("difference_arcsec").get<double>(),
                rot.at("theta_arcsec").get<double>() - 3600.0, 1e-9);
  }
  const auto table = RunShutterlab("accuracy " + trace + " --reference-deg 1");
  ASSERT_EQ(table.exit_code, 0) << table.output;
  EXPECT_NE(table.output.find("Turns detected: 3"), std::string::npos) << table.output;
}

TEST(AccuracyCli, NoTurnOrNoReferenceIsExit2) {
  test::TempDir dir;
  const std::string trace = dir / "still.csv";
  WriteSession(trace, 8.0, 0);
  const auto none = RunShutterlab("accuracy " + trace + " --reference-deg 1");
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_EQ(test::LineCount(none.output), 1u) << none.output;
  EXPECT_NE(none.output.find("no rotation found"), std::string::npos) << none.output;
  const auto missing = RunShutterlab("accuracy " + trace);
  EXPECT_EQ(missing.exit_code, 2);
  const auto bad = RunShutterlab("accuracy " + trace + " --reference-deg -1");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_EQ(test::LineCount(bad.output), 1u) << bad.output;
}

}  // namespace
}  // namespace shutterlab
