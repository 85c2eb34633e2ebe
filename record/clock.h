#pragma once
// The recorder's one clock. Every sample, FIFO read and trigger edge is stamped on it: on a
// Raspberry Pi CLOCK_MONOTONIC (what libgpiod's kernel event timestamps use since Linux 5.7); in
// tests a VirtualClock, so that an 8 kHz trace with 300 ms writer stalls runs in milliseconds and
// gives the same result every time.

#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>
#include <vector>

namespace shutterlab {

class Clock {
 public:
  virtual ~Clock() = default;
  virtual int64_t NowNs() const = 0;
  // Returns at t_ns or later (at once when t_ns has passed).
  virtual void SleepUntilNs(int64_t t_ns) = 0;
  // The calling thread takes part in the clock's time (see VirtualClock); no-ops on a real clock.
  // Every thread that sleeps on a virtual clock joins it first and leaves it when it ends.
  virtual void Join() {}
  virtual void Leave() {}
};

// CLOCK_MONOTONIC, sleeping with clock_nanosleep(TIMER_ABSTIME).
class MonotonicClock : public Clock {
 public:
  int64_t NowNs() const override;
  void SleepUntilNs(int64_t t_ns) override;
};

// Discrete-event time for tests: time stands still while any joined thread runs, and moves to
// the earliest wake-up once every joined thread sleeps. So the work a thread does takes no time,
// a sleep takes exactly its length, and a run does not depend on how the threads are scheduled.
// A thread that has not joined may sleep too; it waits for the others to move time (or, when no
// thread has joined, moves it itself).
class VirtualClock : public Clock {
 public:
  explicit VirtualClock(int64_t start_ns = 0) : now_ns_(start_ns) {}
  int64_t NowNs() const override;
  void SleepUntilNs(int64_t t_ns) override;
  void Join() override;
  void Leave() override;

 private:
  // With the lock held: when every joined thread sleeps, move time to the earliest wake-up.
  void AdvanceIfAllAsleep();

  mutable std::mutex mutex_;
  std::condition_variable changed_;
  int64_t now_ns_;
  std::vector<std::thread::id> joined_;
  std::vector<std::pair<std::thread::id, int64_t>> sleeping_;  // joined threads and their wake-ups
};

}  // namespace shutterlab
