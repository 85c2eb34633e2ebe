#pragma once
// Readers and writers of gyro logs. Every reader throws IoError("PATH:LINE: problem") on bad input
// and never returns a partial trace.

#include <string>

#include "sim/gyro_trace.h"
#include "sim/raw_csv.h"  // TimeUnit, ReadRawCsv, WriteRawCsv

namespace shutterlab {

enum class GyroFormat {
  kAuto,     // detect from the content
  kGyroCsv,  // FORMATS.md gyro.csv: header t,gx,gy,gz[,...]; seconds and rad/s
  kGcsv,     // Gyroflow .gcsv ("GYROFLOW IMU LOG" header block)
  kRaw,      // the source paper's raw-count CSV: time and three int16 counts per line
};

struct GyroReadOptions {
  GyroFormat format = GyroFormat::kAuto;
  // Raw-count logs only: full-scale range in deg/s (250, 500, 1000 or 2000 -> 131, 65.5, 32.8,
  // 16.4 LSB per deg/s, the MPU-9250 sensitivities) and the unit of the time column.
  int raw_range_dps = 250;
  TimeUnit raw_time_unit = TimeUnit::kSeconds;
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

// Reads a gyro log of any supported format; the result is in seconds / rad/s, sensor axes.
GyroTrace ReadGyro(const std::string& path, const GyroReadOptions& options = {});

// FORMATS.md gyro.csv. Extra columns after gz are ignored.
GyroTrace ReadGyroCsv(const std::string& path);
// Writes gyro.csv whole or not at all; times exact to the nanosecond, rates round-trip exact.
void WriteGyroCsv(const std::string& path, const GyroTrace& trace);

// Parses a name such as "gyro.csv", "gcsv", "raw", "auto"; throws std::invalid_argument otherwise.
GyroFormat ParseGyroFormat(const std::string& name);
TimeUnit ParseTimeUnit(const std::string& name);  // "s", "ms", "us", "ns"
const char* GyroFormatName(GyroFormat format);

}  // namespace shutterlab
