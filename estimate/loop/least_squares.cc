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
void Linearise(const RobustProblem& problem, const Eigen::VectorXd& x, const Evaluation& at,
               Eigen::MatrixXd* a, Eigen::VectorXd* g, int* evaluations,
               Eigen::MatrixXd* jacobian = nullptr, Eigen::VectorXd* irls_weights = nullptr) {
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
  for (Eigen::Index i = 0; i < n; ++i) {
    const double w = problem.weights[i];
    if (w <= 0 || !ok[i] || !at.valid[i]) {
      jac.middleRows(2 * i, 2).setZero();
      continue;
    }
    const double s = std::sqrt(at.r[2 * i] * at.r[2 * i] + at.r[2 * i + 1] * at.r[2 * i + 1]);
    const double wh = w * HuberWeight(s, problem.huber_delta);
    if (irls_weights) (*irls_weights)[i] = wh;
    const auto j = jac.middleRows(2 * i, 2);
    a->noalias() += wh * j.transpose() * j;
    g->noalias() += wh * j.transpose() * at.r.segment(2 * i, 2);
  }
}

}  // namespace

RobustSolution SolveRobust(const RobustProblem& problem, const Eigen::VectorXd& x0,
                           const RobustOptions& options) {
  SHUTTERLAB_CHECK(problem.steps.size() == x0.size()) << "one step per parameter";
  RobustSolution out;
  Eigen::VectorXd x = x0;
  Evaluation cur = Evaluate(problem, x, &out.evaluations);
  const Eigen::Index p = x.size();
  Eigen::MatrixXd a;
  Eigen::VectorXd g;
  if (p > 0) {
    double lambda = 1e-4;
    for (int it = 0; it < options.max_iterations; ++it) {
      out.iterations = it + 1;
      Linearise(problem, x, cur, &a, &g, &out.evaluations);
      bool accepted = false;
      double decrease = 0.0;
      while (lambda < 1e12) {
        Eigen::MatrixXd damped = a;
        for (Eigen::Index k = 0; k < p; ++k) {
          damped(k, k) += lambda * std::max(a(k, k), 1e-12 * (1.0 + a.diagonal().maxCoeff()));
        }
        const Eigen::VectorXd dx = damped.ldlt().solve(g);
        if (!dx.allFinite()) {
          lambda *= 10;
          continue;
        }
        const Evaluation next = Evaluate(problem, x + dx, &out.evaluations);
        if (next.cost < cur.cost) {
          decrease = cur.cost - next.cost;
          x += dx;
          cur = next;
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
