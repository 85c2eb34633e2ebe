// The reader-to-writer ring: its size rounded up to a power of two, oldest-first order across the
// wrap, a full ring refusing what does not fit (never overwriting), the high-water mark, and a
// producer and a consumer thread passing every sample through a small ring in order.

#include "record/sample_ring.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <thread>
#include <vector>

namespace shutterlab {
namespace {

// Sample i of a test stream: its time and counts all derived from i, so that a sample out of
// order, lost or doubled shows.
RecordedSample NumberedRingSample(int64_t i) {
  RecordedSample s;
  s.t_ns = 1000 + 125000 * i;
  s.counts = {static_cast<int16_t>(i % 30000), static_cast<int16_t>(-(i % 20000)),
              static_cast<int16_t>(i % 7)};
  return s;
}

std::vector<RecordedSample> NumberedRingSamples(int64_t first, int64_t n) {
  std::vector<RecordedSample> samples;
  for (int64_t i = first; i < first + n; ++i) samples.push_back(NumberedRingSample(i));
  return samples;
}

void ExpectRingSampleIs(const RecordedSample& got, int64_t i) {
  const RecordedSample want = NumberedRingSample(i);
  EXPECT_EQ(got.t_ns, want.t_ns) << "sample " << i;
  EXPECT_EQ(got.counts, want.counts) << "sample " << i;
}

TEST(SampleRing, CapacityIsRoundedUpToAPowerOfTwo) {
  EXPECT_EQ(SampleRing(1).capacity(), 1u);
  EXPECT_EQ(SampleRing(5).capacity(), 8u);
  EXPECT_EQ(SampleRing(8).capacity(), 8u);
  EXPECT_EQ(SampleRing(64001).capacity(), 65536u);
  EXPECT_THROW(SampleRing(0), std::invalid_argument);
}

TEST(SampleRing, KeepsOldestFirstOrderAcrossTheWrap) {
  SampleRing ring(8);
  const auto first = NumberedRingSamples(0, 6);
  ASSERT_EQ(ring.Push(first.data(), first.size()), 6u);
  std::vector<RecordedSample> out(8);
  ASSERT_EQ(ring.Pop(out.data(), 4), 4u);  // take fewer than there are
  for (int i = 0; i < 4; ++i) ExpectRingSampleIs(out[i], i);
  // Six more: slots 6, 7, then 0..3 again.
  const auto second = NumberedRingSamples(6, 6);
  ASSERT_EQ(ring.Push(second.data(), second.size()), 6u);
  EXPECT_EQ(ring.size(), 8u);
  ASSERT_EQ(ring.Pop(out.data(), out.size()), 8u);
  for (int i = 0; i < 8; ++i) ExpectRingSampleIs(out[i], 4 + i);
  EXPECT_EQ(ring.size(), 0u);
  EXPECT_EQ(ring.Pop(out.data(), out.size()), 0u);  // empty
}

TEST(SampleRing, AFullRingTakesWhatFitsAndKeepsWhatItHas) {
  SampleRing ring(8);
  const auto samples = NumberedRingSamples(0, 11);
  EXPECT_EQ(ring.Push(samples.data(), samples.size()), 8u);  // 3 do not fit
  EXPECT_EQ(ring.Push(samples.data() + 8, 3), 0u);           // still full: none
  EXPECT_EQ(ring.size(), 8u);
  std::vector<RecordedSample> out(16);
  ASSERT_EQ(ring.Pop(out.data(), out.size()), 8u);
  for (int i = 0; i < 8; ++i) ExpectRingSampleIs(out[i], i);  // the first 8, none overwritten
}

TEST(SampleRing, HighWaterIsTheMostEverHeld) {
  SampleRing ring(16);
  std::vector<RecordedSample> out(16);
  const auto samples = NumberedRingSamples(0, 20);
  ring.Push(samples.data(), 5);
  EXPECT_EQ(ring.high_water(), 5u);
  ring.Pop(out.data(), 5);
  ring.Push(samples.data() + 5, 3);
  EXPECT_EQ(ring.high_water(), 5u);  // 3 held now; 5 was the most
  ring.Push(samples.data() + 8, 9);
  EXPECT_EQ(ring.high_water(), 12u);
  ring.Push(samples.data(), 20);  // only 4 fit
  EXPECT_EQ(ring.high_water(), 16u);
}

TEST(SampleRing, AProducerAndAConsumerThreadPassEverySampleInOrder) {
  constexpr int64_t kSamples = 200000;
  SampleRing ring(64);  // small, so that it fills and wraps thousands of times
  std::thread producer([&] {
    int64_t next = 0;
    std::vector<RecordedSample> batch;
    while (next < kSamples) {
      batch = NumberedRingSamples(next, std::min<int64_t>(13, kSamples - next));
      size_t pushed = 0;
      while (pushed < batch.size()) {
        pushed += ring.Push(batch.data() + pushed, batch.size() - pushed);
        if (pushed < batch.size()) std::this_thread::yield();
      }
      next += static_cast<int64_t>(batch.size());
    }
  });
  int64_t received = 0, wrong = 0;
  std::vector<RecordedSample> out(29);
  while (received < kSamples) {
    const size_t n = ring.Pop(out.data(), out.size());
    if (n == 0) std::this_thread::yield();
    for (size_t i = 0; i < n; ++i, ++received) {
      const RecordedSample want = NumberedRingSample(received);
      wrong += out[i].t_ns != want.t_ns || out[i].counts != want.counts;
    }
  }
  producer.join();
  EXPECT_EQ(received, kSamples);
  EXPECT_EQ(wrong, 0);
  EXPECT_EQ(ring.size(), 0u);
  EXPECT_LE(ring.high_water(), ring.capacity());
}

}  // namespace
}  // namespace shutterlab
