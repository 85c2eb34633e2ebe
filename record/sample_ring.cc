#include "record/sample_ring.h"

#include "sim/check.h"

#include <algorithm>

namespace shutterlab {

SampleRing::SampleRing(size_t capacity) {
  SHUTTERLAB_CHECK(capacity > 0 && capacity < (size_t{1} << 40)) << "ring capacity " << capacity;
  size_t slots = 1;
  while (slots < capacity) slots <<= 1;
  slots_.assign(slots, RecordedSample{});
  mask_ = slots - 1;
}

size_t SampleRing::size() const {
  return head_.load(std::memory_order_acquire) - tail_.load(std::memory_order_acquire);
}

size_t SampleRing::Push(const RecordedSample* samples, size_t n) {
  const size_t head = head_.load(std::memory_order_relaxed);
  const size_t tail = tail_.load(std::memory_order_acquire);
  const size_t room = slots_.size() - (head - tail);
  const size_t count = std::min(n, room);
  for (size_t i = 0; i < count; ++i) slots_[(head + i) & mask_] = samples[i];
  head_.store(head + count, std::memory_order_release);
  const size_t used = head + count - tail;
  if (used > high_water_.load(std::memory_order_relaxed)) {
    high_water_.store(used, std::memory_order_relaxed);
  }
  return count;
}

size_t SampleRing::Pop(RecordedSample* out, size_t max) {
  const size_t tail = tail_.load(std::memory_order_relaxed);
  const size_t head = head_.load(std::memory_order_acquire);
  const size_t count = std::min(max, head - tail);
  for (size_t i = 0; i < count; ++i) out[i] = slots_[(tail + i) & mask_];
  tail_.store(tail + count, std::memory_order_release);
  return count;
}

}  // namespace shutterlab
