#pragma once
// CLI options shared by every command that reads a gyro trace (format selection, bias segment,
// a second sensor), and the printing of what the log pipeline says.

#include "app/command.h"
#include "estimate/paper/analyze.h"
#include "estimate/paper/log_pipeline.h"
#include "sim/bias.h"
#include "sim/log_warning.h"
#include "sim/logs/flight_log_io.h"

#include <CLI/CLI.hpp>

#include <stdexcept>
#include <string>
#include <utility>
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
  std::string format = "auto";  // LogFormatNames(): auto, gyro.csv, gcsv, raw, ulog, ... columns
  bool raw = false;             // shorthand for --format raw
  int range_dps = 250;          // raw counts: full-scale range
  ColumnFlags column_flags;     // --time-unit, --columns, --delimiter, --rate-unit
  std::string bias = "0:5s";    // bias segment A:B after the first sample
  bool auto_bias = false;       // find the still segment automatically instead of --bias
  bool zero_bias = false;       // the rates are bias-free: no segment, every sample analysed
  std::string second_path;      // --second: a second sensor's log on the same clock
  bool sync_second = false;     // --sync-second: ... or on a clock of its own
  CLI::Option* bias_option = nullptr;  // --bias, to tell a given segment from the default

  // Adds TRACE (positional) and the options above to a subcommand. with_bias: add --bias too.
  void Add(CLI::App* command, bool with_bias);
  // Adds --second (noise, flight): the second sensor of a pair.
  void AddSecond(CLI::App* command);
  FlightLogReadOptions ReadOptions() const;
  // The log pipeline's input (estimate/paper/log_pipeline.h): TRACE, the read options, --second,
  // --auto-bias.
  LogInput Input() const;
  // --bias A:B (throws std::invalid_argument for a bad one).
  BiasSegment Segment() const { return ParseBiasSegment(bias); }
  // The bias segment when none of --bias, --auto-bias, --zero-bias was given: said as assumed.
  std::vector<Assumption> BiasAssumptions() const;
};

// Prints each assumption's line ("assumed: ...; give ...") on stdout after a command's table.
void PrintAssumptions(const std::vector<Assumption>& assumptions);

// --sync-second (it needs --second): every command that takes a second sensor's log.
void AddSyncSecond(CLI::App* command, bool* sync_second);

// The --format option of a command that reads logs: every format of the reader table
// (sim/logs/flight_log_io.h LogReaders) in its help, after `what`.
CLI::Option* AddFormatOption(CLI::App* command, std::string* format,
                             const std::string& what = "log format");

// --range: a raw-count gyro's full scale, an angular rate in whole deg/s ("2000dps").
CLI::Option* AddRangeOption(CLI::App* command, int* range_dps,
                            const std::string& what = "raw counts: gyro full-scale range");

// What the reader could not read or trust, one "warning: PATH: LINE" on stderr each, so that no
// command analyses less than the file holds without saying so.
void PrintLogWarnings(const std::string& path, const std::vector<LogWarning>& warnings);

// Prints what the log pipeline says (estimate/paper/log_pipeline.h PipelineEvents) on stderr:
// progress on a terminal (a bar per stage, cleared before any line), each log's warnings as
// PrintLogWarnings does, notes as they are. Lives as long as the pipeline's run.
class PipelinePrinter {
 public:
  PipelineEvents Events();
  // Clears the progress bar: call when the run is done, before its results are printed.
  void Done() { progress_.Clear(); }

 private:
  StagedProgress progress_;
};

// Runs analysis(trace, options) on a log read whole, as noise and accuracy do: --bias is parsed
// and the options checked before the read, the log's warnings printed (and handed back in
// *loaded), and the analysis's own errors prefixed with the log's path. With --second the
// analysis runs on the pair's fused trace (loaded->pair holds both traces and their fusion).
template <typename Options, typename Analysis>
auto AnalyzeTrace(const TraceOptions& trace_options, Options options, const Analysis& analysis,
                  LoadedTrace* loaded_out = nullptr) {
  if (!trace_options.auto_bias) options.bias = trace_options.Segment();
  options.zero_bias = trace_options.zero_bias;
  options.Check();
  PipelinePrinter printer;
  LoadedTrace loaded = LoadTrace(trace_options.Input(), options.bias, printer.Events());
  printer.Done();
  options.bias = loaded.segment;
  try {
    auto result = analysis(loaded.trace, options);
    if (loaded_out) *loaded_out = std::move(loaded);
    return result;
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(trace_options.path + ": " + e.what());
  }
}

}  // namespace shutterlab::app
