#pragma once
// CLI options shared by every command that reads a gyro trace: format selection and bias segment.

#include "sim/bias.h"
#include "sim/logs/flight_log_io.h"
#include "sim/logs/gyro_io.h"
#include "sim/still_detect.h"

#include <CLI/CLI.hpp>

#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace shutterlab::app {

// --time-unit, --columns, --delimiter and --rate-unit: how to read a file by its columns (and the
// time unit of raw counts), shared by the trace commands and analyze.
struct ColumnFlags {
  std::string columns;          // "" = detect the format from the content
  std::string delimiter;        // "" = auto
  std::string rate_unit;        // "" = rad/s
  std::string time_unit = "s";  // raw counts and --columns: unit of the time column

  void Add(CLI::App* command);
  // Sets the time units and, with --columns, the column reader (options->format = kColumns).
  // Throws std::invalid_argument for a bad value, --delimiter or --rate-unit without --columns, or
  // --columns with a --format other than auto / columns.
  void Apply(FlightLogReadOptions* options) const;
};

struct TraceOptions {
  std::string path;
  std::string format = "auto";  // auto | csv | gcsv | raw | ulog | blackbox | dataflash | columns
  bool raw = false;             // shorthand for --format raw
  int range_dps = 250;          // raw counts: full-scale range
  ColumnFlags column_flags;     // --time-unit, --columns, --delimiter, --rate-unit
  std::string bias = "0:5";     // bias segment A:B, seconds after the first sample
  bool auto_bias = false;       // find the still segment automatically instead of --bias

  // Adds TRACE (positional) and the options above to a subcommand. with_bias: add --bias too.
  void Add(CLI::App* command, bool with_bias);
  FlightLogReadOptions ReadOptions() const;
  // Reads the log and prints its warnings on stderr (PrintLogWarnings).
  FlightLog Load() const;
  // Reads the log as a stream, a block at a time with the reader a chunk ahead on a second thread,
  // handing each chunk to consume; shows progress on a terminal (label), prints the warnings on
  // stderr once the log is read, and returns them with the sampling.
  StreamedLog Stream(const std::string& label,
                     const std::function<void(const GyroChunk&)>& consume) const;
  // The bias segment for this trace: with --auto-bias the detected still segment
  // (DetectStillSegment, default StillDetectOptions; one note "auto-bias: still segment A:B s" on
  // stderr), otherwise --bias A:B. Throws std::invalid_argument when neither gives a segment.
  BiasSegment Segment(const GyroTrace& trace) const;
};

// What the reader could not read or trust, one "warning: PATH: LINE" on stderr each, so that no
// command analyses less than the file holds without saying so.
void PrintLogWarnings(const std::string& path, const std::vector<LogWarning>& warnings);

// Runs analysis(trace, options) the way every trace command does: --bias is parsed and the options
// checked before the (possibly long) read, the log's warnings are printed (and handed back in
// *warnings for --json), the segment is resolved after the read (--auto-bias detects the still
// segment), and the analysis's own errors are prefixed with the trace's path.
template <typename Options, typename Analysis>
auto AnalyzeTrace(const TraceOptions& trace_options, Options options, const Analysis& analysis,
                  std::vector<LogWarning>* warnings = nullptr) {
  if (!trace_options.auto_bias) options.bias = ParseBiasSegment(trace_options.bias);
  options.Check();
  FlightLog log = trace_options.Load();
  if (warnings) *warnings = log.warnings;
  const GyroTrace& trace = log.gyro;
  options.bias = trace_options.Segment(trace);
  try {
    return analysis(trace, options);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(trace_options.path + ": " + e.what());
  }
}

}  // namespace shutterlab::app
