// The response fit's solver on its own (pipeline/hinge_least_squares.h): problems whose minimum is
// known in closed form (linear least squares, a soft one-sided constraint, bounds, rank-deficient
// systems) and two non-linear ones (Rosenbrock's valley, free and bounded; a disc as a soft
// constraint), one step at a time and through the Levenberg-Marquardt loop.
#include <Eigen/Dense>
#include <cmath>
#include <functional>
#include <limits>
#include <vector>

#include "pipeline/hinge_least_squares.h"
#include "test_support.h"

using namespace rigbake;

namespace {

constexpr double kUnbounded = std::numeric_limits<double>::infinity();

// Residuals r(θ) (kept) and slacks c(θ) (hinges), with their Jacobians: the form the fit gives the solver.
struct HingeTestProblem {
  std::function<Eigen::VectorXd(const Eigen::VectorXd&)> residuals;
  std::function<Eigen::MatrixXd(const Eigen::VectorXd&)> jacobian;
  std::function<Eigen::VectorXd(const Eigen::VectorXd&)> slacks;  // empty: no hinges
  std::function<Eigen::MatrixXd(const Eigen::VectorXd&)> slack_jacobian;
};

HingeLinearModel linearize(const HingeTestProblem& problem, const Eigen::VectorXd& theta, double* objective) {
  HingeLinearModel model;
  const Eigen::VectorXd r = problem.residuals(theta);
  const Eigen::MatrixXd j = problem.jacobian(theta);
  *objective = r.squaredNorm();
  for (Eigen::Index i = 0; i < r.size(); ++i) {
    model.rows.push_back(j.row(i).transpose());
    model.rhs.push_back(-r[i]);
  }
  if (problem.slacks) {
    const Eigen::VectorXd c = problem.slacks(theta);
    const Eigen::MatrixXd h = problem.slack_jacobian(theta);
    for (Eigen::Index i = 0; i < c.size(); ++i) {
      model.hinges.push_back(h.row(i).transpose());
      model.slack.push_back(c[i]);
      if (c[i] < 0.0) *objective += c[i] * c[i];
    }
  }
  return model;
}

struct Visit {
  Eigen::VectorXd theta;
  bool measure_only;
};

HingeEvaluator evaluatorOf(const HingeTestProblem& problem, std::vector<Visit>* visits) {
  return [&problem, visits](const Eigen::VectorXd& theta, int evaluation, bool measure_only) {
    CHECK(evaluation == static_cast<int>(visits->size()));
    visits->push_back({theta, measure_only});
    HingeEvaluation out;
    out.model = linearize(problem, theta, &out.objective);
    return out;
  };
}

HingePrior noPrior(Eigen::Index unknowns) {
  return {Eigen::VectorXd::Zero(unknowns), Eigen::VectorXd::Ones(unknowns), 0.0};
}

HingeBounds unbounded(Eigen::Index unknowns) {
  return {Eigen::VectorXd::Constant(unknowns, -kUnbounded), Eigen::VectorXd::Constant(unknowns, kUnbounded)};
}

// A x = b over three rows, two unknowns: the minimum of |A x - b|² is (4/3, 7/3).
HingeTestProblem overdetermined() {
  Eigen::Matrix<double, 3, 2> a;
  a << 1, 0, 0, 1, 1, 1;
  const Eigen::Vector3d b(1, 2, 4);
  HingeTestProblem problem;
  problem.residuals = [a, b](const Eigen::VectorXd& x) -> Eigen::VectorXd { return a * x - b; };
  problem.jacobian = [a](const Eigen::VectorXd&) -> Eigen::MatrixXd { return a; };
  return problem;
}

// One unknown: the residual x - 2, and the hinge k (limit - x) >= 0 (a soft x <= limit).
HingeTestProblem softCeiling(double limit, double k) {
  HingeTestProblem problem;
  problem.residuals = [](const Eigen::VectorXd& x) -> Eigen::VectorXd { return Eigen::VectorXd::Constant(1, x[0] - 2.0); };
  problem.jacobian = [](const Eigen::VectorXd&) -> Eigen::MatrixXd { return Eigen::MatrixXd::Ones(1, 1); };
  problem.slacks = [limit, k](const Eigen::VectorXd& x) -> Eigen::VectorXd { return Eigen::VectorXd::Constant(1, k * (limit - x[0])); };
  problem.slack_jacobian = [k](const Eigen::VectorXd&) -> Eigen::MatrixXd { return Eigen::MatrixXd::Constant(1, 1, -k); };
  return problem;
}

Eigen::VectorXd stepOf(const HingeTestProblem& problem, const Eigen::VectorXd& theta, const HingePrior& prior, const HingeBounds& bounds,
                       double damping) {
  double objective = 0.0;
  return hingeStep(linearize(problem, theta, &objective), theta, prior, bounds, damping);
}

// Rosenbrock's function as residuals 10 (y - x²) and 1 - x: minimum 0 at (1, 1), at the end of a
// curved valley that Gauss-Newton alone overshoots.
HingeTestProblem rosenbrock() {
  HingeTestProblem problem;
  problem.residuals = [](const Eigen::VectorXd& p) -> Eigen::VectorXd { return Eigen::Vector2d(10.0 * (p[1] - p[0] * p[0]), 1.0 - p[0]); };
  problem.jacobian = [](const Eigen::VectorXd& p) -> Eigen::MatrixXd {
    Eigen::MatrixXd j(2, 2);
    j << -20.0 * p[0], 10.0, -1.0, 0.0;
    return j;
  };
  return problem;
}

}  // namespace

TEST_CASE("hinge fit: one step solves linear least squares exactly and the prior is a Tikhonov row per unknown",
          "[hinge-least-squares]") {
  const HingeTestProblem problem = overdetermined();
  const Eigen::VectorXd start = Eigen::VectorXd::Zero(2);
  const Eigen::VectorXd step = stepOf(problem, start, noPrior(2), unbounded(2), 0.0);
  CHECK(step[0] == Approx(4.0 / 3.0).margin(1e-12));
  CHECK(step[1] == Approx(7.0 / 3.0).margin(1e-12));

  // With a prior pulling towards (5, -1), weight 0.5, scales (1, 3): the least-squares solution of A x = b
  // stacked over the rows 0.5 * scale_u * (x_u - target_u) = 0, solved independently by QR.
  const HingePrior prior{Eigen::Vector2d(5.0, -1.0), Eigen::Vector2d(1.0, 3.0), 0.5};
  Eigen::MatrixXd stacked(5, 2);
  stacked << 1, 0, 0, 1, 1, 1, 0.5, 0, 0, 1.5;
  Eigen::VectorXd rhs(5);
  rhs << 1, 2, 4, 0.5 * 5.0, 1.5 * -1.0;
  const Eigen::VectorXd expected = stacked.colPivHouseholderQr().solve(rhs);
  const Eigen::VectorXd with_prior = stepOf(problem, start, prior, unbounded(2), 0.0);
  CHECK(with_prior[0] == Approx(expected[0]).margin(1e-12));
  CHECK(with_prior[1] == Approx(expected[1]).margin(1e-12));
  CHECK((with_prior - Eigen::Vector2d(4.0 / 3.0, 7.0 / 3.0)).norm() > 0.1);  // the prior did pull

  // Marquardt's damping shortens the step along the scaled diagonal: λ = 1 with no prior on a problem
  // whose normal equations are diagonal halves it.
  HingeTestProblem diagonal;
  diagonal.residuals = [](const Eigen::VectorXd& x) -> Eigen::VectorXd { return Eigen::Vector2d(2.0 * x[0] - 2.0, x[1] - 3.0); };
  diagonal.jacobian = [](const Eigen::VectorXd&) -> Eigen::MatrixXd { return Eigen::Vector2d(2.0, 1.0).asDiagonal(); };
  const Eigen::VectorXd damped = stepOf(diagonal, start, noPrior(2), unbounded(2), 1.0);
  CHECK(damped[0] == Approx(0.5).margin(1e-12));
  CHECK(damped[1] == Approx(1.5).margin(1e-12));
}

TEST_CASE("hinge fit: a hinge counts when the optimum violates it and not when it does not", "[hinge-least-squares]") {
  const Eigen::VectorXd start = Eigen::VectorXd::Zero(1);
  // min (x - 2)² + 100 (1 - x)² over x > 1: x = 204 / 202; the hinge holds at the start, so the first
  // solve ignores it, overshoots to 2, and the re-solve takes it in.
  const Eigen::VectorXd active = stepOf(softCeiling(1.0, 10.0), start, noPrior(1), unbounded(1), 0.0);
  CHECK(active[0] == Approx(204.0 / 202.0).margin(1e-12));
  // With the ceiling at 3 the unconstrained minimum holds it: x = 2 exactly, the hinge never enters.
  const Eigen::VectorXd inactive = stepOf(softCeiling(3.0, 10.0), start, noPrior(1), unbounded(1), 0.0);
  CHECK(inactive[0] == Approx(2.0).margin(1e-12));
  // Violated at the start (x = 5 > 3), so in the first solve (which stops at 2.99); the re-solve sees
  // the step no longer violates it and releases it: x = 2.
  const Eigen::VectorXd released = stepOf(softCeiling(3.0, 10.0), Eigen::VectorXd::Constant(1, 5.0), noPrior(1), unbounded(1), 0.0);
  CHECK(5.0 + released[0] == Approx(2.0).margin(1e-12));
  // Capped at one solve the step stands as it is after the first: the hinge still in.
  double objective = 0.0;
  const HingeTestProblem ceiling = softCeiling(3.0, 10.0);
  const Eigen::VectorXd five = Eigen::VectorXd::Constant(1, 5.0);
  const Eigen::VectorXd capped = hingeStep(linearize(ceiling, five, &objective), five, noPrior(1), unbounded(1), 0.0, 1);
  CHECK(5.0 + capped[0] == Approx((2.0 + 100.0 * 3.0) / 101.0).margin(1e-12));
}

TEST_CASE("hinge fit: sparse hinges step as the same hinges dense, beside dense ones", "[hinge-least-squares]") {
  // Five unknowns pulled to 1, 2, ..., 5 by kept rows; hinges x0 + x3 <= 4 (violated by the pull),
  // x1 - x4 >= 0 (violated) and x2 <= 10 (never): each once dense and once sparse, in either mix.
  const Eigen::Index n = 5;
  HingeLinearModel base;
  for (Eigen::Index u = 0; u < n; ++u) {
    base.rows.push_back(Eigen::VectorXd::Unit(n, u));
    base.rhs.push_back(static_cast<double>(u + 1));
  }
  const std::vector<SparseRow> sparse = {{{{0, -3.0}, {3, -3.0}}}, {{{1, 2.0}, {4, -2.0}}}, {{{2, -1.0}}}};
  const std::vector<double> slack = {3.0 * 4.0, 0.0, 10.0};
  auto dense = [&](const SparseRow& row) {
    Eigen::VectorXd out = Eigen::VectorXd::Zero(n);
    for (const auto& [u, value] : row.entries) out[u] = value;
    return out;
  };
  const Eigen::VectorXd theta = Eigen::VectorXd::Zero(n);
  HingeLinearModel all_dense = base, all_sparse = base, mixed = base;
  for (size_t h = 0; h < sparse.size(); ++h) {
    all_dense.hinges.push_back(dense(sparse[h]));
    all_dense.slack.push_back(slack[h]);
    all_sparse.sparse_hinges.push_back(sparse[h]);
    all_sparse.sparse_slack.push_back(slack[h]);
    if (h == 1) {
      mixed.hinges.push_back(dense(sparse[h]));
      mixed.slack.push_back(slack[h]);
    } else {
      mixed.sparse_hinges.push_back(sparse[h]);
      mixed.sparse_slack.push_back(slack[h]);
    }
  }
  const Eigen::VectorXd expected = hingeStep(all_dense, theta, noPrior(n), unbounded(n), 0.0);
  // The hinges pulled the step: x0 + x3 = 1 + 4 unpulled, and x1 < x4 unpulled.
  CHECK(expected[0] + expected[3] < 5.0 - 0.1);
  CHECK(expected[4] - expected[1] < 3.0 - 0.1);
  CHECK(expected[2] == Approx(3.0).margin(1e-12));
  for (const HingeLinearModel* model : {&all_sparse, &mixed}) {
    const Eigen::VectorXd step = hingeStep(*model, theta, noPrior(n), unbounded(n), 0.0);
    for (Eigen::Index u = 0; u < n; ++u) CHECK(step[u] == Approx(expected[u]).margin(1e-12));
  }
}

TEST_CASE("hinge fit: a bound holds an unknown and the others are solved again with it held", "[hinge-least-squares]") {
  // min (x - 5)² with x <= 2: exactly on the bound.
  HingeTestProblem single;
  single.residuals = [](const Eigen::VectorXd& x) -> Eigen::VectorXd { return Eigen::VectorXd::Constant(1, x[0] - 5.0); };
  single.jacobian = [](const Eigen::VectorXd&) -> Eigen::MatrixXd { return Eigen::MatrixXd::Ones(1, 1); };
  const HingeBounds ceiling{Eigen::VectorXd::Constant(1, -kUnbounded), Eigen::VectorXd::Constant(1, 2.0)};
  CHECK(stepOf(single, Eigen::VectorXd::Zero(1), noPrior(1), ceiling, 0.0)[0] == 2.0);
  // Coupled: residuals x - 3 and y - x; free, (3, 3); with x <= 1 held, y follows x to 1, not 3.
  HingeTestProblem coupled;
  coupled.residuals = [](const Eigen::VectorXd& p) -> Eigen::VectorXd { return Eigen::Vector2d(p[0] - 3.0, p[1] - p[0]); };
  coupled.jacobian = [](const Eigen::VectorXd&) -> Eigen::MatrixXd {
    Eigen::MatrixXd j(2, 2);
    j << 1, 0, -1, 1;
    return j;
  };
  const HingeBounds x_ceiling{Eigen::Vector2d(-kUnbounded, -kUnbounded), Eigen::Vector2d(1.0, kUnbounded)};
  const Eigen::VectorXd held = stepOf(coupled, Eigen::VectorXd::Zero(2), noPrior(2), x_ceiling, 0.0);
  CHECK(held[0] == 1.0);
  CHECK(held[1] == Approx(1.0).margin(1e-12));
  // A lower bound the same way, from a start inside: min (x + 4)² with x >= -1.5.
  HingeTestProblem below;
  below.residuals = [](const Eigen::VectorXd& x) -> Eigen::VectorXd { return Eigen::VectorXd::Constant(1, x[0] + 4.0); };
  below.jacobian = single.jacobian;
  const HingeBounds floor{Eigen::VectorXd::Constant(1, -1.5), Eigen::VectorXd::Constant(1, kUnbounded)};
  CHECK(0.5 + stepOf(below, Eigen::VectorXd::Constant(1, 0.5), noPrior(1), floor, 0.0)[0] == -1.5);
}

TEST_CASE("hinge fit: a bound one step runs into is released by the next when the minimum is inside", "[hinge-least-squares]") {
  // r = x² - 1 from x = 0.3: Gauss-Newton's first step reaches 1.82, past the bound 1.2, so it stops at
  // 1.2 (a lower objective: kept); the next step starts free and goes back inside, to the minimum at 1.
  HingeTestProblem square;
  square.residuals = [](const Eigen::VectorXd& x) -> Eigen::VectorXd { return Eigen::VectorXd::Constant(1, x[0] * x[0] - 1.0); };
  square.jacobian = [](const Eigen::VectorXd& x) -> Eigen::MatrixXd { return Eigen::MatrixXd::Constant(1, 1, 2.0 * x[0]); };
  const HingeBounds bounds{Eigen::VectorXd::Constant(1, -10.0), Eigen::VectorXd::Constant(1, 1.2)};
  std::vector<Visit> visits;
  HingeSolveOptions options;
  options.iterations = 20;
  options.initial_damping = 1e-9;
  const HingeSolveResult result =
      solveHingeLeastSquares(Eigen::VectorXd::Constant(1, 0.3), noPrior(1), bounds, evaluatorOf(square, &visits), options);
  REQUIRE(visits.size() >= 3);
  CHECK(visits[1].theta[0] == Approx(1.2).margin(1e-15));
  CHECK(visits[2].theta[0] < 1.2 - 0.1);
  CHECK(result.theta[0] == Approx(1.0).margin(1e-9));
  CHECK(result.objective < 1e-16);
}

TEST_CASE("hinge fit: rank-deficient and empty systems give finite steps", "[hinge-least-squares]") {
  // x + y = 2 alone: singular normal equations. Undamped and unregularized the step still solves the
  // row (LDLT with pivoting zeroes the null-space part) and stays finite.
  HingeTestProblem sum;
  sum.residuals = [](const Eigen::VectorXd& p) -> Eigen::VectorXd { return Eigen::VectorXd::Constant(1, p[0] + p[1] - 2.0); };
  sum.jacobian = [](const Eigen::VectorXd&) -> Eigen::MatrixXd { return Eigen::MatrixXd::Ones(1, 2); };
  const Eigen::VectorXd singular = stepOf(sum, Eigen::VectorXd::Zero(2), noPrior(2), unbounded(2), 0.0);
  REQUIRE(singular.allFinite());
  CHECK(singular[0] + singular[1] == Approx(2.0).margin(1e-12));
  // A small prior towards 0 picks the symmetric solution: min (x + y - 2)² + w² (x² + y²) is at
  // x = y = 2 / (2 + w²).
  const double w = 0.1;
  const HingePrior prior{Eigen::VectorXd::Zero(2), Eigen::VectorXd::Ones(2), w};
  const Eigen::VectorXd regular = stepOf(sum, Eigen::VectorXd::Zero(2), prior, unbounded(2), 0.0);
  CHECK(regular[0] == Approx(2.0 / (2.0 + w * w)).margin(1e-12));
  CHECK(regular[1] == Approx(2.0 / (2.0 + w * w)).margin(1e-12));
  // An unknown no row moves: the prior alone sets it (from 0.3 to its target 0.7), and Marquardt's
  // damping scales with the prior's diagonal (λ = 1 halves the step); with no prior either, the floored
  // diagonal keeps the step finite and zero.
  HingeTestProblem first_only;
  first_only.residuals = [](const Eigen::VectorXd& p) -> Eigen::VectorXd { return Eigen::VectorXd::Constant(1, p[0] - 1.0); };
  first_only.jacobian = [](const Eigen::VectorXd&) -> Eigen::MatrixXd { return Eigen::RowVector2d(1.0, 0.0); };
  const Eigen::Vector2d from(0.0, 0.3);
  const HingePrior pull{Eigen::Vector2d(0.0, 0.7), Eigen::Vector2d(1e-3, 1.0), 0.5};
  CHECK(stepOf(first_only, from, pull, unbounded(2), 0.0)[1] == Approx(0.4).margin(1e-12));
  CHECK(stepOf(first_only, from, pull, unbounded(2), 1.0)[1] == Approx(0.2).margin(1e-12));
  const Eigen::VectorXd untouched = stepOf(first_only, from, noPrior(2), unbounded(2), 1.0);
  REQUIRE(untouched.allFinite());
  CHECK(untouched[1] == 0.0);
  CHECK(untouched[0] == Approx(0.5).margin(1e-9));
  // No rows and no hinges at all: only the prior moves anything.
  const Eigen::VectorXd empty = hingeStep(HingeLinearModel{}, from, pull, unbounded(2), 0.0);
  CHECK(empty[0] == Approx(0.0).margin(1e-15));
  CHECK(empty[1] == Approx(0.4).margin(1e-12));
}

TEST_CASE("hinge fit: Levenberg-Marquardt finds Rosenbrock's minimum, free and against a bound", "[hinge-least-squares]") {
  const HingeTestProblem problem = rosenbrock();
  HingeSolveOptions options;
  options.iterations = 200;
  options.initial_damping = 1e-3;
  options.settled_share = 0.0;  // to the end: the test asks for the minimum, not for when to stop
  std::vector<Visit> visits;
  const HingeSolveResult free =
      solveHingeLeastSquares(Eigen::Vector2d(-1.2, 1.0), noPrior(2), unbounded(2), evaluatorOf(problem, &visits), options);
  CHECK(free.theta[0] == Approx(1.0).margin(1e-6));
  CHECK(free.theta[1] == Approx(1.0).margin(1e-6));
  CHECK(free.objective < 1e-12);
  CHECK(free.evaluations == static_cast<int>(visits.size()));
  // x <= 0.5: along the bound the valley's floor is y = x², and (1 - x)² falls towards the bound, so
  // the minimum is (0.5, 0.25) with objective 0.25.
  const HingeBounds ceiling{Eigen::Vector2d(-kUnbounded, -kUnbounded), Eigen::Vector2d(0.5, kUnbounded)};
  visits.clear();
  const HingeSolveResult bounded =
      solveHingeLeastSquares(Eigen::Vector2d(-1.2, 1.0), noPrior(2), ceiling, evaluatorOf(problem, &visits), options);
  CHECK(bounded.theta[0] == Approx(0.5).margin(1e-9));
  CHECK(bounded.theta[1] == Approx(0.25).margin(1e-6));
  CHECK(bounded.objective == Approx(0.25).margin(1e-9));
}

TEST_CASE("hinge fit: a disc as a soft constraint on a non-linear hinge", "[hinge-least-squares]") {
  // min (x - 2)² + (y - 2)² with the hinge k (1 - x² - y²) >= 0. By symmetry x = y = a with
  // 4 (a - 2) + 8 k² a (2a² - 1) = 0, solved here by bisection on [1/sqrt 2, 2].
  const double k = 10.0;
  HingeTestProblem problem;
  problem.residuals = [](const Eigen::VectorXd& p) -> Eigen::VectorXd { return p - Eigen::Vector2d(2.0, 2.0); };
  problem.jacobian = [](const Eigen::VectorXd&) -> Eigen::MatrixXd { return Eigen::Matrix2d::Identity(); };
  problem.slacks = [k](const Eigen::VectorXd& p) -> Eigen::VectorXd { return Eigen::VectorXd::Constant(1, k * (1.0 - p.squaredNorm())); };
  problem.slack_jacobian = [k](const Eigen::VectorXd& p) -> Eigen::MatrixXd { return -2.0 * k * p.transpose(); };
  auto derivative = [k](double a) { return 4.0 * (a - 2.0) + 8.0 * k * k * a * (2.0 * a * a - 1.0); };
  double low = std::sqrt(0.5), high = 2.0;
  for (int i = 0; i < 200; ++i) (derivative(0.5 * (low + high)) > 0.0 ? high : low) = 0.5 * (low + high);
  const double a = 0.5 * (low + high);
  HingeSolveOptions options;
  options.iterations = 100;
  options.initial_damping = 1e-3;
  options.settled_share = 0.0;
  std::vector<Visit> visits;
  const HingeSolveResult result =
      solveHingeLeastSquares(Eigen::Vector2d(0.0, 0.5), noPrior(2), unbounded(2), evaluatorOf(problem, &visits), options);
  CHECK(result.theta[0] == Approx(a).margin(1e-7));
  CHECK(result.theta[1] == Approx(a).margin(1e-7));
  CHECK(result.theta.squaredNorm() > 1.0);  // a soft constraint: the optimum sits just outside
}

TEST_CASE("hinge fit: the loop evaluates iterations + 1 times at most, the last only to measure, and keeps the best",
          "[hinge-least-squares]") {
  const HingeTestProblem problem = rosenbrock();
  HingeSolveOptions options;
  options.iterations = 3;
  options.initial_damping = 1e-3;
  std::vector<Visit> visits;
  const HingeSolveResult result =
      solveHingeLeastSquares(Eigen::Vector2d(-1.2, 1.0), noPrior(2), unbounded(2), evaluatorOf(problem, &visits), options);
  REQUIRE(visits.size() == 4);
  CHECK(!visits[0].measure_only);
  CHECK(!visits[1].measure_only);
  CHECK(!visits[2].measure_only);
  CHECK(visits[3].measure_only);
  // The result is the evaluated point with the lowest objective.
  double lowest = std::numeric_limits<double>::infinity();
  int best = -1;
  for (size_t i = 0; i < visits.size(); ++i) {
    double objective = 0.0;
    linearize(problem, visits[i].theta, &objective);
    if (objective < lowest) {
      lowest = objective;
      best = static_cast<int>(i);
    }
  }
  CHECK(result.best_evaluation == best);
  CHECK(result.objective == lowest);
  CHECK(result.theta == visits[static_cast<size_t>(best)].theta);
  // A linear problem is solved by the first step; the next gains nothing and ends the loop early.
  visits.clear();
  options.iterations = 10;
  options.initial_damping = 1e-9;
  const HingeSolveResult linear =
      solveHingeLeastSquares(Eigen::VectorXd::Zero(2), noPrior(2), unbounded(2), evaluatorOf(overdetermined(), &visits), options);
  CHECK(linear.evaluations < 11);
  CHECK(linear.theta[0] == Approx(4.0 / 3.0).margin(1e-9));
  CHECK(linear.theta[1] == Approx(7.0 / 3.0).margin(1e-9));
}
