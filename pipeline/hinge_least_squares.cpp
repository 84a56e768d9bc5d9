// Levenberg-Marquardt with hinges and bounds (pipeline/hinge_least_squares.h, which gives the method and
// its sources).
#include "pipeline/hinge_least_squares.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <utility>

namespace rigbake {
namespace {

// `rows` (those with keep[r] set, or all when keep is null) as the rows of one matrix, in their order:
// the normal equations' JᵀJ is then one blocked product instead of a rank-one update per row.
Eigen::MatrixXd stackRows(const std::vector<Eigen::VectorXd>& rows, const std::vector<char>* keep, Eigen::Index columns) {
  Eigen::Index count = 0;
  for (size_t r = 0; r < rows.size(); ++r) count += keep == nullptr || (*keep)[r];
  Eigen::MatrixXd stacked(count, columns);
  Eigen::Index next = 0;
  for (size_t r = 0; r < rows.size(); ++r) {
    if (keep == nullptr || (*keep)[r]) stacked.row(next++) = rows[r].transpose();
  }
  return stacked;
}

// Adds rowsᵀ rows to the lower triangle of `normal`. Eigen's blocked product divides by the inner
// size, so no rows is no update.
void addGram(const Eigen::MatrixXd& rows, Eigen::MatrixXd* normal) {
  if (rows.rows() > 0) normal->selfadjointView<Eigen::Lower>().rankUpdate(rows.transpose());
}

// Adds the sparse rows with keep[r] set, rowᵀ row each, to the lower triangle of `normal`; and minus
// row times its slack to `gradient` when that is given.
void addSparseGram(const std::vector<SparseRow>& rows, const std::vector<char>& keep, const std::vector<double>& slack,
                   Eigen::MatrixXd* normal, Eigen::VectorXd* gradient) {
  for (size_t r = 0; r < rows.size(); ++r) {
    if (!keep[r]) continue;
    const auto& entries = rows[r].entries;
    for (size_t a = 0; a < entries.size(); ++a) {
      for (size_t b = 0; b <= a; ++b) (*normal)(entries[a].first, entries[b].first) += entries[a].second * entries[b].second;
      if (gradient) (*gradient)[entries[a].first] -= entries[a].second * slack[r];
    }
  }
}

// The damped normal equations of the kept rows and the prior at θ (lower triangle, symmetric in use).
struct NormalEquations {
  Eigen::MatrixXd normal;
  Eigen::VectorXd gradient;  // the right-hand side: Jᵀ rhs and the prior's pull
};

// Minimizes the model with the hinges in `active` as kept rows, each unknown within its bounds: an
// unknown the solution carries past a bound is held there and the free ones solved again with the held
// ones' pull, until none crosses (at most one pass per unknown, as each pass holds one more).
Eigen::VectorXd boundedStep(const NormalEquations& equations, const HingeLinearModel& model, const std::vector<char>& active,
                            const std::vector<char>& sparse_active, const Eigen::VectorXd& theta, const HingeBounds& bounds) {
  const Eigen::Index unknowns = theta.size();
  Eigen::MatrixXd n = equations.normal;
  const Eigen::MatrixXd kept_hinges = stackRows(model.hinges, &active, unknowns);
  Eigen::VectorXd kept_slack(kept_hinges.rows());
  for (size_t h = 0, next = 0; h < model.hinges.size(); ++h) {
    if (active[h]) kept_slack[static_cast<Eigen::Index>(next++)] = model.slack[h];
  }
  addGram(kept_hinges, &n);
  Eigen::VectorXd g = equations.gradient - kept_hinges.transpose() * kept_slack;
  addSparseGram(model.sparse_hinges, sparse_active, model.sparse_slack, &n, &g);
  n.triangularView<Eigen::StrictlyUpper>() = n.transpose();
  std::vector<int> held(static_cast<size_t>(unknowns), 0);  // 0 free, -1 at its lower bound, +1 at its upper bound
  auto heldAt = [&](Eigen::Index u) { return held[u] < 0 ? bounds.lower[u] : bounds.upper[u]; };
  Eigen::VectorXd step = Eigen::VectorXd::Zero(unknowns);
  for (Eigen::Index pass = 0; pass <= unknowns; ++pass) {
    std::vector<Eigen::Index> free;
    for (Eigen::Index u = 0; u < unknowns; ++u) {
      step[u] = held[u] != 0 ? heldAt(u) - theta[u] : 0.0;
      if (held[u] == 0) free.push_back(u);
    }
    if (!free.empty()) {
      const Eigen::Index count = static_cast<Eigen::Index>(free.size());
      Eigen::MatrixXd n_free(count, count);
      Eigen::VectorXd g_free(count);
      const Eigen::VectorXd pushed = g - n * step;  // the held unknowns' pull on the free ones
      for (Eigen::Index a = 0; a < count; ++a) {
        g_free[a] = pushed[free[a]];
        for (Eigen::Index b = 0; b < count; ++b) n_free(a, b) = n(free[a], free[b]);
      }
      // LDLᵀ with pivoting: a singular system (an unknown nothing moves, undamped and unregularized)
      // still gives a finite least-squares step, zero along the null space.
      const Eigen::VectorXd x = n_free.ldlt().solve(g_free);
      for (Eigen::Index a = 0; a < count; ++a) step[free[a]] = x[a];
    }
    bool changed = false;
    for (Eigen::Index u : free) {
      if (theta[u] + step[u] < bounds.lower[u] - 1e-12) {
        held[u] = -1;
        changed = true;
      } else if (theta[u] + step[u] > bounds.upper[u] + 1e-12) {
        held[u] = 1;
        changed = true;
      }
    }
    if (!changed) break;
  }
  return step;
}

}  // namespace

Eigen::VectorXd hingeStep(const HingeLinearModel& model, const Eigen::VectorXd& theta, const HingePrior& prior,
                          const HingeBounds& bounds, double damping, int hinge_passes) {
  const Eigen::Index unknowns = theta.size();
  assert(model.rows.size() == model.rhs.size() && model.hinges.size() == model.slack.size());
  assert(model.sparse_hinges.size() == model.sparse_slack.size());
  const Eigen::MatrixXd rows = stackRows(model.rows, nullptr, unknowns);
  NormalEquations equations;
  equations.normal = Eigen::MatrixXd::Zero(unknowns, unknowns);
  addGram(rows, &equations.normal);
  equations.gradient = rows.transpose() * Eigen::Map<const Eigen::VectorXd>(model.rhs.data(), rows.rows());
  for (Eigen::Index u = 0; u < unknowns; ++u) {
    // weight / (1 / scale) rather than weight · scale: the response fit formed it so before this solver
    // had a file of its own, and the bakes stayed byte-identical through the move.
    const double unit = 1.0 / prior.scale[u];
    const double w = prior.weight / unit;
    equations.normal(u, u) += w * w;
    equations.gradient[u] += w * w * (prior.target[u] - theta[u]);
  }
  // Marquardt's damping scales with the diagonal the step starts from: the hinges violated at θ are in
  // it, so an unknown that only a violated hinge moves is damped like the others.
  std::vector<char> active(model.hinges.size(), 0);
  for (size_t h = 0; h < model.hinges.size(); ++h) active[h] = model.slack[h] < 0.0;
  std::vector<char> sparse_active(model.sparse_hinges.size(), 0);
  for (size_t h = 0; h < model.sparse_hinges.size(); ++h) sparse_active[h] = model.sparse_slack[h] < 0.0;
  Eigen::MatrixXd start = equations.normal;
  addGram(stackRows(model.hinges, &active, unknowns), &start);
  addSparseGram(model.sparse_hinges, sparse_active, model.sparse_slack, &start, nullptr);
  const Eigen::VectorXd damping_diagonal = damping * start.diagonal().cwiseMax(1e-12);
  for (Eigen::Index u = 0; u < unknowns; ++u) equations.normal(u, u) += damping_diagonal[u];

  // The hinges' active set: those the step would leave violated, until it settles.
  Eigen::VectorXd step = boundedStep(equations, model, active, sparse_active, theta, bounds);
  for (int pass = 1; pass < hinge_passes; ++pass) {
    bool changed = false;
    for (size_t h = 0; h < model.hinges.size(); ++h) {
      const char violated = model.slack[h] + model.hinges[h].dot(step) < 0.0;
      if (violated != active[h]) {
        active[h] = violated;
        changed = true;
      }
    }
    for (size_t h = 0; h < model.sparse_hinges.size(); ++h) {
      const char violated = model.sparse_slack[h] + model.sparse_hinges[h].dot(step) < 0.0;
      if (violated != sparse_active[h]) {
        sparse_active[h] = violated;
        changed = true;
      }
    }
    if (!changed) break;
    step = boundedStep(equations, model, active, sparse_active, theta, bounds);
  }
  return step;
}

HingeSolveResult solveHingeLeastSquares(const Eigen::VectorXd& start, const HingePrior& prior, const HingeBounds& bounds,
                                        const HingeEvaluator& evaluate, const HingeSolveOptions& options) {
  const Eigen::Index unknowns = start.size();
  assert(prior.target.size() == unknowns && prior.scale.size() == unknowns);
  assert(bounds.lower.size() == unknowns && bounds.upper.size() == unknowns);
  HingeSolveResult result;
  Eigen::VectorXd theta = start;
  result.theta = start;
  result.objective = std::numeric_limits<double>::infinity();
  HingeLinearModel best_model;
  double damping = options.initial_damping;
  for (int iteration = 0; iteration <= options.iterations; ++iteration) {
    const bool measure_only = iteration == options.iterations;
    HingeEvaluation evaluation = evaluate(theta, iteration, measure_only);
    ++result.evaluations;
    double objective = evaluation.objective;
    for (Eigen::Index u = 0; u < unknowns; ++u) {
      const double prior_residual = prior.weight * (theta[u] - prior.target[u]) * prior.scale[u];
      objective += prior_residual * prior_residual;
    }
    const bool better = objective < result.objective;
    // Each evaluation costs as much as the first: a gain this small is not worth another.
    const bool settled = better && result.objective - objective < options.settled_share * result.objective;
    if (better) {
      result.objective = objective;
      result.theta = theta;
      result.best_evaluation = iteration;
      best_model = std::move(evaluation.model);
      damping = std::max(damping / 3.0, 1e-6);
    } else {
      theta = result.theta;
      damping *= 4.0;
    }
    if (measure_only || settled) break;
    theta += hingeStep(best_model, theta, prior, bounds, damping, options.hinge_passes);
  }
  return result;
}

}  // namespace rigbake
