// `shutterlab sync A B`: the offset (and over a long overlap the rate) between two gyro logs'
// clocks, and the mounting between the gyros, from the motion alone (sim/gyro_sync.h).

#include "app/command.h"
#include "app/trace_options.h"
#include "sim/gyro_sync.h"
#include "sim/logs/flight_log_io.h"
#include "sim/text_file.h"

#include <nlohmann/json.hpp>

#include <iostream>
#include <memory>
#include <string>

namespace shutterlab::app {
namespace {

struct SyncCommand {
  std::string a_path, b_path;
  GyroSyncOptions options;
  bool json = false;
};

nlohmann::json SyncToJson(const SyncCommand& command, const GyroSync& s) {
  nlohmann::json rows = nlohmann::json::array();
  for (int i = 0; i < 3; ++i)
    rows.push_back({s.a_from_b(i, 0), s.a_from_b(i, 1), s.a_from_b(i, 2)});
  return {{"format", "sync/1"},
          {"a", command.a_path},
          {"b", command.b_path},
          {"offset_s", s.offset_s},
          {"offset_stderr_s", s.offset_stderr_s},
          {"reference_a_s", s.reference_a_s},
          {"rate_ppm", s.rate_ppm ? nlohmann::json(*s.rate_ppm) : nlohmann::json()},
          {"rate_stderr_ppm",
           s.rate_stderr_ppm ? nlohmann::json(*s.rate_stderr_ppm) : nlohmann::json()},
          {"a_from_b", rows},
          {"mounting_fitted", s.mounting_fitted},
          {"mounting_angle_deg", s.mounting_angle_deg},
          {"peak_correlation", s.peak_correlation},
          {"runner_up_correlation", s.runner_up_correlation},
          {"overlap_s", s.overlap_s},
          {"faster_interval_s", s.faster_interval_s},
          {"slower_interval_s", s.slower_interval_s},
          {"residual_rms_rad_s", s.residual_rms_rad_s},
          {"residuals", s.residuals}};
}

void Run(const SyncCommand& command) {
  const FlightLog a = ReadFlightLog(command.a_path);
  PrintLogWarnings(command.a_path, a.warnings);
  const FlightLog b = ReadFlightLog(command.b_path);
  PrintLogWarnings(command.b_path, b.warnings);
  GyroSyncOptions options = command.options;
  options.a_name = command.a_path;
  options.b_name = command.b_path;
  options.bound_option = "--max-offset";
  const GyroSync s = SyncGyros(a.gyro, b.gyro, options);
  if (command.json) {
    std::cout << JsonText(SyncToJson(command, s)) << "\n";
    return;
  }
  std::cout << "B's clock = A's + " << FormatNumber("%.6f", s.offset_s) << " s +- "
            << FormatNumber("%.6f", s.offset_stderr_s) << " s (one standard error; "
            << FormatNumber("%.3f", s.offset_stderr_s / s.faster_interval_s)
            << " of the faster stream's " << FormatNumber("%.3g", 1e3 * s.faster_interval_s)
            << " ms interval), at A's " << FormatNumber("%.3f", s.reference_a_s) << " s\n";
  if (s.rate_ppm) {
    std::cout << "clock rate: B's runs " << FormatNumber("%.2f", *s.rate_ppm) << " +- "
              << FormatNumber("%.2f", *s.rate_stderr_ppm) << " ppm faster than A's (over "
              << FormatNumber("%.1f", s.overlap_s) << " s)\n";
  } else {
    std::cout << "clock rate: not fitted (overlap " << FormatNumber("%.1f", s.overlap_s)
              << " s, under " << FormatNumber("%.0f", command.options.min_rate_overlap_s)
              << " s)\n";
  }
  std::cout << "mounting: w_A = R w_B, R a turn of " << FormatNumber("%.2f", s.mounting_angle_deg)
            << " deg"
            << (s.mounting_fitted ? " (fitted from the motion)"
                                  : " (identity kept: the motion turns about one axis only)")
            << "\n";
  std::cout << "the rates' magnitudes correlate " << FormatNumber("%.2f", s.peak_correlation)
            << " at the offset, " << FormatNumber("%.2f", s.runner_up_correlation)
            << " at the next best; residual " << FormatNumber("%.4f", s.residual_rms_rad_s)
            << " rad/s per axis over " << s.residuals << " samples\n";
}

const CommandRegistration kSyncRegistration(96, [](CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "sync",
      "the offset (and rate) between two gyro logs' clocks and their mounting, from the "
      "motion");
  auto command = std::make_shared<SyncCommand>();
  CheckLogPath(cmd->add_option("A", command->a_path, "the first gyro or flight log")->required());
  CheckLogPath(cmd->add_option("B", command->b_path, "the second")->required());
  AddQuantityOption(cmd, "--max-offset", &command->options.max_offset_s, "s", "s",
                    "search offsets up to this far both ways (0: every offset that leaves 10 s "
                    "of overlap)");
  AddQuantityOption(cmd, "--min-rate-overlap", &command->options.min_rate_overlap_s, "s", "s",
                    "fit the clock rate too when the overlap is at least this long");
  cmd->add_flag("--json", command->json, "print the result as JSON (sync/1)");
  return std::function<void()>([command] { Run(*command); });
});

}  // namespace
}  // namespace shutterlab::app
