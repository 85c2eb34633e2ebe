#pragma once
// The recorder's files. Per sensor a Gyroflow .gcsv (docs/FORMATS.md "shutterlab record"):
//
//   GYROFLOW IMU LOG / version,1.3 / id,shutterlab record / orientation,XYZ
//   note, vendor, fwversion, timestamp (unix s at the start)
//   part, who_am_i, device, odr_hz, range_dps, lsb_per_dps, filter   the sensor's settings
//   clock (CLOCK_MONOTONIC), t0_clock_ns                              the time base
//   samples, rate_hz, drift_ppm, timestamp_rms_us                     what the reads gave
//   gaps, samples_lost, ring_high_water, max_read_interval_ms, max_writer_stall_ms
//   still_s, still_bias_rad_s (x;y;z), still_std_rad_s               the still bias at start
//   gap,T_S,LOST,KIND                                                one line per gap
//   tscale,0.000000001 / gscale (rad/s per count) / t,gx,gy,gz
//   rows: t in ns from t0, the raw counts (sensor axes)
//
// The rows stream into a temporary file beside the output while recording; Finish writes the
// header and copies the rows after it into a second temporary file, then renames it: the .gcsv
// appears whole or not at all.

#include "record/recording.h"
#include "record/sample_ring.h"

#include <string>

namespace shutterlab {

// The rows of one sensor while recording.
class RowFile {
 public:
  // Creates "DIR/.NAME.rows-XXXXXX" beside final_path. Throws IoError.
  explicit RowFile(const std::string& final_path);
  ~RowFile();  // removes the temporary file unless Finish moved the rows
  RowFile(const RowFile&) = delete;
  RowFile& operator=(const RowFile&) = delete;

  // Appends text (whole rows); throws IoError naming the output when the write fails.
  void Append(const std::string& text);
  // Writes header + rows to final_path, whole or not at all, and removes the temporary file.
  void Finish(const std::string& header);

 private:
  std::string final_path_, rows_path_;
  int fd_ = -1;
};

// "t_ns,gx,gy,gz\n" of one sample, t relative to t0.
void AppendRecordedRow(const RecordedSample& sample, int64_t t0_ns, std::string* out);

// The .gcsv header of sensor `index` of a finished recording.
std::string RecordedGcsvHeader(const RecordSummary& summary, int index,
                               const RecorderOptions& options);

// The triggers file: '#' lines with the source and the filter, then "image,t" (IMG_0001, ...; t
// in s on the logs' clock), as `analyze --triggers` reads it. Written whole.
void WriteTriggersFile(const std::string& path, const RecordSummary& summary,
                       const RecorderOptions& options);

}  // namespace shutterlab
