#pragma once
// The two lens distortion models of docs/FORMATS.md camera.json, as OpenCV defines them, and the
// one place that tells them apart: a LensDistortion is one or the other (std::variant), and
// everything that depends on which it is goes through the functions below.
//
// Both map a ray in the camera frame (x right, y down, z along the optical axis) to a distorted
// normalised point x_d; the pixel is K x_d (model/camera.h).
//  - BrownConrady, OpenCV's standard model (calib3d "Detailed description"): the undistorted
//    normalised point (x, y) = (X/Z, Y/Z), r^2 = x^2 + y^2, radial 1 + k1 r^2 + k2 r^4 + k3 r^6,
//    tangential p1, p2. Only rays in front of the camera (Z > 0) have a point.
//  - Fisheye, OpenCV's fisheye model (Kannala-Brandt: equidistant with a polynomial; what
//  Gyroflow's
//    lens profiles hold): theta = the ray's angle from the optical axis, theta_d = theta (1 + k1
//    theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8), x_d = theta_d (X, Y) / |(X, Y)|. OpenCV
//    writes theta = atan(r) and so stops at 90 degrees; here theta = atan2(|(X, Y)|, Z), which is
//    the same in front of the camera and goes on beyond 90 degrees for lenses wider than 180.
//    The model holds while theta_d increases with theta (up to max_theta_rad()): a ray beyond
//    has no point, and a point beyond the image circle the model reaches has no ray.

#include <Eigen/Core>

#include <array>
#include <optional>
#include <variant>

namespace shutterlab {

// OpenCV's Brown-Conrady distortion.
struct BrownConrady {
  std::array<double, 5> coeffs{};  // k1, k2, p1, p2, k3 (OpenCV's order), dimensionless

  // Distorted normalised point of a ray; nullopt when it does not point forward (Z <= 0).
  std::optional<Eigen::Vector2d> DistortedFromRay(const Eigen::Vector3d& ray) const;
  // The ray (Z = 1) whose distorted point is x_d: Newton's method on the distortion map to 1e-15
  // (converges where the map is invertible; OpenCV's plain fixed-point iteration stalls for strong
  // distortion at the corners).
  Eigen::Vector3d RayFromDistorted(const Eigen::Vector2d& x_d) const;
  // True when the radial map r (1 + k1 r^2 + k2 r^4 + k3 r^6) increases on [0, r_max]
  // (undistorted normalised radius): the image does not fold there.
  bool MonotonicTo(double r_max) const;

  bool operator==(const BrownConrady& other) const { return coeffs == other.coeffs; }
  bool operator!=(const BrownConrady& other) const { return !(*this == other); }
};

// OpenCV's fisheye distortion. A value type; the angle at which the polynomial turns is worked out
// once, when the coefficients are set.
class Fisheye {
 public:
  Fisheye() = default;  // k = 0: the equidistant projection, theta_d = theta
  explicit Fisheye(const std::array<double, 4>& coeffs);

  const std::array<double, 4>& coeffs() const { return coeffs_; }  // k1, k2, k3, k4
  // theta_d of an incidence angle theta, rad.
  double ThetaD(double theta_rad) const;
  // The largest incidence angle (rad, at most pi) up to which theta_d increases; NaN when a
  // coefficient is not finite.
  double max_theta_rad() const { return max_theta_rad_; }

  // Distorted normalised point of a ray at any angle below max_theta_rad() (behind the image plane
  // too, for lenses wider than 180 degrees); nullopt beyond.
  std::optional<Eigen::Vector2d> DistortedFromRay(const Eigen::Vector3d& ray) const;
  // The ray whose distorted point is x_d: (x, y, 1) while it points forward (theta < 90 degrees),
  // a unit vector with Z <= 0 from 90 degrees on (never the forward ray on the other side: a wide
  // lens's corners must not wrap round). NaN where x_d lies beyond the radius theta_d reaches
  // before it turns (outside the model's image circle). theta by safeguarded Newton to 1e-15 rad.
  Eigen::Vector3d RayFromDistorted(const Eigen::Vector2d& x_d) const;

  bool operator==(const Fisheye& other) const { return coeffs_ == other.coeffs_; }
  bool operator!=(const Fisheye& other) const { return !(*this == other); }

 private:
  std::array<double, 4> coeffs_{};
  double max_theta_rad_ = 3.14159265358979323846;
};

// A camera's lens distortion: one of the two models.
using LensDistortion = std::variant<BrownConrady, Fisheye>;

// camera.json's name of the model: "brown" or "fisheye".
const char* LensModelName(const LensDistortion& lens);
// False only for the plain pinhole projection: Brown-Conrady with every coefficient 0 (a fisheye
// with k = 0 is the equidistant projection, which is not a pinhole's).
bool HasDistortion(const LensDistortion& lens);
// Every coefficient finite.
bool DistortionFinite(const LensDistortion& lens);
// The radial coefficients k1 and k2, which both models have in the same places (the lens effect
// fits them): adds dk1, dk2.
void AddToK1K2(double dk1, double dk2, LensDistortion* lens);

}  // namespace shutterlab
