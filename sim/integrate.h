#pragma once
// Integration of gyro rates: the source paper's per-axis angles and SO(3) orientation.

#include "sim/gyro_trace.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <vector>

namespace shutterlab {

// Per-axis integrated angles, rad, structure-of-arrays for the window statistics.
// angle[a][k] = sum over 0 < i <= k of (w_i[a] - bias[a]) * (t_i - t_{i-1})   (docs/FORMATS.md),
// so angle[a][0] = 0: the first sample has no interval before it.
struct PerAxisAngles {
  std::vector<int64_t> t_ns;
  std::vector<double> angle_rad[3];
  size_t size() const { return t_ns.size(); }
};

// The paper's integration (rectangle rule at the right sample) over samples [first, last).
PerAxisAngles IntegratePerAxis(const GyroTrace& trace, const Eigen::Vector3d& bias_rad_s,
                               size_t first = 0, size_t last = static_cast<size_t>(-1));

// Orientation over time from body rates: q(t) = world_from_body, Hamilton, unit norm.
// Integration is by right multiplication (as basalt's propagateState: the increment in the body
// frame):
//   q_{k+1} = q_k * Exp(0.5 (w_k + w_{k+1}) dt)    (trapezoid on the rates).
// Between samples the rate is taken as linear in time, so the orientation at t_k + tau is
//   q_k * Exp(w_k tau + (w_{k+1} - w_k) tau^2 / (2 dt)),
// which equals the trapezoid step at tau = dt: the lookup is exact to the sample, not a slerp.
// One trapezoid step of that integration: world_from_body at a sample from the one before it
// (q_prev, rate w_prev) and its own rate w, dt_s after it.
Eigen::Quaterniond OrientationStep(const Eigen::Quaterniond& q_prev, const Eigen::Vector3d& w_prev,
                                   const Eigen::Vector3d& w, double dt_s);

class OrientationTrace {
 public:
  OrientationTrace() = default;
  // rates in the body frame of interest (rotate them first if the gyro is not the body);
  // initial: world_from_body at the first sample.
  explicit OrientationTrace(const GyroTrace& body_rates,
                            const Eigen::Quaterniond& initial = Eigen::Quaterniond::Identity());
  // A stretch of an orientation integrated elsewhere (a trace streamed past, OrientationStep),
  // samples k: t_ns[k] (non-decreasing), the body rate and world_from_body there. Lookups inside
  // the stretch give what the whole trace gives.
  OrientationTrace(std::vector<int64_t> t_ns, std::vector<Eigen::Vector3d> omega_rad_s,
                   std::vector<Eigen::Quaterniond> world_from_body);

  // world_from_body at t_ns + offset_s. Throws std::out_of_range when the instant is outside
  // [first sample, last sample]: a validator must not extrapolate silently.
  Eigen::Quaterniond WorldFromBodyAt(int64_t t_ns, double offset_s = 0.0) const;

  const std::vector<int64_t>& t_ns() const { return t_ns_; }
  const std::vector<Eigen::Quaterniond>& world_from_body() const { return q_; }
  size_t size() const { return t_ns_.size(); }

 private:
  std::vector<int64_t> t_ns_;
  std::vector<Eigen::Vector3d> omega_rad_s_;
  std::vector<Eigen::Quaterniond> q_;
};

}  // namespace shutterlab
