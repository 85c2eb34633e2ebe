#include "estimate/loop/point_screen.h"

#include "estimate/loop/effect_model.h"
#include "sim/check.h"
#include "sim/gyro_trace.h"
#include "sim/integrate.h"
#include "sim/so3.h"
#include "sim/text_file.h"
#include "sim/units.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <random>

namespace shutterlab {

const char* PointStatusName(PointStatus status) {
  switch (status) {
    case PointStatus::kKept:
      return "kept";
    case PointStatus::kCameraFixed:
      return "camera_fixed";
    case PointStatus::kMoving:
      return "moving";
    case PointStatus::kOffEpipolar:
      return "off_epipolar";
  }
  return "?";
}

void ScreenOptions::Check() const {}

bool CameraFixedRegion::Contains(double u, double v) const {
  if (fixed.empty() || !(u >= 0) || !(v >= 0)) return false;
  const int c = static_cast<int>(u / step_px), r = static_cast<int>(v / step_px);
  return c < cols && r < rows && fixed[static_cast<size_t>(r) * cols + c] != 0;
}

namespace {

// A frame needs this many points for its consensus to judge any of them.
constexpr size_t kMinConsensusPoints = 20;
// A residual's median over its per-component sigma: |e| of a 2-D Gaussian is Rayleigh (median
// sigma sqrt(2 ln 2)), |d| of a 1-D one half-normal (median 0.6745 sigma).
constexpr double kRayleighMedian = 1.1774;
constexpr double kHalfNormalMedian = 0.6745;
// Check 3 tests a pair whose predicted motion (median over its points) is at least this long and
// kMinTestableNoise times its noise.
constexpr double kMinGyroTestPx = 3.0;
constexpr int kMinGyroTestPairs = 3;

// Whether a point takes part in the checks: a positive weight and a finite measurement.
bool Usable(const MeasuredPoint& p) {
  return p.weight > 0 && std::isfinite(p.dx) && std::isfinite(p.dy);
}

// Each point's frame index and its offset into the concatenated per-point arrays.
struct FrameRange {
  size_t begin = 0, end = 0;
};
std::vector<FrameRange> Ranges(const std::vector<FramePoints>& frames) {
  std::vector<FrameRange> ranges;
  size_t at = 0;
  for (const FramePoints& f : frames) {
    ranges.push_back({at, at + f.points.size()});
    at += f.points.size();
  }
  return ranges;
}

double Testable(double noise_px) { return std::max(kMinTestablePx, kMinTestableNoise * noise_px); }

// Cells that stay in too few frames are not fixed; a fixed cell with no fixed neighbour (of the 8)
// is dropped.
void DropIsolated(CameraFixedRegion* region) {
  std::vector<uint8_t> kept = region->fixed;
  for (int r = 0; r < region->rows; ++r) {
    for (int c = 0; c < region->cols; ++c) {
      const size_t k = static_cast<size_t>(r) * region->cols + c;
      if (!region->fixed[k]) continue;
      bool neighbour = false;
      for (int dr = -1; dr <= 1 && !neighbour; ++dr) {
        for (int dc = -1; dc <= 1 && !neighbour; ++dc) {
          const int rr = r + dr, cc = c + dc;
          if ((dr || dc) && rr >= 0 && cc >= 0 && rr < region->rows && cc < region->cols &&
              region->fixed[static_cast<size_t>(rr) * region->cols + cc]) {
            neighbour = true;
          }
        }
      }
      kept[k] = neighbour;
    }
  }
  region->fixed = std::move(kept);
}

// The cells with no testable measurement that touch the region (4-neighbours, repeatedly) join
// it, from each connected part of at least kMinRegionSeedCells fixed cells: a dark, flat part of
// a dashboard measures nothing that can be trusted, and the scene's cells bound the region.
void JoinUnmeasured(CameraFixedRegion* region) {
  const int cols = region->cols, rows = region->rows;
  std::vector<int> part(region->fixed.size(), -1);
  std::vector<size_t> part_size;
  std::vector<size_t> stack;
  const auto neighbours = [&](size_t k, auto&& visit) {
    const int r = static_cast<int>(k) / cols, c = static_cast<int>(k) % cols;
    if (r > 0) visit(k - cols);
    if (r + 1 < rows) visit(k + cols);
    if (c > 0) visit(k - 1);
    if (c + 1 < cols) visit(k + 1);
  };
  for (size_t k = 0; k < part.size(); ++k) {  // the connected parts of the fixed cells
    if (!region->fixed[k] || part[k] >= 0) continue;
    const int id = static_cast<int>(part_size.size());
    part_size.push_back(0);
    part[k] = id;
    stack.assign(1, k);
    while (!stack.empty()) {
      const size_t at = stack.back();
      stack.pop_back();
      ++part_size[id];
      neighbours(at, [&](size_t n) {
        if (region->fixed[n] && part[n] < 0) part[n] = id, stack.push_back(n);
      });
    }
  }
  stack.clear();
  for (size_t k = 0; k < part.size(); ++k) {
    if (part[k] >= 0 && part_size[part[k]] >= kMinRegionSeedCells) stack.push_back(k);
  }
  while (!stack.empty()) {
    const size_t at = stack.back();
    stack.pop_back();
    neighbours(at, [&](size_t n) {
      if (!region->fixed[n] && region->testable[n] == 0) region->fixed[n] = 1, stack.push_back(n);
    });
  }
}

// The rotational flow of a small rotation theta applied to the ray through undistorted normalised
// (x, y): d(u, v) / d theta, px per rad (X -> X + theta x X, X = (x, y, 1)).
Eigen::Matrix<double, 2, 3> RotationFlow(const PinholeCamera& camera, const Eigen::Vector3d& ray) {
  const double x = ray.x() / ray.z(), y = ray.y() / ray.z();
  Eigen::Matrix<double, 2, 3> j;
  j << -x * y, 1 + x * x, -y, -(1 + y * y), x * y, x;
  j.row(0) *= camera.fx;
  j.row(1) *= camera.fy;
  return j;
}

// One frame's rotation-consensus problem: per candidate point, r = measured - predicted and
// A = d r / d dw (RotationFlow at the predicted point times the point's time between the views).
struct RateProblem {
  std::vector<size_t> index;  // the candidates' indices in the concatenated points
  std::vector<Eigen::Vector2d> r;
  std::vector<Eigen::Matrix<double, 2, 3>> a;
  std::vector<double> w;
};

RateProblem FrameRateProblem(const TrueModel& declared, const FramePoints& frame, size_t first,
                             const std::vector<Eigen::Vector2d>& predicted,
                             const std::vector<PointStatus>& status) {
  const PinholeCamera& camera = declared.rig.camera;
  RateProblem problem;
  const double row0_s = declared.RowGyroOffsetS(frame.t_first_row_ns, 0);
  for (size_t i = 0; i < frame.points.size(); ++i) {
    const size_t k = first + i;
    const MeasuredPoint& p = frame.points[i];
    if (status[k] != PointStatus::kKept || !Usable(p) || !predicted[k].allFinite()) continue;
    const Eigen::Vector2d q = Eigen::Vector2d(p.u, p.v) + predicted[k];
    // Seconds between the two views of the point: its row against the reference's row 0 (still),
    // or against its match's row in the earlier frame (video).
    double dt_s = declared.RowGyroOffsetS(frame.t_first_row_ns, p.v) - row0_s;
    if (frame.earlier) {
      dt_s = (frame.t_first_row_ns - frame.earlier->t_first_row_ns) * 1e-9 +
             declared.RowGyroOffsetS(frame.t_first_row_ns, p.v) -
             declared.RowGyroOffsetS(frame.earlier->t_first_row_ns, q.y());
    }
    problem.index.push_back(k);
    problem.r.emplace_back(Eigen::Vector2d(p.dx, p.dy) - predicted[k]);
    problem.a.push_back(RotationFlow(camera, camera.CamFromImg(q)) * dt_s);
    problem.w.push_back(p.weight);
  }
  return problem;
}

// Weighted least squares dw over the points `use` keeps; false when singular.
bool SolveRate(const RateProblem& problem, const std::vector<uint8_t>& use, Eigen::Vector3d* dw) {
  Eigen::Matrix3d n = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < problem.r.size(); ++i) {
    if (!use[i]) continue;
    n.noalias() += problem.w[i] * problem.a[i].transpose() * problem.a[i];
    b.noalias() += problem.w[i] * problem.a[i].transpose() * problem.r[i];
  }
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(n);
  if (ldlt.info() != Eigen::Success || !(n.diagonal().minCoeff() > 0)) return false;
  *dw = ldlt.solve(b);
  return dw->allFinite() && ldlt.isPositive();
}

// The residual lengths under dw.
std::vector<double> RateResiduals(const RateProblem& problem, const Eigen::Vector3d& dw) {
  std::vector<double> e(problem.r.size());
  for (size_t i = 0; i < e.size(); ++i) e[i] = (problem.r[i] - problem.a[i] * dw).norm();
  return e;
}

// MSAC over two-point samples (seeded by the frame), then the refit on the inliers at the noise
// threshold; the final threshold and inliers as the header says.
FrameConsensus FrameRotationConsensus(const RateProblem& problem, double noise_px, uint64_t seed,
                                      std::vector<uint8_t>* inlier) {
  FrameConsensus out;
  const size_t n = problem.r.size();
  out.candidates = n;
  inlier->assign(n, 1);
  if (n < kMinConsensusPoints) return out;
  const double sigma_noise = noise_px / std::sqrt(2.0);
  const double t0 = kInlierSigmas * sigma_noise;
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<size_t> pick(0, n - 1);
  std::vector<uint8_t> sample(n, 0);
  Eigen::Vector3d best = Eigen::Vector3d::Zero();
  double best_cost = std::numeric_limits<double>::infinity();
  for (int h = 0; h < kHypotheses; ++h) {
    const size_t i = pick(rng), j = pick(rng);
    if (i == j) continue;
    sample[i] = sample[j] = 1;
    Eigen::Vector3d dw;
    const bool solved = SolveRate(problem, sample, &dw);
    sample[i] = sample[j] = 0;
    if (!solved) continue;
    double cost = 0.0;
    for (size_t m = 0; m < n && cost < best_cost; ++m) {
      cost += std::min((problem.r[m] - problem.a[m] * dw).squaredNorm(), t0 * t0);
    }
    if (cost < best_cost) {
      best_cost = cost;
      best = dw;
    }
  }
  // Refit on the inliers at the noise threshold, then at the final one (twice: the threshold moves
  // with the refit's residuals).
  double threshold = t0;
  for (int round = 0; round < 3; ++round) {
    const std::vector<double> e = RateResiduals(problem, best);
    if (round > 0) threshold = kInlierSigmas * std::max(sigma_noise, Median(e) / kRayleighMedian);
    for (size_t i = 0; i < n; ++i) (*inlier)[i] = e[i] <= threshold;
    Eigen::Vector3d refit;
    if (SolveRate(problem, *inlier, &refit)) best = refit;
  }
  const std::vector<double> e = RateResiduals(problem, best);
  threshold = kInlierSigmas * std::max(sigma_noise, Median(e) / kRayleighMedian);
  for (size_t i = 0; i < n; ++i) {
    (*inlier)[i] = e[i] <= threshold;
    out.rejected += (*inlier)[i] ? 0 : 1;
  }
  out.threshold_px = threshold;
  out.delta_omega_rad_s = best;
  out.determined = true;
  return out;
}

// The orientation of the camera under the declared model, integrated over the whole log.
OrientationTrace CameraOrientation(const TrueModel& declared, const GyroTrace& gyro) {
  std::vector<GyroSample> rates = gyro.samples();
  for (GyroSample& s : rates) s.omega_rad_s = declared.CamRate(s.omega_rad_s);
  return OrientationTrace(GyroTrace(std::move(rates)));
}

// Share of the usable points whose status is `what`.
double StatusShare(const std::vector<FramePoints>& frames, const std::vector<PointStatus>& status,
                   PointStatus what) {
  size_t usable = 0, count = 0;
  size_t k = 0;
  for (const FramePoints& f : frames) {
    for (const MeasuredPoint& p : f.points) {
      if (Usable(p)) {
        ++usable;
        count += status[k] == what;
      }
      ++k;
    }
  }
  return usable > 0 ? static_cast<double>(count) / usable : 0.0;
}

}  // namespace

CameraFixedRegion DetectCameraFixed(const std::vector<FramePoints>& frames,
                                    const std::vector<Eigen::Vector2d>& predicted,
                                    const std::vector<double>& frame_noise_px, int width,
                                    int height, int step_px) {
  SHUTTERLAB_CHECK(step_px > 0 && width > 0 && height > 0) << "bad camera-fixed grid";
  SHUTTERLAB_CHECK(frame_noise_px.size() == frames.size()) << "one noise per frame is needed";
  CameraFixedRegion region;
  region.step_px = step_px;
  region.cols = (width + step_px - 1) / step_px;
  region.rows = (height + step_px - 1) / step_px;
  const size_t cells = static_cast<size_t>(region.cols) * region.rows;
  region.fixed.assign(cells, 0);
  region.testable.assign(cells, 0);
  region.still.assign(cells, 0);
  const std::vector<FrameRange> ranges = Ranges(frames);
  for (size_t f = 0; f < frames.size(); ++f) {
    const double testable_px = Testable(frame_noise_px[f]);
    for (size_t i = 0; i < frames[f].points.size(); ++i) {
      const MeasuredPoint& p = frames[f].points[i];
      const Eigen::Vector2d& d = predicted[ranges[f].begin + i];
      if (!Usable(p) || !d.allFinite() || d.norm() < testable_px) continue;
      const int c = std::clamp(static_cast<int>(p.u / step_px), 0, region.cols - 1);
      const int r = std::clamp(static_cast<int>(p.v / step_px), 0, region.rows - 1);
      const size_t k = static_cast<size_t>(r) * region.cols + c;
      ++region.testable[k];
      region.still[k] += std::hypot(p.dx, p.dy) <= kStillRatio * d.norm();
    }
  }
  for (size_t k = 0; k < cells; ++k) {
    if (region.testable[k] == 0) continue;
    ++region.cells_testable;
    region.fixed[k] = region.testable[k] >= kMinTestableFrames &&
                      region.still[k] >= kFixedShare * region.testable[k];
  }
  DropIsolated(&region);
  const size_t seeds = static_cast<size_t>(std::count(region.fixed.begin(), region.fixed.end(), 1));
  if (region.cells_testable > 0 &&
      seeds > kMaxRegionShare * static_cast<double>(region.cells_testable)) {
    region.whole_image = true;
  }
  if (!region.whole_image) JoinUnmeasured(&region);
  region.cells_fixed = static_cast<size_t>(std::count(region.fixed.begin(), region.fixed.end(), 1));
  region.cells_joined = region.cells_fixed - seeds;
  return region;
}

std::vector<FrameConsensus> RotationConsensus(const TrueModel& declared,
                                              const std::vector<FramePoints>& frames,
                                              const std::vector<Eigen::Vector2d>& predicted,
                                              const std::vector<double>& frame_noise_px,
                                              std::vector<PointStatus>* status) {
  SHUTTERLAB_CHECK(frame_noise_px.size() == frames.size()) << "one noise per frame is needed";
  const std::vector<FrameRange> ranges = Ranges(frames);
  std::vector<FrameConsensus> out(frames.size());
  for (size_t f = 0; f < frames.size(); ++f) {
    const RateProblem problem =
        FrameRateProblem(declared, frames[f], ranges[f].begin, predicted, *status);
    std::vector<uint8_t> inlier;
    out[f] = FrameRotationConsensus(problem, frame_noise_px[f], f + 1, &inlier);
    for (size_t i = 0; i < inlier.size(); ++i) {
      if (!inlier[i]) (*status)[problem.index[i]] = PointStatus::kMoving;
    }
  }
  return out;
}

namespace {

// Each vector less its running mean over kSlowPairs neighbours (centred, shorter at the ends).
std::vector<Eigen::Vector3d> FastPart(const std::vector<Eigen::Vector3d>& rates) {
  std::vector<Eigen::Vector3d> out;
  const int n = static_cast<int>(rates.size()), half = kSlowPairs / 2;
  for (int k = 0; k < n; ++k) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    const int a = std::max(0, k - half), b = std::min(n - 1, k + half);
    for (int j = a; j <= b; ++j) mean += rates[j];
    out.push_back(rates[k] - mean / (b - a + 1));
  }
  return out;
}

// Row a of M (w_img = M w_gyro, least squares) for each axis: *norm = |M_a|, *stderr its standard
// error (from the residual's scatter), *gain = M_aa. False when the gyro's rates do not span the
// three axes well enough to solve for M, or too few pairs.
bool FitRateMap(const std::vector<Eigen::Vector3d>& gyro, const std::vector<Eigen::Vector3d>& image,
                std::array<double, 3>* norm, std::array<double, 3>* stderr_norm,
                std::array<double, 3>* gain) {
  const size_t n = gyro.size();
  if (n < 6) return false;
  Eigen::Matrix3d gtg = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& g : gyro) gtg += g * g.transpose();
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(gtg);
  if (ldlt.info() != Eigen::Success || !(ldlt.rcond() > 1e-9)) return false;
  const Eigen::Matrix3d inv = ldlt.solve(Eigen::Matrix3d::Identity());
  for (int a = 0; a < 3; ++a) {
    Eigen::Vector3d gti = Eigen::Vector3d::Zero();
    for (size_t k = 0; k < n; ++k) gti += gyro[k] * image[k](a);
    const Eigen::Vector3d row = inv * gti;
    double sq = 0.0;
    for (size_t k = 0; k < n; ++k) sq += std::pow(image[k](a) - row.dot(gyro[k]), 2);
    const double var = sq / static_cast<double>(n - 3);
    (*norm)[a] = row.norm();
    (*gain)[a] = row(a);
    // Along the row's own direction (or any, for a row of zeros: the largest variance).
    const Eigen::Matrix3d cov = var * inv;
    (*stderr_norm)[a] = row.norm() > 0 ? std::sqrt(row.dot(cov * row)) / row.norm()
                                       : std::sqrt(cov.diagonal().maxCoeff());
  }
  return true;
}

void CheckAxes(GyroFollowCheck* check) {
  std::array<double, 3> norm{}, se{}, gain{};
  if (FitRateMap(check->gyro_rate_cam_rad_s, check->image_rate_cam_rad_s, &norm, &se, &gain)) {
    for (int a = 0; a < 3; ++a) {
      AxisFollow& axis = check->axes[a];
      axis.gain = gain[a];
      axis.row_norm = norm[a];
      axis.row_norm_stderr = se[a];
      axis.determined = se[a] <= kMaxFollowStderr;
    }
  }
  const std::vector<Eigen::Vector3d> fast_gyro = FastPart(check->gyro_rate_cam_rad_s);
  const std::vector<Eigen::Vector3d> fast_image = FastPart(check->image_rate_cam_rad_s);
  if (FitRateMap(fast_gyro, fast_image, &norm, &se, &gain)) {
    for (int a = 0; a < 3; ++a) {
      AxisFollow& axis = check->axes[a];
      axis.fast_row_norm = norm[a];
      axis.fast_row_norm_stderr = se[a];
      axis.fast_determined = se[a] <= kMaxFollowStderr;
    }
  }
  // Below kMinGain by kFollowSigmas standard errors: a fast part that is small and noisy (a
  // consensus biased by a large correction) is no stabiliser.
  for (AxisFollow& axis : check->axes) {
    const double k = kFollowSigmas;
    const bool below =
        (axis.determined && axis.row_norm + k * axis.row_norm_stderr < kMinGain) ||
        (axis.fast_determined && axis.fast_row_norm + k * axis.fast_row_norm_stderr < kMinGain);
    // Clearly following about its own axis: the declared mapping holds there too (a wrong one
    // turns the rows, and then a large correction biases the consensus about the other axes).
    const bool above =
        axis.determined && axis.gain - k * axis.row_norm_stderr >= kMinGain &&
        axis.row_norm - k * axis.row_norm_stderr >= kMinGain &&
        (!axis.fast_determined || axis.fast_row_norm - k * axis.fast_row_norm_stderr >= kMinGain);
    axis.follows = !below;
    axis.clearly_follows = above && !below;
  }
}

}  // namespace

bool GyroFollowCheck::OnSomeAxes() const {
  int follow = 0, not_follow = 0;
  for (const AxisFollow& a : axes) {
    not_follow += a.follows ? 0 : 1;
    follow += a.clearly_follows ? 1 : 0;
  }
  return follow > 0 && not_follow > 0;
}

std::vector<int> GyroFollowCheck::AxesNotFollowing() const {
  std::vector<int> out;
  for (int a = 0; a < 3; ++a) {
    if (!axes[a].follows) out.push_back(a);
  }
  return out;
}

GyroFollowCheck CheckImageFollowsGyro(const TrueModel& declared, const GyroTrace& gyro,
                                      const std::vector<FramePoints>& pairs,
                                      const std::vector<Eigen::Vector2d>& predicted,
                                      const std::vector<double>& frame_noise_px,
                                      const std::vector<FrameConsensus>& consensus) {
  GyroFollowCheck check;
  const OrientationTrace orientation = CameraOrientation(declared, gyro);
  const std::vector<FrameRange> ranges = Ranges(pairs);
  const double mid_row = 0.5 * (declared.rig.camera.height - 1);
  std::vector<double> gains;
  for (size_t k = 0; k < pairs.size(); ++k) {
    const FramePoints& pair = pairs[k];
    if (!pair.earlier || !consensus[k].determined) continue;
    std::vector<double> lengths;
    for (size_t i = ranges[k].begin; i < ranges[k].end; ++i) {
      if (predicted[i].allFinite()) lengths.push_back(predicted[i].norm());
    }
    // Every pair with a consensus enters the per-axis fit (a slow pair weighs little there);
    // only those that move enough enter the gain.
    const bool testable =
        !lengths.empty() &&
        Median(lengths) >= std::max(kMinGyroTestPx, kMinTestableNoise * frame_noise_px[k]);
    const int64_t t_e = pair.earlier->t_first_row_ns, t_l = pair.t_first_row_ns;
    const double off_e = declared.RowGyroOffsetS(t_e, mid_row);
    const double off_l = declared.RowGyroOffsetS(t_l, mid_row);
    Eigen::Vector3d w_gyro;
    try {
      // The model's rotation between the two images (with each frame's cam_from_image).
      const Eigen::Quaterniond rel = Eigen::Quaterniond(pair.earlier->cam_from_image).conjugate() *
                                     orientation.WorldFromBodyAt(t_e, off_e).conjugate() *
                                     orientation.WorldFromBodyAt(t_l, off_l) *
                                     Eigen::Quaterniond(pair.cam_from_image);
      w_gyro = LogSO3(rel.normalized()) / ((t_l - t_e) * 1e-9 + off_l - off_e);
    } catch (const std::out_of_range&) {
      continue;
    }
    if (!(w_gyro.norm() > 0)) continue;
    const Eigen::Vector3d w_image = w_gyro + consensus[k].delta_omega_rad_s;
    check.gyro_rate_cam_rad_s.push_back(w_gyro);
    check.image_rate_cam_rad_s.push_back(w_image);
    if (!testable) continue;
    const double image_rate = w_image.norm();
    gains.push_back(image_rate / w_gyro.norm());
    check.frames.push_back(pair.frame);
    check.gyro_rate_rad_s.push_back(w_gyro.norm());
    check.image_rate_rad_s.push_back(image_rate);
  }
  check.pairs_tested = static_cast<int>(gains.size());
  if (check.pairs_tested < kMinGyroTestPairs) {
    check.verdict = "not determined: " + std::to_string(check.pairs_tested) +
                    " pair(s) with enough predicted motion to compare the image with the gyro";
    return check;
  }
  check.determined = true;
  check.gain = Median(gains);
  CheckAxes(&check);
  // No axis that follows: the whole image is re-rendered, whatever its median gain.
  const bool none_follows = std::none_of(check.axes.begin(), check.axes.end(),
                                         [](const AxisFollow& a) { return a.follows; });
  check.follows = check.OnSomeAxes() || (check.gain >= kMinGain && !none_follows);
  char text[256];
  std::snprintf(text, sizeof(text),
                "the image turns %.2fx as fast as the gyro says (median over %d pairs)", check.gain,
                check.pairs_tested);
  std::string axes;
  for (int a = 0; a < 3; ++a) {
    const AxisFollow& f = check.axes[a];
    const auto value = [](bool determined, double v, double se) {
      return determined ? FormatNumber("%.2f", v) + FormatNumber(" +- %.2f", se)
                        : std::string("not determined");
    };
    axes += std::string(a ? ", " : "; per camera axis ") + kAxisNames[a] + " " +
            value(f.determined, f.row_norm, f.row_norm_stderr) + " (fast part " +
            value(f.fast_determined, f.fast_row_norm, f.fast_row_norm_stderr) + ")";
  }
  if (check.OnSomeAxes()) {
    std::string names;
    for (int a : check.AxesNotFollowing()) {
      names += std::string(names.empty() ? "" : " and ") + kAxisNames[a];
    }
    check.verdict =
        "the image does not follow the gyro about camera axis " + names +
        " (a stabiliser re-renders that rotation; about the others it follows): " + text + axes;
  } else {
    check.verdict = check.follows ? std::string("the image follows the gyro: ") + text + axes
                                  : std::string(
                                        "the image does not follow the gyro (a stabiliser "
                                        "re-rendered it, in the camera or afterwards): ") +
                                        text + axes;
  }
  return check;
}

std::vector<size_t> FollowImageAbout(const TrueModel& declared, const GyroFollowCheck& check,
                                     const std::vector<FrameConsensus>& consensus,
                                     std::vector<FramePoints>* pairs) {
  const std::vector<int> axes = check.AxesNotFollowing();
  const double mid_row = 0.5 * (declared.rig.camera.height - 1);
  // Each frame's turn, accumulated along the chain of pairs: the stabiliser turned the earlier
  // frame too, and the gyro's rotation about the axes that follow shows turned by it. A frame
  // first met as an earlier one (after a pair left out) takes the last turn known (no step
  // across the gap), the first frame none.
  std::map<int64_t, Eigen::Matrix3d> turned;
  Eigen::Matrix3d last = Eigen::Matrix3d::Identity();
  std::vector<FramePoints> kept;
  std::vector<size_t> removed;
  for (size_t k = 0; k < pairs->size(); ++k) {
    FramePoints& pair = (*pairs)[k];
    if (!pair.earlier || !consensus[k].determined) {
      removed.push_back(k);
      continue;
    }
    const int64_t t_e = pair.earlier->t_first_row_ns, t_l = pair.t_first_row_ns;
    const double dt_s = (t_l - t_e) * 1e-9 + declared.RowGyroOffsetS(t_l, mid_row) -
                        declared.RowGyroOffsetS(t_e, mid_row);
    Eigen::Vector3d turn = Eigen::Vector3d::Zero();
    for (int a : axes) turn(a) = consensus[k].delta_omega_rad_s(a) * dt_s;
    const auto earlier = turned.find(pair.earlier->frame);
    const Eigen::Matrix3d s_e = earlier == turned.end() ? last : earlier->second;
    const Eigen::Matrix3d s_l = s_e * ExpSO3(turn).toRotationMatrix();
    turned[pair.frame] = last = s_l;
    pair.earlier->cam_from_image = pair.earlier->cam_from_image * s_e;
    pair.cam_from_image = pair.cam_from_image * s_l;
    kept.push_back(std::move(pair));
  }
  *pairs = std::move(kept);
  return removed;
}

namespace {

// Check 2's epipolar consensus (video pairs) on the points whose translation status is kKept.
std::vector<FrameConsensus> EpipolarConsensus(const TrueModel& declared, const GyroTrace& gyro,
                                              const std::vector<FramePoints>& frames,
                                              const std::vector<double>& frame_noise_px,
                                              std::vector<PointStatus>* status) {
  std::vector<double> thresholds;
  for (double noise : frame_noise_px) thresholds.push_back(kInlierSigmas * noise / std::sqrt(2.0));
  const VideoPairPredictor epipolar(gyro, WithoutScreened(frames, *status),
                                    /*pair_translation=*/true, thresholds.front());
  const std::vector<double> d = epipolar.ConsensusDistances(declared, thresholds, kHypotheses);
  const std::vector<FrameRange> ranges = Ranges(frames);
  std::vector<FrameConsensus> out;
  for (size_t f = 0; f < frames.size(); ++f) {
    FrameConsensus c;
    std::vector<size_t> tested;
    std::vector<double> lengths;
    for (size_t i = ranges[f].begin; i < ranges[f].end; ++i) {
      if (Usable(frames[f].points[i - ranges[f].begin]) && (*status)[i] == PointStatus::kKept &&
          std::isfinite(d[i])) {
        tested.push_back(i);
        lengths.push_back(std::abs(d[i]));
      }
    }
    c.candidates = lengths.size();
    if (lengths.size() >= kMinConsensusPoints) {
      const double sigma_noise = frame_noise_px[f] / std::sqrt(2.0);
      c.threshold_px = kInlierSigmas * std::max(sigma_noise, Median(lengths) / kHalfNormalMedian);
      c.determined = true;
      for (size_t i : tested) {
        if (std::abs(d[i]) <= c.threshold_px) continue;
        (*status)[i] = PointStatus::kOffEpipolar;
        ++c.rejected;
      }
    }
    out.push_back(c);
  }
  return out;
}

// Checks 1 and 2 (screen's statuses and consensus); with `region`, its cells are left out first.
void LeaveOut(const TrueModel& declared, const GyroTrace& gyro,
              const std::vector<FramePoints>& frames, const std::vector<Eigen::Vector2d>& predicted,
              const std::vector<double>& frame_noise_px, bool use_region,
              const ScreenOptions& options, PointScreen* screen) {
  size_t total = 0;
  for (const FramePoints& f : frames) total += f.points.size();
  screen->rotation_status.assign(total, PointStatus::kKept);
  if (use_region) {
    size_t k = 0;
    for (const FramePoints& f : frames) {
      for (const MeasuredPoint& p : f.points) {
        if (screen->region.Contains(p.u, p.v))
          screen->rotation_status[k] = PointStatus::kCameraFixed;
        ++k;
      }
    }
  }
  screen->translation_status = screen->rotation_status;
  screen->rotation.clear();
  screen->translation.clear();
  if (!options.consensus) return;
  screen->rotation =
      RotationConsensus(declared, frames, predicted, frame_noise_px, &screen->rotation_status);
  if (!frames.empty() && frames.front().earlier) {
    screen->translation =
        EpipolarConsensus(declared, gyro, frames, frame_noise_px, &screen->translation_status);
  }
}

// Check 1 on the frames' corner tracks (FramePoints::tracks); nothing when no frame has any.
std::optional<CameraFixedRegion> CameraFixedFromTracks(const TrueModel& declared,
                                                       const GyroTrace& gyro,
                                                       const std::vector<FramePoints>& frames,
                                                       const std::vector<double>& frame_noise_px,
                                                       int width, int height, int step_px) {
  std::vector<FramePoints> tracked;
  bool any = false;
  for (const FramePoints& f : frames) {
    FramePoints t;
    t.frame = f.frame;
    t.t_first_row_ns = f.t_first_row_ns;
    t.earlier = f.earlier;
    t.cam_from_image = f.cam_from_image;
    t.points = f.tracks;
    any = any || !t.points.empty();
    tracked.push_back(std::move(t));
  }
  if (!any) return std::nullopt;
  std::vector<Eigen::Vector2d> predicted;
  MakePredictor(gyro, tracked, /*pair_translation=*/false, /*robust_delta_px=*/1.0)
      ->Predict(declared, &predicted);
  return DetectCameraFixed(tracked, predicted, frame_noise_px, width, height, step_px);
}

}  // namespace

PointScreen ScreenPoints(const TrueModel& declared, const GyroTrace& gyro,
                         const std::vector<FramePoints>& frames,
                         const std::vector<double>& measured_noise_px, int step_px,
                         const ScreenOptions& options) {
  options.Check();
  std::vector<double> frame_noise_px;  // identical frames measure 0: never judge against that
  for (double noise : measured_noise_px) frame_noise_px.push_back(std::max(kMinNoisePx, noise));
  PointScreen screen;
  const std::unique_ptr<PointPredictor> predictor =
      MakePredictor(gyro, frames, /*pair_translation=*/false, /*robust_delta_px=*/1.0);
  std::vector<Eigen::Vector2d> predicted;
  predictor->Predict(declared, &predicted);
  const int width = declared.rig.camera.width, height = declared.rig.camera.height;
  if (options.camera_fixed) {
    std::optional<CameraFixedRegion> tracked =
        CameraFixedFromTracks(declared, gyro, frames, frame_noise_px, width, height, step_px);
    screen.region =
        tracked ? std::move(*tracked)
                : DetectCameraFixed(frames, predicted, frame_noise_px, width, height, step_px);
  }
  bool use_region = options.camera_fixed && !screen.region.whole_image;
  LeaveOut(declared, gyro, frames, predicted, frame_noise_px, use_region, options, &screen);
  const bool video = !frames.empty() && frames.front().earlier.has_value();
  if (video && options.consensus) {
    screen.gyro_follow =
        CheckImageFollowsGyro(declared, gyro, frames, predicted, frame_noise_px, screen.rotation);
    // An image that does not follow the gyro stays behind it everywhere: the cells that stayed
    // are the stabiliser's doing, not a part of the frame that moves with the camera.
    if (use_region && screen.gyro_follow.determined && !screen.gyro_follow.follows) {
      screen.region.whole_image = true;
      use_region = false;
      LeaveOut(declared, gyro, frames, predicted, frame_noise_px, use_region, options, &screen);
    }
  }
  screen.camera_fixed_share =
      StatusShare(frames, screen.rotation_status, PointStatus::kCameraFixed);
  screen.moving_share = StatusShare(frames, screen.rotation_status, PointStatus::kMoving);
  if (video) {
    screen.off_epipolar_share =
        StatusShare(frames, screen.translation_status, PointStatus::kOffEpipolar);
  }
  return screen;
}

std::vector<FramePoints> WithoutScreened(const std::vector<FramePoints>& frames,
                                         const std::vector<PointStatus>& status) {
  std::vector<FramePoints> out = frames;
  size_t k = 0;
  for (FramePoints& f : out) {
    for (MeasuredPoint& p : f.points) {
      if (status[k] != PointStatus::kKept) p.weight = 0.0;
      ++k;
    }
  }
  return out;
}

}  // namespace shutterlab
