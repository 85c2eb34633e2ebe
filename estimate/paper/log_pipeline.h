#pragma once
// The log pipeline that every command reading a gyro log runs, and the benchmark and the fleet
// batch call as the commands do: reader (sim/logs/flight_log_io.h: detect, open, stream) -> what
// the log lost (its reader's warnings and the trace audit's) -> the bias (a segment given, the
// still segment searched, or a known bias) -> the analyses (the flight table, the per-image
// analysis, the photos placed on the log), for one log or for a pair of logs on one clock
// (sim/sensor_pair.h) fused as they are read.
//
// Streamed in memory bounded by a chunk whatever the log's length: a reading in passes (the still
// search, the pair's fit, the per-image analysis) opens the log again for each (sim/text_file.h
// ReopenableFile: a regular file checked unchanged after the last pass, a pipe copied once to a
// temporary file); one pass reads it as it comes, the reader a chunk ahead on a second thread.
//
// What a person should see while it works goes through PipelineEvents: progress by stage, each
// log's warnings once it has been read through (before the analysis's own, in the order the
// --json's "warnings" lists them), notes. The commands (app/) only parse options and print.

#include "estimate/paper/analyze.h"
#include "estimate/paper/flight.h"
#include "estimate/paper/photo_flight.h"
#include "io/photo_set.h"
#include "sim/bias.h"
#include "sim/gyro_trace.h"
#include "sim/log_warning.h"
#include "sim/logs/flight_log_io.h"
#include "sim/logs/trigger_file.h"
#include "sim/sensor_pair.h"

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace shutterlab {

// The log a command reads and how.
struct LogInput {
  std::string path;  // "/dev/stdin" reads a pipe
  FlightLogReadOptions read;
  std::string second_path;  // a second sensor's log on the same clock, read alike; "" for none
  // The second log runs on a clock of its own (another recorder, a camera's gyro): put on the
  // first's from the motion (sim/gyro_sync.h, both logs read whole once) before it is paired;
  // the pair's clock_offset_s says what was found.
  bool second_own_clock = false;
  // Search the still segment for the bias (sim/still_detect.h DetectStillSegment, its defaults)
  // instead of the segment the analysis's options give.
  bool find_still_segment = false;
  bool read_ahead = true;  // parse a chunk ahead on a second thread (false: one thread)
};

// What the pipeline says while it works. Each may be empty (not told).
struct PipelineEvents {
  // The share done of a stage, 0 to 1: "LABEL (opening)" (a flight-controller log's first pass),
  // "LABEL" (the analysis's pass), "auto-bias" (the still search), "pair" (the pair's passes),
  // "analyze". Set only where a person watches (a terminal): work done only to feed it is skipped
  // when it is empty.
  std::function<void(const std::string& stage, double fraction)> progress;
  // What a log lost, named by its path, once it has been read through; then the analysis's own
  // (windows refused as too short), named by the first log.
  std::function<void(const std::string& path, const std::vector<LogWarning>& warnings)> warnings;
  // One line for a person: "auto-bias: still segment 1.000:6.000 s".
  std::function<void(const std::string& line)> note;
};

// A log read whole for an analysis of a trace (noise, accuracy).
struct TracePair {
  GyroTrace first, second;
  SensorPair pair;
};
struct LoadedTrace {
  GyroTrace trace;                   // the log's; with a second log the pair's fused trace
  BiasSegment segment;               // the one given, or the still segment found
  std::vector<LogWarning> warnings;  // the first log's, then the second's
  std::optional<TracePair> pair;     // with a second log
};
// segment: the bias segment (ignored with input.find_still_segment). Throws IoError naming a log
// it cannot read, std::invalid_argument (prefixed by the log's path) when no still segment is
// found or the logs do not pair.
LoadedTrace LoadTrace(const LogInput& input, const BiasSegment& segment,
                      const PipelineEvents& events = {});

// `flight`: the flight table of the log (or the pair's fused samples), streamed.
struct FlightRun {
  FlightResult result;
  std::vector<LogWarning> warnings;  // each log's, then the analysis's (FlightResult::warnings)
  std::optional<SensorPair> pair;    // with a second log (every field but `fused`)
};
// options.bias is the segment unless input.find_still_segment; options.known_bias_rad_s wins over
// both. The analysis's errors are prefixed by the log's path.
FlightRun RunFlight(const LogInput& input, FlightOptions options,
                    const PipelineEvents& events = {});

// The image triggers of a trigger file (sim/logs/trigger_file.h) as `analyze` takes them; its
// warnings go with the log's into the outputs, named by the file.
struct TriggerInput {
  TriggerFile file;
  std::string path;
};

// `analyze LOG`: the per-image analysis, streamed (estimate/paper/analyze.h AnalyzeStream). With
// triggers, the images are the trigger file's on the log's clock (options.triggers is set from
// them); options.progress is set from events.
struct AnalyzeRun {
  AnalyzeResult result;
  std::optional<SensorPair> pair;  // with a second log
};
AnalyzeRun RunAnalyze(const LogInput& input, AnalyzeOptions options,
                      const std::optional<TriggerInput>& triggers,
                      const PipelineEvents& events = {});

// `analyze --photos DIR LOG`: the photos placed on the log and analysed, streamed
// (estimate/paper/photo_flight.h AnalyzePhotoFlightStream).
struct PhotosOnLogRun {
  PhotoFlightResult result;
  std::optional<SensorPair> pair;  // with a second log
};
PhotosOnLogRun RunPhotosOnLog(const LogInput& input, const PhotoSet& set,
                              PhotoFlightOptions options,
                              const std::optional<TriggerInput>& triggers,
                              const PipelineEvents& events = {});

}  // namespace shutterlab
