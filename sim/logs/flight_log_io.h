#pragma once
// One entry point for every log the project reads: flight-controller logs (PX4 ULog, ArduPilot
// DataFlash, Betaflight blackbox native or CSV export) and plain gyro logs (gyro.csv, Gyroflow
// .gcsv, the source paper's raw counts), detected by content. Plain gyro logs are wrapped into a
// FlightLog with no camera events and no altitude, so that `analyze` treats every source alike.

#include "sim/logs/flight_log.h"
#include "sim/logs/raw_csv.h"

#include <string>
#include <string_view>

namespace shutterlab {

enum class FlightLogFormat {
  kAuto,       // detect from the content (DetectFlightLogFormat)
  kULog,       // PX4 .ulg
  kDataFlash,  // ArduPilot .bin
  kBlackbox,   // Betaflight / INAV blackbox, native or CSV export
  kGyroCsv,    // FORMATS.md gyro.csv
  kGcsv,       // Gyroflow .gcsv
  kRaw,        // raw int16 counts (sim/raw_csv.h)
};

struct FlightLogReadOptions {
  FlightLogFormat format = FlightLogFormat::kAuto;
  int log_index = -1;  // blackbox files only: which log (ListBlackboxLogs); -1 = the longest
  // Raw-count logs only (sim/gyro_io.h GyroReadOptions): full-scale range and time unit.
  int raw_range_dps = 250;
  TimeUnit raw_time_unit = TimeUnit::kSeconds;
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

// Detects the format from the first bytes of a file (a few KiB): ULog magic, DataFlash FMT
// header, blackbox marker or CSV header, in that order; otherwise the plain gyro formats by
// sim/gyro_io.h DetectGyroFormat. Throws IoError naming path when none matches.
FlightLogFormat DetectFlightLogFormat(std::string_view first_bytes, const std::string& path);

// Reads any supported log. Plain gyro logs give format "gyro.csv" / "gcsv" / "raw", gyro_source
// "t,gx,gy,gz" / "gcsv" / "raw counts", no camera events and no altitude. Throws IoError (path,
// line or byte, problem) on unreadable or unknown input.
FlightLog ReadFlightLog(const std::string& path, const FlightLogReadOptions& options = {});

// "auto", "ulog", "dataflash", "blackbox", "gyro.csv" / "csv", "gcsv", "raw"; throws
// std::invalid_argument otherwise.
FlightLogFormat ParseFlightLogFormat(const std::string& name);
const char* FlightLogFormatName(FlightLogFormat format);

}  // namespace shutterlab
