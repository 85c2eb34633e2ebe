#include "render/warp_kernel.h"

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

void BilinearRowFloat(const cv::Mat& src, const float* xs, const float* ys, int width,
                      float* out) {
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
// neighbouring output pixels of a map close to a shift read from one source row pair and from
// columns ix0 .. ix0 + 4: one 16-byte load per row holds every tap. A byte shuffle then lines up,
// for each of the 12 outputs (4 pixels x 3 channels), its (left, right) taps as two 16-bit lanes,
// once from the top row and once from the bottom row, and madd applies the row's (left, right)
// weights and sums them. Same weights and rounding as BilinearPixel: bit-identical. A block whose
// taps do not fit (a row boundary inside it, a stretched map, the source's last columns or rows)
// takes the one-pixel path.
//
// Output j = 3 k + c (pixel k, channel c) sits in 32-bit lane j % 4 of register j / 4; its control
// bytes pick (left, right) = bytes (3 dx_k + c, 3 dx_k + 3 + c), zero-extended (0x80: zero; adding
// the pixel's offset keeps bit 7 set). Register r holds the outputs of pixels (0,0,0,1), (1,1,2,2),
// (2,3,3,3).
#define SHUTTERLAB_CTRL(a, b, c, d)                                                      \
  a, -128, a + 3, -128, b, -128, b + 3, -128, c, -128, c + 3, -128, d, -128, d + 3, -128
#define SHUTTERLAB_CTRL0 SHUTTERLAB_CTRL(0, 1, 2, 0)
#define SHUTTERLAB_CTRL1 SHUTTERLAB_CTRL(1, 2, 0, 1)
#define SHUTTERLAB_CTRL2 SHUTTERLAB_CTRL(2, 0, 1, 2)

// The block of 4 pixels at u: fits when 0 <= dx <= 3 and dy == 0 for every pixel and the loads
// stay inside the source (3 ix0 + 16 <= 3 width, iy0 + 1 <= height - 1).
struct BlockLimits {
  unsigned max_ix0, max_iy0;
  explicit BlockLimits(const cv::Mat& src)
      : max_ix0(static_cast<unsigned>(std::max(-1, src.cols - 6))),
        max_iy0(static_cast<unsigned>(std::max(-1, src.rows - 2))) {}
  bool Inside(int ix0, int iy0) const {
    return static_cast<unsigned>(ix0) <= max_ix0 && static_cast<unsigned>(iy0) <= max_iy0;
  }
};

__attribute__((target("sse4.1"))) void BilinearRow8uc3Sse41(const cv::Mat& src, const int* xi,
                                                            const int* yi, int width,
                                                            uint8_t* out) {
  const uint8_t* base = src.data;
  const size_t step = src.step;
  const BlockLimits limits(src);
  const __m128i ctrl0 = _mm_setr_epi8(SHUTTERLAB_CTRL0), ctrl1 = _mm_setr_epi8(SHUTTERLAB_CTRL1),
                ctrl2 = _mm_setr_epi8(SHUTTERLAB_CTRL2);
  const __m128i mask = _mm_set1_epi32(kFracMask), one = _mm_set1_epi32(kFracOne);
  const __m128i three = _mm_set1_epi32(3), bytes = _mm_set1_epi32(0x01010101);
  const __m128i round = _mm_set1_epi32(1 << (2 * kSampleFracBits - 1));
  int u = 0;
  for (; u + 4 <= width; u += 4) {
    const __m128i vx = _mm_loadu_si128(reinterpret_cast<const __m128i*>(xi + u));
    const __m128i vy = _mm_loadu_si128(reinterpret_cast<const __m128i*>(yi + u));
    const __m128i ix = _mm_srai_epi32(vx, kSampleFracBits);
    const __m128i iy = _mm_srai_epi32(vy, kSampleFracBits);
    const int ix0 = _mm_cvtsi128_si32(ix), iy0 = _mm_cvtsi128_si32(iy);
    const __m128i dx = _mm_sub_epi32(ix, _mm_shuffle_epi32(ix, 0));
    const __m128i dy = _mm_sub_epi32(iy, _mm_shuffle_epi32(iy, 0));
    const __m128i misfit = _mm_or_si128(_mm_andnot_si128(three, dx), dy);
    if (!_mm_testz_si128(misfit, misfit) || !limits.Inside(ix0, iy0)) {
      BilinearRow8uc3(src, xi + u, yi + u, 4, out + 3 * u);
      continue;
    }
    const uint8_t* p0 = base + iy0 * step + ix0 * 3;
    const __m128i top = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p0));
    const __m128i bottom = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p0 + step));
    // Each pixel's byte offset 3 dx, repeated in the four bytes of its 32-bit lane.
    const __m128i offsets = _mm_mullo_epi32(_mm_add_epi32(dx, _mm_add_epi32(dx, dx)), bytes);
    const __m128i fx = _mm_and_si128(vx, mask), fy = _mm_and_si128(vy, mask);
    const __m128i gx = _mm_sub_epi32(one, fx), gy = _mm_sub_epi32(one, fy);
    // (left | right << 16) weights of the top and the bottom row, per pixel (products < 2^15).
    const __m128i w_top =
        _mm_or_si128(_mm_mullo_epi16(gx, gy), _mm_slli_epi32(_mm_mullo_epi16(fx, gy), 16));
    const __m128i w_bottom =
        _mm_or_si128(_mm_mullo_epi16(gx, fy), _mm_slli_epi32(_mm_mullo_epi16(fx, fy), 16));
#define SHUTTERLAB_SUM(ctrl, lanes)                                                           \
  _mm_srli_epi32(                                                                             \
      _mm_add_epi32(                                                                          \
          _mm_add_epi32(                                                                      \
              _mm_madd_epi16(                                                                 \
                  _mm_shuffle_epi8(top, _mm_add_epi8(ctrl, _mm_shuffle_epi32(offsets, lanes))), \
                  _mm_shuffle_epi32(w_top, lanes)),                                           \
              _mm_madd_epi16(_mm_shuffle_epi8(                                                \
                                 bottom, _mm_add_epi8(ctrl, _mm_shuffle_epi32(offsets, lanes))), \
                             _mm_shuffle_epi32(w_bottom, lanes))),                            \
          round),                                                                             \
      2 * kSampleFracBits)
    const __m128i r0 = SHUTTERLAB_SUM(ctrl0, _MM_SHUFFLE(1, 0, 0, 0));
    const __m128i r1 = SHUTTERLAB_SUM(ctrl1, _MM_SHUFFLE(2, 2, 1, 1));
    const __m128i r2 = SHUTTERLAB_SUM(ctrl2, _MM_SHUFFLE(3, 3, 3, 2));
#undef SHUTTERLAB_SUM
    const __m128i packed = _mm_packus_epi16(_mm_packs_epi32(r0, r1), _mm_packs_epi32(r2, r2));
    _mm_storel_epi64(reinterpret_cast<__m128i*>(out + 3 * u), packed);
    const uint32_t last4 = static_cast<uint32_t>(_mm_cvtsi128_si32(_mm_srli_si128(packed, 8)));
    std::memcpy(out + 3 * u + 8, &last4, 4);
  }
  if (u < width) BilinearRow8uc3(src, xi + u, yi + u, width - u, out + 3 * u);
}

// The same, two blocks of four at a time, one per 128-bit lane (AVX2 shuffles and packs stay in
// their lane, which is what the blocks need).
__attribute__((target("avx2"))) void BilinearRow8uc3Avx2(const cv::Mat& src, const int* xi,
                                                         const int* yi, int width, uint8_t* out) {
  const uint8_t* base = src.data;
  const size_t step = src.step;
  const BlockLimits limits(src);
  const __m256i ctrl0 = _mm256_setr_epi8(SHUTTERLAB_CTRL0, SHUTTERLAB_CTRL0),
                ctrl1 = _mm256_setr_epi8(SHUTTERLAB_CTRL1, SHUTTERLAB_CTRL1),
                ctrl2 = _mm256_setr_epi8(SHUTTERLAB_CTRL2, SHUTTERLAB_CTRL2);
  const __m256i mask = _mm256_set1_epi32(kFracMask), one = _mm256_set1_epi32(kFracOne);
  const __m256i three = _mm256_set1_epi32(3), bytes = _mm256_set1_epi32(0x01010101);
  const __m256i round = _mm256_set1_epi32(1 << (2 * kSampleFracBits - 1));
  int u = 0;
  for (; u + 8 <= width; u += 8) {
    const __m256i vx = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(xi + u));
    const __m256i vy = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(yi + u));
    const __m256i ix = _mm256_srai_epi32(vx, kSampleFracBits);
    const __m256i iy = _mm256_srai_epi32(vy, kSampleFracBits);
    const int ix0 = _mm256_extract_epi32(ix, 0), iy0 = _mm256_extract_epi32(iy, 0);
    const int ix4 = _mm256_extract_epi32(ix, 4), iy4 = _mm256_extract_epi32(iy, 4);
    const __m256i dx = _mm256_sub_epi32(ix, _mm256_shuffle_epi32(ix, 0));
    const __m256i dy = _mm256_sub_epi32(iy, _mm256_shuffle_epi32(iy, 0));
    const __m256i misfit = _mm256_or_si256(_mm256_andnot_si256(three, dx), dy);
    if (!_mm256_testz_si256(misfit, misfit) || !limits.Inside(ix0, iy0) ||
        !limits.Inside(ix4, iy4)) {
      BilinearRow8uc3Sse41(src, xi + u, yi + u, 8, out + 3 * u);
      continue;
    }
    const uint8_t* p0 = base + iy0 * step + ix0 * 3;
    const uint8_t* p4 = base + iy4 * step + ix4 * 3;
    const __m256i top = _mm256_inserti128_si256(
        _mm256_castsi128_si256(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p0))),
        _mm_loadu_si128(reinterpret_cast<const __m128i*>(p4)), 1);
    const __m256i bottom = _mm256_inserti128_si256(
        _mm256_castsi128_si256(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p0 + step))),
        _mm_loadu_si128(reinterpret_cast<const __m128i*>(p4 + step)), 1);
    const __m256i offsets =
        _mm256_mullo_epi32(_mm256_add_epi32(dx, _mm256_add_epi32(dx, dx)), bytes);
    const __m256i fx = _mm256_and_si256(vx, mask), fy = _mm256_and_si256(vy, mask);
    const __m256i gx = _mm256_sub_epi32(one, fx), gy = _mm256_sub_epi32(one, fy);
    const __m256i w_top = _mm256_or_si256(_mm256_mullo_epi16(gx, gy),
                                          _mm256_slli_epi32(_mm256_mullo_epi16(fx, gy), 16));
    const __m256i w_bottom = _mm256_or_si256(_mm256_mullo_epi16(gx, fy),
                                             _mm256_slli_epi32(_mm256_mullo_epi16(fx, fy), 16));
#define SHUTTERLAB_SUM(ctrl, lanes)                                                              \
  _mm256_srli_epi32(                                                                             \
      _mm256_add_epi32(                                                                          \
          _mm256_add_epi32(                                                                      \
              _mm256_madd_epi16(_mm256_shuffle_epi8(top, _mm256_add_epi8(                        \
                                                             ctrl, _mm256_shuffle_epi32(offsets, lanes))), \
                                _mm256_shuffle_epi32(w_top, lanes)),                             \
              _mm256_madd_epi16(_mm256_shuffle_epi8(bottom, _mm256_add_epi8(                     \
                                                                ctrl, _mm256_shuffle_epi32(offsets, lanes))), \
                                _mm256_shuffle_epi32(w_bottom, lanes))),                         \
          round),                                                                                \
      2 * kSampleFracBits)
    const __m256i r0 = SHUTTERLAB_SUM(ctrl0, _MM_SHUFFLE(1, 0, 0, 0));
    const __m256i r1 = SHUTTERLAB_SUM(ctrl1, _MM_SHUFFLE(2, 2, 1, 1));
    const __m256i r2 = SHUTTERLAB_SUM(ctrl2, _MM_SHUFFLE(3, 3, 3, 2));
#undef SHUTTERLAB_SUM
    // Per lane: the block's 12 output bytes first.
    const __m256i packed =
        _mm256_packus_epi16(_mm256_packs_epi32(r0, r1), _mm256_packs_epi32(r2, r2));
    const __m128i lo = _mm256_castsi256_si128(packed), hi = _mm256_extracti128_si256(packed, 1);
    _mm_storel_epi64(reinterpret_cast<__m128i*>(out + 3 * u), lo);
    const uint32_t lo4 = static_cast<uint32_t>(_mm_cvtsi128_si32(_mm_srli_si128(lo, 8)));
    std::memcpy(out + 3 * u + 8, &lo4, 4);
    _mm_storel_epi64(reinterpret_cast<__m128i*>(out + 3 * u + 12), hi);
    const uint32_t hi4 = static_cast<uint32_t>(_mm_cvtsi128_si32(_mm_srli_si128(hi, 8)));
    std::memcpy(out + 3 * u + 20, &hi4, 4);
  }
  if (u < width) BilinearRow8uc3Sse41(src, xi + u, yi + u, width - u, out + 3 * u);
}
#undef SHUTTERLAB_CTRL
#undef SHUTTERLAB_CTRL0
#undef SHUTTERLAB_CTRL1
#undef SHUTTERLAB_CTRL2

// Which wide path this CPU runs: 2 AVX2, 1 SSE4.1, 0 none.
int WideLevel() {
  static const int level = __builtin_cpu_supports("avx2") ? 2 : __builtin_cpu_supports("sse4.1") ? 1 : 0;
  return level;
}
#endif

std::atomic<bool> wide_sampler_enabled{true};

}  // namespace

int ToFixed(float x) {
  // NaN and anything beyond +-2^23 px is outside every image.
  return std::abs(x) < 8388608.0f ? cvRound(x * kFracOne) : kInvalidFixed;
}

bool WideSamplerAvailable() {
#if defined(SHUTTERLAB_WIDE_SAMPLER)
  return WideLevel() > 0 && wide_sampler_enabled.load(std::memory_order_relaxed);
#else
  return false;
#endif
}

bool SetWideSampler(bool enabled) { return wide_sampler_enabled.exchange(enabled); }

void SampleRowFixed(const cv::Mat& src, const int* xi, const int* yi, int n, uchar* out) {
  const int cn = src.channels();
  if (src.depth() == CV_8U) {
    if (cn == 3) {
#if defined(SHUTTERLAB_WIDE_SAMPLER)
      if (WideSamplerAvailable()) {
        return WideLevel() == 2 ? BilinearRow8uc3Avx2(src, xi, yi, n, out)
                                : BilinearRow8uc3Sse41(src, xi, yi, n, out);
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

void SampleRowFloat(const cv::Mat& src, const float* xs, const float* ys, int n,
                    Interpolation interpolation, uchar* out) {
  SampleRowFloatImpl(src, xs, ys, n, interpolation, out);
}

}  // namespace shutterlab
