#pragma once
// Sliding-window statistics of a sampled signal: range (max - min) and standard deviation.
//
// A window is given by its first sample k and its end e_k (one past its last sample):
//  - fixed count N: e_k = k + N, windows k = 0 .. size-N (the paper's 120-sample windows);
//  - fixed duration W: e_k = first index with t >= t_k + W (docs/FORMATS.md `flight`); windows
//    whose span would run past the last sample are left out.
//
// Window ends must be non-decreasing with k < e_k <= size: that is what both constructions give,
// and it is what lets every fast function here run in O(N) total.

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace shutterlab {

// Window ends for windows of duration window_ns over sample times t_ns (non-decreasing): one entry
// per window start k whose window [t_k, t_k + window_ns) fits inside the trace, i.e.
// t_k + window_ns <= t_last. Entry k is e_k (exclusive end index). Empty when window_ns exceeds the
// trace's span.
std::vector<uint32_t> WindowEndsByDuration(const std::vector<int64_t>& t_ns, int64_t window_ns);

// Window ends for windows of `count` consecutive samples over `size` samples: e_k = k + count for
// k = 0 .. size - count. Throws std::invalid_argument when count is 0 or larger than size.
std::vector<uint32_t> WindowEndsByCount(size_t size, size_t count);

// Brute-force reference twins, O(N * window). Used by tests and as the definition.
std::vector<double> SlidingRangeBruteForce(const std::vector<double>& x,
                                           const std::vector<uint32_t>& window_end);
std::vector<double> SlidingStdDevBruteForce(const std::vector<double>& x,
                                            const std::vector<uint32_t>& window_end);

// O(N) sliding range, equal (==) to SlidingRangeBruteForce: max and min are exact (only a window
// of zeros alone may differ in the sign of its zero range). Van Herk / Gil-Werman block
// prefix/suffix extrema, processed in chunks so the work memory is O(chunk + longest window).
// Throws std::invalid_argument on malformed window ends.
std::vector<double> SlidingRange(const std::vector<double>& x,
                                 const std::vector<uint32_t>& window_end);
// O(N) sliding population standard deviation (divide by n), by running sums about a local anchor
// that is re-set periodically and whenever the window mean drifts far from it, so that a signal
// far from zero (an integrated angle) with a tiny window sigma keeps full relative precision.
// Agrees with SlidingStdDevBruteForce to ~1e-9 relative on such signals (see the tests).
std::vector<double> SlidingStdDev(const std::vector<double>& x,
                                  const std::vector<uint32_t>& window_end);

// Fixed-count conveniences (the `noise` analysis): windows of `count` consecutive samples, step 1.
// Throw std::invalid_argument when count is 0 or larger than x.size().
std::vector<double> SlidingRangeByCount(const std::vector<double>& x, size_t count);
std::vector<double> SlidingStdDevByCount(const std::vector<double>& x, size_t count);

// The streaming kernel behind SlidingRange, for callers that process a long signal chunk by chunk
// without materialising all window ends (estimate/paper/flight). Reuse one object across calls: it
// owns the block buffers.
class SlidingRangeKernel {
 public:
  // Ranges of the windows k in [k_begin, k_end): window k holds x[k .. e_k) with
  // e_k = chunk_end[k - k_begin] (indices into x). out[k - k_begin] receives max - min.
  // Preconditions (not re-checked here, for speed; SlidingRange checks them): ends non-decreasing,
  // k < e_k, and x valid up to the last e_k.
  void Run(const double* x, const uint32_t* chunk_end, size_t k_begin, size_t k_end, double* out);
  // The same for three signals with the same windows (the three gyro axes) in one pass: the window
  // bookkeeping is shared, and on x86 the six extrema of a sample are kept in three SSE2 registers.
  void Run3(const std::array<const double*, 3>& x, const uint32_t* chunk_end, size_t k_begin,
            size_t k_end, const std::array<double*, 3>& out);
  // Windows of several durations starting at the same samples k_begin, k_begin + 1, ...: their
  // block extrema are built once for all (the flight analysis' 10 and 20 ms windows), with
  // results bit-identical to one Run3 per set. Set i's windows k in [k_begin, k_begin + count) end
  // at ends[k - k_begin]; out[axis][k - k_begin] receives their ranges.
  struct WindowSet {
    const uint32_t* ends = nullptr;
    size_t count = 0;
    std::array<double*, 3> out{};
  };
  void Run3Sets(const std::array<const double*, 3>& x, size_t k_begin,
                const std::vector<WindowSet>& sets);

 private:
  // The extrema of each sample's prefix and suffix in its block, and of each block.
  std::vector<double> buffers_[3];
};

}  // namespace shutterlab
