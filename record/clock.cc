#include "record/clock.h"

#include "sim/check.h"

#include <algorithm>
#include <cerrno>
#include <ctime>

namespace shutterlab {

int64_t MonotonicClock::NowNs() const {
  timespec ts{};
  ::clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

void MonotonicClock::SleepUntilNs(int64_t t_ns) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(t_ns / 1000000000);
  ts.tv_nsec = static_cast<long>(t_ns % 1000000000);
  while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

int64_t VirtualClock::NowNs() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return now_ns_;
}

void VirtualClock::Join() {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto id = std::this_thread::get_id();
  SHUTTERLAB_CHECK(std::find(joined_.begin(), joined_.end(), id) == joined_.end())
      << "a thread joined the virtual clock twice";
  joined_.push_back(id);
}

void VirtualClock::Leave() {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto id = std::this_thread::get_id();
  joined_.erase(std::remove(joined_.begin(), joined_.end(), id), joined_.end());
  AdvanceIfAllAsleep();  // the threads left may all be asleep now
}

void VirtualClock::AdvanceIfAllAsleep() {
  if (joined_.empty() || sleeping_.size() < joined_.size()) return;
  int64_t earliest = sleeping_.front().second;
  for (const auto& [id, wake_ns] : sleeping_) earliest = std::min(earliest, wake_ns);
  if (earliest > now_ns_) now_ns_ = earliest;
  changed_.notify_all();
}

void VirtualClock::SleepUntilNs(int64_t t_ns) {
  std::unique_lock<std::mutex> lock(mutex_);
  const auto id = std::this_thread::get_id();
  const bool joined = std::find(joined_.begin(), joined_.end(), id) != joined_.end();
  if (!joined) {
    if (joined_.empty()) {
      now_ns_ = std::max(now_ns_, t_ns);
      changed_.notify_all();
      return;
    }
    changed_.wait(lock, [&] { return now_ns_ >= t_ns || joined_.empty(); });
    now_ns_ = std::max(now_ns_, t_ns);
    return;
  }
  if (t_ns <= now_ns_) return;
  sleeping_.emplace_back(id, t_ns);
  AdvanceIfAllAsleep();
  changed_.wait(lock, [&] { return now_ns_ >= t_ns; });
  sleeping_.erase(std::find(sleeping_.begin(), sleeping_.end(), std::make_pair(id, t_ns)));
}

}  // namespace shutterlab
