// The recorder's clocks: VirtualClock's discrete-event time (a sleep takes exactly its length, work
// takes none, and the result does not depend on how the threads are scheduled), and
// MonotonicClock's sleep returning no earlier than asked.

#include "record/clock.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <thread>
#include <vector>

namespace shutterlab {
namespace {

constexpr int64_t kClockTestStartNs = 5000000000;  // any positive start

// Joins the clock, waits until `ready` threads have joined (so that no thread moves time before
// the others take part), sleeps `steps` times by period_ns, and records the time after each wake.
void SleepInStepsOnClock(VirtualClock* clock, std::atomic<int>* joined, int ready,
                         int64_t period_ns, int steps, std::vector<int64_t>* woke_at) {
  clock->Join();
  joined->fetch_add(1);
  while (joined->load() < ready) std::this_thread::yield();
  for (int i = 1; i <= steps; ++i) {
    clock->SleepUntilNs(kClockTestStartNs + i * period_ns);
    woke_at->push_back(clock->NowNs());
    // Work takes no virtual time: however long this thread runs, the clock stands still.
    for (int spin = 0; spin < 1000; ++spin) std::this_thread::yield();
    woke_at->push_back(clock->NowNs());
  }
  clock->Leave();
}

TEST(VirtualClock, AThreadAloneMovesTimeToItsWakeUpAndNeverBack) {
  VirtualClock clock(kClockTestStartNs);
  EXPECT_EQ(clock.NowNs(), kClockTestStartNs);
  clock.SleepUntilNs(kClockTestStartNs + 300000000);
  EXPECT_EQ(clock.NowNs(), kClockTestStartNs + 300000000);
  clock.SleepUntilNs(kClockTestStartNs);  // a time already past returns at once
  EXPECT_EQ(clock.NowNs(), kClockTestStartNs + 300000000);
}

TEST(VirtualClock, JoinedThreadsWakeExactlyWhenTheyAskedWhileTheOthersSleep) {
  VirtualClock clock(kClockTestStartNs);
  std::atomic<int> joined{0};
  std::vector<int64_t> fast_woke, slow_woke;
  // 10 ms and 25 ms sleeps interleave: time must visit 10, 20, 25, 30, 40, 50 ms in order, each
  // thread waking at its own multiples only.
  std::thread fast(SleepInStepsOnClock, &clock, &joined, 2, 10000000, 5, &fast_woke);
  std::thread slow(SleepInStepsOnClock, &clock, &joined, 2, 25000000, 2, &slow_woke);
  fast.join();
  slow.join();
  ASSERT_EQ(fast_woke.size(), 10u);
  ASSERT_EQ(slow_woke.size(), 4u);
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(fast_woke[2 * i], kClockTestStartNs + (i + 1) * 10000000) << "wake " << i;
    EXPECT_EQ(fast_woke[2 * i + 1], fast_woke[2 * i]) << "time moved while the thread ran";
  }
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(slow_woke[2 * i], kClockTestStartNs + (i + 1) * 25000000) << "wake " << i;
    EXPECT_EQ(slow_woke[2 * i + 1], slow_woke[2 * i]) << "time moved while the thread ran";
  }
  EXPECT_EQ(clock.NowNs(), kClockTestStartNs + 50000000);
}

TEST(VirtualClock, ASleeperWakesWhenTheOnlyOtherJoinedThreadLeaves) {
  VirtualClock clock(kClockTestStartNs);
  std::atomic<int> joined{0};
  std::atomic<bool> may_leave{false};
  int64_t woke_ns = 0;
  std::thread sleeper([&] {
    clock.Join();
    joined.fetch_add(1);
    while (joined.load() < 2) std::this_thread::yield();
    clock.SleepUntilNs(kClockTestStartNs + 70000000);
    woke_ns = clock.NowNs();
    clock.Leave();
  });
  std::thread worker([&] {
    clock.Join();
    joined.fetch_add(1);
    while (!may_leave.load()) std::this_thread::yield();
    clock.Leave();  // never sleeps: time may move only once it has gone
  });
  while (joined.load() < 2) std::this_thread::yield();
  EXPECT_EQ(clock.NowNs(), kClockTestStartNs);  // the worker runs: time stands still
  may_leave = true;
  worker.join();
  sleeper.join();
  EXPECT_EQ(woke_ns, kClockTestStartNs + 70000000);
}

TEST(MonotonicClock, SleepUntilReturnsNoEarlierThanAsked) {
  MonotonicClock clock;
  const int64_t start_ns = clock.NowNs();
  const int64_t wake_ns = start_ns + 2000000;
  clock.SleepUntilNs(wake_ns);
  EXPECT_GE(clock.NowNs(), wake_ns);
  clock.SleepUntilNs(start_ns);  // past: returns at once (a hang here would time the test out)
  EXPECT_GE(clock.NowNs(), wake_ns);
}

}  // namespace
}  // namespace shutterlab
