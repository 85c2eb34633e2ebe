// The log pipeline (estimate/paper/log_pipeline.h) against the analyses it streams, run on the log
// read whole: the same tables and images, the warnings told in the --json's order, errors named by
// the log, and the pair of two logs fused as FuseSensorPair fuses them.

#include "estimate/paper/log_pipeline.h"

#include "estimate/paper/analyze.h"
#include "estimate/paper/flight.h"
#include "sim/logs/flight_log_io.h"
#include "sim/logs/gyro_io.h"
#include "sim/still_detect.h"
#include "tests/estimate/paper/paper_fixtures.h"
#include "tests/model/model_fixtures.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace shutterlab {
namespace {

// A 1 kHz gyro.csv: still for 4 s, then a rate that smears about 7 cm over a 30 ms readout at
// 50 m, turning on and off every 0.3 s (so that some windows are flagged and some are not), with
// a 0.5 s gap at 9 s (a warning the pipeline must tell).
GyroTrace PipelineTrace() {
  const double rate = test::RateForGroundSmear(0.07);
  FlightLog log = test::StillThenRateLog(
      14.0,
      [rate](double t_s) {
        const bool on = static_cast<int>(std::floor(t_s / 0.3)) % 2 == 0;
        return Eigen::Vector3d(on ? rate : 0.1 * rate, 0.5 * rate, 0.0);
      },
      "pipeline");
  std::vector<GyroSample> samples;
  for (const GyroSample& s : log.gyro.samples()) {
    if (s.t_ns < 9'000'000'000 || s.t_ns >= 9'500'000'000) samples.push_back(s);
  }
  return GyroTrace(std::move(samples));
}

// What a pipeline told, in order: "warnings PATH KIND", "note TEXT", and the stages it reported.
struct Told {
  std::vector<std::string> lines;
  std::vector<std::string> stages;
  PipelineEvents Events() {
    PipelineEvents events;
    events.warnings = [this](const std::string& path, const std::vector<LogWarning>& warnings) {
      for (const LogWarning& w : warnings) lines.push_back("warning " + path + " " + w.kind);
    };
    events.note = [this](const std::string& line) { lines.push_back("note " + line); };
    events.progress = [this](const std::string& stage, double) {
      if (stages.empty() || stages.back() != stage) stages.push_back(stage);
    };
    return events;
  }
};

TEST(LogPipeline, RunFlightEqualsTheFlightOfTheLogReadWholeOnOneThreadOrTwo) {
  test::TempDir dir;
  const std::string path = dir / "gyro.csv";
  WriteGyroCsv(path, PipelineTrace());
  FlightOptions options;
  options.windows_s = {0.030, 0.010};  // rows[0]: 5 cm in 30 ms, which the turning exceeds
  const FlightLog whole = ReadFlightLog(path);
  const FlightResult expected = Flight(whole.gyro, options);
  ASSERT_GT(expected.rows[0].flagged, 0u);
  ASSERT_LT(expected.rows[0].flagged, expected.rows[0].windows);
  for (bool read_ahead : {false, true}) {
    LogInput input;
    input.path = path;
    input.read_ahead = read_ahead;
    Told told;
    const FlightRun run = RunFlight(input, options, told.Events());
    test::ExpectSameFlightRows(run.result, expected);
    EXPECT_FALSE(run.pair);
    // The log's warnings (its gap), told under its path and listed first.
    ASSERT_FALSE(whole.warnings.empty());
    ASSERT_GE(run.warnings.size(), whole.warnings.size());
    for (size_t i = 0; i < whole.warnings.size(); ++i)
      EXPECT_EQ(run.warnings[i].kind, whole.warnings[i].kind) << i;
    ASSERT_FALSE(told.lines.empty());
    EXPECT_EQ(told.lines.front(), "warning " + path + " gap");
    EXPECT_EQ(told.stages.back(), "flight");
  }
}

TEST(LogPipeline, RunFlightFindsTheStillSegmentWhenAskedAndSaysWhichInANote) {
  test::TempDir dir;
  const std::string path = dir / "gyro.csv";
  WriteGyroCsv(path, PipelineTrace());
  const FlightLog whole = ReadFlightLog(path);
  const BiasSegment still = DetectStillSegment(whole.gyro).segment;
  FlightOptions options;
  options.bias = {20.0, 30.0};  // beyond the log: ignored when the still segment is searched
  LogInput input;
  input.path = path;
  input.find_still_segment = true;
  Told told;
  const FlightRun run = RunFlight(input, options, told.Events());
  options.bias = still;
  test::ExpectSameFlightRows(run.result, Flight(whole.gyro, options));
  ASSERT_FALSE(told.lines.empty());
  EXPECT_EQ(told.lines.front(), "note auto-bias: still segment " +
                                    FormatNumber("%.3f:", still.begin_s) +
                                    FormatNumber("%.3f s", still.end_s));
  EXPECT_EQ(told.stages.front(), "auto-bias");
}

TEST(LogPipeline, TheAnalysisErrorsAreNamedByTheLog) {
  test::TempDir dir;
  const std::string path = dir / "gyro.csv";
  WriteGyroCsv(path, PipelineTrace());
  FlightOptions options;
  options.bias = {20.0, 30.0};  // after the log's end: no sample to take the bias from
  LogInput input;
  input.path = path;
  try {
    RunFlight(input, options);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).rfind(path + ": ", 0), 0u) << e.what();
  }
  LoadTrace(input, options.bias);  // reading alone is fine
}

TEST(LogPipeline, LoadTraceReadsTheLogWholeAndFusesASecondAsFuseSensorPairDoes) {
  test::TempDir dir;
  const GyroTrace trace = PipelineTrace();
  WriteGyroCsv(dir / "a.csv", trace);
  // The second sensor: the same motion with the axes swapped (x <-> y) and a little offset.
  std::vector<GyroSample> b;
  for (const GyroSample& s : trace.samples()) {
    b.push_back({s.t_ns, Eigen::Vector3d(s.omega_rad_s.y(), s.omega_rad_s.x(), s.omega_rad_s.z()) +
                             Eigen::Vector3d(1e-4, -2e-4, 3e-4)});
  }
  WriteGyroCsv(dir / "b.csv", GyroTrace(std::move(b)));
  LogInput input;
  input.path = dir / "a.csv";
  const BiasSegment segment{0.0, 3.0};
  Told alone_told;
  const LoadedTrace alone = LoadTrace(input, segment, alone_told.Events());
  EXPECT_EQ(alone.trace.size(), ReadFlightLog(input.path).gyro.size());
  EXPECT_FALSE(alone.pair);
  EXPECT_EQ(alone.segment.end_s, 3.0);

  input.second_path = dir / "b.csv";
  Told told;
  const LoadedTrace paired = LoadTrace(input, segment, told.Events());
  ASSERT_TRUE(paired.pair);
  SensorPairOptions pair_options;
  pair_options.still = segment;
  const SensorPair expected = FuseSensorPair(ReadFlightLog(input.path).gyro,
                                             ReadFlightLog(input.second_path).gyro, pair_options);
  EXPECT_TRUE(paired.pair->pair.a_from_b.isApprox(expected.a_from_b, 1e-12));
  EXPECT_EQ(paired.trace.size(), expected.fused.size());
  // Each log's gap, under its own path, the first's first.
  ASSERT_EQ(told.lines.size(), 2u);
  EXPECT_EQ(told.lines[0], "warning " + input.path + " gap");
  EXPECT_EQ(told.lines[1], "warning " + input.second_path + " gap");
  EXPECT_EQ(paired.warnings.size(), 2u);
}

TEST(LogPipeline, RunFlightOfAPairIsTheFlightOfTheFusedTrace) {
  test::TempDir dir;
  const GyroTrace trace = PipelineTrace();
  WriteGyroCsv(dir / "a.csv", trace);
  WriteGyroCsv(dir / "b.csv", trace);
  LogInput input;
  input.path = dir / "a.csv";
  input.second_path = dir / "b.csv";
  FlightOptions options;
  const FlightRun run = RunFlight(input, options);
  ASSERT_TRUE(run.pair);
  const LoadedTrace whole = LoadTrace(input, options.bias);
  test::ExpectSameFlightRows(run.result, Flight(whole.trace, options));
  EXPECT_TRUE(run.pair->a_from_b.isApprox(whole.pair->pair.a_from_b, 1e-12));
}

TEST(LogPipeline, RunAnalyzeEqualsAnalyzeOfTheLogReadWhole) {
  test::TempDir dir;
  const std::string path = dir / "gyro.csv";
  WriteGyroCsv(path, PipelineTrace());
  AnalyzeOptions options;
  options.rig = test::MappingRig();
  options.every_s = 1.0;
  LogInput input;
  input.path = path;
  Told told;
  const AnalyzeRun run = RunAnalyze(input, options, std::nullopt, told.Events());
  const AnalyzeResult whole = Analyze(ReadFlightLog(path), options);
  ASSERT_EQ(run.result.images.size(), whole.images.size());
  ASSERT_GT(whole.images.size(), 5u);
  for (size_t i = 0; i < whole.images.size(); ++i) {
    EXPECT_EQ(run.result.images[i].name, whole.images[i].name);
    EXPECT_EQ(run.result.images[i].d_full_m, whole.images[i].d_full_m) << i;
  }
  ASSERT_TRUE(run.result.flight && whole.flight);
  test::ExpectSameFlightRows(*run.result.flight, *whole.flight);
  EXPECT_EQ(told.lines.front(), "warning " + path + " gap");
  EXPECT_EQ(told.stages.back(), "analyze");
}

}  // namespace
}  // namespace shutterlab
