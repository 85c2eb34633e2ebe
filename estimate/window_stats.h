#pragma once
// Sliding-window statistics of a sampled signal: range (max - min) and standard deviation.
//
// A window is given by its first sample k and its end e_k (one past its last sample):
//  - fixed count N: e_k = k + N, windows k = 0 .. size-N (the paper's 120-sample windows);
//  - fixed duration W: e_k = first index with t >= t_k + W (FORMATS.md `flight`); windows whose
//    span would run past the last sample are left out.

#include <cstdint>
#include <vector>

namespace shutterlab {

// Window ends for windows of duration window_ns over sample times t_ns (non-decreasing): one entry
// per window start k whose window [t_k, t_k + window_ns) fits inside the trace, i.e. t_k + window_ns
// <= t_last. Entry k is e_k (exclusive end index).
std::vector<uint32_t> WindowEndsByDuration(const std::vector<int64_t>& t_ns, int64_t window_ns);

// Brute-force reference twins, O(N * window). Used by tests and as the definition.
std::vector<double> SlidingRangeBruteForce(const std::vector<double>& x,
                                           const std::vector<uint32_t>& window_end);
std::vector<double> SlidingStdDevBruteForce(const std::vector<double>& x,
                                            const std::vector<uint32_t>& window_end);

}  // namespace shutterlab
