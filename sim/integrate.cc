#include "sim/integrate.h"

#include "sim/check.h"
#include "sim/so3.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace shutterlab {

PerAxisAngles IntegratePerAxis(const GyroTrace& trace, const Eigen::Vector3d& bias_rad_s,
                               size_t first, size_t last) {
  last = std::min(last, trace.size());
  SHUTTERLAB_CHECK(first <= last) << "empty integration range";
  PerAxisAngles out;
  const size_t n = last - first;
  out.t_ns.resize(n);
  for (auto& a : out.angle_rad) a.resize(n);
  double angle[3] = {0.0, 0.0, 0.0};
  for (size_t k = 0; k < n; ++k) {
    const GyroSample& s = trace[first + k];
    if (k > 0) {
      const double dt_s = (s.t_ns - trace[first + k - 1].t_ns) * 1e-9;
      for (int a = 0; a < 3; ++a) angle[a] += (s.omega_rad_s[a] - bias_rad_s[a]) * dt_s;
    }
    out.t_ns[k] = s.t_ns;
    for (int a = 0; a < 3; ++a) out.angle_rad[a][k] = angle[a];
  }
  return out;
}

OrientationTrace::OrientationTrace(const GyroTrace& body_rates, const Eigen::Quaterniond& initial) {
  SHUTTERLAB_CHECK(!body_rates.empty()) << "cannot integrate an empty gyro trace";
  const size_t n = body_rates.size();
  t_ns_.resize(n);
  omega_rad_s_.resize(n);
  q_.resize(n);
  q_[0] = initial.normalized();
  for (size_t k = 0; k < n; ++k) {
    t_ns_[k] = body_rates[k].t_ns;
    omega_rad_s_[k] = body_rates[k].omega_rad_s;
    if (k == 0) continue;
    const double dt_s = (t_ns_[k] - t_ns_[k - 1]) * 1e-9;
    q_[k] = OrientationStep(q_[k - 1], omega_rad_s_[k - 1], omega_rad_s_[k], dt_s);
  }
}

Eigen::Quaterniond OrientationStep(const Eigen::Quaterniond& q_prev, const Eigen::Vector3d& w_prev,
                                   const Eigen::Vector3d& w, double dt_s) {
  return (q_prev * ExpSO3(0.5 * (w_prev + w) * dt_s)).normalized();
}

OrientationTrace::OrientationTrace(std::vector<int64_t> t_ns,
                                   std::vector<Eigen::Vector3d> omega_rad_s,
                                   std::vector<Eigen::Quaterniond> world_from_body)
    : t_ns_(std::move(t_ns)), omega_rad_s_(std::move(omega_rad_s)), q_(std::move(world_from_body)) {
  SHUTTERLAB_CHECK(!t_ns_.empty() && omega_rad_s_.size() == t_ns_.size() &&
                   q_.size() == t_ns_.size())
      << "an orientation stretch needs as many rates and orientations as times, at least one";
}

Eigen::Quaterniond OrientationTrace::WorldFromBodyAt(int64_t t_ns, double offset_s) const {
  SHUTTERLAB_CHECK(!t_ns_.empty()) << "orientation lookup in an empty trace";
  // Split the offset into whole nanoseconds (exact integer search) and a sub-ns remainder.
  const double offset_ns = offset_s * 1e9;
  SHUTTERLAB_CHECK(std::isfinite(offset_ns) && std::abs(offset_ns) < 9e18) << "bad time offset";
  const int64_t whole_ns = static_cast<int64_t>(std::floor(offset_ns));
  const int64_t t = t_ns + whole_ns;
  const double frac_ns = offset_ns - static_cast<double>(whole_ns);  // in [0, 1)
  if (t < t_ns_.front() || t > t_ns_.back() || (t == t_ns_.back() && frac_ns > 0.0)) {
    throw std::out_of_range("orientation requested at t = " + std::to_string((t + frac_ns) * 1e-9) +
                            " s, outside the gyro trace [" + std::to_string(t_ns_.front() * 1e-9) +
                            ", " + std::to_string(t_ns_.back() * 1e-9) + "] s");
  }
  // k: last sample with t_k <= t (upper_bound - 1), so duplicates resolve to the later one.
  size_t k = std::upper_bound(t_ns_.begin(), t_ns_.end(), t) - t_ns_.begin() - 1;
  const double tau_s = ((t - t_ns_[k]) + frac_ns) * 1e-9;
  if (tau_s == 0.0 || k + 1 >= t_ns_.size()) return q_[k];
  const double dt_s = (t_ns_[k + 1] - t_ns_[k]) * 1e-9;
  const Eigen::Vector3d& w0 = omega_rad_s_[k];
  const Eigen::Vector3d& w1 = omega_rad_s_[k + 1];
  const Eigen::Vector3d rotation = w0 * tau_s + (w1 - w0) * (tau_s * tau_s / (2.0 * dt_s));
  return (q_[k] * ExpSO3(rotation)).normalized();
}

}  // namespace shutterlab
