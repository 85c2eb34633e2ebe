#pragma once
// Betaflight / Cleanflight / INAV blackbox flight logs: the native binary format (.bbl, .bfl,
// .txt; several logs in one file, each starting with the "H Product:Blackbox flight data recorder
// by Nicholas Sherlock" header line) and the CSV that blackbox_decode / Blackbox Explorer export.
//
// The gyro trace is the main frames' `gyroADC[0..2]` (`gyroData[..]` in old logs) at the main
// frames' `time` (µs, flight-controller clock, 32-bit rollover undone), converted to rad/s with
// the header's gyro_scale (see GyroRadPerSecondPerLsb in blackbox.cc for the rule and its source).
// Axes are the flight controller's (Betaflight: x roll, y pitch, z yaw after board alignment).
//
// FlightLog::altitude_above_ground_m is left empty: Betaflight's BaroAlt is relative to the
// barometer's power-on level and drifts by metres (LOG00037: -6.6 .. +2.9 m on a 17 s flight), and
// GPS altitude is above sea level. camera_events stay empty: Betaflight logs no camera triggers.
//
// Corrupt input never crashes or hangs the reader: frames that do not decode are skipped and
// counted (FlightLog::records_skipped, one warning line per kind), as blackbox-tools does; a file
// that has no usable header or no main frame throws IoError naming the path and the problem.

#include "sim/logs/flight_log.h"

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace shutterlab {

// One log of a blackbox file, as ListBlackboxLogs finds it.
struct BlackboxLogInfo {
  int index = 0;               // 0-based position in the file; what ReadBlackbox's log_index takes
  size_t begin_byte = 0;       // offset of its "H Product:" line in the file
  size_t size_bytes = 0;       // up to the next log or the end of the file
  size_t main_frames = 0;      // I and P frames accepted, i.e. gyro samples
  size_t i_frames = 0;         // of which intra frames
  size_t skipped_frames = 0;   // corrupt frames plus main frames rejected while resynchronising
  double duration_s = 0.0;     // first to last accepted main frame
  double rate_hz = 0.0;        // 1 / median interval between accepted main frames
  bool ended_cleanly = false;  // closed by a LOG_END event ("End of log")
  std::string
      firmware;  // "Firmware revision" header, e.g. "Betaflight 4.2.8 (101738d8e) STM32F7X2"
  std::string craft_name;  // "Craft name" header, may be empty
  std::string problem;     // why the log cannot be read (e.g. truncated header); empty when fine
};

// True when the start of a file looks like a blackbox log: the native start marker anywhere in
// first_bytes, or a CSV header line naming loopIteration, time and gyroADC[0] (blackbox_decode /
// Blackbox Explorer export). Pass the first few KiB.
bool LooksLikeBlackbox(std::string_view first_bytes);

// Lists every log in a blackbox file (a CSV export is one log). Decodes each log fully to count
// its frames. Throws IoError when the file cannot be read or is not a blackbox log.
std::vector<BlackboxLogInfo> ListBlackboxLogs(const std::string& path);

// Reads one log of a blackbox file: log_index from ListBlackboxLogs, or -1 for the one with the
// most main frames (the first of equals). FlightLog::format is "betaflight" (native) or
// "betaflight_csv"; gyro_source "gyroADC". Throws IoError when the file is not a blackbox log,
// log_index is out of range, the chosen log's header lacks what the gyro needs, or it holds no
// main frame.
FlightLog ReadBlackbox(const std::string& path, int log_index = -1);

// Decoding statistics of the last call, for the benchmark and tests: bytes of the decoded logs.
// Not needed by ordinary callers.
struct BlackboxDecodeStats {
  size_t bytes_decoded = 0;
};
// Decodes every log of an in-memory native blackbox file and returns the chosen log as
// ReadBlackbox does; `path` only names the source in messages. Exposed for benchmarks and
// corruption tests that mutate the bytes without touching the disk.
FlightLog DecodeBlackbox(std::string_view bytes, const std::string& path, int log_index = -1,
                         BlackboxDecodeStats* stats = nullptr);
// ListBlackboxLogs on an in-memory native blackbox file.
std::vector<BlackboxLogInfo> ListBlackboxLogsInBuffer(std::string_view bytes,
                                                      const std::string& path);

}  // namespace shutterlab
