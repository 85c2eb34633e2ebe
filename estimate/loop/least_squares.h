#pragma once
// Robust Levenberg-Marquardt over 2-D residuals (one pair per measured point), with numeric
// central-difference Jacobians and the Huber loss on each pair's length.
//
// Cost: sum_i w_i rho(|r_i|), rho(s) = s^2 / 2 for s <= delta, delta (s - delta / 2) beyond
// (Huber 1964): a point far off the model pulls with a bounded force, so a few bad measurements
// cannot steer the fit, while Gaussian points (|r| << delta) are fitted by plain least squares.
// Each iteration linearises at the current residual and solves (H + lambda diag(A)) dx = g, H the
// cost's Gauss-Newton Hessian (a point beyond delta curves only across its residual), A = J^T W J
// with the Huber weights W (IRLS; Marquardt's scaling makes it unit-free), g = J^T W r; a step is
// accepted only when the robust cost decreases, and then doubled while it decreases further.
// `normal` is A at the solution (the covariances' information matrix).

#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <vector>

namespace shutterlab {

struct RobustProblem {
  // residuals(x, r, valid): r gets 2 values per point (measured - predicted); valid[i] = 0 where
  // point i has no prediction (it then costs `invalid_cost` and contributes no derivative).
  std::function<void(const Eigen::VectorXd& x, Eigen::VectorXd* r, std::vector<uint8_t>* valid)>
      residuals;
  Eigen::VectorXd weights;    // per point, >= 0
  Eigen::VectorXd steps;      // central-difference step per parameter
  double huber_delta = 1.0;   // on |r_i|, residual units
  double invalid_cost = 0.0;  // cost of a point without prediction
};

struct RobustOptions {
  int max_iterations = 40;
  double relative_tolerance = 1e-9;  // stop when the cost decreases by less than this share
};

struct RobustSolution {
  Eigen::VectorXd x;
  double cost = 0.0;             // sum w rho at x
  Eigen::MatrixXd normal;        // J^T W_huber J at x (the Gauss-Newton information)
  Eigen::MatrixXd jacobian;      // d predicted / d x at x, 2 rows per point (0 where undefined)
  Eigen::VectorXd irls_weights;  // w_i * Huber weight at x, per point (0 where undefined)
  Eigen::VectorXd residuals;     // r(x), 2 per point
  std::vector<uint8_t> valid;    // per point
  int iterations = 0;
  int evaluations = 0;
};

// Huber loss and its IRLS weight for a residual length s.
double HuberRho(double s, double delta);
double HuberWeight(double s, double delta);

// Robust cost of a residual vector (as the solver defines it); the second form sums only the
// points [begin, end).
double RobustCost(const RobustProblem& problem, const Eigen::VectorXd& r,
                  const std::vector<uint8_t>& valid);
double RobustCost(const RobustProblem& problem, const Eigen::VectorXd& r,
                  const std::vector<uint8_t>& valid, size_t begin, size_t end);

// Minimises from x0. With no parameters (x0 empty) it only evaluates.
RobustSolution SolveRobust(const RobustProblem& problem, const Eigen::VectorXd& x0,
                           const RobustOptions& options = {});

}  // namespace shutterlab
