#pragma once
// SO(3) exponential and logarithm on unit quaternions (Hamilton, Eigen's convention).
// Modelled on Sophus SO3::exp / logAndTheta (Strasdat), which follow
// Hertzberg et al., "Integrating generic sensor fusion algorithms with sound state
// representations through encapsulation of manifolds", Information Fusion 14(1), 2013, §A.

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace shutterlab {

// Skew-symmetric matrix: Hat(a) * b = a x b.
Eigen::Matrix3d Hat(const Eigen::Vector3d& a);

// Exp: rotation vector (axis * angle, rad) -> unit quaternion. Taylor branch near 0 keeps
// full precision for |v| down to 0.
Eigen::Quaterniond ExpSO3(const Eigen::Vector3d& rotation_vector_rad);

// Log: unit quaternion -> rotation vector with |v| <= pi (q and -q give the same result).
Eigen::Vector3d LogSO3(const Eigen::Quaterniond& q);

// Geodesic angle between two orientations, rad, in [0, pi].
double AngularDistance(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b);

// R = Rz(alpha) * Ry(beta) * Rx(gamma), angles in rad (the source paper's convention).
Eigen::Matrix3d RotationZYX(double alpha_rad, double beta_rad, double gamma_rad);

// Rotation angle of a rotation matrix from its trace, trace R = 1 + 2 cos(theta); rad.
double AngleFromTrace(const Eigen::Matrix3d& r);

// True when m is a proper rotation to within tol (orthonormal, det +1).
bool IsRotationMatrix(const Eigen::Matrix3d& m, double tol = 1e-6);

}  // namespace shutterlab
