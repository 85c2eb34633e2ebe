#include "app/trace_options.h"

#include "sim/check.h"
#include "sim/logs/flight_log_io.h"
#include "sim/logs/gyro_io.h"
#include "sim/logs/log_format.h"
#include "sim/units.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <unistd.h>

namespace shutterlab::app {

void ColumnFlags::Add(CLI::App* command) {
  command
      ->add_option("--time-unit", time_unit,
                   "unit of the time column for raw counts and --columns (s, ms, us, ns)")
      ->capture_default_str();
  command->add_option("--columns", columns,
                      "read any delimited file by its columns TIME,X,Y,Z: header names "
                      "(t,gx,gy,gz) or 1-based numbers (4,1,2,3); content detection otherwise");
  command->add_option("--delimiter", delimiter,
                      "with --columns: comma, semicolon, tab, whitespace (default: from the first "
                      "line)");
  command->add_option("--rate-unit", rate_unit, "with --columns: rad/s (default) or deg/s");
}

void ColumnFlags::Apply(FlightLogReadOptions* options) const {
  const TimeUnit unit = ParseTimeUnit(time_unit);
  options->raw.time_unit = unit;
  if (columns.empty()) {
    SHUTTERLAB_CHECK(delimiter.empty() && rate_unit.empty())
        << "--delimiter and --rate-unit are for --columns: give --columns TIME,X,Y,Z too";
    return;
  }
  SHUTTERLAB_CHECK(options->format == LogFormat::kAuto || options->format == LogFormat::kColumns)
      << "--columns reads the file by its columns; it cannot go with --format "
      << LogFormatName(options->format);
  options->format = LogFormat::kColumns;
  options->columns.columns = ParseColumnList(columns);
  options->columns.delimiter = delimiter.empty() ? '\0' : ParseDelimiter(delimiter);
  options->columns.rate_unit =
      rate_unit.empty() ? RateUnit::kRadPerSecond : ParseRateUnit(rate_unit);
  options->columns.time_unit = unit;
}

void TraceOptions::Add(CLI::App* command, bool with_bias) {
  CheckLogPath(command
                   ->add_option("TRACE", path,
                                "gyro log: gyro.csv, Gyroflow .gcsv, raw-count CSV, PX4 ULog, "
                                "Betaflight blackbox, ArduPilot DataFlash, GoPro MP4 (- = stdin)")
                   ->required());
  AddFormatOption(command, &format);
  command->add_flag("--raw", raw, "the log holds raw int16 counts (the source paper's logger)");
  AddRangeOption(command, &range_dps);
  column_flags.Add(command);
  if (with_bias) {
    bias_option =
        command
            ->add_option("--bias", bias,
                         "still segment for the bias, A:B after the first sample (0:5s, 2s:7s)")
            ->capture_default_str();
    auto* automatic = command->add_flag(
        "--auto-bias", auto_bias,
        "detect the still segment automatically (longest stretch >= 2 s whose 0.1 s mean "
        "and variance stay at the quiet level); overrides --bias");
    command
        ->add_flag("--zero-bias", zero_bias,
                   "take the logged rates as bias-free and analyse every sample "
                   "(flight-controller logs, calibrated at arming)")
        ->excludes(automatic)
        ->excludes(bias_option);
  }
}

std::vector<Assumption> TraceOptions::BiasAssumptions() const {
  if (bias_option == nullptr || bias_option->count() > 0 || auto_bias || zero_bias) return {};
  return {{"bias", "the mean over " + bias + " after the first sample",
           "the camera taken as still then",
           "--bias A:B over a still part, --auto-bias, or --zero-bias"}};
}

void PrintAssumptions(const std::vector<Assumption>& assumptions) {
  for (const Assumption& a : assumptions) std::cout << AssumptionLine(a) << "\n";
}

void TraceOptions::AddSecond(CLI::App* command) {
  CheckLogPath(command->add_option(
      "--second", second_path,
      "a second sensor's log on the same clock (record --device twice): paired, the mounting "
      "fitted from the motion, and fused"));
  AddSyncSecond(command, &sync_second);
}

void AddSyncSecond(CLI::App* command, bool* sync_second) {
  command
      ->add_flag("--sync-second", *sync_second,
                 "the --second log runs on a clock of its own (another recorder, a camera's "
                 "gyro): put it on LOG's from the motion first, as sync does (both read whole)")
      ->needs("--second");
}

FlightLogReadOptions TraceOptions::ReadOptions() const {
  FlightLogReadOptions options;
  options.format = raw ? LogFormat::kRaw : ParseLogFormat(format);
  options.raw.range_dps = range_dps;
  SHUTTERLAB_CHECK(!raw || column_flags.columns.empty())
      << "--raw and --columns exclude each other";
  column_flags.Apply(&options);
  options.Check();
  return options;
}

LogInput TraceOptions::Input() const {
  LogInput input;
  input.path = path;
  input.read = ReadOptions();
  input.second_path = second_path;
  input.second_own_clock = sync_second;
  input.find_still_segment = auto_bias;
  return input;
}

CLI::Option* AddFormatOption(CLI::App* command, std::string* format, const std::string& what) {
  std::string names = "auto";
  for (const LogReader& reader : LogReaders()) {
    if (reader.detection != LogDetection::kNever) names += std::string(", ") + reader.names[0];
  }
  return command
      ->add_option("--format", *format, what + ": " + names + " (columns: set by --columns)")
      ->capture_default_str();
}

CLI::Option* AddRangeOption(CLI::App* command, int* range_dps, const std::string& what) {
  return command
      ->add_option_function<std::string>(
          "--range",
          [range_dps](const std::string& text) {
            const double dps = ParseQuantityOption(text, "deg/s", "--range", "deg/s");
            if (dps != std::round(dps) || dps <= 0 || dps > 1e6) {
              throw CLI::ValidationError("--range '" + text +
                                         "': a full scale is a whole number of deg/s, e.g. "
                                         "2000deg/s");
            }
            *range_dps = static_cast<int>(dps);
          },
          what + " (250, 500, 1000, 2000deg/s)")
      ->type_name("ANGULAR RATE")
      ->default_str(QuantityText(*range_dps, "deg/s"));
}

void PrintLogWarnings(const std::string& path, const std::vector<LogWarning>& warnings) {
  for (const LogWarning& w : warnings)
    std::fprintf(stderr, "warning: %s: %s\n", path.c_str(), WarningLine(w).c_str());
}

PipelineEvents PipelinePrinter::Events() {
  PipelineEvents events;
  if (::isatty(STDERR_FILENO)) {
    events.progress = [this](const std::string& stage, double fraction) {
      progress_(stage, static_cast<size_t>(std::clamp(fraction, 0.0, 1.0) * 1000), 1000);
    };
  }
  events.warnings = [this](const std::string& path, const std::vector<LogWarning>& warnings) {
    if (warnings.empty()) return;
    progress_.Clear();
    PrintLogWarnings(path, warnings);
  };
  events.note = [this](const std::string& line) {
    progress_.Clear();
    std::fprintf(stderr, "%s\n", line.c_str());
  };
  return events;
}

}  // namespace shutterlab::app
