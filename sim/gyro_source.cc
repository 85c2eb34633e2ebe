#include "sim/gyro_source.h"

#include "sim/check.h"

#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <optional>
#include <thread>

namespace shutterlab {

GyroTrace ReadAllSamples(GyroSource* source) {
  std::vector<GyroSample> samples;
  for (GyroChunk chunk = source->Next(); !chunk.empty(); chunk = source->Next())
    samples.insert(samples.end(), chunk.begin(), chunk.end());
  return GyroTrace(std::move(samples));
}

GyroTrace ReadAllSamples(GyroSource* source, const std::string& path) {
  GyroTrace trace = ReadAllSamples(source);
  const std::vector<LogWarning> lost = source->Warnings();
  if (!lost.empty())
    throw IoError(path + ": " + lost.front().message + " (this reader keeps no warnings)");
  return trace;
}

void FillingSource::TakeTimeInOrder(const std::string& path, long line_number, int64_t t_ns,
                                    std::string_view time_as_written) {
  if (last_t_ns_ && t_ns < *last_t_ns_) {
    throw IoError(IoMessage(
        path, line_number,
        "timestamp decreases (" + std::string(time_as_written) + " after an earlier, larger one)"));
  }
  last_t_ns_ = t_ns;
}

namespace {

class ReadAheadSource : public GyroSource {
 public:
  explicit ReadAheadSource(std::unique_ptr<GyroSource> source)
      : source_(std::move(source)), thread_([this] { Run(); }) {}

  ~ReadAheadSource() override {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    changed_.notify_all();
    thread_.join();
  }

  GyroChunk Next() override {
    std::unique_lock<std::mutex> lock(mutex_);
    if (handed_) {  // the caller is done with the chunk handed out last: its buffer is free again
      free_.push_back(std::move(*handed_));
      handed_.reset();
      changed_.notify_all();
    }
    changed_.wait(lock, [this] { return !ready_.empty() || finished_; });
    if (ready_.empty()) {
      if (error_) std::rethrow_exception(error_);
      return {};
    }
    handed_ = std::move(ready_.front());
    ready_.pop_front();
    fraction_ = handed_fraction_.front();
    handed_fraction_.pop_front();
    return {handed_->data(), handed_->size()};
  }

  double Fraction() const override {
    std::lock_guard<std::mutex> lock(mutex_);
    return fraction_;
  }

  // The source's, once its thread has read to the end (before that, nothing is complete).
  std::vector<LogWarning> Warnings() const override {
    std::lock_guard<std::mutex> lock(mutex_);
    return finished_ ? source_->Warnings() : std::vector<LogWarning>{};
  }

 private:
  static constexpr size_t kBuffers = 3;

  void Run() {
    try {
      while (true) {
        std::vector<GyroSample> buffer;
        {
          std::unique_lock<std::mutex> lock(mutex_);
          changed_.wait(lock, [this] { return stop_ || ready_.size() + 1 < kBuffers; });
          if (stop_) return;
          if (!free_.empty()) {
            buffer = std::move(free_.back());
            free_.pop_back();
          }
        }
        if (!source_->NextInto(&buffer)) break;  // outside the lock: the slow part
        const double fraction = source_->Fraction();
        std::lock_guard<std::mutex> lock(mutex_);
        ready_.push_back(std::move(buffer));
        handed_fraction_.push_back(fraction);
        changed_.notify_all();
      }
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex_);
      error_ = std::current_exception();
    }
    std::lock_guard<std::mutex> lock(mutex_);
    finished_ = true;
    changed_.notify_all();
  }

  std::unique_ptr<GyroSource> source_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<std::vector<GyroSample>> ready_;
  std::deque<double> handed_fraction_;
  std::vector<std::vector<GyroSample>> free_;
  std::optional<std::vector<GyroSample>> handed_;
  double fraction_ = 0.0;
  bool stop_ = false, finished_ = false;
  std::exception_ptr error_;
  std::thread thread_;  // last: started once everything above exists
};

}  // namespace

std::unique_ptr<GyroSource> ReadAhead(std::unique_ptr<GyroSource> source) {
  return std::make_unique<ReadAheadSource>(std::move(source));
}

}  // namespace shutterlab
