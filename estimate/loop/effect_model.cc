#include "estimate/loop/effect_model.h"

#include "estimate/loop/least_squares.h"
#include "render/rs_warp.h"
#include "sim/check.h"
#include "sim/integrate.h"
#include "sim/so3.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <opencv2/core/utility.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <random>

namespace shutterlab {

namespace {

// The rays K^-1 p depend on these alone: a cache of them stays valid while they do not change.
bool SameIntrinsics(const PinholeCamera& a, const PinholeCamera& b) {
  return a.fx == b.fx && a.fy == b.fy && a.cx == b.cx && a.cy == b.cy &&
         a.distortion == b.distortion;
}

}  // namespace

const std::vector<Eigen::Matrix3d>& AxisRotations() {
  static const std::vector<Eigen::Matrix3d> rotations = [] {
    std::vector<Eigen::Matrix3d> out;
    const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    for (const auto& perm : perms) {
      for (int signs = 0; signs < 8; ++signs) {
        Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
        for (int row = 0; row < 3; ++row) m(row, perm[row]) = (signs >> row) & 1 ? -1.0 : 1.0;
        if (m.determinant() > 0) out.push_back(m);
      }
    }
    return out;
  }();
  return rotations;
}

DisplacementPredictor::DisplacementPredictor(const GyroTrace& gyro,
                                             const std::vector<FramePoints>& frames)
    : gyro_(gyro) {
  SHUTTERLAB_CHECK(gyro.size() >= 2) << "the gyro trace needs at least two samples";
  for (const FramePoints& f : frames) {
    Frame frame;
    frame.t_first_row_ns = f.t_first_row_ns;
    frame.first = points_;
    for (const MeasuredPoint& p : f.points) frame.rows.push_back(p.v);
    std::sort(frame.rows.begin(), frame.rows.end());
    frame.rows.erase(std::unique(frame.rows.begin(), frame.rows.end()), frame.rows.end());
    for (const MeasuredPoint& p : f.points) {
      frame.px.emplace_back(p.u, p.v);
      frame.row_of_point.push_back(static_cast<int>(
          std::lower_bound(frame.rows.begin(), frame.rows.end(), p.v) - frame.rows.begin()));
    }
    points_ += f.points.size();
    frames_span_s_ = std::max(frames_span_s_, std::abs(f.t_first_row_ns * 1e-9));
    frames_.push_back(std::move(frame));
  }
}

void DisplacementPredictor::RefreshRays(const PinholeCamera& camera) const {
  if (rays_valid_ && SameIntrinsics(camera, rays_camera_)) return;
  rays_.resize(points_);
  for (const Frame& frame : frames_) {
    for (size_t i = 0; i < frame.px.size(); ++i)
      rays_[frame.first + i] = camera.CamFromImg(frame.px[i]);
  }
  rays_camera_ = camera;
  rays_valid_ = true;
}

namespace {

// The camera-frame orientation, integrated from the true rates of the gyro samples that cover the
// instants t_ns + [lo_s, hi_s] (gyro clock): from the last sample at or before lo to the first at
// or after hi, one more on each side so that the lookup's whole-ns rounding stays inside. nullopt
// when the span is absurd or the trace has nothing there.
std::optional<OrientationTrace> CoveringTrace(const GyroTrace& gyro, const TrueModel& model,
                                              int64_t t_ns, double lo_s, double hi_s) {
  if (!std::isfinite(lo_s) || !std::isfinite(hi_s) || std::abs(lo_s) > 1e9 ||
      std::abs(hi_s) > 1e9) {
    return std::nullopt;
  }
  const std::vector<GyroSample>& samples = gyro.samples();
  const int64_t lo_ns = t_ns + static_cast<int64_t>(std::floor(lo_s * 1e9));
  const int64_t hi_ns = t_ns + static_cast<int64_t>(std::ceil(hi_s * 1e9));
  size_t begin = gyro.LowerBound(lo_ns);
  begin = begin > 0 ? begin - 1 : 0;
  size_t end = std::min(gyro.LowerBound(hi_ns) + 1, samples.size() - 1);
  if (end <= begin) end = std::min(begin + 1, samples.size() - 1);
  if (end <= begin) return std::nullopt;
  std::vector<GyroSample> span(samples.begin() + begin, samples.begin() + end + 1);
  for (GyroSample& s : span) s.omega_rad_s = model.CamRate(s.omega_rad_s);
  return OrientationTrace(GyroTrace(std::move(span)));
}

// True when OrientationTrace::WorldFromBodyAt(t_ns, offset_s) over samples [front, back] would
// answer (the same whole-ns / fraction split, so the two agree at the ends).
bool InSpan(int64_t t_ns, double offset_s, int64_t front_ns, int64_t back_ns) {
  const double offset_ns = offset_s * 1e9;
  if (!std::isfinite(offset_ns) || std::abs(offset_ns) >= 9e18) return false;
  const int64_t whole_ns = static_cast<int64_t>(std::floor(offset_ns));
  const int64_t t = t_ns + whole_ns;
  const double frac_ns = offset_ns - static_cast<double>(whole_ns);
  return !(t < front_ns || t > back_ns || (t == back_ns && frac_ns > 0.0));
}

}  // namespace

void DisplacementPredictor::Predict(const TrueModel& model,
                                    std::vector<Eigen::Vector2d>* out) const {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  out->assign(points_, Eigen::Vector2d(kNaN, kNaN));
  const PinholeCamera& camera = model.rig.camera;
  RefreshRays(camera);
  std::vector<double> row_offset_s;
  std::vector<Eigen::Matrix3d> row_rotation;
  std::vector<uint8_t> row_ok;
  for (const Frame& frame : frames_) {
    if (frame.px.empty()) continue;
    const int64_t t_first = frame.t_first_row_ns;
    // Gyro-clock offsets (from t_first on the camera clock) of row 0 and of every point row.
    const double t0_offset_s = model.RowGyroOffsetS(t_first, 0);
    row_offset_s.resize(frame.rows.size());
    double lo_s = t0_offset_s, hi_s = t0_offset_s;
    for (size_t r = 0; r < frame.rows.size(); ++r) {
      row_offset_s[r] = model.RowGyroOffsetS(t_first, frame.rows[r]);
      lo_s = std::min(lo_s, row_offset_s[r]);
      hi_s = std::max(hi_s, row_offset_s[r]);
    }
    const std::optional<OrientationTrace> covering =
        CoveringTrace(gyro_, model, t_first, lo_s, hi_s);
    if (!covering) continue;
    const OrientationTrace& trace = *covering;
    const int64_t front_ns = trace.t_ns().front(), back_ns = trace.t_ns().back();
    // Whole frame undefined when row 0 (the reference) is outside the trace (the renderer throws);
    // single rows outside are undefined on their own.
    if (!InSpan(t_first, t0_offset_s, front_ns, back_ns)) continue;
    // As CameraMotion::Frame: R_v = R(t_0)^-1 R(t_v), c_v = velocity * (t_v - t_0).
    const Eigen::Quaterniond ref_from_world =
        trace.WorldFromBodyAt(t_first, t0_offset_s).conjugate();
    row_rotation.resize(frame.rows.size());
    row_ok.assign(frame.rows.size(), 0);
    for (size_t r = 0; r < frame.rows.size(); ++r) {
      if (!InSpan(t_first, row_offset_s[r], front_ns, back_ns)) continue;
      const Eigen::Quaterniond q = ref_from_world * trace.WorldFromBodyAt(t_first, row_offset_s[r]);
      row_rotation[r] = q.normalized().toRotationMatrix();
      row_ok[r] = 1;
    }
    // As FrameGeometry::GroundPoint / RefPixel (the reference pose is the identity at c(t_0) = 0).
    const double altitude_m = model.rig.altitude_m;
    for (size_t i = 0; i < frame.px.size(); ++i) {
      const int r = frame.row_of_point[i];
      if (!row_ok[r]) continue;
      const Eigen::Vector3d ray_w = row_rotation[r] * rays_[frame.first + i];
      const Eigen::Vector3d c = model.rig.velocity_mps * (row_offset_s[r] - t0_offset_s);
      const double s = (altitude_m - c.z()) / ray_w.z();
      if (!(s > 0) || !std::isfinite(s)) continue;
      const Eigen::Vector3d x = c + s * ray_w;
      const std::optional<Eigen::Vector2d> ref = camera.ImgFromCam(x);
      if (!ref) continue;
      (*out)[frame.first + i] = *ref - frame.px[i];
    }
  }
}

VideoPairPredictor::VideoPairPredictor(const GyroTrace& gyro,
                                       const std::vector<FramePoints>& frames,
                                       bool pair_translation, double robust_delta_px)
    : gyro_(gyro), pair_translation_(pair_translation), robust_delta_px_(robust_delta_px) {
  SHUTTERLAB_CHECK(gyro.size() >= 2) << "the gyro trace needs at least two samples";
  SHUTTERLAB_CHECK(!pair_translation || robust_delta_px > 0)
      << "pair translation needs a positive robust threshold";
  for (const FramePoints& f : frames) {
    SHUTTERLAB_CHECK(f.earlier) << "frame " << f.frame << " is not a video pair";
    Pair pair;
    pair.t_later_ns = f.t_first_row_ns;
    pair.t_earlier_ns = f.earlier->t_first_row_ns;
    pair.first = points_;
    for (const MeasuredPoint& p : f.points) pair.rows.push_back(p.v);
    std::sort(pair.rows.begin(), pair.rows.end());
    pair.rows.erase(std::unique(pair.rows.begin(), pair.rows.end()), pair.rows.end());
    for (const MeasuredPoint& p : f.points) {
      pair.px.emplace_back(p.u, p.v);
      pair.measured.emplace_back(p.dx, p.dy);
      pair.match.emplace_back(p.u + p.dx, p.v + p.dy);
      pair.weight.push_back(std::isfinite(p.weight) ? std::max(0.0, p.weight) : 0.0);
      pair.row_of_point.push_back(static_cast<int>(
          std::lower_bound(pair.rows.begin(), pair.rows.end(), p.v) - pair.rows.begin()));
    }
    pair.later_cam_from_image = f.cam_from_image;
    pair.earlier_cam_from_image = f.earlier->cam_from_image;
    points_ += f.points.size();
    frames_span_s_ = std::max({frames_span_s_, std::abs(f.t_first_row_ns * 1e-9),
                               std::abs(f.earlier->t_first_row_ns * 1e-9)});
    pairs_.push_back(std::move(pair));
  }
  previous_dirs_.assign(pairs_.size(),
                        Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN()));
}

void VideoPairPredictor::RefreshRays(const PinholeCamera& camera) const {
  if (rays_valid_ && SameIntrinsics(camera, rays_camera_)) return;
  const Eigen::Vector3d nan = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  rays_.resize(points_);
  match_rays_.resize(points_);
  for (const Pair& pair : pairs_) {
    for (size_t i = 0; i < pair.px.size(); ++i) {
      rays_[pair.first + i] = camera.CamFromImg(pair.px[i]);
      // Only pair_translation reads the measured matches.
      match_rays_[pair.first + i] =
          pair_translation_ && pair.match[i].allFinite() ? camera.CamFromImg(pair.match[i]) : nan;
    }
  }
  rays_camera_ = camera;
  rays_valid_ = true;
}

void VideoPairPredictor::Predict(const TrueModel& model, std::vector<Eigen::Vector2d>* out) const {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  out->assign(points_, Eigen::Vector2d(kNaN, kNaN));
  RefreshRays(model.rig.camera);
  translation_dirs_.assign(pair_translation_ ? pairs_.size() : 0, Eigen::Vector3d::Zero());
  // Pairs are independent and each writes only its own points and direction: the same numbers
  // whatever the thread count.
  cv::parallel_for_(cv::Range(0, static_cast<int>(pairs_.size())), [&](const cv::Range& range) {
    for (int k = range.start; k < range.end; ++k) PredictPair(model, k, out);
  });
}

// The epipole's neighbourhood that pair translation's distances are weighted down in, as a share of
// the image diagonal (PredictPair).
constexpr double kEpipoleRadiusShare = 0.05;

namespace {

// What PredictPair reads of one pair (VideoPairPredictor::Pair, its rays) and its points in *out.
struct PairView {
  int64_t t_earlier_ns;
  int64_t t_later_ns;
  const std::vector<double>& rows;
  const std::vector<int>& row_of_point;
  const std::vector<Eigen::Vector2d>& px;
  const std::vector<Eigen::Vector2d>& measured;
  const std::vector<Eigen::Vector2d>& match;
  const std::vector<double>& weight;
  const Eigen::Vector3d* rays;                  // K^-1 p of the pair's points
  const Eigen::Vector3d* match_rays;            // K^-1 q of the pair's points
  Eigen::Vector2d* out;                         // the pair's predictions
  const Eigen::Matrix3d& later_cam_from_image;  // VideoPairPredictor::Pair's
  const Eigen::Matrix3d& earlier_cam_from_image;
};

// The view of a VideoPairPredictor::Pair (deduced: the type is the class's own) and its rays,
// predictions into out.
template <typename Pair>
PairView ViewOf(const Pair& pair, const std::vector<Eigen::Vector3d>& rays,
                const std::vector<Eigen::Vector3d>& match_rays, Eigen::Vector2d* out) {
  return {pair.t_earlier_ns,
          pair.t_later_ns,
          pair.rows,
          pair.row_of_point,
          pair.px,
          pair.measured,
          pair.match,
          pair.weight,
          rays.data() + pair.first,
          match_rays.data() + pair.first,
          out,
          pair.later_cam_from_image,
          pair.earlier_cam_from_image};
}

// The orientation trace that covers the pair: everything relative to the earlier frame's
// t_first_row (camera clock) on the gyro clock. *later_offset_s: each later row's gyro offset.
std::optional<OrientationTrace> PairTrace(const GyroTrace& gyro, const TrueModel& model,
                                          const PairView& pair,
                                          std::vector<double>* later_offset_s) {
  const double last_row = model.rig.camera.height - 1;
  const int64_t t_e = pair.t_earlier_ns, t_l = pair.t_later_ns;
  const double dt_s = (t_l - t_e) * 1e-9;
  const double e0 = model.RowGyroOffsetS(t_e, 0), e1 = model.RowGyroOffsetS(t_e, last_row);
  double lo_s = std::min(e0, e1), hi_s = std::max(e0, e1);
  later_offset_s->resize(pair.rows.size());
  for (size_t r = 0; r < pair.rows.size(); ++r) {
    (*later_offset_s)[r] = model.RowGyroOffsetS(t_l, pair.rows[r]);
    lo_s = std::min(lo_s, dt_s + (*later_offset_s)[r]);
    hi_s = std::max(hi_s, dt_s + (*later_offset_s)[r]);
  }
  return CoveringTrace(gyro, model, t_e, lo_s, hi_s);
}

// The pair's world_from_cam rotations from its covering trace: the later frame's at its point
// rows, the earlier frame's at any row (on demand).
class PairRotations {
 public:
  PairRotations(const TrueModel& model, const OrientationTrace& trace, const PairView& pair,
                const std::vector<double>& later_offset_s)
      : model_(model),
        trace_(trace),
        t_e_(pair.t_earlier_ns),
        height_(model.rig.camera.height),
        front_ns_(trace.t_ns().front()),
        back_ns_(trace.t_ns().back()),
        earlier_rot_(height_),
        earlier_state_(height_, 0),
        later_rot_(pair.rows.size()),
        later_ok_(pair.rows.size(), 0),
        earlier_cam_from_image_(pair.earlier_cam_from_image),
        earlier_reimaged_(!pair.earlier_cam_from_image.isIdentity(0.0)) {
    for (size_t r = 0; r < pair.rows.size(); ++r) {
      if (!InSpan(pair.t_later_ns, later_offset_s[r], front_ns_, back_ns_)) continue;
      later_rot_[r] = trace.WorldFromBodyAt(pair.t_later_ns, later_offset_s[r])
                          .normalized()
                          .toRotationMatrix() *
                      pair.later_cam_from_image;
      later_ok_[r] = 1;
    }
  }

  // Whether later row r is inside the trace, and its world_from_image rotation (the camera's
  // times the frame's cam_from_image).
  bool later_ok(int r) const { return later_ok_[r] != 0; }
  const Eigen::Matrix3d& later_rot(int r) const { return later_rot_[r]; }

  bool CamFromWorldAt(double w, const Eigen::Vector3d& y, Eigen::Vector3d* z) {
    return RotateAt(w, y, true, z);
  }
  bool WorldFromCamAt(double w, const Eigen::Vector3d& x, Eigen::Vector3d* z) {
    return RotateAt(w, x, false, z);
  }

 private:
  const Eigen::Matrix3d* EarlierRow(int row) {
    if (earlier_state_[row] == 0) {
      const double offset_s = model_.RowGyroOffsetS(t_e_, row);
      earlier_state_[row] = 2;
      if (InSpan(t_e_, offset_s, front_ns_, back_ns_)) {
        earlier_rot_[row] = trace_.WorldFromBodyAt(t_e_, offset_s).normalized().toRotationMatrix();
        earlier_state_[row] = 1;
      }
    }
    return earlier_state_[row] == 1 ? &earlier_rot_[row] : nullptr;
  }

  // (R(w) S)^T y (inverse) or R(w) S y at a fractional row w, S the earlier frame's
  // cam_from_image: linear between the neighbouring rows' products (rows ~30 us apart: ~1e-10
  // from the integrated trace). False when a row is outside the trace.
  bool RotateAt(double w, const Eigen::Vector3d& y, bool inverse, Eigen::Vector3d* z) {
    if (!earlier_reimaged_) return RotateCameraAt(w, y, inverse, z);
    if (!inverse) return RotateCameraAt(w, earlier_cam_from_image_ * y, false, z);
    if (!RotateCameraAt(w, y, true, z)) return false;
    *z = earlier_cam_from_image_.transpose() * *z;
    return true;
  }

  // R(w)^T y or R(w) y, the physical camera's.
  bool RotateCameraAt(double w, const Eigen::Vector3d& y, bool inverse, Eigen::Vector3d* z) {
    const int r0 = std::min(static_cast<int>(w), std::max(0, height_ - 2));
    const double a = w - r0;
    const auto apply = [&](int row, Eigen::Vector3d* out) {
      const Eigen::Matrix3d* m = EarlierRow(row);
      if (m == nullptr) return false;
      *out = inverse ? Eigen::Vector3d(m->transpose() * y) : Eigen::Vector3d(*m * y);
      return true;
    };
    if (!apply(r0, z)) return false;
    if (a > 0) {
      Eigen::Vector3d z1;
      if (!apply(r0 + 1, &z1)) return false;
      *z = (1 - a) * *z + a * z1;
    }
    return true;
  }

  const TrueModel& model_;
  const OrientationTrace& trace_;
  int64_t t_e_;
  int height_;
  int64_t front_ns_, back_ns_;
  std::vector<Eigen::Matrix3d> earlier_rot_;  // world_from_cam per earlier row, on demand
  std::vector<uint8_t> earlier_state_;        // 0 not yet, 1 known, 2 outside the trace
  std::vector<Eigen::Matrix3d> later_rot_;
  std::vector<uint8_t> later_ok_;
  Eigen::Matrix3d earlier_cam_from_image_;
  bool earlier_reimaged_ = false;
};

// Rotation-only: each point's match in the earlier frame, the row it lies on found by fixed-point
// iteration. It starts at the measured match's row, which is the answer to within the measurement
// and the model's error: one or two steps instead of the five or six from the point's own row
// (the fixed point is the same from any start, the map being a contraction).
void PredictRotationOnly(const PinholeCamera& camera, const PairView& pair, PairRotations* rot) {
  const double last_row = camera.height - 1;
  for (size_t i = 0; i < pair.px.size(); ++i) {
    const int r = pair.row_of_point[i];
    if (!rot->later_ok(r)) continue;
    const Eigen::Vector3d y = rot->later_rot(r) * pair.rays[i];  // world direction
    constexpr int kMaxIterations = 50;
    const double start = std::isfinite(pair.match[i].y()) ? pair.match[i].y() : pair.px[i].y();
    double w = std::clamp(start, 0.0, last_row);
    for (int it = 0; it < kMaxIterations; ++it) {
      Eigen::Vector3d z;
      if (!rot->CamFromWorldAt(w, y, &z)) break;
      const std::optional<Eigen::Vector2d> q = camera.ImgFromCam(z);
      if (!q || !q->allFinite()) break;
      const double next = std::clamp(q->y(), 0.0, last_row);
      if (std::abs(next - w) <= kVideoMatchTolPx) {
        // A clamped row: the match lies above or below the earlier frame (beyond rounding).
        if (q->y() >= -kVideoMatchTolPx && q->y() <= last_row + kVideoMatchTolPx) {
          pair.out[i] = *q - pair.px[i];
        }
        break;
      }
      w = next;
    }
  }
}

// pair_translation: the cross products a_i = (R_w x_q) x (R_v x_p) at the measured matches.
struct CrossProducts {
  std::vector<Eigen::Vector3d> a, y;
  std::vector<double> w_row;  // the measured match's row; < 0: no constraint
};

CrossProducts MatchCrossProducts(const PinholeCamera& camera, const PairView& pair,
                                 PairRotations* rot) {
  const double last_row = camera.height - 1;
  const size_t n = pair.px.size();
  CrossProducts c;
  c.a.resize(n);
  c.y.resize(n);
  c.w_row.assign(n, -1.0);
  for (size_t i = 0; i < n; ++i) {
    const int r = pair.row_of_point[i];
    const Eigen::Vector3d& xq = pair.match_rays[i];
    const double w = pair.match[i].y();
    if (!rot->later_ok(r) || !xq.allFinite() || !(w >= 0.0 && w <= last_row)) continue;
    Eigen::Vector3d zq;
    if (!rot->WorldFromCamAt(w, xq, &zq)) continue;
    c.y[i] = rot->later_rot(r) * pair.rays[i];
    c.a[i] = zq.cross(c.y[i]);
    c.w_row[i] = w;
  }
  return c;
}

// Pixel length of the epipolar line's normal for direction v: the algebraic error v . a_i over
// it is the distance of the measured match from the line, px.
double NormalPx(const PinholeCamera& camera, const CrossProducts& c, size_t i,
                const Eigen::Vector3d& v, PairRotations* rot, Eigen::Vector3d* n_cam) {
  if (!rot->CamFromWorldAt(c.w_row[i], c.y[i].cross(v), n_cam)) return 0.0;
  const double nx = n_cam->x() / camera.fx, ny = n_cam->y() / camera.fy;
  return std::sqrt(nx * nx + ny * ny);  // not std::hypot: far slower, and no overflow here
}

// The translation direction V (world axes, sign arbitrary): the least eigenvector of the cross
// products' outer products, weighted to pixel distances and made robust by Huber IRLS. Zero when
// the fit fails.
Eigen::Vector3d TranslationDirection(const PinholeCamera& camera, const PairView& pair,
                                     const CrossProducts& c, double robust_delta_px,
                                     PairRotations* rot) {
  const std::vector<Eigen::Vector3d>& a = c.a;
  const double f_px = 0.5 * (camera.fx + camera.fy);
  Eigen::Vector3d v_dir = Eigen::Vector3d::Zero();
  constexpr int kIrlsRounds = 4;
  for (int round = 0; round < kIrlsRounds; ++round) {
    Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
    for (size_t i = 0; i < a.size(); ++i) {
      if (c.w_row[i] < 0 || pair.weight[i] <= 0) continue;
      double g;
      Eigen::Vector3d n_cam;
      if (round == 0) {
        g = a[i].norm() * f_px > 0 ? a[i].norm() / f_px : 0.0;  // before any v: |a_i| / f
      } else {
        g = NormalPx(camera, c, i, v_dir, rot, &n_cam);
      }
      if (!(g > 0)) continue;
      double alpha = pair.weight[i] / (g * g);
      if (round > 0) alpha *= HuberWeight(std::abs(v_dir.dot(a[i])) / g, robust_delta_px);
      m.noalias() += alpha * a[i] * a[i].transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(m);
    if (eig.info() != Eigen::Success || !m.allFinite() || m.isZero(0.0)) {
      v_dir.setZero();
      break;
    }
    v_dir = eig.eigenvectors().col(0).normalized();  // eigenvalues ascending
  }
  return v_dir;
}

// Each measured match's signed distance from its epipolar line, px: across the line in
// undistorted pixels, or (with a lens) from the match to its foot on the line, distorted. The
// "prediction" is the measured match moved by that distance along x, so that measured -
// predicted is (distance, 0): a residual whose second component is always 0, and whose
// derivatives are the distance's alone. (The foot itself would turn the residual vector with the
// line, and Gauss-Newton would count that turning, which changes no distance, as information.)
void PredictDistances(const PinholeCamera& camera, const PairView& pair, const CrossProducts& c,
                      const Eigen::Vector3d& v_dir, PairRotations* rot) {
  const Eigen::Matrix3d k_mat = camera.K(), k_inv = k_mat.inverse();
  const double epipole_radius_px = kEpipoleRadiusShare * std::hypot(camera.width, camera.height);
  for (size_t i = 0; i < c.a.size(); ++i) {
    if (c.w_row[i] < 0) continue;
    Eigen::Vector3d n_cam;
    const double g = NormalPx(camera, c, i, v_dir, rot, &n_cam);
    if (!(g > 0)) continue;
    const double distance_px = v_dir.dot(c.a[i]) / g;
    const Eigen::Vector2d normal(n_cam.x() / camera.fx / g, n_cam.y() / camera.fy / g);
    const Eigen::Vector3d& xq = pair.match_rays[i];
    if (!(xq.z() > 0)) continue;  // a fisheye's ray 90 degrees or more off the axis: no such pixel
    const Eigen::Vector2d q_undistorted = (k_mat * xq).hnormalized();
    const Eigen::Vector2d foot = q_undistorted - distance_px * normal;
    double across_px = distance_px;
    if (camera.HasDistortion()) {
      const std::optional<Eigen::Vector2d> q = camera.ImgFromCam(k_inv * foot.homogeneous());
      if (!q || !q->allFinite()) continue;
      across_px = std::copysign((pair.match[i] - *q).norm(), distance_px);
    }
    // Near the epipole a point's line turns fast with V, so its distance depends on the model far
    // beyond what it says (one such point held a fifth of all the information on a readout time
    // in karma.mp4). Its distance counts the less the nearer it is: weight rho / sqrt(rho^2 + R^2),
    // rho its distance from the epipole (the projection of V at the match's row), R a twentieth of
    // the image diagonal: 1 far away (the noise level stays that of one component), smooth, so the
    // solver's derivatives stay honest.
    Eigen::Vector3d epipole;
    if (rot->CamFromWorldAt(c.w_row[i], v_dir, &epipole) && std::abs(epipole.z()) > 1e-12) {
      const double rho = (q_undistorted - (k_mat * (epipole / epipole.z())).head<2>()).norm();
      across_px *= rho / std::sqrt(rho * rho + epipole_radius_px * epipole_radius_px);
    }
    if (std::isfinite(across_px)) {
      pair.out[i] = pair.measured[i] - Eigen::Vector2d(across_px, 0.0);
    }
  }
}

}  // namespace

void VideoPairPredictor::PredictPair(const TrueModel& model, size_t k,
                                     std::vector<Eigen::Vector2d>* out) const {
  const Pair& pair = pairs_[k];
  if (pair.px.empty()) return;
  const PairView view = ViewOf(pair, rays_, match_rays_, out->data() + pair.first);
  std::vector<double> later_offset_s;
  const std::optional<OrientationTrace> trace = PairTrace(gyro_, model, view, &later_offset_s);
  if (!trace) return;
  PairRotations rot(model, *trace, view, later_offset_s);
  const PinholeCamera& camera = model.rig.camera;
  if (!pair_translation_) {
    PredictRotationOnly(camera, view, &rot);
    return;
  }
  const CrossProducts c = MatchCrossProducts(camera, view, &rot);
  Eigen::Vector3d v_dir = TranslationDirection(camera, view, c, robust_delta_px_, &rot);
  if (!v_dir.allFinite() || v_dir.isZero(0.0)) return;
  // V's sign is the eigen-solver's choice, and every distance's sign follows it: orient V as the
  // pair's previous one. A solver's evaluations come in small steps, V turns little from one to
  // the next, and each distance then stays a continuous function of the model (a point's line
  // may turn fast near the epipole, its distance does not jump).
  Eigen::Vector3d& previous_dir = previous_dirs_[k];
  if (previous_dir.allFinite() && v_dir.dot(previous_dir) < 0) v_dir = -v_dir;
  previous_dir = v_dir;
  // Report the direction in the earlier frame's row-0 camera frame.
  Eigen::Vector3d v_cam;
  translation_dirs_[k] = rot.CamFromWorldAt(0.0, v_dir, &v_cam) ? v_cam.normalized() : v_dir;
  PredictDistances(camera, view, c, v_dir, &rot);
}

std::vector<double> VideoPairPredictor::ConsensusDistances(const TrueModel& model,
                                                           const std::vector<double>& threshold_px,
                                                           int hypotheses) const {
  SHUTTERLAB_CHECK(pair_translation_) << "the epipolar consensus needs pair translation";
  SHUTTERLAB_CHECK(threshold_px.size() == pairs_.size()) << "one threshold per pair is needed";
  std::vector<double> out(points_, std::numeric_limits<double>::quiet_NaN());
  RefreshRays(model.rig.camera);
  const PinholeCamera& camera = model.rig.camera;
  cv::parallel_for_(cv::Range(0, static_cast<int>(pairs_.size())), [&](const cv::Range& range) {
    for (int k = range.start; k < range.end; ++k) {
      const Pair& pair = pairs_[k];
      std::vector<Eigen::Vector2d> unused(pair.px.size());
      const PairView view = ViewOf(pair, rays_, match_rays_, unused.data());
      std::vector<double> later_offset_s;
      const std::optional<OrientationTrace> trace = PairTrace(gyro_, model, view, &later_offset_s);
      if (!trace) continue;
      PairRotations rot(model, *trace, view, later_offset_s);
      const CrossProducts c = MatchCrossProducts(camera, view, &rot);
      std::vector<size_t> usable;
      for (size_t i = 0; i < c.a.size(); ++i) {
        if (c.w_row[i] >= 0 && pair.weight[i] > 0) usable.push_back(i);
      }
      if (usable.size() < 2) continue;
      const auto distance = [&](const Eigen::Vector3d& v, size_t i) {
        Eigen::Vector3d n_cam;
        const double g = NormalPx(camera, c, i, v, &rot, &n_cam);
        return g > 0 ? v.dot(c.a[i]) / g : std::numeric_limits<double>::quiet_NaN();
      };
      const double t2 = threshold_px[k] * threshold_px[k];
      std::mt19937_64 rng(static_cast<uint64_t>(k) + 1);
      std::uniform_int_distribution<size_t> pick(0, usable.size() - 1);
      Eigen::Vector3d best = Eigen::Vector3d::Zero();
      double best_cost = std::numeric_limits<double>::infinity();
      for (int h = 0; h < hypotheses; ++h) {
        const size_t i = usable[pick(rng)], j = usable[pick(rng)];
        const Eigen::Vector3d v = c.a[i].cross(c.a[j]);
        if (i == j || !(v.norm() > 0) || !v.allFinite()) continue;
        const Eigen::Vector3d v_dir = v.normalized();
        double cost = 0.0;
        for (size_t m : usable) {
          const double d = distance(v_dir, m);
          cost += std::isfinite(d) ? std::min(d * d, t2) : t2;
          if (cost >= best_cost) break;
        }
        if (cost < best_cost) {
          best_cost = cost;
          best = v_dir;
        }
      }
      if (best.isZero(0.0)) continue;
      // Refined on its inliers: the least eigenvector of their outer products, each weighted to
      // pixel distances (as TranslationDirection).
      Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
      for (size_t i : usable) {
        Eigen::Vector3d n_cam;
        const double g = NormalPx(camera, c, i, best, &rot, &n_cam);
        if (!(g > 0) || std::pow(best.dot(c.a[i]) / g, 2) > t2) continue;
        m.noalias() += pair.weight[i] / (g * g) * c.a[i] * c.a[i].transpose();
      }
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(m);
      if (eig.info() == Eigen::Success && m.allFinite() && !m.isZero(0.0)) {
        best = eig.eigenvectors().col(0).normalized();
      }
      for (size_t i = 0; i < c.a.size(); ++i) {
        if (c.w_row[i] >= 0) out[pair.first + i] = distance(best, i);
      }
    }
  });
  return out;
}

std::unique_ptr<PointPredictor> MakePredictor(const GyroTrace& gyro,
                                              const std::vector<FramePoints>& frames,
                                              bool pair_translation, double robust_delta_px) {
  size_t video = 0;
  for (const FramePoints& f : frames) video += f.earlier ? 1 : 0;
  SHUTTERLAB_CHECK(video == 0 || video == frames.size())
      << "frames mix video pairs and reference frames";
  if (video > 0) {
    return std::make_unique<VideoPairPredictor>(gyro, frames, pair_translation, robust_delta_px);
  }
  SHUTTERLAB_CHECK(!pair_translation) << "pair translation needs video pairs";
  return std::make_unique<DisplacementPredictor>(gyro, frames);
}

}  // namespace shutterlab
