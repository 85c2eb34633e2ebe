#include "estimate/loop/frame_residuals.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace shutterlab {

double PooledNoisePx(const std::vector<FrameValidation>& frames) {
  double noise_sum = 0.0;
  size_t noise_points = 0;
  for (const FrameValidation& f : frames) {
    noise_sum += f.noise_px * f.noise_px * static_cast<double>(f.points);
    noise_points += f.points;
  }
  const double pooled = noise_points > 0 ? std::sqrt(noise_sum / noise_points) : 0.0;
  return std::max(kMinNoisePx, pooled);
}

void FillFrameResiduals(const std::vector<FramePoints>& frames, const LoopResult& loop,
                        const LoopResult* translation, const PointScreen& screen,
                        bool keep_residuals, std::vector<FrameValidation>* out) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const auto status_at = [](const std::vector<PointStatus>& status, size_t at) {
    return at < status.size() ? status[at] : PointStatus::kKept;
  };
  size_t offset = 0;
  for (size_t k = 0; k < frames.size(); ++k) {
    FrameValidation& f = (*out)[k];
    f.camera_fixed = f.moving = f.off_epipolar = 0;
    std::vector<double> before_sq, after_sq, translation_sq;
    for (size_t i = 0; i < frames[k].points.size(); ++i) {
      const size_t at = offset + i;
      const PointStatus status = status_at(screen.rotation_status, at);
      const PointStatus translation_status = status_at(screen.translation_status, at);
      f.camera_fixed += status == PointStatus::kCameraFixed;
      f.moving += status == PointStatus::kMoving;
      f.off_epipolar += translation_status == PointStatus::kOffEpipolar;
      const Eigen::Vector2d& rb = loop.residuals_before[at];
      const Eigen::Vector2d& ra = loop.residuals_after[at];
      if (!rb.allFinite() || !ra.allFinite()) continue;
      if (status == PointStatus::kKept) {
        before_sq.push_back(rb.squaredNorm());
        after_sq.push_back(ra.squaredNorm());
      }
      Eigen::Vector2f rt(nan, nan);
      if (translation != nullptr && translation->residuals_after[at].allFinite()) {
        rt = translation->residuals_after[at].cast<float>();
        if (translation_status == PointStatus::kKept) {
          translation_sq.push_back(translation->residuals_after[at].squaredNorm());
        }
      }
      if (keep_residuals) {
        const MeasuredPoint& p = frames[k].points[i];
        f.residuals.push_back({static_cast<float>(p.u), static_cast<float>(p.v),
                               static_cast<float>(rb.x()), static_cast<float>(rb.y()),
                               static_cast<float>(ra.x()), static_cast<float>(ra.y()), rt.x(),
                               rt.y(), status, translation_status});
      }
    }
    f.before = ResidualStatsOf(before_sq);
    f.after = ResidualStatsOf(after_sq);
    if (translation != nullptr) {
      f.translation_after = ResidualStatsOf(translation_sq);
      if (k < translation->pair_translation_dirs.size()) {
        f.translation_dir = translation->pair_translation_dirs[k];
      }
    }
    offset += frames[k].points.size();
  }
}

}  // namespace shutterlab
