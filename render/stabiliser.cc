#include "render/stabiliser.h"

#include "sim/check.h"
#include "sim/so3.h"

#include <cmath>

namespace shutterlab {

const char* StabiliserModeName(StabiliserMode mode) {
  switch (mode) {
    case StabiliserMode::kOff:
      return "off";
    case StabiliserMode::kWhole:
      return "whole";
    case StabiliserMode::kRoll:
      return "roll";
    case StabiliserMode::kRollLock:
      return "roll-lock";
  }
  return "off";
}

std::optional<StabiliserMode> ParseStabiliserMode(const std::string& name) {
  for (StabiliserMode m : {StabiliserMode::kOff, StabiliserMode::kWhole, StabiliserMode::kRoll,
                           StabiliserMode::kRollLock}) {
    if (name == StabiliserModeName(m)) return m;
  }
  return std::nullopt;
}

void StabiliserOptions::Check() const {
  SHUTTERLAB_CHECK(std::isfinite(window_s) && window_s > 0 && window_s <= 60)
      << "--stabiliser-window must be above 0 s and at most 60 s";
}

namespace {

// Gaussian average of values over the times (sigma_s), each frame's own weights normalised.
template <typename T>
std::vector<T> GaussianAverage(const std::vector<T>& values, const std::vector<double>& t_s,
                               double sigma_s) {
  std::vector<T> out;
  for (size_t k = 0; k < values.size(); ++k) {
    T sum = values[k] * 0.0;
    double weights = 0.0;
    for (size_t j = 0; j < values.size(); ++j) {
      const double z = (t_s[j] - t_s[k]) / sigma_s;
      if (std::abs(z) > 4) continue;
      const double w = std::exp(-0.5 * z * z);
      sum = sum + values[j] * w;
      weights += w;
    }
    out.push_back(sum * (1.0 / weights));
  }
  return out;
}

Eigen::Matrix3d RotationZ(double angle_rad) {
  return Eigen::AngleAxisd(angle_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

}  // namespace

std::vector<Eigen::Matrix3d> StabiliserRotations(const StabiliserOptions& options,
                                                 const std::vector<FrameMotion>& motions,
                                                 const std::vector<double>& t_s) {
  const size_t n = motions.size();
  std::vector<Eigen::Matrix3d> out(n, Eigen::Matrix3d::Identity());
  if (options.mode == StabiliserMode::kOff || n == 0) return out;
  std::vector<Eigen::Matrix3d> r(n);
  for (size_t k = 0; k < n; ++k) {
    const FrameMotion& m = motions[k];
    r[k] = m.world_from_cam[m.world_from_cam.size() / 2];
  }
  if (options.mode == StabiliserMode::kWhole) {
    std::vector<Eigen::Vector3d> phi;
    for (size_t k = 0; k < n; ++k) {
      phi.push_back(LogSO3(Eigen::Quaterniond(r[0].transpose() * r[k]).normalized()));
      // Averaging rotation vectors past pi would average across the wrap.
      SHUTTERLAB_CHECK(phi.back().norm() < 170.0 * M_PI / 180.0)
          << "--stabiliser whole: the clip turns more than 170 degrees from its first frame "
             "(render a shorter clip)";
    }
    const std::vector<Eigen::Vector3d> smooth = GaussianAverage(phi, t_s, options.window_s);
    for (size_t k = 0; k < n; ++k) {
      out[k] = r[k].transpose() * r[0] * ExpSO3(smooth[k]).toRotationMatrix();
    }
    return out;
  }
  // The roll about the optical axis, accumulated frame to frame.
  std::vector<double> roll(n, 0.0);
  for (size_t k = 1; k < n; ++k) {
    roll[k] =
        roll[k - 1] + LogSO3(Eigen::Quaterniond(r[k - 1].transpose() * r[k]).normalized()).z();
  }
  const std::vector<double> kept = options.mode == StabiliserMode::kRoll
                                       ? GaussianAverage(roll, t_s, options.window_s)
                                       : std::vector<double>(n, 0.0);
  for (size_t k = 0; k < n; ++k) out[k] = RotationZ(kept[k] - roll[k]);
  return out;
}

void TurnFrame(const Eigen::Matrix3d& cam_from_image, FrameMotion* motion) {
  for (Eigen::Matrix3d& r : motion->world_from_cam) r = r * cam_from_image;
  motion->world_from_ref = motion->world_from_ref * cam_from_image;
}

}  // namespace shutterlab
