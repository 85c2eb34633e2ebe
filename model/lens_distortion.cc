#include "model/lens_distortion.h"

#include "sim/units.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace shutterlab {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

template <class... Ts>
struct Overloaded : Ts... {
  using Ts::operator()...;
};
template <class... Ts>
Overloaded(Ts...) -> Overloaded<Ts...>;

}  // namespace

// ---- Brown-Conrady

std::optional<Eigen::Vector2d> BrownConrady::DistortedFromRay(const Eigen::Vector3d& ray) const {
  if (!(ray.z() > 0)) return std::nullopt;
  const double x = ray.x() / ray.z(), y = ray.y() / ray.z();
  const double k1 = coeffs[0], k2 = coeffs[1], p1 = coeffs[2], p2 = coeffs[3], k3 = coeffs[4];
  const double r2 = x * x + y * y;
  const double radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3));
  return Eigen::Vector2d(x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x),
                         y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y);
}

Eigen::Vector3d BrownConrady::RayFromDistorted(const Eigen::Vector2d& x_d) const {
  const double xd = x_d.x(), yd = x_d.y();
  const double k1 = coeffs[0], k2 = coeffs[1], p1 = coeffs[2], p2 = coeffs[3], k3 = coeffs[4];
  double x = xd, y = yd;
  for (int it = 0; it < 50; ++it) {
    const double r2 = x * x + y * y;
    const double radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3));
    const double d_radial_d_r2 = k1 + r2 * (2 * k2 + 3 * r2 * k3);
    const double fx = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x) - xd;
    const double fy = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y - yd;
    const double j00 = radial + 2 * x * x * d_radial_d_r2 + 2 * p1 * y + 6 * p2 * x;
    const double j01 = 2 * x * y * d_radial_d_r2 + 2 * p1 * x + 2 * p2 * y;
    const double j10 = 2 * x * y * d_radial_d_r2 + 2 * p1 * x + 2 * p2 * y;
    const double j11 = radial + 2 * y * y * d_radial_d_r2 + 6 * p1 * y + 2 * p2 * x;
    const double det = j00 * j11 - j01 * j10;
    if (det == 0) break;
    const double dx = (j11 * fx - j01 * fy) / det, dy = (j00 * fy - j10 * fx) / det;
    x -= dx;
    y -= dy;
    if (std::abs(dx) + std::abs(dy) < 1e-15) break;
  }
  return Eigen::Vector3d(x, y, 1.0);
}

bool BrownConrady::MonotonicTo(double r_max) const {
  const double k1 = coeffs[0], k2 = coeffs[1], k3 = coeffs[4];
  if (k1 == 0 && k2 == 0 && k3 == 0) return true;
  constexpr int kSteps = 64;
  for (int i = 1; i <= kSteps; ++i) {
    const double r2 = std::pow(r_max * i / kSteps, 2);
    // d/dr [r (1 + k1 r^2 + k2 r^4 + k3 r^6)]
    if (!(1 + 3 * k1 * r2 + 5 * k2 * r2 * r2 + 7 * k3 * r2 * r2 * r2 > 0)) return false;
  }
  return true;
}

// ---- Fisheye

namespace {

// d theta_d / d theta = 1 + 3 k1 s + 5 k2 s^2 + 7 k3 s^3 + 9 k4 s^4, s = theta^2.
double FisheyeSlope(const std::array<double, 4>& k, double theta) {
  const double s = theta * theta;
  return 1 + s * (3 * k[0] + s * (5 * k[1] + s * (7 * k[2] + s * 9 * k[3])));
}

// The first angle in (0, pi] at which the slope reaches 0, or pi: a scan in steps of pi/1024
// (a polynomial of degree 4 in theta^2 changes sign at most 4 times; calibrated lenses turn, if at
// all, far from 0), then bisection to 1e-15 rad.
double FoldAngle(const std::array<double, 4>& k) {
  for (double c : k) {
    if (!std::isfinite(c)) return kNaN;
  }
  constexpr int kSteps = 1024;
  double lo = 0.0;
  for (int i = 1; i <= kSteps; ++i) {
    const double hi = kPi * i / kSteps;
    if (FisheyeSlope(k, hi) > 0) {
      lo = hi;
      continue;
    }
    double a = lo, b = hi;
    while (b - a > 1e-15) {
      const double mid = 0.5 * (a + b);
      if (mid <= a || mid >= b) break;
      (FisheyeSlope(k, mid) > 0 ? a : b) = mid;
    }
    return a;
  }
  return kPi;
}

}  // namespace

Fisheye::Fisheye(const std::array<double, 4>& coeffs)
    : coeffs_(coeffs), max_theta_rad_(FoldAngle(coeffs)) {}

double Fisheye::ThetaD(double theta_rad) const {
  const double s = theta_rad * theta_rad;
  const std::array<double, 4>& k = coeffs_;
  return theta_rad * (1 + s * (k[0] + s * (k[1] + s * (k[2] + s * k[3]))));
}

std::optional<Eigen::Vector2d> Fisheye::DistortedFromRay(const Eigen::Vector3d& ray) const {
  // sqrt rather than hypot (several times slower; no ray here comes near overflow).
  const double r = std::sqrt(ray.x() * ray.x() + ray.y() * ray.y());
  const double theta = std::atan2(r, ray.z());
  if (!(theta < max_theta_rad_)) return std::nullopt;
  if (r == 0) {
    if (!(ray.z() > 0)) return std::nullopt;
    return Eigen::Vector2d::Zero();
  }
  const double scale = ThetaD(theta) / r;
  return Eigen::Vector2d(scale * ray.x(), scale * ray.y());
}

Eigen::Vector3d Fisheye::RayFromDistorted(const Eigen::Vector2d& x_d) const {
  const double r_d = x_d.norm();
  if (r_d == 0) return Eigen::Vector3d(0, 0, 1);
  const Eigen::Vector3d none(kNaN, kNaN, kNaN);
  if (!std::isfinite(r_d) || !(r_d < ThetaD(max_theta_rad_))) return none;
  // theta_d increases on [0, max_theta): one root, kept inside a bracket; Newton steps that leave
  // it are replaced by bisection.
  double lo = 0.0, hi = max_theta_rad_;
  double theta = std::min(r_d, 0.5 * (lo + hi));
  for (int it = 0; it < 100; ++it) {
    const double f = ThetaD(theta) - r_d;
    if (f == 0) break;
    (f < 0 ? lo : hi) = theta;
    const double slope = FisheyeSlope(coeffs_, theta);
    double next = slope > 0 ? theta - f / slope : 0.5 * (lo + hi);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const double step = std::abs(next - theta);
    theta = next;
    if (step < 1e-15 || hi - lo < 1e-15) break;
  }
  const double ux = x_d.x() / r_d, uy = x_d.y() / r_d;
  if (theta < 0.5 * kPi) {
    const double t = std::tan(theta);
    return Eigen::Vector3d(t * ux, t * uy, 1.0);
  }
  const double s = std::sin(theta);
  return Eigen::Vector3d(s * ux, s * uy, std::cos(theta));
}

// ---- either

const char* LensModelName(const LensDistortion& lens) {
  return std::holds_alternative<Fisheye>(lens) ? "fisheye" : "brown";
}

bool HasDistortion(const LensDistortion& lens) {
  const auto* brown = std::get_if<BrownConrady>(&lens);
  return !brown ||
         std::any_of(brown->coeffs.begin(), brown->coeffs.end(), [](double c) { return c != 0; });
}

bool DistortionFinite(const LensDistortion& lens) {
  const auto finite = [](const auto& coeffs) {
    return std::all_of(coeffs.begin(), coeffs.end(), [](double c) { return std::isfinite(c); });
  };
  return std::visit(Overloaded{[&](const BrownConrady& b) { return finite(b.coeffs); },
                               [&](const Fisheye& f) { return finite(f.coeffs()); }},
                    lens);
}

void AddToK1K2(double dk1, double dk2, LensDistortion* lens) {
  std::visit(Overloaded{[&](BrownConrady& b) {
                          b.coeffs[0] += dk1;
                          b.coeffs[1] += dk2;
                        },
                        [&](Fisheye& f) {
                          std::array<double, 4> k = f.coeffs();
                          k[0] += dk1;
                          k[1] += dk2;
                          f = Fisheye(k);
                        }},
             *lens);
}

}  // namespace shutterlab
