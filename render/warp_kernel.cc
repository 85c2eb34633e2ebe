#include "render/warp_kernel.h"

#include "io/image_io.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#define SHUTTERLAB_WIDE_SAMPLER 1
#endif

namespace shutterlab {
namespace {

// Fixed-point bilinear sampling for integer images: coordinates in 1/128 px (7 fractional bits per
// axis), so a weight product is at most 2^14: it fits the signed 16-bit lanes of _mm_madd_epi16,
// and a 16-bit sample times 2^14 fits in uint32. Quantisation error <= 1/256 px per axis.
constexpr int kFracOne = 1 << kSampleFracBits;
constexpr int kFracMask = kFracOne - 1;

template <typename T>
inline T RoundFixed(uint32_t acc) {
  return static_cast<T>((acc + (1u << (2 * kSampleFracBits - 1))) >> (2 * kSampleFracBits));
}

// Scalar bilinear sample of one pixel at fixed-point (xi, yi); taps outside the scene read as 0.
template <typename T>
inline void BilinearPixel(const T* base, size_t step, int sw, int sh, int cn, int xi, int yi,
                          T* out) {
  const int ix = xi >> kSampleFracBits, iy = yi >> kSampleFracBits;  // arithmetic shift: floor
  if (xi == kInvalidFixed || yi == kInvalidFixed || ix < -1 || iy < -1 || ix >= sw || iy >= sh) {
    for (int c = 0; c < cn; ++c) out[c] = 0;
    return;
  }
  const uint32_t fx = xi & kFracMask, fy = yi & kFracMask;
  const uint32_t w00 = (kFracOne - fx) * (kFracOne - fy), w01 = fx * (kFracOne - fy);
  const uint32_t w10 = (kFracOne - fx) * fy, w11 = fx * fy;
  if (ix >= 0 && iy >= 0 && ix < sw - 1 && iy < sh - 1) {
    const T* p0 = base + iy * step + static_cast<size_t>(ix) * cn;
    const T* p1 = p0 + step;
    for (int c = 0; c < cn; ++c) {
      out[c] = RoundFixed<T>(p0[c] * w00 + p0[c + cn] * w01 + p1[c] * w10 + p1[c + cn] * w11);
    }
    return;
  }
  const bool x0 = ix >= 0, x1 = ix + 1 < sw, y0 = iy >= 0, y1 = iy + 1 < sh;
  for (int c = 0; c < cn; ++c) {
    uint32_t acc = 0;
    if (y0 && x0) acc += base[iy * step + static_cast<size_t>(ix) * cn + c] * w00;
    if (y0 && x1) acc += base[iy * step + static_cast<size_t>(ix + 1) * cn + c] * w01;
    if (y1 && x0) acc += base[(iy + 1) * step + static_cast<size_t>(ix) * cn + c] * w10;
    if (y1 && x1) acc += base[(iy + 1) * step + static_cast<size_t>(ix + 1) * cn + c] * w11;
    out[c] = RoundFixed<T>(acc);
  }
}

template <typename T, int kCn>
void BilinearRowInt(const cv::Mat& src, const int* xi, const int* yi, int width, int cn_runtime,
                    T* out) {
  const int cn = kCn > 0 ? kCn : cn_runtime;
  const T* base = src.ptr<T>();
  for (int u = 0; u < width; ++u)
    BilinearPixel(base, src.step1(), src.cols, src.rows, cn, xi[u], yi[u], out + u * cn);
}

#if defined(__SSE2__)
// 8-bit RGB, the common case, one pixel per step in SSE2: the 2x2 neighbourhood is two 8-byte
// loads; interleaving the top and bottom rows pairs each tap with its vertical partner, so
// _mm_madd_epi16 applies the (top, bottom) weights of one column and sums them in one instruction.
// Same weights and rounding as BilinearPixel: the result is bit-identical to the scalar path.
// Weight pairs of pixels [0, n): weights[2u] = column ix's (top | bottom << 16), weights[2u+1] =
// column ix+1's, four pixels per step. Products are < 2^15, so 16-bit multiplies are exact.
void BilinearWeights(const int* xi, const int* yi, int n, int32_t* weights) {
  const __m128i mask = _mm_set1_epi32(kFracMask), one = _mm_set1_epi32(kFracOne);
  int u = 0;
  for (; u + 4 <= n; u += 4) {
    const __m128i fx =
        _mm_and_si128(_mm_loadu_si128(reinterpret_cast<const __m128i*>(xi + u)), mask);
    const __m128i fy =
        _mm_and_si128(_mm_loadu_si128(reinterpret_cast<const __m128i*>(yi + u)), mask);
    const __m128i gx = _mm_sub_epi32(one, fx), gy = _mm_sub_epi32(one, fy);
    const __m128i w0 =
        _mm_or_si128(_mm_mullo_epi16(gx, gy), _mm_slli_epi32(_mm_mullo_epi16(gx, fy), 16));
    const __m128i w1 =
        _mm_or_si128(_mm_mullo_epi16(fx, gy), _mm_slli_epi32(_mm_mullo_epi16(fx, fy), 16));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(weights + 2 * u), _mm_unpacklo_epi32(w0, w1));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(weights + 2 * u + 4), _mm_unpackhi_epi32(w0, w1));
  }
  for (; u < n; ++u) {
    const int fx = xi[u] & kFracMask, fy = yi[u] & kFracMask;
    const int gx = kFracOne - fx, gy = kFracOne - fy;
    weights[2 * u] = (gx * gy) | ((gx * fy) << 16);
    weights[2 * u + 1] = (fx * gy) | ((fx * fy) << 16);
  }
}

void BilinearRow8uc3(const cv::Mat& src, const int* xi, const int* yi, int width, uint8_t* out) {
  const int sw = src.cols, sh = src.rows;
  const size_t step = src.step;
  const uint8_t* base = src.data;
  const __m128i zero = _mm_setzero_si128();
  const __m128i round = _mm_set1_epi32(1 << (2 * kSampleFracBits - 1));
  // The fast path reads 8 bytes from column ix: ix <= sw - 3 keeps the read inside the row.
  const unsigned fast_x = static_cast<unsigned>(std::max(0, sw - 2)),
                 fast_y = static_cast<unsigned>(std::max(0, sh - 1));
  constexpr int kBlock = 256;  // weights of a block of pixels, computed four at a time
  alignas(16) int32_t weights[2 * kBlock];
  // The row's last pixel goes through the scalar path, after the loop: the 4-byte store below would
  // spill past it.
  const int last = width - 1;
  for (int u0 = 0; u0 < last; u0 += kBlock) {
    const int n = std::min(kBlock, last - u0);
    BilinearWeights(xi + u0, yi + u0, n, weights);
    for (int k = 0; k < n; ++k) {
      const int u = u0 + k;
      const int ix = xi[u] >> kSampleFracBits, iy = yi[u] >> kSampleFracBits;
      if (static_cast<unsigned>(ix) >= fast_x || static_cast<unsigned>(iy) >= fast_y) {
        BilinearPixel<uint8_t>(base, step, sw, sh, 3, xi[u], yi[u], out + 3 * u);
        continue;
      }
      const uint8_t* p0 = base + iy * step + ix * 3;
      const __m128i top = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(p0));
      const __m128i bottom = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(p0 + step));
      // r0t r0b g0t g0b b0t b0b r1t r1b g1t g1b b1t b1b ..
      const __m128i pairs = _mm_unpacklo_epi8(top, bottom);
      const __m128i lo = _mm_unpacklo_epi8(pairs, zero);  // int16: r0t r0b g0t g0b b0t b0b r1t r1b
      const __m128i hi = _mm_unpackhi_epi8(pairs, zero);  // int16: g1t g1b b1t b1b ...
      // (w0, w1, ., .): the (top, bottom) weights of columns ix and ix+1.
      const __m128i w01 = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(weights + 2 * k));
      const __m128i sum_lo =
          _mm_madd_epi16(lo, _mm_shuffle_epi32(w01, _MM_SHUFFLE(1, 0, 0, 0)));  // R0 G0 B0 R1
      const __m128i sum_hi =
          _mm_madd_epi16(_mm_unpacklo_epi64(hi, zero),
                         _mm_shuffle_epi32(w01, _MM_SHUFFLE(1, 1, 1, 1)));  // G1 B1 0 0
      __m128i sum = _mm_add_epi32(sum_lo, _mm_slli_si128(sum_hi, 4));       // R0 G G B R1
      sum = _mm_add_epi32(sum, _mm_srli_si128(sum, 12));                    // R G B R1
      sum = _mm_srli_epi32(_mm_add_epi32(sum, round), 2 * kSampleFracBits);
      sum = _mm_packs_epi32(sum, sum);
      sum = _mm_packus_epi16(sum, sum);
      const uint32_t rgbx = static_cast<uint32_t>(_mm_cvtsi128_si32(sum));
      // 4-byte store: its 4th byte belongs to pixel u+1, which is written afterwards.
      std::memcpy(out + 3 * u, &rgbx, 4);
    }
  }
  if (width > 0) {
    BilinearPixel<uint8_t>(base, step, sw, sh, 3, xi[last], yi[last], out + 3 * last);
  }
}
#endif

void BilinearRowFloat(const cv::Mat& src, const float* xs, const float* ys, int width, float* out) {
  const int cn = src.channels();
  const int sw = src.cols, sh = src.rows;
  const size_t step = src.step1();
  const float* base = src.ptr<float>();
  for (int u = 0; u < width; ++u, out += cn) {
    const float x = xs[u], y = ys[u];
    for (int c = 0; c < cn; ++c) out[c] = 0.0f;
    if (!(x > -1.0f && x < static_cast<float>(sw) && y > -1.0f && y < static_cast<float>(sh)))
      continue;
    const int ix = static_cast<int>(std::floor(x)), iy = static_cast<int>(std::floor(y));
    const float fx = x - ix, fy = y - iy;
    const float w[2][2] = {{(1 - fx) * (1 - fy), fx * (1 - fy)}, {(1 - fx) * fy, fx * fy}};
    for (int dy = 0; dy < 2; ++dy) {
      const int yy = iy + dy;
      if (yy < 0 || yy >= sh) continue;
      for (int dx = 0; dx < 2; ++dx) {
        const int xx = ix + dx;
        if (xx < 0 || xx >= sw) continue;
        const float* p = base + yy * step + static_cast<size_t>(xx) * cn;
        for (int c = 0; c < cn; ++c) out[c] += w[dy][dx] * p[c];
      }
    }
  }
}

// OpenCV's cubic convolution kernel (A = -0.75), the one INTER_CUBIC uses.
inline void CubicWeights(float t, float w[4]) {
  constexpr float kA = -0.75f;
  w[0] = ((kA * (t + 1) - 5 * kA) * (t + 1) + 8 * kA) * (t + 1) - 4 * kA;
  w[1] = ((kA + 2) * t - (kA + 3)) * t * t + 1;
  w[2] = ((kA + 2) * (1 - t) - (kA + 3)) * (1 - t) * (1 - t) + 1;
  w[3] = 1.0f - w[0] - w[1] - w[2];
}

template <typename T>
void BicubicRow(const cv::Mat& src, const float* xs, const float* ys, int width, T* out) {
  const int cn = src.channels();
  const int sw = src.cols, sh = src.rows;
  const size_t step = src.step1();
  const T* base = src.ptr<T>();
  float acc[4];
  for (int u = 0; u < width; ++u, out += cn) {
    const float x = xs[u], y = ys[u];
    if (!(x > -2.0f && x < static_cast<float>(sw + 1) && y > -2.0f &&
          y < static_cast<float>(sh + 1))) {
      for (int c = 0; c < cn; ++c) out[c] = 0;
      continue;
    }
    const int ix = static_cast<int>(std::floor(x)), iy = static_cast<int>(std::floor(y));
    float wx[4], wy[4];
    CubicWeights(x - ix, wx);
    CubicWeights(y - iy, wy);
    for (int c = 0; c < cn; ++c) acc[c] = 0.0f;
    for (int dy = 0; dy < 4; ++dy) {
      const int yy = iy - 1 + dy;
      if (yy < 0 || yy >= sh) continue;
      for (int dx = 0; dx < 4; ++dx) {
        const int xx = ix - 1 + dx;
        if (xx < 0 || xx >= sw) continue;
        const float w = wy[dy] * wx[dx];
        const T* p = base + yy * step + static_cast<size_t>(xx) * cn;
        for (int c = 0; c < cn; ++c) acc[c] += w * static_cast<float>(p[c]);
      }
    }
    for (int c = 0; c < cn; ++c) out[c] = cv::saturate_cast<T>(acc[c]);
  }
}

// Float-coordinate rows: bicubic for every type, bilinear for float images.
void SampleRowFloatImpl(const cv::Mat& src, const float* xs, const float* ys, int width,
                        Interpolation interpolation, uchar* out) {
  const int depth = src.depth();
  if (interpolation == Interpolation::kBicubic) {
    if (depth == CV_8U) return BicubicRow<uint8_t>(src, xs, ys, width, out);
    if (depth == CV_16U)
      return BicubicRow<uint16_t>(src, xs, ys, width, reinterpret_cast<uint16_t*>(out));
    return BicubicRow<float>(src, xs, ys, width, reinterpret_cast<float*>(out));
  }
  BilinearRowFloat(src, xs, ys, width, reinterpret_cast<float*>(out));
}

// Fixed-point rows: bilinear for 8- and 16-bit images.
#if defined(SHUTTERLAB_WIDE_SAMPLER)
// 8-bit RGB, four pixels per 128-bit lane (SSE4.1: one lane; AVX2: two, eight pixels a step). Four
// neighbouring output pixels of a map close to a shift read from columns ix0 .. ix0 + 4 of one
// source row pair: one 16-byte load per row holds every tap. For each channel, a byte shuffle lines
// up every pixel's (left, right) taps as two 16-bit lanes of its 32-bit lane, and madd applies the
// row's (left, right) weights and sums them; one shuffle at the end interleaves the channels. Where
// a row boundary runs through the block (each pixel's rows are iy or iy + 1 from the block's
// lowest) three rows are loaded, each pixel's weights on the two it reads and zero on the third.
// Same integer weights, sums and rounding as BilinearPixel: bit-identical. A block whose taps do
// not fit (a stretched map, the source's last columns or rows, no source) takes the next narrower
// path (Block8's four-pixel blocks, Block4's the one-pixel path).

// The source as the blocks read it: its pixels and row step (copied: read through the cv::Mat,
// which the blocks' stores might alias for all the compiler knows, they were loaded again for
// every block), and where a block fits: its loads stay inside the source when
// 3 ix0 + 16 <= 3 width and iy0 + 1 <= height - 1. A source of fewer than 6 columns or 2 rows
// fits no block, which no unsigned limit can say (the limit -1 let every block through, reading
// outside the source): its rows take the one-pixel path whole.
struct BlockSource {
  const uint8_t* data;
  size_t step;
  int max_ix0, max_iy0;
  bool blocks_fit;
  explicit BlockSource(const cv::Mat& src)
      : data(src.data),
        step(src.step),
        max_ix0(src.cols - 6),
        max_iy0(src.rows - 2),
        blocks_fit(max_ix0 >= 0 && max_iy0 >= 0) {}
  // Unsigned: a negative ix0 or iy0 is outside. Only where blocks_fit.
  bool Inside(int ix0, int iy0) const {
    return static_cast<unsigned>(ix0) <= static_cast<unsigned>(max_ix0) &&
           static_cast<unsigned>(iy0) <= static_cast<unsigned>(max_iy0);
  }
};

// Control bytes of channel c for every 32-bit lane: (left, right) = bytes (c, c + 3), each
// zero-extended (0x80 selects zero; adding a pixel's offset 3 dx < 16 keeps bit 7 set).
#define SHUTTERLAB_CHANNEL_CTRL(c) \
  c, -128, c + 3, -128, c, -128, c + 3, -128, c, -128, c + 3, -128, c, -128, c + 3, -128
// Bytes R0 R1 R2 R3 G0 .. G3 B0 .. B3 (planar, as packed) to R0 G0 B0 R1 G1 B1 ...
#define SHUTTERLAB_INTERLEAVE 0, 4, 8, 1, 5, 9, 2, 6, 10, 3, 7, 11, 12, 13, 14, 15

__attribute__((target("sse4.1"))) inline __m128i ChannelSum4(bool three_rows, __m128i row0,
                                                             __m128i row1, __m128i row2,
                                                             __m128i ctrl, __m128i w0, __m128i w1,
                                                             __m128i w2) {
  __m128i sum = _mm_add_epi32(_mm_madd_epi16(_mm_shuffle_epi8(row0, ctrl), w0),
                              _mm_madd_epi16(_mm_shuffle_epi8(row1, ctrl), w1));
  if (three_rows) sum = _mm_add_epi32(sum, _mm_madd_epi16(_mm_shuffle_epi8(row2, ctrl), w2));
  const __m128i round = _mm_set1_epi32(1 << (2 * kSampleFracBits - 1));
  return _mm_srli_epi32(_mm_add_epi32(sum, round), 2 * kSampleFracBits);
}

template <bool kThreeRows>
__attribute__((target("sse4.1"))) inline bool Block4(const BlockSource& source, const int* xi,
                                                     const int* yi, uint8_t* out) {
  const __m128i vx = _mm_loadu_si128(reinterpret_cast<const __m128i*>(xi));
  const __m128i vy = _mm_loadu_si128(reinterpret_cast<const __m128i*>(yi));
  const __m128i ix = _mm_srai_epi32(vx, kSampleFracBits);
  const __m128i iy = _mm_srai_epi32(vy, kSampleFracBits);
  __m128i low = _mm_shuffle_epi32(iy, 0);
  if (kThreeRows) {
    low = _mm_min_epi32(iy, _mm_shuffle_epi32(iy, _MM_SHUFFLE(1, 0, 3, 2)));
    low = _mm_min_epi32(low, _mm_shuffle_epi32(low, _MM_SHUFFLE(2, 3, 0, 1)));
  }
  const __m128i dx = _mm_sub_epi32(ix, _mm_shuffle_epi32(ix, 0));
  const __m128i dy = _mm_sub_epi32(iy, low);
  const __m128i misfit = _mm_or_si128(_mm_andnot_si128(_mm_set1_epi32(3), dx),
                                      _mm_andnot_si128(_mm_set1_epi32(kThreeRows ? 1 : 0), dy));
  const int ix0 = _mm_cvtsi128_si32(ix), iy0 = _mm_cvtsi128_si32(low);
  if (!_mm_testz_si128(misfit, misfit) || !source.Inside(ix0, iy0) ||
      (kThreeRows && !source.Inside(ix0, iy0 + 1))) {
    return false;
  }
  const size_t step = source.step;
  const uint8_t* p0 = source.data + iy0 * step + ix0 * 3;
  const __m128i row0 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p0));
  const __m128i row1 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p0 + step));
  const __m128i row2 =
      kThreeRows ? _mm_loadu_si128(reinterpret_cast<const __m128i*>(p0 + 2 * step)) : row1;
  // The next output row reads these columns one source row further down (a map close to a shift):
  // fetch that row now. A map with a slope across rows walks the source diagonally in short
  // pieces, which the hardware prefetcher does not follow (20 MP, 2 % slope: 2x the time without).
  _mm_prefetch(reinterpret_cast<const char*>(p0 + (kThreeRows ? 3 : 2) * step), _MM_HINT_T0);
  // Each pixel's byte offset 3 dx, in every byte of its 32-bit lane.
  const __m128i offsets =
      _mm_mullo_epi32(_mm_add_epi32(dx, _mm_add_epi32(dx, dx)), _mm_set1_epi32(0x01010101));
  const __m128i mask = _mm_set1_epi32(kFracMask), one = _mm_set1_epi32(kFracOne);
  const __m128i fx = _mm_and_si128(vx, mask), fy = _mm_and_si128(vy, mask);
  const __m128i gx = _mm_sub_epi32(one, fx), gy = _mm_sub_epi32(one, fy);
  // (left | right << 16) weights of the top and the bottom row (products < 2^15).
  const __m128i w_top =
      _mm_or_si128(_mm_mullo_epi16(gx, gy), _mm_slli_epi32(_mm_mullo_epi16(fx, gy), 16));
  const __m128i w_bottom =
      _mm_or_si128(_mm_mullo_epi16(gx, fy), _mm_slli_epi32(_mm_mullo_epi16(fx, fy), 16));
  // Weights on rows 0, 1, 2: a pixel of the lower pair (dy = 1) reads rows 1 and 2.
  const __m128i lower = _mm_cmpeq_epi32(dy, _mm_set1_epi32(1));
  const __m128i w0 = kThreeRows ? _mm_andnot_si128(lower, w_top) : w_top;
  const __m128i w1 = kThreeRows ? _mm_blendv_epi8(w_bottom, w_top, lower) : w_bottom;
  const __m128i w2 = kThreeRows ? _mm_and_si128(lower, w_bottom) : w_bottom;
  const __m128i r =
      ChannelSum4(kThreeRows, row0, row1, row2,
                  _mm_add_epi8(_mm_setr_epi8(SHUTTERLAB_CHANNEL_CTRL(0)), offsets), w0, w1, w2);
  const __m128i g =
      ChannelSum4(kThreeRows, row0, row1, row2,
                  _mm_add_epi8(_mm_setr_epi8(SHUTTERLAB_CHANNEL_CTRL(1)), offsets), w0, w1, w2);
  const __m128i b =
      ChannelSum4(kThreeRows, row0, row1, row2,
                  _mm_add_epi8(_mm_setr_epi8(SHUTTERLAB_CHANNEL_CTRL(2)), offsets), w0, w1, w2);
  const __m128i planar = _mm_packus_epi16(_mm_packs_epi32(r, g), _mm_packs_epi32(b, b));
  const __m128i rgb = _mm_shuffle_epi8(planar, _mm_setr_epi8(SHUTTERLAB_INTERLEAVE));
  _mm_storel_epi64(reinterpret_cast<__m128i*>(out), rgb);
  const uint32_t last4 = static_cast<uint32_t>(_mm_cvtsi128_si32(_mm_srli_si128(rgb, 8)));
  std::memcpy(out + 8, &last4, 4);
  return true;
}

// True when none of four pixels has a tap inside the source (BilinearPixel's early black: the
// cell's top-left tap left of -1, above -1, right of width-1 or below height-1, or no source).
__attribute__((target("sse4.1"))) inline bool AllOutside4(const cv::Mat& src, const int* xi,
                                                          const int* yi) {
  const __m128i one = _mm_set1_epi32(1);
  // -1 <= ix < width as unsigned(ix + 1) < width + 1 (kInvalidFixed wraps far above).
  const __m128i x = _mm_add_epi32(
      _mm_srai_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(xi)), kSampleFracBits), one);
  const __m128i y = _mm_add_epi32(
      _mm_srai_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(yi)), kSampleFracBits), one);
  const __m128i x_in = _mm_cmpeq_epi32(_mm_min_epu32(x, _mm_set1_epi32(src.cols)), x);
  const __m128i y_in = _mm_cmpeq_epi32(_mm_min_epu32(y, _mm_set1_epi32(src.rows)), y);
  const __m128i inside = _mm_and_si128(x_in, y_in);
  return _mm_testz_si128(inside, inside);
}

__attribute__((target("sse4.1"))) void BilinearRow8uc3Sse41(const cv::Mat& src, const int* xi,
                                                            const int* yi, int width,
                                                            uint8_t* out) {
  const BlockSource source(src);
  if (!source.blocks_fit) return BilinearRow8uc3(src, xi, yi, width, out);
  int u = 0;
  for (; u + 4 <= width; u += 4) {
    if (Block4<false>(source, xi + u, yi + u, out + 3 * u)) continue;
    if (Block4<true>(source, xi + u, yi + u, out + 3 * u)) continue;
    if (AllOutside4(src, xi + u, yi + u)) {
      std::memset(out + 3 * u, 0, 12);
      continue;
    }
    BilinearRow8uc3(src, xi + u, yi + u, 4, out + 3 * u);
  }
  if (u < width) BilinearRow8uc3(src, xi + u, yi + u, width - u, out + 3 * u);
}

// Block8's constants, made once a row and hidden from constant folding (an empty asm that may
// change them): folded, GCC rebuilt each broadcast constant inside the loop from a general
// register, three instructions each, 12 of a block's 125.
struct WideConstants {
  __m256i three, one_row, frac_mask, frac_one, half;
  // Each 32-bit lane's low byte into both its 16-bit halves; the fraction and one in both halves.
  __m256i low_byte_twice, frac_mask_pair, frac_one_pair;
  __attribute__((target("avx2"))) WideConstants()
      : three(Opaque(_mm256_set1_epi32(3))),
        one_row(Opaque(_mm256_set1_epi32(1))),
        frac_mask(Opaque(_mm256_set1_epi32(kFracMask))),
        frac_one(Opaque(_mm256_set1_epi32(kFracOne))),
        half(Opaque(_mm256_set1_epi32(1 << (2 * kSampleFracBits - 1)))),
        low_byte_twice(Opaque(_mm256_setr_epi8(0, -128, 0, -128, 4, -128, 4, -128, 8, -128, 8, -128,
                                               12, -128, 12, -128, 0, -128, 0, -128, 4, -128, 4,
                                               -128, 8, -128, 8, -128, 12, -128, 12, -128))),
        frac_mask_pair(Opaque(_mm256_set1_epi32(kFracMask | kFracMask << 16))),
        frac_one_pair(Opaque(_mm256_set1_epi32(kFracOne | kFracOne << 16))) {}
  __attribute__((target("avx2"))) static __m256i Opaque(__m256i v) {
    asm("" : "+x"(v));
    return v;
  }
};

__attribute__((target("avx2"))) inline __m256i ChannelSum8(bool three_rows, __m256i row0,
                                                           __m256i row1, __m256i row2, __m256i ctrl,
                                                           __m256i w0, __m256i w1, __m256i w2,
                                                           __m256i half) {
  __m256i sum = _mm256_add_epi32(_mm256_madd_epi16(_mm256_shuffle_epi8(row0, ctrl), w0),
                                 _mm256_madd_epi16(_mm256_shuffle_epi8(row1, ctrl), w1));
  if (three_rows) {
    sum = _mm256_add_epi32(sum, _mm256_madd_epi16(_mm256_shuffle_epi8(row2, ctrl), w2));
  }
  return _mm256_srli_epi32(_mm256_add_epi32(sum, half), 2 * kSampleFracBits);
}

// Two source rows' 16 bytes, from p_low (first block) and p_high (second block), k rows down.
__attribute__((target("avx2"))) inline __m256i LoadRows(const uint8_t* p_low, const uint8_t* p_high,
                                                        size_t offset) {
  return _mm256_inserti128_si256(
      _mm256_castsi128_si256(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p_low + offset))),
      _mm_loadu_si128(reinterpret_cast<const __m128i*>(p_high + offset)), 1);
}

// Block4 for two blocks of four at once, one per 128-bit lane (AVX2 shuffles and packs stay in
// their lane, which is what the blocks need). False, writing nothing, when either does not fit.
// With spare_after, the 4 bytes after the block's 24 are the caller's to overwrite (pixels it
// writes later): two 16-byte stores then do the work of four.
template <bool kThreeRows>
__attribute__((target("avx2"))) inline bool Block8(const BlockSource& source,
                                                   const WideConstants& k, const int* xi,
                                                   const int* yi, bool spare_after, uint8_t* out) {
  const __m256i vx = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(xi));
  const __m256i vy = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(yi));
  const __m256i ix = _mm256_srai_epi32(vx, kSampleFracBits);
  const __m256i iy = _mm256_srai_epi32(vy, kSampleFracBits);
  __m256i low = _mm256_shuffle_epi32(iy, 0);
  if (kThreeRows) {
    low = _mm256_min_epi32(iy, _mm256_shuffle_epi32(iy, _MM_SHUFFLE(1, 0, 3, 2)));
    low = _mm256_min_epi32(low, _mm256_shuffle_epi32(low, _MM_SHUFFLE(2, 3, 0, 1)));
  }
  const __m256i dx = _mm256_sub_epi32(ix, _mm256_shuffle_epi32(ix, 0));
  const __m256i dy = _mm256_sub_epi32(iy, low);
  const __m256i misfit = kThreeRows ? _mm256_or_si256(_mm256_andnot_si256(k.three, dx),
                                                      _mm256_andnot_si256(k.one_row, dy))
                                    : _mm256_or_si256(_mm256_andnot_si256(k.three, dx), dy);
  // The blocks' first pixels from memory: a lane's extract costs two instructions.
  const int ix0 = xi[0] >> kSampleFracBits, ix4 = xi[4] >> kSampleFracBits;
  const int iy0 = kThreeRows ? _mm256_extract_epi32(low, 0) : yi[0] >> kSampleFracBits;
  const int iy4 = kThreeRows ? _mm256_extract_epi32(low, 4) : yi[4] >> kSampleFracBits;
  if (!_mm256_testz_si256(misfit, misfit) || !source.Inside(ix0, iy0) || !source.Inside(ix4, iy4) ||
      (kThreeRows && (!source.Inside(ix0, iy0 + 1) || !source.Inside(ix4, iy4 + 1)))) {
    return false;
  }
  const size_t step = source.step;
  const uint8_t* p0 = source.data + iy0 * step + ix0 * 3;
  const uint8_t* p4 = source.data + iy4 * step + ix4 * 3;
  const __m256i row0 = LoadRows(p0, p4, 0), row1 = LoadRows(p0, p4, step);
  const __m256i row2 = kThreeRows ? LoadRows(p0, p4, 2 * step) : row1;
  _mm_prefetch(reinterpret_cast<const char*>(p0 + (kThreeRows ? 3 : 2) * step), _MM_HINT_T0);
  _mm_prefetch(reinterpret_cast<const char*>(p4 + (kThreeRows ? 3 : 2) * step), _MM_HINT_T0);
  // 3 dx (0 to 9) in each byte of its lane: a byte shuffle, where a multiply by 0x01010101 takes
  // two instructions of ten cycles' latency.
  const __m256i offsets =
      _mm256_shuffle_epi8(_mm256_add_epi32(dx, _mm256_add_epi32(dx, dx)),
                          _mm256_setr_epi8(0, 0, 0, 0, 4, 4, 4, 4, 8, 8, 8, 8, 12, 12, 12, 12, 0, 0,
                                           0, 0, 4, 4, 4, 4, 8, 8, 8, 8, 12, 12, 12, 12));
  // Each row's (left, right) weights: x's pair (1 - fx, fx) times y's weight in both halves, one
  // 16-bit multiply a row (each product at most 128 x 128).
  const __m256i fx = _mm256_and_si256(vx, k.frac_mask);
  const __m256i x_pair =
      _mm256_or_si256(_mm256_sub_epi32(k.frac_one, fx), _mm256_slli_epi32(fx, 16));
  const __m256i fy_pair =
      _mm256_and_si256(_mm256_shuffle_epi8(vy, k.low_byte_twice), k.frac_mask_pair);
  const __m256i gy_pair = _mm256_sub_epi16(k.frac_one_pair, fy_pair);
  const __m256i w_top = _mm256_mullo_epi16(x_pair, gy_pair);
  const __m256i w_bottom = _mm256_mullo_epi16(x_pair, fy_pair);
  const __m256i lower = _mm256_cmpeq_epi32(dy, k.one_row);
  const __m256i w0 = kThreeRows ? _mm256_andnot_si256(lower, w_top) : w_top;
  const __m256i w1 = kThreeRows ? _mm256_blendv_epi8(w_bottom, w_top, lower) : w_bottom;
  const __m256i w2 = kThreeRows ? _mm256_and_si256(lower, w_bottom) : w_bottom;
  const __m256i r = ChannelSum8(
      kThreeRows, row0, row1, row2,
      _mm256_add_epi8(_mm256_setr_epi8(SHUTTERLAB_CHANNEL_CTRL(0), SHUTTERLAB_CHANNEL_CTRL(0)),
                      offsets),
      w0, w1, w2, k.half);
  const __m256i g = ChannelSum8(
      kThreeRows, row0, row1, row2,
      _mm256_add_epi8(_mm256_setr_epi8(SHUTTERLAB_CHANNEL_CTRL(1), SHUTTERLAB_CHANNEL_CTRL(1)),
                      offsets),
      w0, w1, w2, k.half);
  const __m256i b = ChannelSum8(
      kThreeRows, row0, row1, row2,
      _mm256_add_epi8(_mm256_setr_epi8(SHUTTERLAB_CHANNEL_CTRL(2), SHUTTERLAB_CHANNEL_CTRL(2)),
                      offsets),
      w0, w1, w2, k.half);
  const __m256i planar = _mm256_packus_epi16(_mm256_packs_epi32(r, g), _mm256_packs_epi32(b, b));
  const __m256i rgb =
      _mm256_shuffle_epi8(planar, _mm256_setr_epi8(SHUTTERLAB_INTERLEAVE, SHUTTERLAB_INTERLEAVE));
  const __m128i lo = _mm256_castsi256_si128(rgb), hi = _mm256_extracti128_si256(rgb, 1);
  if (spare_after) {  // each lane's 12 bytes, then 4 that the next store or the caller overwrites
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out), lo);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + 12), hi);
    return true;
  }
  _mm_storel_epi64(reinterpret_cast<__m128i*>(out), lo);
  const uint32_t lo4 = static_cast<uint32_t>(_mm_cvtsi128_si32(_mm_srli_si128(lo, 8)));
  std::memcpy(out + 8, &lo4, 4);
  _mm_storel_epi64(reinterpret_cast<__m128i*>(out + 12), hi);
  const uint32_t hi4 = static_cast<uint32_t>(_mm_cvtsi128_si32(_mm_srli_si128(hi, 8)));
  std::memcpy(out + 20, &hi4, 4);
  return true;
}

// Sixteen pixels a step (AVX-512 BW and VBMI) where their taps lie in one 64-byte span of each of
// two (or three) source rows: columns ix0 .. ix0 + 20 from the block's first pixel's, as a map
// close to a shift has them. One load a row holds every tap; VBMI's byte permute, free to take any
// of the 64 bytes, lines up each pixel's (left, right) taps of a channel as two 16-bit lanes of its
// 32-bit lane (zeroing the high bytes), and madd applies the row's weights, as in Block8. The
// channels are packed and interleaved by a second permute into 48 contiguous bytes. Same integer
// weights, sums and rounding as BilinearPixel: bit-identical.

// Block16's constants, made once a row and hidden from constant folding (as WideConstants).
struct Wide512Constants {
  __m512i one_row, frac_mask, frac_one, half, low_byte_twice, frac_mask_pair, frac_one_pair;
  __m512i three_twice;      // 3 in both 16-bit halves: a pixel's 3 dx at its left and right taps
  __m512i channel_ctrl[3];  // (c, c + 3) in the two 16-bit halves of every 32-bit lane
  // vpermb's index: the four 128-bit lanes' planar 12 bytes (R0 .. R3 G0 .. G3 B0 .. B3, as the
  // packs leave them) to 48 bytes of interleaved pixels, lane 0's first; bytes 48 to 63 repeat
  // output bytes 0 to 15 (a 64-byte store leaves them for later pixels to overwrite).
  __m512i interleave;
  __attribute__((target("avx512f,avx512bw,avx512vbmi"))) Wide512Constants()
      : one_row(Opaque(_mm512_set1_epi32(1))),
        frac_mask(Opaque(_mm512_set1_epi32(kFracMask))),
        frac_one(Opaque(_mm512_set1_epi32(kFracOne))),
        half(Opaque(_mm512_set1_epi32(1 << (2 * kSampleFracBits - 1)))),
        low_byte_twice(Opaque(_mm512_broadcast_i32x4(_mm_setr_epi8(
            0, -128, 0, -128, 4, -128, 4, -128, 8, -128, 8, -128, 12, -128, 12, -128)))),
        frac_mask_pair(Opaque(_mm512_set1_epi32(kFracMask | kFracMask << 16))),
        frac_one_pair(Opaque(_mm512_set1_epi32(kFracOne | kFracOne << 16))),
        three_twice(Opaque(_mm512_set1_epi32(3 | 3 << 16))),
        channel_ctrl{Opaque(_mm512_set1_epi32(0 | 3 << 16)), Opaque(_mm512_set1_epi32(1 | 4 << 16)),
                     Opaque(_mm512_set1_epi32(2 | 5 << 16))},
        interleave(Opaque(InterleaveIndex())) {}
  __attribute__((target("avx512f"))) static __m512i Opaque(__m512i v) {
    asm("" : "+v"(v));
    return v;
  }
  __attribute__((target("avx512f"))) static __m512i InterleaveIndex() {
    static constexpr uint8_t kWithinLane[16] = {SHUTTERLAB_INTERLEAVE};
    alignas(64) uint8_t index[64];
    for (int j = 0; j < 64; ++j) {
      index[j] = static_cast<uint8_t>(16 * (j % 48 / 12) + kWithinLane[j % 12]);
    }
    return _mm512_load_si512(index);
  }
};

// One channel's bilinear sums of sixteen pixels, rounded: each row's taps picked by `index` (the
// pixel's left tap in the low byte of its 32-bit lane, its right tap in the third, the other bytes
// zeroed) and weighed by the row's (left, right) weights.
__attribute__((target("avx512f,avx512bw,avx512vbmi"))) inline __m512i ChannelSum16(
    bool three_rows, __m512i row0, __m512i row1, __m512i row2, __m512i index, __m512i w0,
    __m512i w1, __m512i w2, __m512i half) {
  constexpr __mmask64 kLowBytes = 0x5555555555555555;
  __m512i sum = _mm512_add_epi32(
      _mm512_madd_epi16(_mm512_maskz_permutexvar_epi8(kLowBytes, index, row0), w0),
      _mm512_madd_epi16(_mm512_maskz_permutexvar_epi8(kLowBytes, index, row1), w1));
  if (three_rows) {
    sum = _mm512_add_epi32(
        sum, _mm512_madd_epi16(_mm512_maskz_permutexvar_epi8(kLowBytes, index, row2), w2));
  }
  return _mm512_srli_epi32(_mm512_add_epi32(sum, half), 2 * kSampleFracBits);
}

// Sixteen pixels whose taps lie in the 64 bytes from column ix0, the first pixel's left tap,
// of rows iy0 and iy0 + 1 (kThreeRows: rows low, low + 1 and low + 2, low the lowest pixel's row;
// each pixel's rows iy or iy + 1). False, writing nothing, where they do not, or those bytes leave
// the source's rows. With spare_after, the 16 bytes after the 48 are the caller's to overwrite:
// one 64-byte store.
template <bool kThreeRows>
__attribute__((target("avx512f,avx512bw,avx512vbmi"))) inline bool Block16(
    const uint8_t* data, size_t step, int max_ix0, int max_iy0, const Wide512Constants& k,
    const int* xi, const int* yi, bool spare_after, uint8_t* out) {
  const __m512i vx = _mm512_loadu_si512(xi);
  const __m512i vy = _mm512_loadu_si512(yi);
  const int ix0 = xi[0] >> kSampleFracBits, iy_first = yi[0] >> kSampleFracBits;
  // 0 <= dx <= 19: the right tap's last byte, 3 dx + 5, is byte 62 of the span at most.
  const __m512i dx =
      _mm512_sub_epi32(_mm512_srai_epi32(vx, kSampleFracBits), _mm512_set1_epi32(ix0));
  const __m512i iy = _mm512_srai_epi32(vy, kSampleFracBits);
  if (_mm512_cmpgt_epu32_mask(dx, _mm512_set1_epi32(19)) != 0) return false;
  int iy0 = iy_first;
  __m512i dy;
  if (kThreeRows) {
    // The lowest row is the first pixel's, or the one above it when any pixel reads higher.
    iy0 -= _mm512_cmplt_epi32_mask(iy, _mm512_set1_epi32(iy_first)) != 0;
    dy = _mm512_sub_epi32(iy, _mm512_set1_epi32(iy0));
    if (_mm512_cmpgt_epu32_mask(dy, k.one_row) != 0) return false;
  } else if (_mm512_cmpneq_epi32_mask(iy, _mm512_set1_epi32(iy_first)) != 0) {
    return false;
  }
  if (static_cast<unsigned>(ix0) > static_cast<unsigned>(max_ix0) || iy0 < 0 ||
      iy0 + (kThreeRows ? 1 : 0) > max_iy0) {
    return false;
  }
  const uint8_t* p0 = data + iy0 * step + ix0 * 3;
  const __m512i row0 = _mm512_loadu_si512(p0), row1 = _mm512_loadu_si512(p0 + step);
  const __m512i row2 = kThreeRows ? _mm512_loadu_si512(p0 + 2 * step) : row1;
  // The next output row reads these columns one source row further down (Block4).
  const char* next = reinterpret_cast<const char*>(p0 + (kThreeRows ? 3 : 2) * step);
  _mm_prefetch(next, _MM_HINT_T0);
  _mm_prefetch(next + 63, _MM_HINT_T0);
  const __m512i offsets = _mm512_mullo_epi32(dx, k.three_twice);
  const __m512i fx = _mm512_and_si512(vx, k.frac_mask);
  const __m512i x_pair =
      _mm512_or_si512(_mm512_sub_epi32(k.frac_one, fx), _mm512_slli_epi32(fx, 16));
  const __m512i fy_pair =
      _mm512_and_si512(_mm512_shuffle_epi8(vy, k.low_byte_twice), k.frac_mask_pair);
  const __m512i gy_pair = _mm512_sub_epi16(k.frac_one_pair, fy_pair);
  const __m512i w_top = _mm512_mullo_epi16(x_pair, gy_pair);
  const __m512i w_bottom = _mm512_mullo_epi16(x_pair, fy_pair);
  __m512i w0 = w_top, w1 = w_bottom, w2 = w_bottom;
  if (kThreeRows) {  // weights on rows 0, 1, 2: a pixel of the lower pair (dy = 1) reads rows 1, 2
    const __mmask16 lower = _mm512_cmpeq_epi32_mask(dy, k.one_row);
    w0 = _mm512_maskz_mov_epi32(_knot_mask16(lower), w_top);
    w1 = _mm512_mask_blend_epi32(lower, w_bottom, w_top);
    w2 = _mm512_maskz_mov_epi32(lower, w_bottom);
  }
  __m512i sums[3];
  for (int c = 0; c < 3; ++c) {
    sums[c] = ChannelSum16(kThreeRows, row0, row1, row2,
                           _mm512_add_epi8(offsets, k.channel_ctrl[c]), w0, w1, w2, k.half);
  }
  const __m512i planar = _mm512_packus_epi16(_mm512_packs_epi32(sums[0], sums[1]),
                                             _mm512_packs_epi32(sums[2], sums[2]));
  const __m512i rgb = _mm512_permutexvar_epi8(k.interleave, planar);
  if (spare_after) {
    _mm512_storeu_si512(out, rgb);
  } else {
    _mm512_mask_storeu_epi8(out, (__mmask64{1} << 48) - 1, rgb);
  }
  return true;
}
#undef SHUTTERLAB_CHANNEL_CTRL
#undef SHUTTERLAB_INTERLEAVE

__attribute__((target("avx2"))) void BilinearRow8uc3Avx2(const cv::Mat& src, const int* xi,
                                                         const int* yi, int width, uint8_t* out) {
  const BlockSource source(src);
  if (!source.blocks_fit) return BilinearRow8uc3(src, xi, yi, width, out);
  const WideConstants k;
  int u = 0;
  for (; u + 8 <= width; u += 8) {
    // Pixels u + 8 and u + 9, which a wide store's last 4 bytes cover, are written later.
    const bool spare_after = u + 10 <= width;
    if (Block8<false>(source, k, xi + u, yi + u, spare_after, out + 3 * u)) continue;
    if (Block8<true>(source, k, xi + u, yi + u, spare_after, out + 3 * u)) continue;
    BilinearRow8uc3Sse41(src, xi + u, yi + u, 8, out + 3 * u);
  }
  if (u < width) BilinearRow8uc3Sse41(src, xi + u, yi + u, width - u, out + 3 * u);
}

__attribute__((target("avx512f,avx512bw,avx512vbmi"))) void BilinearRow8uc3Avx512(
    const cv::Mat& src, const int* xi, const int* yi, int width, uint8_t* out) {
  // A block's 64-byte loads stay inside the source's rows when 3 ix0 + 64 <= 3 src.cols and
  // iy0 + 1 <= src.rows - 1: a source of fewer than 22 columns or 2 rows fits none.
  const int max_ix0 = src.cols - 22, max_iy0 = src.rows - 2;
  if (max_ix0 < 0 || max_iy0 < 0) return BilinearRow8uc3Avx2(src, xi, yi, width, out);
  const Wide512Constants k;
  int u = 0;
  for (; u + 16 <= width; u += 16) {
    // Pixels u + 16 to u + 21, which the 64-byte store's last 16 bytes cover, are written later.
    const bool spare_after = u + 22 <= width;
    if (Block16<false>(src.data, src.step, max_ix0, max_iy0, k, xi + u, yi + u, spare_after,
                       out + 3 * u)) {
      continue;
    }
    if (Block16<true>(src.data, src.step, max_ix0, max_iy0, k, xi + u, yi + u, spare_after,
                      out + 3 * u)) {
      continue;
    }
    BilinearRow8uc3Avx2(src, xi + u, yi + u, 16, out + 3 * u);
  }
  if (u < width) BilinearRow8uc3Avx2(src, xi + u, yi + u, width - u, out + 3 * u);
}

// The widest path this CPU runs.
SamplerPath WidestOnThisCpu() {
  static const SamplerPath path = __builtin_cpu_supports("avx512f") &&
                                          __builtin_cpu_supports("avx512bw") &&
                                          __builtin_cpu_supports("avx512vbmi")
                                      ? SamplerPath::kAvx512
                                  : __builtin_cpu_supports("avx2")   ? SamplerPath::kAvx2
                                  : __builtin_cpu_supports("sse4.1") ? SamplerPath::kSse41
                                                                     : SamplerPath::kOnePixel;
  return path;
}
#else
SamplerPath WidestOnThisCpu() { return SamplerPath::kOnePixel; }
#endif

// InsideMaskBits one pixel at a time.
void InsideMaskBitsScalar(const int* xi, const int* yi, int n, int width, int height,
                          uint8_t* bits) {
  std::memset(bits, 0, (n + 7) / 8);
  for (int k = 0; k < n; ++k) {
    if (TapsInside(xi[k], yi[k], width, height)) SetMaskBit(k, bits);
  }
}

#if defined(SHUTTERLAB_WIDE_SAMPLER)
__attribute__((target("avx2"))) void LinearFixedRowsAvx2(float ax, float bx, float ay, float by,
                                                         int n, int* x_out, int* y_out) {
  const __m256 vax = _mm256_set1_ps(ax), vbx = _mm256_set1_ps(bx);
  const __m256 vay = _mm256_set1_ps(ay), vby = _mm256_set1_ps(by);
  const __m256 eight = _mm256_set1_ps(8.0f);
  // Both lines in one loop: the count k's float add is a chain of one add a step, which the two
  // lines' work hides (each line in a loop of its own waited on it: 20 % slower).
  __m256 vk = _mm256_setr_ps(0, 1, 2, 3, 4, 5, 6, 7);
  int k = 0;
  for (; k + 8 <= n; k += 8, vk = _mm256_add_ps(vk, eight)) {
    // cvtps rounds to nearest (the default MXCSR mode), as cvRound does.
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(x_out + k),
                        _mm256_cvtps_epi32(_mm256_add_ps(vax, _mm256_mul_ps(vk, vbx))));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(y_out + k),
                        _mm256_cvtps_epi32(_mm256_add_ps(vay, _mm256_mul_ps(vk, vby))));
  }
  if (k < n) {
    // The last values by the same vector formula: a line's values must be one formula's, monotone
    // in k (CorrectionMap::SourceRowFixed bounds a piece by its ends), whether or not a compiler
    // fuses the scalar formula's multiply and add.
    alignas(32) int last[8];
    _mm256_store_si256(reinterpret_cast<__m256i*>(last),
                       _mm256_cvtps_epi32(_mm256_add_ps(vax, _mm256_mul_ps(vk, vbx))));
    std::memcpy(x_out + k, last, sizeof(int) * (n - k));
    _mm256_store_si256(reinterpret_cast<__m256i*>(last),
                       _mm256_cvtps_epi32(_mm256_add_ps(vay, _mm256_mul_ps(vk, vby))));
    std::memcpy(y_out + k, last, sizeof(int) * (n - k));
  }
}

// LinearFixedRowsAvx2 sixteen at a time, the last ones by a masked store. The product is kept
// apart from the sum (an empty asm): AVX-512 brings FMA, and a fused multiply-add would round once
// where the other paths round twice.
__attribute__((target("avx512f"))) inline __m512i LinePoints16(__m512 a, __m512 b, __m512 k) {
  __m512 kb = _mm512_mul_ps(k, b);
  asm("" : "+v"(kb));
  return _mm512_cvtps_epi32(_mm512_add_ps(a, kb));  // to nearest, as cvRound
}

__attribute__((target("avx512f"))) void LinearFixedRowsAvx512(float ax, float bx, float ay,
                                                              float by, int n, int* x_out,
                                                              int* y_out) {
  const __m512 vax = _mm512_set1_ps(ax), vbx = _mm512_set1_ps(bx);
  const __m512 vay = _mm512_set1_ps(ay), vby = _mm512_set1_ps(by);
  const __m512 sixteen = _mm512_set1_ps(16.0f);
  __m512 vk = _mm512_setr_ps(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  int k = 0;
  for (; k + 16 <= n; k += 16, vk = _mm512_add_ps(vk, sixteen)) {
    _mm512_storeu_si512(x_out + k, LinePoints16(vax, vbx, vk));
    _mm512_storeu_si512(y_out + k, LinePoints16(vay, vby, vk));
  }
  if (k < n) {
    const __mmask16 last = static_cast<__mmask16>((1u << (n - k)) - 1);
    _mm512_mask_storeu_epi32(x_out + k, last, LinePoints16(vax, vbx, vk));
    _mm512_mask_storeu_epi32(y_out + k, last, LinePoints16(vay, vby, vk));
  }
}

__attribute__((target("avx2"))) void InsideMaskBitsAvx2(const int* xi, const int* yi, int n,
                                                        int width, int height, uint8_t* bits) {
  const int max_x = (width - 1) << kSampleFracBits, max_y = (height - 1) << kSampleFracBits;
  const __m256i low = _mm256_set1_epi32(-1), high_x = _mm256_set1_epi32(max_x + 1),
                high_y = _mm256_set1_epi32(max_y + 1);
  const __m256i reversed = _mm256_setr_epi32(7, 6, 5, 4, 3, 2, 1, 0);
  int k = 0;
  for (; k + 8 <= n; k += 8) {
    const __m256i x = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(xi + k));
    const __m256i y = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(yi + k));
    // -1 < x < max + 1, all ones where inside; pixel k's sign bit to bit 7 (lanes reversed).
    const __m256i inside = _mm256_and_si256(
        _mm256_and_si256(_mm256_cmpgt_epi32(x, low), _mm256_cmpgt_epi32(high_x, x)),
        _mm256_and_si256(_mm256_cmpgt_epi32(y, low), _mm256_cmpgt_epi32(high_y, y)));
    bits[k / 8] = static_cast<uint8_t>(
        _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_permutevar8x32_epi32(inside, reversed))));
  }
  if (k < n) InsideMaskBitsScalar(xi + k, yi + k, n - k, width, height, bits + k / 8);
}
#endif

std::atomic<SamplerPath> sampler_path_cap{SamplerPath::kAvx512};

}  // namespace

int ToFixed(float x) {
  // NaN and anything beyond +-2^23 px is outside every image.
  return std::abs(x) < 8388608.0f ? cvRound(x * kFracOne) : kInvalidFixed;
}

SamplerPath WidestSamplerPath() {
  return std::min(WidestOnThisCpu(), sampler_path_cap.load(std::memory_order_relaxed));
}

SamplerPath CapSamplerPath(SamplerPath widest) { return sampler_path_cap.exchange(widest); }

void SampleRowFixed(const cv::Mat& src, const int* xi, const int* yi, int n, uchar* out) {
  const int cn = src.channels();
  if (src.depth() == CV_8U) {
    if (cn == 3) {
#if defined(SHUTTERLAB_WIDE_SAMPLER)
      switch (WidestSamplerPath()) {
        case SamplerPath::kAvx512:
          return BilinearRow8uc3Avx512(src, xi, yi, n, out);
        case SamplerPath::kAvx2:
          return BilinearRow8uc3Avx2(src, xi, yi, n, out);
        case SamplerPath::kSse41:
          return BilinearRow8uc3Sse41(src, xi, yi, n, out);
        case SamplerPath::kOnePixel:
          break;
      }
#endif
#if defined(__SSE2__)
      return BilinearRow8uc3(src, xi, yi, n, out);
#else
      return BilinearRowInt<uint8_t, 3>(src, xi, yi, n, cn, out);
#endif
    }
    if (cn == 1) return BilinearRowInt<uint8_t, 1>(src, xi, yi, n, cn, out);
    return BilinearRowInt<uint8_t, 0>(src, xi, yi, n, cn, out);
  }
  auto* out16 = reinterpret_cast<uint16_t*>(out);
  if (cn == 3) return BilinearRowInt<uint16_t, 3>(src, xi, yi, n, cn, out16);
  if (cn == 1) return BilinearRowInt<uint16_t, 1>(src, xi, yi, n, cn, out16);
  return BilinearRowInt<uint16_t, 0>(src, xi, yi, n, cn, out16);
}

void LinearFixedRows(float ax, float bx, float ay, float by, int n, int* x_out, int* y_out) {
#if defined(SHUTTERLAB_WIDE_SAMPLER)
  const SamplerPath widest = WidestSamplerPath();
  if (widest == SamplerPath::kAvx512) return LinearFixedRowsAvx512(ax, bx, ay, by, n, x_out, y_out);
  if (widest == SamplerPath::kAvx2) return LinearFixedRowsAvx2(ax, bx, ay, by, n, x_out, y_out);
#endif
  for (int k = 0; k < n; ++k) {
    x_out[k] = cvRound(ax + k * bx);
    y_out[k] = cvRound(ay + k * by);
  }
}

void InsideMaskBits(const int* xi, const int* yi, int n, int width, int height, uint8_t* bits) {
#if defined(SHUTTERLAB_WIDE_SAMPLER)
  if (WidestSamplerPath() >= SamplerPath::kAvx2)
    return InsideMaskBitsAvx2(xi, yi, n, width, height, bits);
#endif
  InsideMaskBitsScalar(xi, yi, n, width, height, bits);
}

void SampleRowFloat(const cv::Mat& src, const float* xs, const float* ys, int n,
                    Interpolation interpolation, uchar* out) {
  SampleRowFloatImpl(src, xs, ys, n, interpolation, out);
}

}  // namespace shutterlab
