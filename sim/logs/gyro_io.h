#pragma once
// Readers and writers of gyro logs. Every reader throws IoError("PATH:LINE: problem") on bad input
// and never returns a partial trace, with one exception: a last line without its line break that
// does not read is the file cut inside it, left out and said by the source's Warnings
// (CutLastLineWarning), which the commands report (sim/logs/flight_log_io.h). The readers that
// return a bare GyroTrace (ReadGyroCsv, ReadRawCsv, ReadGyro) keep no warnings: they refuse such
// a file with an IoError instead.

#include "sim/gyro_source.h"
#include "sim/gyro_trace.h"
#include "sim/logs/gcsv.h"        // GcsvLog, ReadGcsv, WriteGcsv
#include "sim/logs/log_format.h"  // LogFormat, RawCountOptions, ParseGyroFormat
#include "sim/logs/raw_csv.h"     // TimeUnit, ReadRawCsv, WriteRawCsv
#include "sim/text_file.h"        // TextBlocks

#include <memory>
#include <string>
#include <string_view>

namespace shutterlab {

struct GyroReadOptions {
  LogFormat format = LogFormat::kAuto;  // kAuto or a plain gyro format (IsPlainGyroFormat)
  RawCountOptions raw;                  // raw-count logs only
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

// Reads a gyro log of any supported format; the result is in seconds / rad/s, sensor axes (for a
// .gcsv: after its orientation string, see sim/logs/gcsv.h). kAuto detects the format with
// DetectGyroFormat. Throws IoError naming path and line on bad input.
GyroTrace ReadGyro(const std::string& path, const GyroReadOptions& options = {});

// Detects the format of a log from its content (path only names it in errors):
//  1. first non-empty line "GYROFLOW IMU LOG" or "CAMERA IMU LOG"            -> kGcsv;
//  2. a header line t,gx,gy,gz[,...] and at least one rate field (gx, gy or gz of any row) that
//     is not an integer (holds '.', an exponent, ...)                        -> kGyroCsv;
//     the same header with every rate field an integer                       -> kRaw;
//     the header and no rows                                                 -> kGyroCsv;
//  3. no header (the first line starts with a number) and every rate an integer -> kRaw;
//     no header and a non-integer rate                                       -> IoError naming that
//     line (neither format: gyro.csv needs its header, raw counts are integers);
//  4. any other first line                                                   -> IoError naming
//  line 1.
// Rule 2's ambiguity: a gyro.csv whose every rate is a whole number of rad/s (in practice: all
// zero) reads as raw counts; with the default --range/--time-unit an all-zero trace is the same
// either way. Override with --format.
LogFormat DetectGyroFormat(std::string_view text, const std::string& path);

// docs/FORMATS.md gyro.csv. Extra columns after gz are ignored.
GyroTrace ReadGyroCsv(const std::string& path);
// The same as a stream: the header is checked at once, the rows are parsed a block at a time as
// the chunks are taken (IoError naming the line on the first bad one). path names the file in
// messages; chunk_samples bounds each chunk. Rows of a shape seen before are read by it
// (sim/logs/gyro_row_shapes.h); kByteLoop reads every row byte by byte, the twin that the tests
// and the fuzz target compare it with, bit for bit.
enum class GyroCsvRows { kByShape, kByteLoop };
std::unique_ptr<GyroSource> OpenGyroCsv(TextBlocks blocks, const std::string& path,
                                        size_t chunk_samples = FillingSource::kDefaultChunkSamples,
                                        GyroCsvRows rows = GyroCsvRows::kByShape);
// Writes gyro.csv whole or not at all; times exact to the nanosecond, rates round-trip exact.
void WriteGyroCsv(const std::string& path, const GyroTrace& trace);

TimeUnit ParseTimeUnit(const std::string& name);  // "s", "ms", "us", "ns"

}  // namespace shutterlab
