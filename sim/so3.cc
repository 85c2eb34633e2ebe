#include "sim/so3.h"

#include <algorithm>
#include <cmath>

namespace shutterlab {

Eigen::Matrix3d Hat(const Eigen::Vector3d& a) {
  Eigen::Matrix3d m;
  m << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
  return m;
}

Eigen::Quaterniond ExpSO3(const Eigen::Vector3d& v) {
  const double theta_sq = v.squaredNorm();
  double real, imag_factor;
  if (theta_sq < 1e-12) {
    // Taylor series of cos(t/2) and sin(t/2)/t to 4th order (Sophus SO3::expAndTheta).
    const double theta_po4 = theta_sq * theta_sq;
    real = 1.0 - theta_sq / 8.0 + theta_po4 / 384.0;
    imag_factor = 0.5 - theta_sq / 48.0 + theta_po4 / 3840.0;
  } else {
    const double theta = std::sqrt(theta_sq);
    real = std::cos(0.5 * theta);
    imag_factor = std::sin(0.5 * theta) / theta;
  }
  Eigen::Quaterniond q(real, imag_factor * v.x(), imag_factor * v.y(), imag_factor * v.z());
  return q.normalized();
}

Eigen::Vector3d LogSO3(const Eigen::Quaterniond& q_in) {
  Eigen::Quaterniond q = q_in.normalized();
  // Keep |theta| <= pi: q and -q are the same rotation; pick w >= 0.
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  const Eigen::Vector3d vec = q.vec();
  const double squared_n = vec.squaredNorm();
  const double w = q.w();
  double two_atan_nbyw_by_n;
  if (squared_n < 1e-20) {
    // Taylor of 2 atan(n/w)/n around n = 0 (Sophus SO3::logAndTheta).
    two_atan_nbyw_by_n = 2.0 / w - 2.0 / 3.0 * squared_n / (w * w * w);
  } else {
    const double n = std::sqrt(squared_n);
    // atan2 stays accurate near w = 0 (theta near pi).
    two_atan_nbyw_by_n = 2.0 * std::atan2(n, w) / n;
  }
  return two_atan_nbyw_by_n * vec;
}

double AngularDistance(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return LogSO3(a.conjugate() * b).norm();
}

Eigen::Matrix3d RotationZYX(double alpha_rad, double beta_rad, double gamma_rad) {
  return (Eigen::AngleAxisd(alpha_rad, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(beta_rad, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(gamma_rad, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

double AngleFromTrace(const Eigen::Matrix3d& r) {
  const double c = std::clamp((r.trace() - 1.0) / 2.0, -1.0, 1.0);
  return std::acos(c);
}

bool IsRotationMatrix(const Eigen::Matrix3d& m, double tol) {
  if (!m.allFinite()) return false;
  return (m * m.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <= tol &&
         std::abs(m.determinant() - 1.0) <= tol;
}

}  // namespace shutterlab
