#include "record/recorder.h"

#include "record/fifo_clock.h"
#include "record/gyro_driver.h"
#include "record/record_output.h"
#include "record/sample_ring.h"
#include "sim/check.h"
#include "sim/logs/gcsv.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <exception>
#include <memory>
#include <mutex>
#include <pthread.h>
#include <random>
#include <sched.h>
#include <thread>

namespace shutterlab {

namespace {

// How long a part fails its health checks (WHO_AM_I and its configuration read back) before it is
// reset: a burst of noise on the bus shorter than this costs only the FIFO it spoiled.
constexpr int64_t kUnhealthyBeforeResetNs = 10000000;

int64_t ToNs(double s) { return static_cast<int64_t>(std::llround(s * 1e9)); }

// Everything about one sensor during a recording. The reader owns the reader fields, the writer
// the writer fields; the atomics are read by the status line.
struct SensorState {
  RecordSensor spec;
  std::unique_ptr<GyroDriver> driver;
  PartSetting setting;
  std::unique_ptr<SampleRing> ring;
  std::unique_ptr<FifoClock> fifo_clock;
  std::unique_ptr<RowFile> rows;
  // reader
  FifoRead read;
  // Samples read but not stamped yet, t_ns holding their index: at the start, until the fit has
  // seen a quarter second of reads (one read knows the phase only to a period).
  std::vector<RecordedSample> held;
  bool settled = false;
  std::vector<RecordedSample> batch;
  int64_t next_index = 0;        // index of the next sample on the current sample train
  const char* resync = nullptr;  // the next read's index comes from the clock (why: a gap kind)
  bool down = false;             // the part failed its health check and is not configured yet
  int64_t reset_issued_ns = INT64_MIN;     // while down: when the reset was sent
  bool check_now = false;                  // bad data or a failed read: check the part at once
  int64_t unhealthy_since_ns = INT64_MIN;  // the first of the failed checks in a row
  bool restarted = false;         // configured again: the first read after it counts the gap
  int64_t last_t_ns = INT64_MIN;  // newest sample time
  int64_t last_read_ns = 0;
  size_t reads = 0;
  double max_read_interval_s = 0;
  int open_buffer_gap = -1;  // gaps_ index of a buffer_full gap still growing
  // writer
  double gscale =
      0.0;  // rad/s per count, set before the threads start (a reconfiguration keeps it)
  std::string text;
  std::vector<RecordedSample> drained;
  size_t written = 0;
  int64_t first_t_ns = INT64_MIN, newest_t_ns = 0;
  double sum[3] = {0, 0, 0}, sum_sq[3] = {0, 0, 0};
  size_t still_n = 0;
  int64_t still_end_ns = 0;
  // status
  std::atomic<size_t> samples{0}, gaps{0};
  std::atomic<int64_t> lost{0};
  std::atomic<double> drift_ppm{0.0};
};

class Session {
 public:
  Session(const std::vector<RecordSensor>& sensors, const RecorderOptions& options, Clock& clock)
      : options_(options), clock_(clock) {
    options_.Check();
    SHUTTERLAB_CHECK(!sensors.empty() && sensors.size() <= 2) << "one or two sensors";
    for (const RecordSensor& spec : sensors) {
      SHUTTERLAB_CHECK(spec.bus != nullptr && !spec.out_path.empty())
          << "a sensor needs a bus and a file";
      auto s = std::make_unique<SensorState>();
      s->spec = spec;
      s->driver = std::make_unique<GyroDriver>(spec.bus, spec.part);
      sensors_.push_back(std::move(s));
    }
  }

  RecordSummary Run();

 private:
  bool Stopping(int64_t now_ns) const {
    return failed_ || (options_.stop && options_.stop->load()) ||
           (options_.duration_s > 0 && now_ns >= t0_ns_ + ToNs(options_.duration_s));
  }
  int64_t ReadIntervalNs() const;
  // Every thread joins the clock before any runs: on a virtual clock, time must not move while a
  // thread that takes part has not joined yet.
  void JoinClock() {
    clock_.Join();
    std::unique_lock<std::mutex> lock(mutex_);
    ++threads_joined_;
    finished_.notify_all();
    finished_.wait(lock, [&] { return threads_joined_ == threads_total_; });
  }
  void Fail() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!error_) error_ = std::current_exception();
    failed_ = true;
  }
  int AddGap(int sensor, int64_t t_clock_ns, int64_t lost, const char* kind);
  void ReaderLoop();
  void ReadSensor(int index);
  int64_t MotionTimeNs(const SensorState& s, int64_t index) const;
  void Resync(int index, SensorState& s);
  void Stamp(int index, SensorState& s, bool force);
  void CheckHealth(int index);
  void Recover(int index);
  void WriterLoop();
  void Drain(SensorState& s);
  void TriggerLoop();
  RecordStatus Status() const;
  RecordSummary Summarise();

  RecorderOptions options_;
  Clock& clock_;
  std::vector<std::unique_ptr<SensorState>> sensors_;
  int64_t t0_ns_ = 0;
  std::atomic<int64_t> stop_ns_{INT64_MAX};  // when the reader stopped
  std::atomic<bool> reader_done_{false}, failed_{false};
  std::atomic<int> threads_running_{0};
  int threads_total_ = 0, threads_joined_ = 0;  // the start gate (mutex_)
  mutable std::mutex mutex_;                    // gaps_, triggers, error_
  std::condition_variable finished_;
  std::exception_ptr error_;
  std::vector<RecordGap> gaps_;
  std::vector<double> trigger_t_s_;
  std::vector<std::string> notes_;
  size_t trigger_edges_ = 0, trigger_bounces_ = 0, trigger_other_ = 0;
  std::atomic<int64_t> max_stall_ns_{0};
  std::chrono::steady_clock::time_point started_;
};

int64_t Session::ReadIntervalNs() const {
  if (options_.read_interval_s > 0) return ToNs(options_.read_interval_s);
  double interval_s = 0.002;
  for (const auto& s : sensors_) {
    const double fill_s =
        (s->driver->info().fifo_bytes / s->driver->info().packet_bytes) / s->setting.odr_hz;
    interval_s = std::min(interval_s, fill_s / 4);
  }
  return ToNs(interval_s);
}

int Session::AddGap(int sensor, int64_t t_clock_ns, int64_t lost, const char* kind) {
  std::lock_guard<std::mutex> lock(mutex_);
  gaps_.push_back({sensor, (t_clock_ns - t0_ns_) * 1e-9, lost, kind});
  sensors_[sensor]->gaps.fetch_add(1);
  sensors_[sensor]->lost.fetch_add(lost);
  return static_cast<int>(gaps_.size()) - 1;
}

// The time of the motion that sample `index` of the current train shows: when the part made it,
// less its filter's delay (the datasheet's; a slow motion reaches the output that much later).
int64_t Session::MotionTimeNs(const SensorState& s, int64_t index) const {
  return s.fifo_clock->SampleTimeNs(index) - std::llround(s.setting.filter_delay_s * 1e9);
}

// After an overflow, bad data or a failed read: these samples are the newest the part produced by
// the latch, so their index comes from the fitted sample clock; the ones between were lost.
void Session::Resync(int index, SensorState& s) {
  const int64_t n = static_cast<int64_t>(s.read.samples.size());
  const int64_t latch_ns = s.read.t_before_ns + (s.read.t_after_ns - s.read.t_before_ns) / 2;
  const int64_t first = std::max(s.fifo_clock->ProducedBy(latch_ns) - n, s.next_index);
  const int64_t lost = first - s.next_index;
  if (lost > 0) AddGap(index, MotionTimeNs(s, s.next_index), lost, s.resync);
  s.next_index = first;
  s.resync = nullptr;
}

// Stamps the held samples on the current fit and hands them to the writer; held back while the fit
// is young unless `force` (a gap: the fit will be asked about later samples only).
void Session::Stamp(int index, SensorState& s, bool force) {
  if (!s.settled) {
    s.settled = s.fifo_clock->reads() >= 50 && s.fifo_clock->SpanSamples() >= s.setting.odr_hz / 4;
    if (!s.settled && !force) return;
  }
  const size_t n = s.held.size();
  s.batch.resize(n);
  for (size_t i = 0; i < n; ++i) {
    int64_t t_ns = MotionTimeNs(s, s.held[i].t_ns);
    t_ns = std::max(t_ns, s.last_t_ns + 1);  // a refit never moves time backwards
    s.batch[i] = {t_ns, s.held[i].counts};
    s.last_t_ns = t_ns;
  }
  s.held.clear();
  const size_t pushed = s.ring->Push(s.batch.data(), n);
  if (pushed < n) {
    const int64_t dropped = static_cast<int64_t>(n - pushed);
    if (s.open_buffer_gap >= 0) {  // the ring is still full: the same gap grows
      std::lock_guard<std::mutex> lock(mutex_);
      gaps_[s.open_buffer_gap].lost += dropped;
      s.lost.fetch_add(dropped);
    } else {
      s.open_buffer_gap = AddGap(index, s.batch[pushed].t_ns, dropped, "buffer_full");
    }
  } else if (n > 0) {
    s.open_buffer_gap = -1;
  }
  s.samples.fetch_add(pushed);
}

void Session::ReadSensor(int index) {
  SensorState& s = *sensors_[index];
  if (s.down) return Recover(index);
  try {
    s.driver->ReadFifo(clock_, &s.read);
  } catch (const IoError&) {
    if (s.fifo_clock->has_reads()) s.resync = "missed_read";
    s.check_now = true;
    return;
  }
  if (s.reads > 0) {
    s.max_read_interval_s =
        std::max(s.max_read_interval_s, (s.read.t_before_ns - s.last_read_ns) * 1e-9);
  }
  s.last_read_ns = s.read.t_before_ns;
  ++s.reads;
  const int64_t n = static_cast<int64_t>(s.read.samples.size());
  if (s.resync) Resync(index, s);
  const bool whole = !s.read.overflow && !s.read.bad_data;
  // Reads before the first sample say nothing about the sample train (the gyro is starting up).
  if (s.next_index + n > 0 && (whole || !s.fifo_clock->has_reads())) {
    s.fifo_clock->AddRead(s.read.t_before_ns, s.read.t_after_ns, s.next_index + n);
    s.drift_ppm = s.fifo_clock->DriftPpm();
  }
  if (s.restarted && n > 0) {
    // The part was configured again: a new sample train, whose first sample follows the last one
    // recorded by the samples that fit in between.
    const double period_ns = s.fifo_clock->PeriodNs();
    const int64_t first_ns = MotionTimeNs(s, s.next_index);
    const int64_t lost =
        std::max<int64_t>(std::llround((first_ns - s.last_t_ns) / period_ns) - 1, 0);
    AddGap(index, s.last_t_ns + static_cast<int64_t>(period_ns), lost, "part_reset");
    s.restarted = false;
  }
  for (int64_t i = 0; i < n; ++i) s.held.push_back({s.next_index + i, s.read.samples[i]});
  s.next_index += n;
  if (s.read.overflow) s.resync = "fifo_overflow";
  if (s.read.bad_data) {
    s.resync = "bad_data";
    s.check_now = true;
  }
  Stamp(index, s, s.resync != nullptr);
}

void Session::CheckHealth(int index) {
  SensorState& s = *sensors_[index];
  s.check_now = false;
  bool healthy = false;
  try {
    healthy = s.driver->Healthy();
  } catch (const IoError&) {
  }
  const int64_t now_ns = clock_.NowNs();
  if (healthy) {
    s.unhealthy_since_ns = INT64_MIN;
    return;
  }
  // Noise on the bus for a few reads is not a dead part: check again at every pass, and reset the
  // part only once it has failed for kUnhealthyBeforeResetNs.
  if (s.unhealthy_since_ns == INT64_MIN) s.unhealthy_since_ns = now_ns;
  if (now_ns - s.unhealthy_since_ns < kUnhealthyBeforeResetNs) {
    s.check_now = true;
    return;
  }
  s.unhealthy_since_ns = INT64_MIN;
  s.down = true;
  s.reset_issued_ns = INT64_MIN;
  Recover(index);
}

// Brings a part that failed its health check back without waiting in the reader: the reset is
// sent, and the part configured on a later pass once its reset time has passed; the other
// sensor is read meanwhile.
void Session::Recover(int index) {
  SensorState& s = *sensors_[index];
  const int64_t now_ns = clock_.NowNs();
  if (s.reset_issued_ns == INT64_MIN) {
    try {
      s.driver->BeginReset();
    } catch (const IoError&) {
    }
    s.reset_issued_ns = now_ns;
    return;
  }
  if (now_ns < s.reset_issued_ns + s.driver->ResetWaitNs()) return;
  try {
    s.setting = s.driver->FinishConfigure(s.spec.config, clock_);
  } catch (const IoError&) {
    s.reset_issued_ns = INT64_MIN;  // not back yet: reset it again
    return;
  }
  s.down = false;
  Stamp(index, s, /*force=*/true);  // on the old train's fit
  s.settled = false;
  s.restarted = s.last_t_ns != INT64_MIN;
  s.resync = nullptr;
  s.next_index = 0;
  s.fifo_clock = std::make_unique<FifoClock>(1e9 / s.setting.odr_hz);
}

void Session::ReaderLoop() {
  JoinClock();
  if (options_.reader_priority > 0) {
    sched_param param{};
    param.sched_priority = options_.reader_priority;
    const int error = ::pthread_setschedparam(::pthread_self(), SCHED_FIFO, &param);
    if (error != 0) {
      std::lock_guard<std::mutex> lock(mutex_);
      notes_.push_back("the reader runs at normal priority: SCHED_FIFO " +
                       std::to_string(options_.reader_priority) + " refused (" +
                       std::strerror(error) + "; run as root or with CAP_SYS_NICE)");
    }
  }
  try {
    const int64_t interval_ns = ReadIntervalNs();
    std::mt19937_64 rng(options_.seed);
    std::uniform_real_distribution<double> dither(0.5, 1.5);
    std::vector<bool> paused(options_.reader_pauses.size(), false);
    size_t since_paper_pause = 0;
    int64_t next_read_ns = clock_.NowNs();
    int64_t next_health_ns = t0_ns_ + ToNs(options_.health_check_s);
    while (!Stopping(clock_.NowNs())) {
      for (size_t i = 0; i < paused.size(); ++i) {
        const auto& [at_s, for_s] = options_.reader_pauses[i];
        if (!paused[i] && clock_.NowNs() >= t0_ns_ + ToNs(at_s)) {
          paused[i] = true;
          clock_.SleepUntilNs(clock_.NowNs() + ToNs(for_s));
        }
      }
      const size_t before = sensors_[0]->samples.load();
      for (size_t i = 0; i < sensors_.size(); ++i) ReadSensor(static_cast<int>(i));
      since_paper_pause += sensors_[0]->samples.load() - before;
      if (options_.paper_pause.buffer_samples > 0 &&
          since_paper_pause >= options_.paper_pause.buffer_samples) {
        clock_.SleepUntilNs(clock_.NowNs() +
                            ToNs(options_.paper_pause.write_s));  // writing, not reading
        since_paper_pause = 0;
      }
      const int64_t now_ns = clock_.NowNs();
      const bool due = now_ns >= next_health_ns;
      if (due) next_health_ns = now_ns + ToNs(options_.health_check_s);
      for (size_t i = 0; i < sensors_.size(); ++i) {
        if (!sensors_[i]->down && (due || sensors_[i]->check_now)) CheckHealth(static_cast<int>(i));
      }
      next_read_ns =
          std::max(next_read_ns + static_cast<int64_t>(interval_ns * dither(rng)), now_ns);
      clock_.SleepUntilNs(next_read_ns);
    }
    for (size_t i = 0; i < sensors_.size(); ++i) {
      if (sensors_[i]->fifo_clock->has_reads()) Stamp(static_cast<int>(i), *sensors_[i], true);
    }
  } catch (...) {
    Fail();
  }
  stop_ns_ = clock_.NowNs();
  reader_done_ = true;
  clock_.Leave();
}

void Session::Drain(SensorState& s) {
  const double gscale = s.gscale;
  s.drained.resize(8192);
  while (const size_t n = s.ring->Pop(s.drained.data(), s.drained.size())) {
    for (size_t i = 0; i < n; ++i) {
      const RecordedSample& sample = s.drained[i];
      if (s.first_t_ns == INT64_MIN) {
        s.first_t_ns = sample.t_ns;
        s.still_end_ns = sample.t_ns + ToNs(options_.still_s);
      }
      s.newest_t_ns = sample.t_ns;
      if (sample.t_ns < s.still_end_ns) {
        for (int axis = 0; axis < 3; ++axis) {
          const double rate = sample.counts[axis] * gscale;
          s.sum[axis] += rate;
          s.sum_sq[axis] += rate * rate;
        }
        ++s.still_n;
      }
      AppendRecordedRow(sample, t0_ns_, &s.text);
    }
    s.written += n;
    if (s.text.size() > (size_t{1} << 20)) {
      s.rows->Append(s.text);
      s.text.clear();
    }
  }
  if (!s.text.empty()) s.rows->Append(s.text);
  s.text.clear();
}

void Session::WriterLoop() {
  JoinClock();
  try {
    const auto& stall = options_.writer_stall;
    int64_t next_stall_ns = t0_ns_ + ToNs(stall.every_s);
    int64_t last_drain_ns = clock_.NowNs();
    while (true) {
      const bool done = reader_done_.load();
      const int64_t drain_ns = clock_.NowNs();
      max_stall_ns_ = std::max(max_stall_ns_.load(), drain_ns - last_drain_ns);
      last_drain_ns = drain_ns;
      for (auto& s : sensors_) Drain(*s);
      if (done || failed_) break;
      if (stall.every_s > 0 && clock_.NowNs() >= next_stall_ns) {
        clock_.SleepUntilNs(clock_.NowNs() + ToNs(stall.for_s));  // a write that blocks
        next_stall_ns += ToNs(stall.every_s);
      }
      clock_.SleepUntilNs(clock_.NowNs() + ToNs(options_.writer_interval_s));
    }
  } catch (...) {
    Fail();
  }
  clock_.Leave();
}

void Session::TriggerLoop() {
  JoinClock();
  try {
    TriggerFilter filter(options_.polarity, ToNs(options_.debounce_s));
    std::vector<TriggerEdge> edges;
    bool last = false;
    while (!last) {
      last = reader_done_.load();
      edges.clear();
      options_.trigger->WaitEdges(last ? clock_.NowNs() : clock_.NowNs() + 50000000, &edges);
      std::lock_guard<std::mutex> lock(mutex_);
      for (const TriggerEdge& edge : edges) {
        if (edge.t_ns < t0_ns_ || edge.t_ns > stop_ns_.load()) continue;
        ++trigger_edges_;
        if (filter.Accept(edge)) trigger_t_s_.push_back((edge.t_ns - t0_ns_) * 1e-9);
      }
      trigger_bounces_ = filter.bounces();
      trigger_other_ = filter.other_polarity();
    }
  } catch (...) {
    Fail();
  }
  clock_.Leave();
}

RecordStatus Session::Status() const {
  RecordStatus status;
  status.elapsed_s = (clock_.NowNs() - t0_ns_) * 1e-9;
  for (const auto& s : sensors_) {
    RecordStatus::Sensor out;
    out.samples = s->samples.load();
    out.rate_hz = status.elapsed_s > 0 ? out.samples / status.elapsed_s : 0.0;
    out.gaps = s->gaps.load();
    out.lost = s->lost.load();
    out.ring_high_water = s->ring->high_water();
    out.ring_capacity = s->ring->capacity();
    out.drift_ppm = s->drift_ppm.load();
    status.sensors.push_back(out);
  }
  std::lock_guard<std::mutex> lock(mutex_);
  status.triggers = trigger_t_s_.size();
  status.max_writer_stall_s = max_stall_ns_.load() * 1e-9;
  return status;
}

}  // namespace

RecordSummary Session::Summarise() {
  RecordSummary summary;
  summary.t0_clock_ns = t0_ns_;
  summary.duration_s = (stop_ns_.load() - t0_ns_) * 1e-9;
  summary.max_writer_stall_s = max_stall_ns_.load() * 1e-9;
  summary.stopped = options_.stop && options_.stop->load();
  summary.gaps = gaps_;
  summary.notes = notes_;
  summary.trigger_t_s = trigger_t_s_;
  summary.triggers = trigger_t_s_.size();
  summary.trigger_edges = trigger_edges_;
  summary.trigger_bounces = trigger_bounces_;
  summary.trigger_other_polarity = trigger_other_;
  for (const auto& s : sensors_) {
    SensorSummary out;
    out.device = s->spec.device;
    out.out_path = s->spec.out_path;
    out.setting = s->setting;
    out.samples = s->written;
    if (s->written > 1 && s->newest_t_ns > s->first_t_ns) {
      out.rate_hz = (s->written - 1) / ((s->newest_t_ns - s->first_t_ns) * 1e-9);
    }
    out.drift_ppm = s->fifo_clock->DriftPpm();
    out.timestamp_rms_us = s->fifo_clock->ResidualRmsNs() * 1e-3;
    out.gaps = s->gaps.load();
    out.lost = s->lost.load();
    out.ring_high_water = s->ring->high_water();
    out.ring_capacity = s->ring->capacity();
    out.reads = s->reads;
    out.max_read_interval_s = s->max_read_interval_s;
    out.still_samples = s->still_n;
    if (s->still_n > 0) {
      out.still_span_s = std::min(options_.still_s, (s->newest_t_ns - s->first_t_ns) * 1e-9);
      for (int axis = 0; axis < 3; ++axis) {
        const double mean = s->sum[axis] / s->still_n;
        out.still_bias_rad_s[axis] = mean;
        out.still_std_rad_s[axis] =
            std::sqrt(std::max(s->sum_sq[axis] / s->still_n - mean * mean, 0.0));
      }
    }
    summary.sensors.push_back(out);
  }
  return summary;
}

RecordSummary Session::Run() {
  for (auto& s : sensors_) {  // before any thread or file: a wrong part is refused here
    s->setting = s->driver->Configure(s->spec.config, clock_);
    s->fifo_clock = std::make_unique<FifoClock>(1e9 / s->setting.odr_hz);
    s->gscale = kPi / 180.0 / s->setting.lsb_per_dps;
    s->ring = std::make_unique<SampleRing>(
        static_cast<size_t>(std::ceil(options_.ring_s * s->setting.odr_hz)));
  }
  // Each file's header on disk before any read: a kill or a power cut leaves a readable file.
  t0_ns_ = clock_.NowNs();
  RecordSummary at_start;
  at_start.t0_clock_ns = t0_ns_;
  for (const auto& s : sensors_) {
    SensorSummary sensor;
    sensor.device = s->spec.device;
    sensor.setting = s->setting;
    at_start.sensors.push_back(sensor);
  }
  for (size_t i = 0; i < sensors_.size(); ++i) {
    sensors_[i]->rows = std::make_unique<RowFile>(
        sensors_[i]->spec.out_path, RecordingGcsvHeader(at_start, static_cast<int>(i), options_),
        options_.sync_interval_s);
  }
  started_ = std::chrono::steady_clock::now();
  std::vector<std::thread> threads;
  threads_total_ = options_.trigger ? 3 : 2;
  auto start = [&](void (Session::*loop)()) {
    ++threads_running_;
    threads.emplace_back([this, loop] {
      (this->*loop)();
      std::lock_guard<std::mutex> lock(mutex_);
      --threads_running_;
      finished_.notify_all();
    });
  };
  start(&Session::ReaderLoop);
  start(&Session::WriterLoop);
  if (options_.trigger) start(&Session::TriggerLoop);
  {
    std::unique_lock<std::mutex> lock(mutex_);
    const auto interval = std::chrono::duration<double>(options_.status_interval_s);
    while (!finished_.wait_for(lock, interval, [&] { return threads_running_ == 0; })) {
      if (!options_.on_status) continue;
      lock.unlock();
      options_.on_status(Status());
      lock.lock();
    }
  }
  for (std::thread& thread : threads) thread.join();
  if (error_) {
    try {
      std::rethrow_exception(error_);
    } catch (const IoError& e) {  // the rows so far are kept: say where
      std::string kept;
      for (const auto& s : sensors_)
        if (s->rows->has_rows()) kept += (kept.empty() ? "" : ", ") + s->rows->partial_path();
      if (kept.empty()) throw;
      throw IoError(std::string(e.what()) + "; the recording stopped: its rows until then are in " +
                    kept + " (every command reads it as it is)");
    }
  }
  RecordSummary summary = Summarise();
  for (const SensorSummary& s : summary.sensors) {
    if (s.samples == 0) {
      throw IoError(IoMessage(
          s.out_path, 0,
          FormatNumber("no samples recorded in %.3f s: no file written", summary.duration_s)));
    }
  }
  const Eigen::Matrix3d orientation = GcsvOrientationMatrix(options_.orientation);
  for (size_t i = 0; i < sensors_.size(); ++i) {
    RowFile& rows = *sensors_[i]->rows;
    const double rad_s_per_count = kPi / 180.0 / summary.sensors[i].setting.lsb_per_dps;
    for (AlsoFormat format : options_.also)
      rows.WriteAlso(AlsoPath(summary.sensors[i].out_path, format), format, rad_s_per_count,
                     orientation);
    rows.Finish(RecordedGcsvHeader(summary, static_cast<int>(i), options_));
  }
  if (options_.trigger) WriteTriggersFile(options_.triggers_path, summary, options_);
  return summary;
}

RecordSummary Record(const std::vector<RecordSensor>& sensors, const RecorderOptions& options,
                     Clock& clock) {
  Session session(sensors, options, clock);
  return session.Run();
}

}  // namespace shutterlab
