#include "render/rs_warp.h"

#include "render/warp_kernel.h"

#include <algorithm>
#include <cmath>
#include <limits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "sim/check.h"

#include <opencv2/imgproc.hpp>

namespace shutterlab {

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
        if (!geometry.SceneRowFixed(v, kSampleFracBits, xi.data(), yi.data(), u0, n)) {
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
