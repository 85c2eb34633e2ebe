#pragma once
// One entry point for every log the project reads: flight-controller logs (PX4 ULog, ArduPilot
// DataFlash, Betaflight blackbox native or CSV export), a GoPro MP4's GPMF gyro, and plain gyro
// logs (gyro.csv, Gyroflow .gcsv, the source paper's raw counts), detected by content. Plain gyro
// logs are wrapped into a FlightLog with no camera events and no altitude, so that `analyze` treats
// every source alike.

#include "sim/gyro_source.h"
#include "sim/logs/column_csv.h"
#include "sim/logs/flight_log.h"
#include "sim/logs/log_format.h"
#include "sim/text_file.h"
#include "sim/trace_audit.h"

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace shutterlab {

struct FlightLogReadOptions {
  LogFormat format = LogFormat::kAuto;
  int log_index = -1;        // blackbox files only: which log (ListBlackboxLogs); -1 = the longest
  RawCountOptions raw;       // raw-count logs only
  ColumnCsvOptions columns;  // format kColumns only (its columns, delimiter, header and units)
  // The flight-controller logs (ULog, DataFlash, blackbox) only: told the share of the log read by
  // the opening's pass 1 (tens of seconds on 10^8 samples) as it goes, never less than before, and
  // 1 at its end. Empty: not told (what a command leaves it when stderr is no terminal).
  OpeningProgress opening_progress;
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

struct FlightLogStream;

// How a format is recognised when no --format is given.
enum class LogDetection {
  kBytes,      // by its first bytes (a magic, a header), before anything else
  kText,       // by its first lines, once the file is known to be text
  kPlainGyro,  // by the plain gyro logs' rules (sim/logs/gyro_io.h DetectGyroFormat), last
  kNever,      // never detected: chosen by --columns / --format
};

// One entry of the reader table: every format the project reads, with what dispatch, the
// --format list, the messages, the fuzz targets and the docs are made from or checked against
// (tests/sim/logs/flight_log_io_test.cc). Adding a log format: docs/model.md.
struct LogReader {
  LogFormat format;
  const char* names[3];      // --format names, case-insensitive; the first is the canonical one
  const char* display_name;  // for a person: "ULog", "GoPro MP4", "raw counts"
  LogDetection detection;
  // Recognises the format (kBytes: the file's first 16 KiB; kText: its whole first lines).
  bool (*recognise)(std::string_view first_bytes);
  // Opens input (path's, for messages) as a stream: a text log's header, or a binary log's first
  // pass (telling progress, may be empty); throws IoError naming path on unreadable input.
  FlightLogStream (*open)(TextBlocks input, const std::string& path,
                          const FlightLogReadOptions& options, const OpeningProgress& progress);
  // Opened in a first pass over the whole file that tells its progress (the flight-controller
  // logs); a GoPro MP4 is decoded whole instead, and text logs open by their header.
  bool opening_pass;
  bool camera_events;         // may carry camera events and GPS time (FlightLog::camera_events)
  const char* fuzz_target;    // fuzz/NAME_fuzz.cc: the fuzz target of its reader
  const char* reader_header;  // the reader's header, as docs/FORMATS.md's table names it
};
// In detection order (and the order messages list the formats in).
const std::vector<LogReader>& LogReaders();
// The reader of a format (not kAuto).
const LogReader& ReaderOf(LogFormat format);

// "auto" or the format's canonical name ("gyro.csv", "ulog", "gopro", ...).
const char* LogFormatName(LogFormat format);
// "auto", then every format's canonical name in the table's order.
std::vector<std::string> LogFormatNames();
// Any name of the table, case-insensitive ("auto", "ulog" / "ulg" / "px4", "csv", ...); throws
// std::invalid_argument naming the text and listing LogFormatNames otherwise.
LogFormat ParseLogFormat(const std::string& name);
// "auto" or a plain gyro format ("gyro.csv" / "csv", "gcsv", "raw"), case-insensitive; throws
// std::invalid_argument naming the text otherwise (a flight-log format too).
LogFormat ParseGyroFormat(const std::string& name);

// Detects the format from the first bytes of a file (a few KiB): ULog magic, DataFlash FMT
// header, blackbox marker, an MP4's first box or CSV header, in that order; otherwise the plain
// gyro formats by sim/logs/gyro_io.h DetectGyroFormat. Throws IoError naming path when none
// matches.
LogFormat DetectFlightLogFormat(std::string_view first_bytes, const std::string& path);

// Reads any supported log. Plain gyro logs give format "gyro.csv" / "gcsv" / "raw", gyro_source
// "t,gx,gy,gz" / "gcsv" / "raw counts", no camera events and no altitude; kColumns gives format
// "columns" and gyro_source the chosen columns ("time_ms,wx,wy,wz" or "4,1,2,3"). Throws IoError
// (path, line or byte, problem) on unreadable or unknown input. FlightLog::warnings holds the
// reader's own (truncation, corrupt records, ...) followed by sim/trace_audit.h's (gaps, rate
// changes, saturation): everything a command must tell the user it could not read or trust.
FlightLog ReadFlightLog(const std::string& path, const FlightLogReadOptions& options = {});

// A log opened to be read as a stream. The text logs (gyro.csv, .gcsv, raw counts, --columns) are
// parsed a block at a time as the chunks are taken, in bounded memory whatever their length; so
// are the flight-controller logs, each in two passes over its mapped bytes: a first when opened
// (everything but the samples, and what choosing and cleaning the gyro stream needs), the samples
// decoded again as they are taken (sim/logs/ulog.h, dataflash.h, blackbox.h). A GoPro MP4 is
// decoded whole when opened (its gyro is ~200 Hz), then handed on in slices.
struct FlightLogStream {
  FlightLog log;                     // all but the samples (log.gyro stays empty)
  std::unique_ptr<GyroSource> gyro;  // the samples; reading errors are thrown from Next
  TraceAuditOptions audit;           // for the trace audit (raw counts: their stated range)
  // false: the samples are made from logs audited already (a fused pair), whose warnings are in
  // log.warnings; ConsumeFlightLog then adds no audit of these (it still gives their sampling).
  bool audit_warnings = true;
};
// Detects the format and reads what comes before the samples (a text log's header, a whole binary
// log); throws IoError as ReadFlightLog does.
FlightLogStream OpenFlightLog(const std::string& path, const FlightLogReadOptions& options = {});
// The same from an input already opened (path names it in messages).
FlightLogStream OpenFlightLog(TextBlocks input, const std::string& path,
                              const FlightLogReadOptions& options = {});
// One pass of a reading in several (sim/text_file.h ReopenableFile: a regular file opened again
// and checked unchanged, a pipe's copy read again).
FlightLogStream OpenFlightLog(const ReopenableFile& file, const FlightLogReadOptions& options = {});

// What a streamed log lost (the reader's warnings, then the trace audit's, as ReadFlightLog gives
// them) and how it was sampled.
struct StreamedLog {
  std::vector<LogWarning> warnings;
  TraceSampling sampling;
};
// Reads the stream to its end, handing every chunk to consume once the trace audit has taken it;
// progress (may be empty) gets the share of the input read.
StreamedLog ConsumeFlightLog(FlightLogStream* stream,
                             const std::function<void(const GyroChunk&)>& consume,
                             const std::function<void(double)>& progress = {});

}  // namespace shutterlab
