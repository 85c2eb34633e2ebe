#pragma once
// A recording's settings and what it gave: the sensors and options `Record` takes
// (record/recorder.h), the status it reports while recording, the summary it returns, and their
// text for a person. Apart from the recorder so that its output files (record/record_output.h)
// and the reports (estimate/report/analysis_json.h) read them without the threads.

#include "record/gyro_part.h"
#include "record/spi_transport.h"
#include "record/trigger_source.h"

#include <Eigen/Core>

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace shutterlab {

// One sensor of the recording.
struct RecordSensor {
  SpiTransport* bus = nullptr;  // not owned; outlives Record
  GyroPart part = GyroPart::kMpu9250;
  SensorConfig config;
  std::string device;    // what the bus is, for the log's header ("/dev/spidev0.0", "emulate:...")
  std::string out_path;  // its .gcsv
};

// A gap in one sensor's samples.
struct RecordGap {
  int sensor = 0;
  double t_s = 0.0;  // time of the first lost sample (or of the event), s on the log's clock
  int64_t lost = 0;  // samples lost (0: an event that cost none, e.g. a part reset caught in time)
  std::string kind;  // fifo_overflow, bad_data, missed_read, part_reset, buffer_full
};

// What the status line shows, every status_interval_s.
struct RecordStatus {
  double elapsed_s = 0.0;
  struct Sensor {
    size_t samples = 0;    // read so far
    double rate_hz = 0.0;  // achieved: samples over the time since the first read
    size_t gaps = 0;
    int64_t lost = 0;
    size_t ring_high_water = 0, ring_capacity = 0;
    double drift_ppm = 0.0;
  };
  std::vector<Sensor> sensors;
  size_t triggers = 0;
  double max_writer_stall_s = 0.0;
};

// The other files `record --also` writes of each sensor at the end, from its rows, beside the
// .gcsv (record/record_output.h AlsoPath): gyro.csv (t s from t0, rad/s on the .gcsv's
// orientation, as its readers see it) and the source paper's raw counts (t s, the counts as the
// part gave them: read with --raw --range).
enum class AlsoFormat { kGyroCsv, kRawCounts };

struct RecorderOptions {
  double duration_s = 0.0;  // 0: until *stop
  double still_s = 5.0;     // the bias at start: the mean of the first still_s seconds
  double ring_s = 8.0;      // ring length per sensor, seconds of samples (8 kHz: 64 Ki samples)
  // Time between FIFO reads; 0 picks a quarter of the FIFO's fill time, at most 2 ms. Each
  // interval is dithered uniformly within +-50 %.
  double read_interval_s = 0.0;
  double writer_interval_s = 0.02;
  // The rows on disk (fdatasync) at least this often: what a power cut can lose.
  double sync_interval_s = 0.5;
  double health_check_s = 1.0;  // WHO_AM_I and the configuration read back this often
  // Testing the buffers: the writer blocks for_s once every every_s (an SD card's stall).
  struct Stall {
    double every_s = 0.0, for_s = 0.0;
  } writer_stall;
  // The source paper's logger, for comparison: the reader itself stops for write_s each time it has
  // read buffer_samples samples (0: off). It loses what the FIFO cannot hold meanwhile.
  struct PaperPause {
    size_t buffer_samples = 0;
    double write_s = 0.0;
  } paper_pause;
  // Testing: the reader is not run for for_s at at_s (a starved reader), once each.
  std::vector<std::pair<double, double>> reader_pauses;
  // Camera triggers (optional): not owned.
  TriggerSource* trigger = nullptr;
  TriggerPolarity polarity = TriggerPolarity::kRising;
  double debounce_s = 0.005;
  std::string triggers_path;        // where they go (with a trigger source)
  std::string orientation = "XYZ";  // the .gcsv's orientation line
  // Other files of each sensor written at the end beside its .gcsv (record/record_output.h).
  std::vector<AlsoFormat> also;
  std::string note;                         // a note line for the header (free text)
  const std::atomic<bool>* stop = nullptr;  // set (from a signal handler) to stop cleanly
  std::function<void(const RecordStatus&)> on_status;  // called from Record's own thread
  double status_interval_s = 1.0;                      // real time between on_status calls
  uint64_t seed = 1;                                   // the read dither
  // Real-time priority (SCHED_FIFO 1..99) for the reader thread; 0 keeps normal scheduling. Needs
  // root or CAP_SYS_NICE; when refused the recording goes on and the summary says so.
  int reader_priority = 0;
  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

struct SensorSummary {
  std::string device, out_path;
  PartSetting setting;
  size_t samples = 0;             // written
  double rate_hz = 0.0;           // achieved: (samples - 1) / (last - first sample time)
  double drift_ppm = 0.0;         // the part's clock error, fitted (positive: runs fast)
  double timestamp_rms_us = 0.0;  // FIFO-clock fit: RMS of the reads about the line
  size_t gaps = 0;
  int64_t lost = 0;
  size_t ring_high_water = 0, ring_capacity = 0;
  size_t reads = 0;
  double max_read_interval_s = 0.0;  // longest time between two FIFO reads
  // The still bias at start: per-axis mean and std of the rates over the first still_s seconds.
  Eigen::Vector3d still_bias_rad_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d still_std_rad_s = Eigen::Vector3d::Zero();
  double still_span_s = 0.0;  // how much of still_s the recording held
  size_t still_samples = 0;
};

struct RecordSummary {
  std::vector<SensorSummary> sensors;
  std::vector<RecordGap> gaps;
  int64_t t0_clock_ns = 0;          // clock time of t = 0 in the files
  double duration_s = 0.0;          // from start to stop, on the clock
  double max_writer_stall_s = 0.0;  // longest time the writer took to come back to the rings
  bool stopped = false;             // by *stop rather than the duration
  std::vector<std::string> notes;   // what a person should know (a refused real-time priority)
  // Triggers
  size_t triggers = 0, trigger_edges = 0, trigger_bounces = 0, trigger_other_polarity = 0;
  std::vector<double> trigger_t_s;
};

// The summary for a person: per sensor the setting, samples, achieved rate, drift, gaps and the
// ring's high-water mark; the still bias; the triggers.
std::string RecordSummaryText(const RecordSummary& summary);
// One status line: "12.0 s  8000.3 Hz  0 gaps  ring 3%  |  ...  triggers 5".
std::string RecordStatusLine(const RecordStatus& status);

}  // namespace shutterlab
