#include "render/rs_warp.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "sim/check.h"

#include <opencv2/imgproc.hpp>

namespace shutterlab {
namespace {

// Fixed-point bilinear sampling for integer images: coordinates in 1/128 px (7 fractional bits per
// axis), so a weight product is at most 2^14: it fits the signed 16-bit lanes of _mm_madd_epi16,
// and a 16-bit sample times 2^14 fits in uint32. Quantisation error <= 1/256 px per axis.
constexpr int kFracBits = 7;
constexpr int kFracOne = 1 << kFracBits;
constexpr int kFracMask = kFracOne - 1;
// Marks a pixel whose ray misses the ground: far outside any scene, so it samples black.
constexpr int kInvalidFixed = std::numeric_limits<int>::min();

}  // namespace

FrameGeometry::FrameGeometry(const PinholeCamera& camera, double altitude_m,
                             const FrameMotion& motion, cv::Size scene_size)
    : camera_(camera), altitude_m_(altitude_m), motion_(motion) {
  SHUTTERLAB_CHECK(static_cast<int>(motion.world_from_cam.size()) == camera.height &&
                   static_cast<int>(motion.cam_center_m.size()) == camera.height)
      << "frame motion has " << motion.world_from_cam.size() << " rows, the camera "
      << camera.height;
  SHUTTERLAB_CHECK(altitude_m > 0) << "altitude must be positive";
  SHUTTERLAB_CHECK(scene_size.width > 0 && scene_size.height > 0) << "empty scene";
  scene_k_ << camera.fx, 0, (scene_size.width - 1) / 2.0, 0, camera.fy,
      (scene_size.height - 1) / 2.0, 0, 0, 1;
  inv_k_ = camera.K().inverse();
  rotation_only_ = !camera.HasDistortion() && !motion.HasTranslation();
}

Eigen::Matrix3d FrameGeometry::SceneFromImageHomography(int v) const {
  return scene_k_ * motion_.world_from_cam[v] * inv_k_;
}

std::optional<Eigen::Vector3d> FrameGeometry::GroundPoint(double u, int v) const {
  const Eigen::Vector3d ray_w =
      motion_.world_from_cam[v] * camera_.CamFromImg(Eigen::Vector2d(u, v));
  const Eigen::Vector3d& c = motion_.cam_center_m[v];
  const double s = (altitude_m_ - c.z()) / ray_w.z();
  if (!(s > 0) || !std::isfinite(s)) return std::nullopt;
  return c + s * ray_w;
}

std::optional<Eigen::Vector2d> FrameGeometry::ScenePixel(double u, int v) const {
  const std::optional<Eigen::Vector3d> x = GroundPoint(u, v);
  if (!x) return std::nullopt;
  return Eigen::Vector2d(scene_k_(0, 0) * x->x() / altitude_m_ + scene_k_(0, 2),
                         scene_k_(1, 1) * x->y() / altitude_m_ + scene_k_(1, 2));
}

std::optional<Eigen::Vector2d> FrameGeometry::RefPixel(double u, int v) const {
  const std::optional<Eigen::Vector3d> x = GroundPoint(u, v);
  if (!x) return std::nullopt;
  return camera_.ImgFromCam(motion_.world_from_ref.transpose() * (*x - motion_.ref_center_m));
}

void FrameGeometry::SceneRow(int v, float* xs, float* ys) const {
  const int width = camera_.width;
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  if (rotation_only_) {
    // (a + u b) / (a_z + u b_z): the row's homography, direct in u (nothing accumulates).
    const Eigen::Matrix3d h = SceneFromImageHomography(v);
    const Eigen::Vector3d a = h.col(1) * v + h.col(2);
    const Eigen::Vector3d b = h.col(0);
    // float: ~1e-4 px rounding on a 5000 px scene, far below the 1/256 px sampling grid.
    const float ax = static_cast<float>(a.x()), ay = static_cast<float>(a.y()),
                az = static_cast<float>(a.z());
    const float bx = static_cast<float>(b.x()), by = static_cast<float>(b.y()),
                bz = static_cast<float>(b.z());
    for (int u = 0; u < width; ++u) {
      const float w = az + u * bz;
      const float inv = w > 0 ? 1.0f / w : kNaN;
      xs[u] = (ax + u * bx) * inv;
      ys[u] = (ay + u * by) * inv;
    }
    return;
  }
  for (int u = 0; u < width; ++u) {
    const std::optional<Eigen::Vector2d> s = ScenePixel(u, v);
    xs[u] = s ? static_cast<float>(s->x()) : kNaN;
    ys[u] = s ? static_cast<float>(s->y()) : kNaN;
  }
}

bool FrameGeometry::SceneRowFixed(int v, int frac_bits, int* xi, int* yi, int u_begin,
                                  int count) const {
  if (!rotation_only_) return false;
  if (count < 0) count = camera_.width - u_begin;
  SHUTTERLAB_CHECK(u_begin >= 0 && u_begin + count <= camera_.width) << "columns outside the image";
  const Eigen::Matrix3d h = SceneFromImageHomography(v);
  // Origin moved to column u_begin, so that u below runs from 0.
  const Eigen::Vector3d a = h.col(0) * u_begin + h.col(1) * v + h.col(2);
  const Eigen::Vector3d b = h.col(0);
  const int width = count;
  // The denominator a_z + u b_z is linear in u: positive at both ends means positive on the span
  // (otherwise part of it looks above the horizon: leave it to the NaN-aware float path).
  if (!(a.z() > 0 && a.z() + (width - 1) * b.z() > 0)) return false;
  const float one = static_cast<float>(1 << frac_bits);
  const float ax = static_cast<float>(a.x()) * one, ay = static_cast<float>(a.y()) * one;
  const float bx = static_cast<float>(b.x()) * one, by = static_cast<float>(b.y()) * one;
  const float az = static_cast<float>(a.z()), bz = static_cast<float>(b.z());
  // Fixed-point coordinates beyond 2^30 would overflow int: such rows see nothing of any scene.
  constexpr float kLimit = 1073741824.0f;
  int u = 0;
#if defined(__SSE2__)
  const __m128 vax = _mm_set1_ps(ax), vay = _mm_set1_ps(ay), vbx = _mm_set1_ps(bx),
               vby = _mm_set1_ps(by);
  const __m128 vaz = _mm_set1_ps(az), vbz = _mm_set1_ps(bz), limit = _mm_set1_ps(kLimit);
  const __m128 abs_mask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
  __m128 vu = _mm_setr_ps(0.0f, 1.0f, 2.0f, 3.0f);
  const __m128 four = _mm_set1_ps(4.0f);
  for (; u + 4 <= width; u += 4, vu = _mm_add_ps(vu, four)) {
    const __m128 inv = _mm_div_ps(_mm_set1_ps(1.0f), _mm_add_ps(vaz, _mm_mul_ps(vu, vbz)));
    const __m128 x = _mm_mul_ps(_mm_add_ps(vax, _mm_mul_ps(vu, vbx)), inv);
    const __m128 y = _mm_mul_ps(_mm_add_ps(vay, _mm_mul_ps(vu, vby)), inv);
    // cvtps rounds to nearest (the default MXCSR mode), as cvRound does.
    __m128i ix = _mm_cvtps_epi32(x), iy = _mm_cvtps_epi32(y);
    const __m128i far = _mm_castps_si128(_mm_or_ps(_mm_cmpge_ps(_mm_and_ps(x, abs_mask), limit),
                                                   _mm_cmpge_ps(_mm_and_ps(y, abs_mask), limit)));
    const __m128i invalid = _mm_set1_epi32(kInvalidFixed);
    ix = _mm_or_si128(_mm_andnot_si128(far, ix), _mm_and_si128(far, invalid));
    iy = _mm_or_si128(_mm_andnot_si128(far, iy), _mm_and_si128(far, invalid));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(xi + u), ix);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(yi + u), iy);
  }
#endif
  for (; u < width; ++u) {
    const float inv = 1.0f / (az + u * bz);
    const float x = (ax + u * bx) * inv, y = (ay + u * by) * inv;
    const bool far = !(std::abs(x) < kLimit && std::abs(y) < kLimit);
    xi[u] = far ? kInvalidFixed : cvRound(x);
    yi[u] = far ? kInvalidFixed : cvRound(y);
  }
  return true;
}

namespace {

inline int ToFixed(float x) {
  // NaN and anything beyond +-2^23 px is outside every scene.
  return std::abs(x) < 8388608.0f ? cvRound(x * kFracOne) : kInvalidFixed;
}

template <typename T>
inline T RoundFixed(uint32_t acc) {
  return static_cast<T>((acc + (1u << (2 * kFracBits - 1))) >> (2 * kFracBits));
}

// Scalar bilinear sample of one pixel at fixed-point (xi, yi); taps outside the scene read as 0.
template <typename T>
inline void BilinearPixel(const T* base, size_t step, int sw, int sh, int cn, int xi, int yi,
                          T* out) {
  const int ix = xi >> kFracBits, iy = yi >> kFracBits;  // arithmetic shift: floor
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
void BilinearRowInt(const cv::Mat& scene, const int* xi, const int* yi, int width, int cn_runtime,
                    T* out) {
  const int cn = kCn > 0 ? kCn : cn_runtime;
  const T* base = scene.ptr<T>();
  for (int u = 0; u < width; ++u)
    BilinearPixel(base, scene.step1(), scene.cols, scene.rows, cn, xi[u], yi[u], out + u * cn);
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

void BilinearRow8uc3(const cv::Mat& scene, const int* xi, const int* yi, int width, uint8_t* out) {
  const int sw = scene.cols, sh = scene.rows;
  const size_t step = scene.step;
  const uint8_t* base = scene.data;
  const __m128i zero = _mm_setzero_si128();
  const __m128i round = _mm_set1_epi32(1 << (2 * kFracBits - 1));
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
      const int ix = xi[u] >> kFracBits, iy = yi[u] >> kFracBits;
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
      sum = _mm_srli_epi32(_mm_add_epi32(sum, round), 2 * kFracBits);
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

void BilinearRowFloat(const cv::Mat& scene, const float* xs, const float* ys, int width,
                      float* out) {
  const int cn = scene.channels();
  const int sw = scene.cols, sh = scene.rows;
  const size_t step = scene.step1();
  const float* base = scene.ptr<float>();
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
void BicubicRow(const cv::Mat& scene, const float* xs, const float* ys, int width, T* out) {
  const int cn = scene.channels();
  const int sw = scene.cols, sh = scene.rows;
  const size_t step = scene.step1();
  const T* base = scene.ptr<T>();
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
void SampleRowFloat(const cv::Mat& scene, const float* xs, const float* ys, int width,
                    Interpolation interpolation, uchar* out) {
  const int depth = scene.depth();
  if (interpolation == Interpolation::kBicubic) {
    if (depth == CV_8U) return BicubicRow<uint8_t>(scene, xs, ys, width, out);
    if (depth == CV_16U)
      return BicubicRow<uint16_t>(scene, xs, ys, width, reinterpret_cast<uint16_t*>(out));
    return BicubicRow<float>(scene, xs, ys, width, reinterpret_cast<float*>(out));
  }
  BilinearRowFloat(scene, xs, ys, width, reinterpret_cast<float*>(out));
}

// Fixed-point rows: bilinear for 8- and 16-bit images.
void SampleRowFixed(const cv::Mat& scene, const int* xi, const int* yi, int width, uchar* out) {
  const int cn = scene.channels();
  if (scene.depth() == CV_8U) {
#if defined(__SSE2__)
    if (cn == 3) return BilinearRow8uc3(scene, xi, yi, width, out);
#else
    if (cn == 3) return BilinearRowInt<uint8_t, 3>(scene, xi, yi, width, cn, out);
#endif
    if (cn == 1) return BilinearRowInt<uint8_t, 1>(scene, xi, yi, width, cn, out);
    return BilinearRowInt<uint8_t, 0>(scene, xi, yi, width, cn, out);
  }
  auto* out16 = reinterpret_cast<uint16_t*>(out);
  if (cn == 3) return BilinearRowInt<uint16_t, 3>(scene, xi, yi, width, cn, out16);
  if (cn == 1) return BilinearRowInt<uint16_t, 1>(scene, xi, yi, width, cn, out16);
  return BilinearRowInt<uint16_t, 0>(scene, xi, yi, width, cn, out16);
}

}  // namespace

void RenderFrame(const cv::Mat& scene, const FrameGeometry& geometry, Interpolation interpolation,
                 cv::Mat* out) {
  SHUTTERLAB_CHECK(!scene.empty()) << "empty scene";
  const int depth = scene.depth();
  SHUTTERLAB_CHECK(depth == CV_8U || depth == CV_16U || depth == CV_32F)
      << "scene must be 8U, 16U or 32F";
  SHUTTERLAB_CHECK(scene.channels() <= 4) << "scene has more than 4 channels";
  const int width = geometry.camera().width, height = geometry.camera().height;
  out->create(height, width, scene.type());
  const bool fixed = interpolation == Interpolation::kBilinear && depth != CV_32F;
  constexpr int kChunk = 512;  // columns per pass: 4 KiB of coordinates
  cv::parallel_for_(cv::Range(0, height), [&](const cv::Range& rows) {
    // Per-range row buffers: a few KiB, no full-size map.
    std::vector<float> xs(width), ys(width);
    std::vector<int> xi(kChunk), yi(kChunk);
    for (int v = rows.start; v < rows.end; ++v) {
      if (!fixed) {
        geometry.SceneRow(v, xs.data(), ys.data());
        SampleRowFloat(scene, xs.data(), ys.data(), width, interpolation, out->ptr(v));
        continue;
      }
      // Column chunks keep the coordinate buffers in L1 between the two passes.
      bool have_floats = false;
      for (int u0 = 0; u0 < width; u0 += kChunk) {
        const int n = std::min(kChunk, width - u0);
        if (!geometry.SceneRowFixed(v, kFracBits, xi.data(), yi.data(), u0, n)) {
          if (!have_floats) geometry.SceneRow(v, xs.data(), ys.data());
          have_floats = true;
          for (int u = 0; u < n; ++u) {
            xi[u] = ToFixed(xs[u0 + u]);
            yi[u] = ToFixed(ys[u0 + u]);
          }
        }
        SampleRowFixed(scene, xi.data(), yi.data(), n, out->ptr(v) + u0 * out->elemSize());
      }
    }
  });
}

cv::Mat DisplacementField(const FrameGeometry& geometry) {
  const int width = geometry.camera().width, height = geometry.camera().height;
  cv::Mat field(height, width, CV_32FC2);
  cv::parallel_for_(cv::Range(0, height), [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      auto* d = field.ptr<cv::Vec2f>(v);
      for (int u = 0; u < width; ++u) {
        const std::optional<Eigen::Vector2d> ref = geometry.RefPixel(u, v);
        d[u] = ref ? cv::Vec2f(static_cast<float>(ref->x() - u), static_cast<float>(ref->y() - v))
                   : cv::Vec2f(std::numeric_limits<float>::quiet_NaN(),
                               std::numeric_limits<float>::quiet_NaN());
      }
    }
  });
  return field;
}

std::optional<Eigen::Vector2d> VideoMatch(const FrameGeometry& later, const FrameGeometry& earlier,
                                          double u, int v) {
  const std::optional<Eigen::Vector3d> x = later.GroundPoint(u, v);
  if (!x) return std::nullopt;
  const PinholeCamera& camera = earlier.camera();
  const FrameMotion& motion = earlier.motion();
  const double last_row = camera.height - 1;
  // The match's row moves by (image rate x row time) per row of w: a contraction far below 1 for
  // any camera that stays sharp, so plain iteration from the point's own row converges quickly.
  constexpr int kMaxIterations = 100;
  double w = std::clamp(static_cast<double>(v), 0.0, last_row);
  for (int it = 0; it < kMaxIterations; ++it) {
    const std::optional<Eigen::Vector2d> q = camera.ImgFromCam(
        motion.WorldFromCamAtRow(w).transpose() * (*x - motion.CamCenterAtRow(w)));
    if (!q || !q->allFinite()) return std::nullopt;
    const double next = std::clamp(q->y(), 0.0, last_row);
    if (std::abs(next - w) <= kVideoMatchTolPx) {
      // A clamped row means the match lies above or below the earlier frame (beyond rounding).
      if (q->y() < -kVideoMatchTolPx || q->y() > last_row + kVideoMatchTolPx) return std::nullopt;
      return q;
    }
    w = next;
  }
  return std::nullopt;
}

cv::Mat VideoDisplacementField(const FrameGeometry& later, const FrameGeometry& earlier) {
  SHUTTERLAB_CHECK(later.camera().width == earlier.camera().width &&
                   later.camera().height == earlier.camera().height)
      << "video pair: frames of different sizes";
  const int width = later.camera().width, height = later.camera().height;
  cv::Mat field(height, width, CV_32FC2);
  cv::parallel_for_(cv::Range(0, height), [&](const cv::Range& rows) {
    constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
    for (int v = rows.start; v < rows.end; ++v) {
      auto* d = field.ptr<cv::Vec2f>(v);
      for (int u = 0; u < width; ++u) {
        const std::optional<Eigen::Vector2d> q = VideoMatch(later, earlier, u, v);
        d[u] = q ? cv::Vec2f(static_cast<float>(q->x() - u), static_cast<float>(q->y() - v))
                 : cv::Vec2f(kNaN, kNaN);
      }
    }
  });
  return field;
}

namespace {

double ConvexPolygonDiameter(const std::vector<cv::Point2f>& hull) {
  const size_t n = hull.size();
  auto dist2 = [&](size_t a, size_t b) {
    const double dx = double{hull[a].x} - hull[b].x, dy = double{hull[a].y} - hull[b].y;
    return dx * dx + dy * dy;
  };
  // Twice the area of triangle (a, b, c), unsigned.
  auto area2 = [&](size_t a, size_t b, size_t c) {
    const double abx = double{hull[b].x} - hull[a].x, aby = double{hull[b].y} - hull[a].y;
    const double acx = double{hull[c].x} - hull[a].x, acy = double{hull[c].y} - hull[a].y;
    return std::abs(abx * acy - aby * acx);
  };
  if (n < 2) return 0.0;
  if (n == 2) return std::sqrt(dist2(0, 1));
  double best = 0.0;
  size_t j = 1;
  for (size_t i = 0; i < n; ++i) {
    const size_t next = (i + 1) % n;
    // Advance j to the vertex farthest from edge (i, next): the antipodal vertex of that edge.
    for (size_t steps = 0; steps < n && area2(i, next, (j + 1) % n) > area2(i, next, j); ++steps)
      j = (j + 1) % n;
    best = std::max({best, dist2(i, j), dist2(next, j)});
  }
  return std::sqrt(best);
}

}  // namespace

double FrameDistortionPx(const cv::Mat& displacement) {
  SHUTTERLAB_CHECK(displacement.type() == CV_32FC2) << "displacement field must be CV_32FC2";
  double d_max = 0.0;
  std::vector<cv::Point2f> column, hull;
  for (int u = 0; u < displacement.cols; ++u) {
    column.clear();
    for (int v = 0; v < displacement.rows; ++v) {
      const cv::Vec2f d = displacement.at<cv::Vec2f>(v, u);
      if (std::isfinite(d[0]) && std::isfinite(d[1])) column.emplace_back(d[0], d[1]);
    }
    if (column.size() < 2) continue;
    // The diameter of a point set is attained between two vertices of its convex hull; rotating
    // calipers (Shamos 1978) find it in O(h): the hull of a smooth field's column has many
    // vertices.
    cv::convexHull(column, hull);
    d_max = std::max(d_max, ConvexPolygonDiameter(hull));
  }
  return d_max;
}

}  // namespace shutterlab
