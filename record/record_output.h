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
// While recording, each sensor's file is OUT.partial: a .gcsv whose header (the sensor's settings
// and time base, no summary yet, and "recording,unfinished: ...") is on disk before any row, the
// rows appended as the writer drains the ring and synced at least every sync_interval. A kill or a
// power cut leaves that file, which every reader takes as it is, with the loss said in its header
// (the rows of the last writer interval for a kill, of the last sync interval for a power cut)
// and by the reader's `truncated` warning. Finish writes OUT whole (the final header, the rows) and
// then removes OUT.partial.

#include "record/recording.h"
#include "record/sample_ring.h"

#include <Eigen/Core>

#include <chrono>
#include <string>
#include <sys/types.h>

namespace shutterlab {

// `record --also`'s names: "gyro.csv" or "raw"; throws std::invalid_argument naming the text and
// the two otherwise.
AlsoFormat ParseAlsoFormat(const std::string& name);
// The .gcsv's path less ".gcsv", plus ".gyro.csv" or ".raw.csv".
std::string AlsoPath(const std::string& gcsv_path, AlsoFormat format);

// The rows of one sensor while recording.
class RowFile {
 public:
  // Creates final_path + ".partial" and writes `partial_header` to it, synced. Throws IoError when
  // that file exists (a recording that was cut: it is kept, never overwritten) or cannot be made.
  RowFile(const std::string& final_path, const std::string& partial_header, double sync_interval_s);
  // Closes the file; removes it if it holds no row (nothing recorded), keeps it otherwise.
  ~RowFile();
  RowFile(const RowFile&) = delete;
  RowFile& operator=(const RowFile&) = delete;

  // Appends text (whole rows), synced when sync_interval has passed since the last sync; throws
  // IoError naming the output when the write fails (a full disk), the file cut back to the rows
  // before `text`.
  void Append(const std::string& text);
  // Writes header + rows to final_path, whole or not at all, then removes the partial file.
  void Finish(const std::string& header);
  // Writes the rows so far to path in another format (AlsoFormat), whole or not at all:
  // rad_s_per_count the .gcsv's gscale, orientation its orientation line's matrix (gyro.csv only).
  void WriteAlso(const std::string& path, AlsoFormat format, double rad_s_per_count,
                 const Eigen::Matrix3d& orientation) const;

  const std::string& partial_path() const { return partial_path_; }
  bool has_rows() const { return size_bytes_ > static_cast<off_t>(header_bytes_); }
  // The bytes on disk at the last fdatasync: what a power cut now would leave of the file.
  off_t synced_bytes() const { return synced_bytes_; }

 private:
  std::string final_path_, partial_path_;
  int fd_ = -1;
  size_t header_bytes_ = 0;
  off_t size_bytes_ = 0;  // the file's length: the header and the whole rows appended
  off_t synced_bytes_ = 0;
  bool finished_ = false;
  std::chrono::steady_clock::duration sync_interval_;
  std::chrono::steady_clock::time_point last_sync_;
};

// "t_ns,gx,gy,gz\n" of one sample, t relative to t0.
void AppendRecordedRow(const RecordedSample& sample, int64_t t0_ns, std::string* out);

// The .gcsv header of sensor `index` of a finished recording.
std::string RecordedGcsvHeader(const RecordSummary& summary, int index,
                               const RecorderOptions& options);
// The header of its .partial while it records: what is known at the start (the sensor's settings
// from summary.sensors, summary.t0_clock_ns) and the line "recording,unfinished: ..." that says
// what a kill or a power cut loses.
std::string RecordingGcsvHeader(const RecordSummary& start, int index,
                                const RecorderOptions& options);

// The triggers file: '#' lines with the source and the filter, then "image,t" (IMG_0001, ...; t
// in s on the logs' clock), as `analyze --triggers` reads it. Written whole.
void WriteTriggersFile(const std::string& path, const RecordSummary& summary,
                       const RecorderOptions& options);

}  // namespace shutterlab
