#include "estimate/loop/least_squares.h"

#include "sim/check.h"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>

namespace shutterlab {

double HuberRho(double s, double delta) {
  return s <= delta ? 0.5 * s * s : delta * (s - 0.5 * delta);
}

double HuberWeight(double s, double delta) { return s <= delta ? 1.0 : delta / s; }

double RobustCost(const RobustProblem& problem, const Eigen::VectorXd& r,
                  const std::vector<uint8_t>& valid) {
  return RobustCost(problem, r, valid, 0, static_cast<size_t>(problem.weights.size()));
}

double RobustCost(const RobustProblem& problem, const Eigen::VectorXd& r,
                  const std::vector<uint8_t>& valid, size_t begin, size_t end) {
  double cost = 0.0;
  for (size_t i = begin; i < end; ++i) {
    const double w = problem.weights[i];
    if (w <= 0) continue;
    if (!valid[i]) {
      cost += w * problem.invalid_cost;
      continue;
    }
    cost += w * HuberRho(std::sqrt(r[2 * i] * r[2 * i] + r[2 * i + 1] * r[2 * i + 1]),
                         problem.huber_delta);
  }
  return cost;
}

namespace {

struct Evaluation {
  Eigen::VectorXd r;
  std::vector<uint8_t> valid;
  double cost = 0.0;
};

Evaluation Evaluate(const RobustProblem& problem, const Eigen::VectorXd& x, int* evaluations) {
  Evaluation e;
  problem.residuals(x, &e.r, &e.valid);
  ++*evaluations;
  SHUTTERLAB_CHECK(e.r.size() == 2 * problem.weights.size() &&
                   e.valid.size() == static_cast<size_t>(problem.weights.size()))
      << "residual function returned " << e.r.size() << " values for " << problem.weights.size()
      << " points";
  e.cost = RobustCost(problem, e.r, e.valid);
  return e;
}

// A = J^T W J and g = J^T W r at x, W = point weight * Huber weight (IRLS), J = d predicted / d x
// = -d r / d x by central differences; points invalid on either side get no derivative.
// *newton (optional) gets the cost's own Gauss-Newton Hessian, which the steps are solved with:
// beyond the Huber threshold a point's cost grows linearly along its residual, so it adds
// curvature only across it, J^T w (delta / s) (I - r r^T / s^2) J. A (the IRLS matrix, kept for
// the covariances) counts delta / s along the residual as well: where many points lie beyond the
// threshold it overstates the curvature, and steps solved with it cover a constant share of the
// remaining way (a Karma clip's gyro scale took 17 steps, now 3).
void Linearise(const RobustProblem& problem, const Eigen::VectorXd& x, const Evaluation& at,
               Eigen::MatrixXd* a, Eigen::VectorXd* g, int* evaluations,
               Eigen::MatrixXd* jacobian = nullptr, Eigen::VectorXd* irls_weights = nullptr,
               Eigen::MatrixXd* newton = nullptr) {
  const Eigen::Index p = x.size(), n = problem.weights.size();
  Eigen::MatrixXd local_jac;
  Eigen::MatrixXd& jac = jacobian ? *jacobian : local_jac;  // d predicted / d x
  jac.resize(2 * n, p);
  if (irls_weights) irls_weights->setZero(n);
  std::vector<uint8_t> ok(n, 1);
  for (Eigen::Index k = 0; k < p; ++k) {
    Eigen::VectorXd xp = x, xm = x;
    const double h = problem.steps[k];
    xp[k] += h;
    xm[k] -= h;
    const Evaluation ep = Evaluate(problem, xp, evaluations);
    const Evaluation em = Evaluate(problem, xm, evaluations);
    jac.col(k) = (em.r - ep.r) / (2 * h);
    for (Eigen::Index i = 0; i < n; ++i) ok[i] &= ep.valid[i] & em.valid[i];
  }
  a->setZero(p, p);
  g->setZero(p);
  if (newton) newton->setZero(p, p);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double w = problem.weights[i];
    if (w <= 0 || !ok[i] || !at.valid[i]) {
      jac.middleRows(2 * i, 2).setZero();
      continue;
    }
    const Eigen::Vector2d r = at.r.segment<2>(2 * i);
    const double s = r.norm();
    const double wh = w * HuberWeight(s, problem.huber_delta);
    if (irls_weights) (*irls_weights)[i] = wh;
    const auto j = jac.middleRows(2 * i, 2);
    const Eigen::Matrix<double, 2, Eigen::Dynamic> wj = wh * j;
    a->noalias() += j.transpose() * wj;
    g->noalias() += wj.transpose() * r;
    if (newton == nullptr) continue;
    if (s <= problem.huber_delta) {
      newton->noalias() += j.transpose() * wj;
    } else {
      const Eigen::Vector2d across(-r.y() / s, r.x() / s);  // unit, perpendicular to r
      const Eigen::RowVectorXd ja = across.transpose() * j;
      newton->noalias() += wh * ja.transpose() * ja;
    }
  }
}

// A step that lowers the cost is tried at twice, four times, ... its length while that lowers it
// further (a line search along it). Gauss-Newton's model leaves out the residuals' own curvature,
// and on a residual that the model does not explain (parallax that rotation-only cannot reproduce,
// a drone's vibration) that term cancels much of J^T W J: a Karma clip's time offset moved 7 % of
// the remaining way per step and stopped, short of its minimum, at the 40-step cap (now 4 steps).
constexpr int kMaxStepDoublings = 6;

}  // namespace

RobustSolution SolveRobust(const RobustProblem& problem, const Eigen::VectorXd& x0,
                           const RobustOptions& options) {
  SHUTTERLAB_CHECK(problem.steps.size() == x0.size()) << "one step per parameter";
  RobustSolution out;
  Eigen::VectorXd x = x0;
  Evaluation cur = Evaluate(problem, x, &out.evaluations);
  const Eigen::Index p = x.size();
  Eigen::MatrixXd a, newton;
  Eigen::VectorXd g;
  if (p > 0) {
    double lambda = 1e-4;
    for (int it = 0; it < options.max_iterations; ++it) {
      out.iterations = it + 1;
      Linearise(problem, x, cur, &a, &g, &out.evaluations, nullptr, nullptr, &newton);
      bool accepted = false;
      double decrease = 0.0;
      while (lambda < 1e12) {
        // Marquardt's scaling by the IRLS diagonal: the cost's own Hessian may have none along a
        // parameter that only outliers' residuals follow.
        Eigen::MatrixXd damped = newton;
        for (Eigen::Index k = 0; k < p; ++k) {
          damped(k, k) += lambda * std::max(a(k, k), 1e-12 * (1.0 + a.diagonal().maxCoeff()));
        }
        const Eigen::VectorXd dx = damped.ldlt().solve(g);
        if (!dx.allFinite()) {
          lambda *= 10;
          continue;
        }
        Evaluation next = Evaluate(problem, x + dx, &out.evaluations);
        if (next.cost < cur.cost) {
          // The step, doubled while the cost keeps falling (a line search along it): see
          // kMaxStepDoublings.
          double scale = 1.0;
          for (int d = 0; d < kMaxStepDoublings; ++d) {
            Evaluation further = Evaluate(problem, x + 2 * scale * dx, &out.evaluations);
            if (!(further.cost < next.cost)) break;
            next = std::move(further);
            scale *= 2;
          }
          decrease = cur.cost - next.cost;
          x += scale * dx;
          cur = std::move(next);
          lambda = std::max(lambda / 10, 1e-12);
          accepted = true;
          break;
        }
        lambda *= 10;
      }
      if (!accepted || decrease <= options.relative_tolerance * cur.cost) break;
    }
    Linearise(problem, x, cur, &a, &g, &out.evaluations, &out.jacobian, &out.irls_weights);
    out.normal = a;
  }
  out.x = x;
  out.cost = cur.cost;
  out.residuals = std::move(cur.r);
  out.valid = std::move(cur.valid);
  return out;
}

}  // namespace shutterlab
