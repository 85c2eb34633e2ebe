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

#include "sim/gyro_source.h"
#include "sim/logs/flight_log.h"
#include "sim/text_file.h"

#include <cstddef>
#include <memory>
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
// its frames (and holds one log's sample times at a time, for its rate). Throws IoError when the
// file cannot be read or is not a blackbox log.
std::vector<BlackboxLogInfo> ListBlackboxLogs(const std::string& path);

// A blackbox log opened to be read as a stream, in memory that does not grow with its length.
// Opening reads the file once (pass 1: the logs' start markers, then every log decoded without
// keeping a sample, to choose one and to count what it lost); `log` then holds all but the
// samples (log.gyro stays empty), with every warning of the reader. `samples` decodes the chosen
// log again (pass 2) and hands its samples on in chunks of chunk_samples. A CSV export is read in
// one pass, a chunk of rows at a time; a row that does not read throws IoError from Next, and a
// cut last line is left out and said in samples->Warnings() (its only warnings).
// A mapped file's pages are handed back behind the decoder every few MiB; a file that changes
// between the passes (still being recorded, or rewritten: MappedFile::CheckUnchanged) makes Next
// throw IoError naming it.
struct BlackboxStream {
  FlightLog log;
  std::unique_ptr<GyroSource> samples;
};

// Opens one log of a blackbox file, native or CSV export: log_index from ListBlackboxLogs, or -1
// for the one with the most main frames (the first of equals). FlightLog::format is "betaflight"
// (native) or "betaflight_csv"; gyro_source "gyroADC". Throws IoError when the file is not a
// blackbox log, log_index is out of range, the chosen log's header lacks what the gyro needs, or it
// holds no main frame.
BlackboxStream OpenBlackbox(const std::string& path, int log_index = -1,
                            size_t chunk_samples = FillingSource::kDefaultChunkSamples);
// The same over a file mapped already (a pipe's bytes copied to a temporary file:
// TextBlocks::TakeMapped).
BlackboxStream OpenBlackbox(std::unique_ptr<MappedFile> file, int log_index = -1,
                            size_t chunk_samples = FillingSource::kDefaultChunkSamples);
// The same over bytes already in memory, which the stream keeps; `path` only names the source in
// messages.
BlackboxStream OpenBlackboxBytes(std::string bytes, const std::string& path, int log_index = -1,
                                 size_t chunk_samples = FillingSource::kDefaultChunkSamples);
// The same over a caller's buffer, which must outlive the stream (tests, fuzzing).
BlackboxStream OpenBlackboxBuffer(std::string_view bytes, const std::string& path,
                                  int log_index = -1,
                                  size_t chunk_samples = FillingSource::kDefaultChunkSamples);

// Reads one log of a blackbox file whole: OpenBlackbox's log with every sample and the samples'
// warnings after its own.
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
// ListBlackboxLogs on a blackbox file in memory.
std::vector<BlackboxLogInfo> ListBlackboxLogsInBuffer(std::string_view bytes,
                                                      const std::string& path);

}  // namespace shutterlab
