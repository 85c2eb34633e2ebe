#pragma once
// The buffer between the reader thread and the writer thread: a single-producer single-consumer
// ring of timestamped samples. The reader never waits on it: when it is full the reader drops the
// samples and records a gap (the writer has been slower than the ring is long), so a slow disk
// costs at most samples it says it lost, never a stalled FIFO.

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace shutterlab {

struct RecordedSample {
  int64_t t_ns = 0;                 // on the recorder's clock
  std::array<int16_t, 3> counts{};  // raw counts, sensor axes
};

class SampleRing {
 public:
  // Room for at least `capacity` samples (rounded up to a power of two); allocated and touched
  // here, so that the reader never faults a fresh page in.
  explicit SampleRing(size_t capacity);

  // Producer: appends up to n samples; returns how many fitted.
  size_t Push(const RecordedSample* samples, size_t n);
  // Consumer: moves up to max samples out, oldest first; returns how many.
  size_t Pop(RecordedSample* out, size_t max);

  size_t capacity() const { return slots_.size(); }
  size_t size() const;
  size_t high_water() const { return high_water_.load(std::memory_order_relaxed); }

 private:
  std::vector<RecordedSample> slots_;
  size_t mask_;
  alignas(64) std::atomic<size_t> head_{0};  // next to write (producer)
  alignas(64) std::atomic<size_t> tail_{0};  // next to read (consumer)
  std::atomic<size_t> high_water_{0};
};

}  // namespace shutterlab
