#include "sim/logs/log_format.h"

#include "sim/check.h"

namespace shutterlab {

bool IsPlainGyroFormat(LogFormat format) {
  return format == LogFormat::kGyroCsv || format == LogFormat::kGcsv || format == LogFormat::kRaw;
}

void RawCountOptions::Check() const {
  SHUTTERLAB_CHECK(range_dps == 250 || range_dps == 500 || range_dps == 1000 || range_dps == 2000)
      << "unknown gyro range " << range_dps << " deg/s (expected 250, 500, 1000 or 2000)";
}

}  // namespace shutterlab
