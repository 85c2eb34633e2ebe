#include "app/trace_options.h"

#include <cstdio>

namespace shutterlab::app {

void TraceOptions::Add(CLI::App* command, bool with_bias) {
  command
      ->add_option("TRACE", path,
                   "gyro log: gyro.csv, Gyroflow .gcsv, raw-count CSV, PX4 ULog, Betaflight "
                   "blackbox, ArduPilot DataFlash")
      ->required()
      ->check(CLI::ExistingFile);
  command
      ->add_option("--format", format,
                   "log format: auto, csv, gcsv, raw, ulog, blackbox, dataflash")
      ->capture_default_str();
  command->add_flag("--raw", raw, "the log holds raw int16 counts (the source paper's logger)");
  command
      ->add_option("--range", range_dps,
                   "raw counts: gyro full-scale range, deg/s (250, 500, 1000, 2000)")
      ->capture_default_str();
  command
      ->add_option("--time-unit", time_unit, "raw counts: unit of the time column (s, ms, us, ns)")
      ->capture_default_str();
  if (with_bias) {
    command
        ->add_option("--bias", bias,
                     "still segment for the bias, A:B seconds after the first sample")
        ->capture_default_str();
    command->add_flag(
        "--auto-bias", auto_bias,
        "detect the still segment automatically (longest stretch >= 2 s whose 0.1 s mean "
        "and variance stay at the quiet level); overrides --bias");
  }
}

FlightLogReadOptions TraceOptions::ReadOptions() const {
  FlightLogReadOptions options;
  options.format = raw ? LogFormat::kRaw : ParseLogFormat(format);
  options.raw.range_dps = range_dps;
  options.raw.time_unit = ParseTimeUnit(time_unit);
  options.Check();
  return options;
}

// Any supported log: the gyro formats and the flight logs (ULog, blackbox, DataFlash) alike.
FlightLog TraceOptions::Load() const {
  FlightLog log = ReadFlightLog(path, ReadOptions());
  PrintLogWarnings(path, log.warnings);
  return log;
}

void PrintLogWarnings(const std::string& path, const std::vector<LogWarning>& warnings) {
  for (const LogWarning& w : warnings)
    std::fprintf(stderr, "warning: %s: %s\n", path.c_str(), WarningLine(w).c_str());
}

BiasSegment TraceOptions::Segment(const GyroTrace& trace) const {
  if (!auto_bias) return ParseBiasSegment(bias);
  const StillSegment still = DetectStillSegment(trace);
  std::fprintf(stderr, "auto-bias: still segment %.3f:%.3f s\n", still.segment.begin_s,
               still.segment.end_s);
  return still.segment;
}

}  // namespace shutterlab::app
