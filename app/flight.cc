// `shutterlab flight`: the source paper's flight analysis (Table 4): the share of readout-long
// windows in which the camera turned more than a ground limit allows.

#include "estimate/paper/flight.h"

#include "app/command.h"
#include "app/trace_options.h"
#include "estimate/report/analysis_json.h"
#include "sim/check.h"
#include "sim/units.h"

#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace shutterlab::app {
namespace {

struct FlightCommand {
  TraceOptions trace;
  FlightOptions flight;
  std::vector<std::string> limits{"5cm", "10cm"};
  std::vector<std::string> windows{"10ms", "20ms"};
  bool no_vector = false;
  bool zero_bias = false;
  bool json = false;
  std::string series_path;
};

void Run(const FlightCommand& command) {
  FlightOptions options = command.flight;
  options.limits_m.clear();
  for (const std::string& text : command.limits) options.limits_m.push_back(ParseLengthM(text));
  options.windows_s.clear();
  for (const std::string& text : command.windows) options.windows_s.push_back(ParseDurationS(text));
  options.vector_criterion = !command.no_vector;
  options.series = !command.series_path.empty();
  // A known (zero) bias takes precedence over the segment in Flight().
  if (command.zero_bias) options.known_bias_rad_s = Eigen::Vector3d::Zero();
  std::vector<LogWarning> warnings;
  FlightResult result;
  SensorPair pair;  // with --second
  const bool with_second = !command.trace.second_path.empty();
  // Streamed: memory stays bounded whatever the log's length. The still segment may lie anywhere
  // in the log: --auto-bias finds it in passes of its own before this one. With --second, the
  // pair is fitted in passes too and its fused samples analysed as they are made. Only a reading
  // in passes opens the log for them (a log on a pipe is then copied once to a temporary file);
  // one pass reads it as it comes.
  // The flags are checked before the log is opened (a pipe's copy can take a while).
  options.Check();
  const FlightLogReadOptions read = command.trace.ReadOptions();
  if (!command.trace.auto_bias) options.bias = ParseBiasSegment(command.trace.bias);
  std::optional<ReopenableFile> first;
  if (command.trace.auto_bias || with_second) first.emplace(command.trace.path);
  if (command.trace.auto_bias) {
    try {
      options.bias = command.trace.StreamedSegment(*first);
    } catch (const std::invalid_argument& e) {  // no still segment: named by the log, as below
      throw std::invalid_argument(command.trace.path + ": " + e.what());
    }
  }
  FlightStream flight(options);
  const auto add = [&flight](const GyroChunk& chunk) { flight.Add(chunk.data, chunk.size); };
  if (with_second) {
    const ReopenableFile second(command.trace.second_path);
    const PairInPasses fitted =
        FitPairInPasses(*first, second, read, OpenFlightLog(*first, read), options.bias);
    pair = fitted.pair;
    warnings = fitted.warnings;
    std::unique_ptr<GyroSource> fused = ReadAhead(fitted.OpenFused());
    Progress progress("flight", 1000);
    for (GyroChunk chunk = fused->Next(); !chunk.empty(); chunk = fused->Next()) {
      add(chunk);
      progress.Update(static_cast<size_t>(fused->Fraction() * 1000));
    }
    second.CheckUnchanged();
  } else {
    warnings = command.trace.Stream("flight", add, first ? &*first : nullptr).warnings;
  }
  if (first) first->CheckUnchanged();
  try {
    result = flight.Finish();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(command.trace.path + ": " + e.what());
  }
  // The analysis's own warnings (windows refused as too short) go on stderr as the reader's did:
  // the list there is the --json's.
  PrintLogWarnings(command.trace.path, result.warnings);
  warnings.insert(warnings.end(), result.warnings.begin(), result.warnings.end());
  if (options.series) WriteFlightSeriesCsv(command.series_path, result.series);
  if (command.json) {
    nlohmann::json json = FlightToJson(result);
    if (!command.trace.second_path.empty())
      json["pair"] = SensorPairToJson(pair, command.trace.second_path);
    json["warnings"] = WarningsToJson(warnings);
    std::cout << JsonText(json) << "\n";
  } else {
    if (!command.trace.second_path.empty()) {
      std::cout << SensorPairText(pair, command.trace.path, command.trace.second_path) << "\n";
    }
    std::cout << FlightTable(result);  // its own line says which rows had too few samples
  }
}

const CommandRegistration kFlightRegistration(40, [](CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "flight",
      "share of time windows whose rotation smears the image beyond a ground limit (Table 4)");
  auto command = std::make_shared<FlightCommand>();
  command->trace.Add(cmd, /*with_bias=*/true);
  command->trace.AddSecond(cmd);
  cmd->add_option("--altitude", command->flight.altitude_m, "height above flat ground, m")
      ->capture_default_str();
  cmd->add_option("--limit", command->limits, "ground limits, e.g. 5cm,10cm (m, cm, mm; bare = m)")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option(
         "--window", command->windows,
         "window durations (the rolling-shutter readout), e.g. 10ms,20ms (s, ms, us; bare = s)")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--noise-allowance", command->flight.noise_allowance_arcsec,
                  "added to each threshold for the gyro's own noise, arcsec")
      ->capture_default_str();
  cmd->add_flag("--no-vector", command->no_vector,
                "skip the vector (SO(3) rotation angle) criterion, about halving the run time");
  cmd->add_flag(
      "--zero-bias", command->zero_bias,
      "take the logged rates as bias-free and analyse every sample (flight-controller logs, "
      "calibrated at arming)");
  cmd->add_flag("--json", command->json,
                "print JSON (docs/FORMATS.md `flight`) instead of a table");
  cmd->add_option("--series", command->series_path,
                  "write per-window ranges for the FIRST --window duration to this CSV: "
                  "t,range_x,range_y,range_z,vector (window start in s; arcsec)");
  return std::function<void()>([command] { Run(*command); });
});

}  // namespace
}  // namespace shutterlab::app
