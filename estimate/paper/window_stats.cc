#include "estimate/paper/window_stats.h"

#include "sim/check.h"

#include <algorithm>
#include <cmath>
#include <limits>

// The three-axis range kernel in SSE2 registers (Extrema<3> below); SHUTTERLAB_PORTABLE_EXTREMA
// builds the portable form instead, what ARM runs, so that a test target checks it on x86 too.
#if defined(__SSE2__) && !defined(SHUTTERLAB_PORTABLE_EXTREMA)
#define SHUTTERLAB_SSE2_EXTREMA 1
#include <emmintrin.h>
#endif

namespace shutterlab {
namespace {

// Window starts per chunk: the block buffers (4 doubles per sample and signal) then stay in L2.
constexpr size_t kChunkWindows = 16384;

// Running sums are rebuilt exactly at least this often (or once per window length if longer), so
// rounding from add/remove updates never accumulates over more than this many windows; this is what
// keeps 10^8-sample traces as accurate as short ones.
constexpr size_t kStdDevRestartWindows = 4096;
// A running-sum variance is used only when it exceeds this multiple of its worst-case rounding
// error (relative sigma error <= 0.5 / kStdDevTrust); otherwise the window is recomputed exactly.
constexpr double kStdDevTrust = 1e9;

// Checks the window-end preconditions; returns the longest window's sample count.
size_t CheckWindowEnds(size_t size, const std::vector<uint32_t>& window_end) {
  size_t longest = 0;
  uint32_t previous = 0;
  for (size_t k = 0; k < window_end.size(); ++k) {
    const uint32_t e = window_end[k];
    SHUTTERLAB_CHECK(e > k && e <= size)
        << "window " << k << " ends at " << e << ", outside (" << k << ", " << size << "]";
    SHUTTERLAB_CHECK(e >= previous) << "window ends decrease at window " << k;
    previous = e;
    longest = std::max<size_t>(longest, e - k);
  }
  return longest;
}

// Block size for the van Herk / Gil-Werman scheme: a low quantile of the window sample counts in
// the chunk. Windows at least this long span whole blocks and take O(1 + len/B); the rare shorter
// ones (windows cut short by a logging gap) are scanned directly at cost len < B.
size_t ChooseBlock(const uint32_t* chunk_end, size_t k_begin, size_t k_end) {
  constexpr size_t kProbes = 33;
  size_t lengths[kProbes];
  const size_t count = k_end - k_begin;
  const size_t probes = std::min(kProbes, count);
  for (size_t p = 0; p < probes; ++p) {
    const size_t i = probes == 1 ? 0 : p * (count - 1) / (probes - 1);
    lengths[p] = chunk_end[i] - (k_begin + i);
  }
  std::nth_element(lengths, lengths + probes / 4, lengths + probes);
  return std::max<size_t>(1, lengths[probes / 4]);
}

}  // namespace

std::vector<uint32_t> WindowEndsByDuration(const std::vector<int64_t>& t_ns, int64_t window_ns) {
  SHUTTERLAB_CHECK(window_ns > 0) << "window duration must be positive";
  SHUTTERLAB_CHECK(t_ns.size() < (1ull << 32)) << "trace too long for 32-bit window indices";
  std::vector<uint32_t> ends;
  if (t_ns.empty()) return ends;
  const int64_t t_last = t_ns.back();
  size_t e = 0;
  for (size_t k = 0; k < t_ns.size() && t_ns[k] + window_ns <= t_last; ++k) {
    while (e < t_ns.size() && t_ns[e] < t_ns[k] + window_ns) ++e;
    ends.push_back(static_cast<uint32_t>(e));
  }
  return ends;
}

std::vector<uint32_t> WindowEndsByCount(size_t size, size_t count) {
  SHUTTERLAB_CHECK(count > 0) << "window must hold at least one sample";
  SHUTTERLAB_CHECK(count <= size) << "window of " << count << " samples is longer than the " << size
                                  << " samples available";
  SHUTTERLAB_CHECK(size < (1ull << 32)) << "trace too long for 32-bit window indices";
  std::vector<uint32_t> ends(size - count + 1);
  for (size_t k = 0; k < ends.size(); ++k) ends[k] = static_cast<uint32_t>(k + count);
  return ends;
}

std::vector<double> SlidingRangeBruteForce(const std::vector<double>& x,
                                           const std::vector<uint32_t>& window_end) {
  std::vector<double> out(window_end.size());
  for (size_t k = 0; k < window_end.size(); ++k) {
    SHUTTERLAB_CHECK(window_end[k] > k && window_end[k] <= x.size()) << "bad window " << k;
    const auto [lo, hi] = std::minmax_element(x.begin() + k, x.begin() + window_end[k]);
    out[k] = *hi - *lo;
  }
  return out;
}

std::vector<double> SlidingStdDevBruteForce(const std::vector<double>& x,
                                            const std::vector<uint32_t>& window_end) {
  std::vector<double> out(window_end.size());
  for (size_t k = 0; k < window_end.size(); ++k) {
    SHUTTERLAB_CHECK(window_end[k] > k && window_end[k] <= x.size()) << "bad window " << k;
    const size_t n = window_end[k] - k;
    double mean = 0;
    for (size_t i = k; i < window_end[k]; ++i) mean += x[i];
    mean /= n;
    double ss = 0;
    for (size_t i = k; i < window_end[k]; ++i) ss += (x[i] - mean) * (x[i] - mean);
    // Population standard deviation (divide by n), as numpy.std and the paper's tables.
    out[k] = std::sqrt(ss / n);
  }
  return out;
}

// The maxima and minima of kAxes signals over a span of samples, as the kernel keeps them (one per
// sample in the prefix and suffix buffers, one per block): Of one sample, Merge of two spans, Load
// and Store as kDoubles doubles, and the ranges stored to out[axis][j]. The axes side by side:
// their running extrema are independent chains, so that a sample costs about one max/min latency
// for all axes rather than one per axis.
template <int kAxes>
struct Extrema {
  static constexpr size_t kDoubles = 2 * kAxes;
  double hi[kAxes], lo[kAxes];

  static Extrema Of(const double* const* xs, size_t i) {
    Extrema e;
    for (int a = 0; a < kAxes; ++a) e.hi[a] = e.lo[a] = xs[a][i];
    return e;
  }
  static Extrema Merge(const Extrema& p, const Extrema& q) {
    Extrema e;
    for (int a = 0; a < kAxes; ++a) {
      e.hi[a] = std::max(p.hi[a], q.hi[a]);
      e.lo[a] = std::min(p.lo[a], q.lo[a]);
    }
    return e;
  }
  static Extrema Load(const double* p) {
    Extrema e;
    for (int a = 0; a < kAxes; ++a) {
      e.hi[a] = p[a];
      e.lo[a] = p[kAxes + a];
    }
    return e;
  }
  void Store(double* p) const {
    for (int a = 0; a < kAxes; ++a) {
      p[a] = hi[a];
      p[kAxes + a] = lo[a];
    }
  }
  void StoreRanges(double* const* out, size_t j) const {
    for (int a = 0; a < kAxes; ++a) out[a][j] = hi[a] - lo[a];
  }
};

#if defined(SHUTTERLAB_SSE2_EXTREMA)
// Three axes with SSE2: the six extrema in three lane pairs, (x, y), (-x, -y) and (z, -z). The
// maximum of negated values is their negated minimum, exactly, so one maxpd keeps two extrema, and
// a range is max + max(-x) = max - min, bit for bit (a - b is defined as a + (-b)). Half the
// instructions of the scalar form, and every buffer access 16 bytes (`flight` on a 30 M-line
// gyro.csv: docs/speed.md).
template <>
struct Extrema<3> {
  static constexpr size_t kDoubles = 6;
  __m128d xy, neg_xy, z_neg_z;

  // Lanes are (low, high): _mm_setr_pd's order.
  static Extrema Of(const double* const* xs, size_t i) {
    const __m128d pair = _mm_loadh_pd(_mm_load_sd(xs[0] + i), xs[1] + i);
    const __m128d z = _mm_load1_pd(xs[2] + i);
    return {pair, _mm_xor_pd(pair, _mm_set1_pd(-0.0)), _mm_xor_pd(z, _mm_setr_pd(0.0, -0.0))};
  }
  static Extrema Merge(const Extrema& p, const Extrema& q) {
    return {_mm_max_pd(p.xy, q.xy), _mm_max_pd(p.neg_xy, q.neg_xy),
            _mm_max_pd(p.z_neg_z, q.z_neg_z)};
  }
  static Extrema Load(const double* p) {
    return {_mm_loadu_pd(p), _mm_loadu_pd(p + 2), _mm_loadu_pd(p + 4)};
  }
  void Store(double* p) const {
    _mm_storeu_pd(p, xy);
    _mm_storeu_pd(p + 2, neg_xy);
    _mm_storeu_pd(p + 4, z_neg_z);
  }
  void StoreRanges(double* const* out, size_t j) const {
    const __m128d range_xy = _mm_add_pd(xy, neg_xy);
    _mm_storel_pd(out[0] + j, range_xy);
    _mm_storeh_pd(out[1] + j, range_xy);
    _mm_storel_pd(out[2] + j, _mm_add_sd(z_neg_z, _mm_unpackhi_pd(z_neg_z, z_neg_z)));
  }
};
#endif

// Van Herk (1992) / Gil & Werman (1993): split the samples into blocks of B; per block keep prefix
// extrema (block start .. i) and suffix extrema (i .. block end). A window of at least B samples
// starting in block bs and ending in block bl > bs is then
//   max(suffix[s], block maxima bs+1 .. bl-1, prefix[e-1]),
// and with B near the window length there are at most one or two whole blocks in between. A window
// of exactly B samples inside one block is that block, where suffix[s] = prefix[e-1] = its maximum,
// so the same formula holds. This is streaming code with predictable branches, against the
// data-dependent branches of the monotonic-deque algorithm. kAxes signals share one pass (the
// window bookkeeping is the same for all).
//
// The block extrema of kAxes signals over their samples [base, base + n), blocks of `block`:
// prefix extrema in buffers[0], suffix in buffers[1], per block in buffers[2].
template <int kAxes>
void BuildBlocks(const double* const* x, size_t base, size_t n, size_t block,
                 std::vector<double>* buffers) {
  using E = Extrema<kAxes>;
  const size_t blocks = (n + block - 1) / block;
  buffers[0].resize(n * E::kDoubles);
  buffers[1].resize(n * E::kDoubles);
  buffers[2].resize(blocks * E::kDoubles);
  double* prefix = buffers[0].data();
  double* suffix = buffers[1].data();
  double* block_extrema = buffers[2].data();
  const double* xs[kAxes];
  for (int a = 0; a < kAxes; ++a) xs[a] = x[a] + base;
  for (size_t b = 0; b < blocks; ++b) {
    const size_t lo = b * block;
    const size_t hi = std::min(n, lo + block);
    E run = E::Of(xs, lo);
    for (size_t i = lo; i < hi; ++i) {
      run = E::Merge(run, E::Of(xs, i));
      run.Store(prefix + i * E::kDoubles);
    }
    run.Store(block_extrema + b * E::kDoubles);
    run = E::Of(xs, hi - 1);
    for (size_t i = hi; i-- > lo;) {
      run = E::Merge(run, E::Of(xs, i));
      run.Store(suffix + i * E::kDoubles);
    }
  }
}

// The ranges of the windows k in [k_begin, k_end) (ends chunk_end[k - k_begin]) from the block
// extrema BuildBlocks made from sample base = k_begin on, with the same block.
template <int kAxes>
void QueryWindows(const double* const* x, const uint32_t* chunk_end, size_t k_begin, size_t k_end,
                  size_t block, const std::vector<double>* buffers, double* const* out) {
  using E = Extrema<kAxes>;
  const size_t base = k_begin;
  const double* prefix = buffers[0].data();
  const double* suffix = buffers[1].data();
  const double* block_extrema = buffers[2].data();
  const double* xs[kAxes];
  double* outs[kAxes];  // locals: a store through one cannot then change another
  for (int a = 0; a < kAxes; ++a) {
    xs[a] = x[a] + base;
    outs[a] = out[a];
  }
  // Block index of the window's first sample, advanced incrementally (s grows by one per window).
  size_t first_block = 0, first_block_end = block;
  for (size_t k = k_begin; k < k_end; ++k) {
    const size_t s = k - base;
    const size_t e = chunk_end[s] - base;
    if (s == first_block_end) {
      ++first_block;
      first_block_end += block;
    }
    E window;
    if (e - s < block) {  // shorter than a block (only near logging gaps): scan directly
      window = E::Of(xs, s);
      for (size_t i = s + 1; i < e; ++i) window = E::Merge(window, E::Of(xs, i));
    } else {
      window = E::Merge(E::Load(suffix + s * E::kDoubles), E::Load(prefix + (e - 1) * E::kDoubles));
      // Whole blocks strictly between the first and the last block, if any.
      for (size_t b = first_block + 1; (b + 1) * block <= e - 1; ++b)
        window = E::Merge(window, E::Load(block_extrema + b * E::kDoubles));
    }
    window.StoreRanges(outs, k - k_begin);
  }
}

template <int kAxes>
void RangeKernel(const double* const* x, const uint32_t* chunk_end, size_t k_begin, size_t k_end,
                 double* const* out, std::vector<double>* buffers) {
  if (k_end <= k_begin) return;
  const size_t n = chunk_end[k_end - 1 - k_begin] - k_begin;  // samples the chunk's windows touch
  const size_t block = ChooseBlock(chunk_end, k_begin, k_end);
  BuildBlocks<kAxes>(x, k_begin, n, block, buffers);
  QueryWindows<kAxes>(x, chunk_end, k_begin, k_end, block, buffers, out);
}

void SlidingRangeKernel::Run(const double* x, const uint32_t* chunk_end, size_t k_begin,
                             size_t k_end, double* out) {
  RangeKernel<1>(&x, chunk_end, k_begin, k_end, &out, buffers_);
}

void SlidingRangeKernel::Run3(const std::array<const double*, 3>& x, const uint32_t* chunk_end,
                              size_t k_begin, size_t k_end, const std::array<double*, 3>& out) {
  RangeKernel<3>(x.data(), chunk_end, k_begin, k_end, out.data(), buffers_);
}

void SlidingRangeKernel::Run3Sets(const std::array<const double*, 3>& x, size_t k_begin,
                                  const std::vector<WindowSet>& sets) {
  // One block for every set: the shortest windows' (a longer window spans more whole blocks,
  // which costs one Merge each); the samples: as far as the farthest window reaches.
  size_t n = 0, block = std::numeric_limits<size_t>::max();
  for (const WindowSet& set : sets) {
    if (set.count == 0) continue;
    n = std::max<size_t>(n, set.ends[set.count - 1] - k_begin);
    block = std::min(block, ChooseBlock(set.ends, k_begin, k_begin + set.count));
  }
  if (n == 0) return;
  BuildBlocks<3>(x.data(), k_begin, n, block, buffers_);
  for (const WindowSet& set : sets) {
    if (set.count == 0) continue;
    QueryWindows<3>(x.data(), set.ends, k_begin, k_begin + set.count, block, buffers_,
                    set.out.data());
  }
}

std::vector<double> SlidingRange(const std::vector<double>& x,
                                 const std::vector<uint32_t>& window_end) {
  const size_t longest = CheckWindowEnds(x.size(), window_end);
  std::vector<double> out(window_end.size());
  // A chunk at least as long as the longest window keeps the total work O(N): each sample is then
  // covered by at most two chunks' block buffers.
  const size_t chunk = std::max(kChunkWindows, longest);
  SlidingRangeKernel kernel;
  for (size_t k0 = 0; k0 < window_end.size(); k0 += chunk) {
    const size_t k1 = std::min(window_end.size(), k0 + chunk);
    kernel.Run(x.data(), window_end.data() + k0, k0, k1, out.data() + k0);
  }
  return out;
}

std::vector<double> SlidingStdDev(const std::vector<double>& x,
                                  const std::vector<uint32_t>& window_end) {
  CheckWindowEnds(x.size(), window_end);
  std::vector<double> out(window_end.size());
  constexpr double kEps = std::numeric_limits<double>::epsilon();
  // Sums of d = x - anchor over the current window [lo, hi), and bounds on their rounding error
  // in units of eps: every add/remove rounds to within one ulp of the running sum. The d values
  // themselves are computed identically when a sample enters and when it leaves, so they cancel
  // exactly; only the accumulation rounds.
  double anchor = 0.0, s1 = 0.0, s2 = 0.0, err1 = 0.0, err2 = 0.0;
  size_t lo = 0, hi = 0, since_restart = 0;
  // Exact restart at window [k, e): anchor at its mean (two passes), sums about it.
  auto restart = [&](size_t k, size_t e) {
    double sum = 0.0;
    for (size_t i = k; i < e; ++i) sum += x[i];
    anchor = sum / static_cast<double>(e - k);
    s1 = s2 = 0.0;
    for (size_t i = k; i < e; ++i) {
      const double d = x[i] - anchor;
      s1 += d;
      s2 += d * d;
    }
    err1 = std::abs(s1) * static_cast<double>(e - k);
    err2 = s2 * static_cast<double>(e - k);
    lo = k;
    hi = e;
    since_restart = 0;
  };
  for (size_t k = 0; k < window_end.size(); ++k) {
    const size_t e = window_end[k];
    bool exact = false;
    if (k == 0 || since_restart >= std::max(kStdDevRestartWindows, e - k)) {
      restart(k, e);
      exact = true;
    } else {
      for (; hi < e; ++hi) {
        const double d = x[hi] - anchor;
        s1 += d;
        s2 += d * d;
        err1 += std::abs(s1);
        err2 += s2;
      }
      for (; lo < k; ++lo) {
        const double d = x[lo] - anchor;
        s1 -= d;
        s2 -= d * d;
        err1 += std::abs(s1);
        err2 += s2;
      }
    }
    ++since_restart;
    const double inv_n = 1.0 / static_cast<double>(hi - lo);
    double offset = s1 * inv_n;
    double variance = s2 * inv_n - offset * offset;
    if (!exact) {
      // Worst-case error of that variance; when it could spoil the result (a window much quieter
      // than the signal's excursion from the anchor: an integrated angle drifting away, or a
      // short window of nearly equal samples), restart exactly here. The restart also re-anchors,
      // so a drifting signal pays O(window) once per ~sqrt(kStdDevTrust) sigmas of drift.
      const double error = kEps * ((err2 + 2.0 * std::abs(offset) * err1) * inv_n +
                                   4.0 * (s2 * inv_n + offset * offset));
      if (variance < kStdDevTrust * error) {
        restart(k, e);
        offset = s1 * inv_n;
        variance = s2 * inv_n - offset * offset;
      }
    }
    out[k] = std::sqrt(std::max(0.0, variance));
  }
  return out;
}

std::vector<double> SlidingRangeByCount(const std::vector<double>& x, size_t count) {
  return SlidingRange(x, WindowEndsByCount(x.size(), count));
}

std::vector<double> SlidingStdDevByCount(const std::vector<double>& x, size_t count) {
  return SlidingStdDev(x, WindowEndsByCount(x.size(), count));
}

}  // namespace shutterlab
