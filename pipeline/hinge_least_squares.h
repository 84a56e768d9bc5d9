// Levenberg-Marquardt least squares with one-sided rows ("hinges") and bounds on the unknowns, the
// solver under the muscles' response fit (pipeline/response_fit.h) and nothing specific to it.
//
// The objective is a sum of squares of three kinds of residual:
//   - kept rows, always in the sum;
//   - hinges, one-sided: a hinge h holds while its slack c_h(θ) >= 0 and adds c_h² only while it is
//     violated (a squared hinge loss, as a soft inequality constraint);
//   - a prior, weight · scale_u · (θ_u - target_u) per unknown (Tikhonov regularization towards a start).
// Each step linearizes the residuals at the best point so far (the caller evaluates them and their
// Jacobian rows), and minimizes that model plus Marquardt's damping λ · diag(JᵀJ) (Marquardt, "An
// Algorithm for Least-Squares Estimation of Nonlinear Parameters", SIAM J. Appl. Math. 11, 1963; Nocedal
// and Wright, Numerical Optimization, 2nd ed., ch. 10.3): the model is piecewise quadratic in the step,
// so the hinges in it are found by an active set that re-solves with the hinges the step would leave
// violated until it settles (a semismooth Newton method), and an unknown the step would carry past its
// bound is held at the bound and the others solved again (an active set on the bounds, never released
// within one step: the next step starts free). A step that does not lower the objective is taken back
// and the damping raised, one that does lowers it (Marquardt's rule, factors 4 and 3).
#pragma once

#include <Eigen/Core>
#include <functional>
#include <utility>
#include <vector>

namespace rigbake {

// A row given by its nonzero entries, (unknown, value) with the unknowns ascending and distinct.
struct SparseRow {
  std::vector<std::pair<Eigen::Index, double>> entries;
  double dot(const Eigen::VectorXd& x) const {
    double sum = 0.0;
    for (const auto& [u, value] : entries) sum += value * x[u];
    return sum;
  }
};

// The residuals linearized at a point θ. Kept row i asks rows[i] · step = rhs[i] (rhs is minus the
// residual at θ); hinge h asks slack[h] + hinges[h] · step >= 0 and counts its square while that fails.
// Every row has as many entries as there are unknowns. Hinges that touch a few of many unknowns may
// come sparse instead (sparse_hinges, sparse_slack; the response fit's roughness cap has tens of thousands,
// each on a few muscles' keys): the same, their squares summed after the dense hinges'.
struct HingeLinearModel {
  std::vector<Eigen::VectorXd> rows;
  std::vector<double> rhs;
  std::vector<Eigen::VectorXd> hinges;
  std::vector<double> slack;
  std::vector<SparseRow> sparse_hinges;
  std::vector<double> sparse_slack;
};

// The prior's residual for unknown u: weight · (θ_u - target[u]) · scale[u]. `scale` says how strongly
// u moves the other residuals (a weak unknown is held closer to its target); it must be positive.
struct HingePrior {
  Eigen::VectorXd target, scale;
  double weight = 0.0;
};

// Bounds lower[u] <= θ_u <= upper[u] (lower <= upper).
struct HingeBounds {
  Eigen::VectorXd lower, upper;
};

// The step from θ that minimizes `model` (kept rows, and the hinges in its active set), the prior and
// the damping λ · diag, each unknown kept within `bounds`. The diagonal the damping scales is the
// normal equations' with the prior and the hinges violated at θ, floored at 1e-12 so an unknown no row
// moves is damped too. At most `hinge_passes` solves for the hinges' active set; at the cap the last
// step is returned as it stands (the objective still judges it).
Eigen::VectorXd hingeStep(const HingeLinearModel& model, const Eigen::VectorXd& theta, const HingePrior& prior,
                          const HingeBounds& bounds, double damping, int hinge_passes = 8);

struct HingeSolveOptions {
  // Evaluations after the first: each but the last is followed by a step. The last evaluation only
  // measures (its model's rows and hinges are not needed).
  int iterations = 6;
  // λ before the first step; the first step, after an evaluation that lowers the objective, is taken at
  // a third of it.
  double initial_damping = 20.0;
  int hinge_passes = 8;
  // A step that gains less than this share of the objective ends the solve.
  double settled_share = 1e-6;
};

// One evaluation at θ: the residuals linearized there and the objective without the prior's terms (the
// kept residuals' squares and every violated hinge's square, candidates for the model or not). When
// `measure_only` is set the model's rows and hinges may be left empty.
struct HingeEvaluation {
  HingeLinearModel model;
  double objective = 0.0;
};

struct HingeSolveResult {
  Eigen::VectorXd theta;  // the best point evaluated
  double objective = 0.0;  // its objective, prior included
  int best_evaluation = -1;  // which evaluation (from 0) it was; -1 when none was finite
  int evaluations = 0;
};

// evaluate(θ, evaluation, measure_only) is called for evaluation = 0, 1, ... at `start`, then at each
// step's point. Deterministic: the same calls in the same order for the same inputs.
using HingeEvaluator = std::function<HingeEvaluation(const Eigen::VectorXd& theta, int evaluation, bool measure_only)>;
HingeSolveResult solveHingeLeastSquares(const Eigen::VectorXd& start, const HingePrior& prior, const HingeBounds& bounds,
                                        const HingeEvaluator& evaluate, const HingeSolveOptions& options = {});

}  // namespace rigbake
