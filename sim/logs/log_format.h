#pragma once
// The log formats the readers know (their names, recognisers and openers: the reader table,
// sim/logs/flight_log_io.h LogReaders), and the options of the source paper's raw-count logs
// shared by every reader that may meet one.

#include "sim/logs/raw_csv.h"  // TimeUnit

#include <string>

namespace shutterlab {

enum class LogFormat {
  kAuto,       // detect from the content (sim/logs/gyro_io.h DetectGyroFormat, or
               // sim/logs/flight_log_io.h DetectFlightLogFormat for every format)
  kGyroCsv,    // docs/FORMATS.md gyro.csv: header t,gx,gy,gz[,...]; seconds and rad/s
  kGcsv,       // Gyroflow .gcsv ("GYROFLOW IMU LOG" header block)
  kRaw,        // the source paper's raw-count CSV: time and three int16 counts per line
  kULog,       // PX4 .ulg
  kBlackbox,   // Betaflight / INAV blackbox, native or CSV export
  kDataFlash,  // ArduPilot .bin
  kGoproMp4,   // a GoPro MP4 with GPMF telemetry (its GYRO stream; sim/logs/gopro_telemetry.h)
  kGyroDump,   // a phone capture app's gyro_dump.txt ("frameid:N gyro:K x .. ts .." lines;
               // sim/logs/gyro_dump.h)
  kColumns,    // any delimited file read by the columns the user names (sim/logs/column_csv.h);
               // never detected: chosen by --columns / --format columns
};

// kGyroCsv, kGcsv and kRaw: the plain gyro logs that ReadGyro reads.
bool IsPlainGyroFormat(LogFormat format);

// Raw-count logs only: full-scale range in deg/s (250, 500, 1000 or 2000 -> 131, 65.5, 32.8,
// 16.4 LSB per deg/s, the MPU-9250 sensitivities) and the unit of the time column.
struct RawCountOptions {
  int range_dps = 250;
  TimeUnit time_unit = TimeUnit::kSeconds;
  // Throws std::invalid_argument naming an unknown range.
  void Check() const;
};

}  // namespace shutterlab
