// `shutterlab flight`: the source paper's flight analysis (Table 4): the share of readout-long
// windows in which the camera turned more than a ground limit allows.

#include "estimate/paper/flight.h"

#include "app/command.h"
#include "app/trace_options.h"
#include "estimate/paper/analyze.h"
#include "estimate/paper/log_pipeline.h"
#include "estimate/report/analysis_json.h"
#include "sim/text_file.h"

#include <iostream>
#include <memory>
#include <string>
#include <vector>

namespace shutterlab::app {
namespace {

struct FlightCommand {
  TraceOptions trace;
  FlightOptions flight;
  bool no_vector = false;
  const CLI::Option* altitude = nullptr;  // given or not: a default is said as assumed
  const CLI::Option* windows = nullptr;
  bool json = false;
  std::string series_path;
};

// The inputs flight took as defaults: the height, the readout windows (the paper's) and the bias.
std::vector<Assumption> Assumptions(const FlightCommand& command) {
  std::vector<Assumption> assumed;
  if (command.altitude->count() == 0) {
    assumed.push_back(
        {"altitude", FormatNumber("%g m", command.flight.altitude_m), "", "--altitude"});
  }
  if (command.windows->count() == 0) {
    std::string windows;
    for (double w : command.flight.windows_s) {
      windows += (windows.empty() ? "" : ", ") + FormatNumber("%g ms", w * 1e3);
    }
    assumed.push_back(
        {"readout", windows + " (the paper's windows)", "", "--window with your camera's readout"});
  }
  const std::vector<Assumption> bias = command.trace.BiasAssumptions();
  assumed.insert(assumed.end(), bias.begin(), bias.end());
  return assumed;
}

void Run(const FlightCommand& command) {
  FlightOptions options = command.flight;
  options.vector_criterion = !command.no_vector;
  options.series = !command.series_path.empty();
  // A known (zero) bias takes precedence over the segment in Flight().
  if (command.trace.zero_bias) options.known_bias_rad_s = Eigen::Vector3d::Zero();
  // The flags are checked before the log is opened (a pipe's copy can take a while).
  options.Check();
  const LogInput input = command.trace.Input();
  if (!command.trace.auto_bias) options.bias = command.trace.Segment();
  PipelinePrinter printer;
  const FlightRun run = RunFlight(input, options, printer.Events());
  printer.Done();
  if (options.series) WriteFlightSeriesCsv(command.series_path, run.result.series);
  const std::vector<Assumption> assumed = Assumptions(command);
  if (command.json) {
    nlohmann::json json = FlightToJson(run.result);
    if (run.pair) json["pair"] = SensorPairToJson(*run.pair, command.trace.second_path);
    json["warnings"] = WarningsToJson(run.warnings);
    json["assumptions"] = AssumptionsToJson(assumed);
    std::cout << JsonText(json) << "\n";
  } else {
    if (run.pair) {
      std::cout << SensorPairText(*run.pair, command.trace.path, command.trace.second_path) << "\n";
    }
    std::cout << FlightTable(run.result);  // its own line says which rows had too few samples
    PrintAssumptions(assumed);
  }
}

const CommandRegistration kFlightRegistration(40, [](CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "flight",
      "share of time windows whose rotation smears the image beyond a ground limit (Table 4)");
  auto command = std::make_shared<FlightCommand>();
  command->trace.Add(cmd, /*with_bias=*/true);
  command->trace.AddSecond(cmd);
  command->altitude = AddQuantityOption(cmd, "--altitude", &command->flight.altitude_m, "m", "m",
                                        "height above flat ground");
  AddQuantityListOption(cmd, "--limit", &command->flight.limits_m, "m", "cm",
                        "ground limits, e.g. 5cm,10cm");
  command->windows =
      AddQuantityListOption(cmd, "--window", &command->flight.windows_s, "s", "ms",
                            "window durations (the rolling-shutter readout), e.g. 10ms,20ms");
  AddQuantityOption(cmd, "--noise-allowance", &command->flight.noise_allowance_arcsec, "arcsec",
                    "arcsec", "added to each threshold for the gyro's own noise");
  cmd->add_flag("--no-vector", command->no_vector,
                "skip the vector (SO(3) rotation angle) criterion, about halving the run time");
  cmd->add_flag("--json", command->json,
                "print JSON (docs/FORMATS.md `flight`) instead of a table");
  cmd->add_option("--series", command->series_path,
                  "write per-window ranges for the FIRST --window duration to this CSV: "
                  "t,range_x,range_y,range_z,vector (window start in s; arcsec)");
  return std::function<void()>([command] { Run(*command); });
});

}  // namespace
}  // namespace shutterlab::app
