// Natural-parameter continuation (natural_parameter.hpp), the second mode of the continuation
// layer, against closed forms: the real root of x³ + x = λ (Cardano), the fold of x² = 1 − λ
// (which natural stepping cannot pass and pseudo-arclength passes at λ = 1), the step rule's
// bound on how close a stalled branch gets to a wall, and the goal and time-budget stops.
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include <wbm/solvers/continuation.hpp>
#include <wbm/solvers/linearization.hpp>
#include <wbm/solvers/natural_parameter.hpp>
#include <wbm/solvers/newton.hpp>

namespace {

using namespace wbm::solvers;

// R(x, λ) = x³ + x − λ: one real root for every λ, x(λ) = ∛(λ/2 + √D) + ∛(λ/2 − √D),
// D = λ²/4 + 1/27 (Cardano).
struct CubicPath {
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x, double lambda) const {
    return Eigen::VectorXd::Constant(1, x(0) * x(0) * x(0) + x(0) - lambda);
  }
  [[nodiscard]] Linearization linearize(const Eigen::VectorXd& x, double lambda) const {
    return {residual(x, lambda), Eigen::MatrixXd::Constant(1, 1, 3.0 * x(0) * x(0) + 1.0), Eigen::VectorXd::Constant(1, -1.0)};
  }
};
double cardano(double lambda) {
  const double d = std::sqrt(lambda * lambda / 4.0 + 1.0 / 27.0);
  return std::cbrt(lambda / 2.0 + d) + std::cbrt(lambda / 2.0 - d);
}

// R(x, λ) = x² + λ − 1: x = √(1 − λ) on the upper sheet, a fold at λ = 1 (x = 0).
struct Fold {
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x, double lambda) const {
    return Eigen::VectorXd::Constant(1, x(0) * x(0) + lambda - 1.0);
  }
  [[nodiscard]] Linearization linearize(const Eigen::VectorXd& x, double lambda) const {
    return {residual(x, lambda), Eigen::MatrixXd::Constant(1, 1, 2.0 * x(0)), Eigen::VectorXd::Constant(1, 1.0)};
  }
};

// Newton at fixed λ as the corrector.
template <class S>
auto newton_corrector(const S& s, double tolerance = 1e-12) {
  return [&s, tolerance](double lambda, Eigen::VectorXd guess) {
    struct Fixed {
      const S* s;
      double lambda;
      [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x) const { return s->residual(x, lambda); }
      [[nodiscard]] Eigen::MatrixXd jacobian(const Eigen::VectorXd& x) const { return s->linearize(x, lambda).jacobian; }
    };
    return to_correction(newton(Fixed{&s, lambda}, std::move(guess), {.tolerance = tolerance, .max_iterations = 8}));
  };
}

TEST(NaturalParameter, FollowsTheCubicAndLandsOnTheListedValuesAndTheRangeEnd) {
  const CubicPath cubic;
  NaturalParameterOptions o;
  o.parameter_min = 0.0;
  o.parameter_max = 2.0;
  o.initial_step = 0.05;
  o.max_step = 0.25;
  o.land_on = {0.3, 1.7, 5.0};  // 5 lies outside the range: never reached
  const Branch b = natural_parameter(newton_corrector(cubic), Eigen::VectorXd::Zero(1), 0.0, o);
  ASSERT_EQ(b.stop, StopReason::RangeReached) << b.message;
  EXPECT_EQ(b.points.back().parameter, 2.0);
  for (const auto& p : b.points) EXPECT_NEAR(p.x(0), cardano(p.parameter), 1e-11) << "λ = " << p.parameter;
  ASSERT_EQ(b.landings.size(), 2U);
  EXPECT_EQ(b.landings[0].parameter, 0.3);
  EXPECT_EQ(b.landings[1].parameter, 1.7);
  EXPECT_NEAR(b.landings[1].x(0), cardano(1.7), 1e-11);
  // The steps grew (the corrector needs few iterations) but never beyond max_step.
  double largest = 0.0;
  for (size_t i = 1; i < b.points.size(); ++i) largest = std::max(largest, b.points[i].parameter - b.points[i - 1].parameter);
  EXPECT_GT(largest, o.initial_step);
  EXPECT_LE(largest, o.max_step * (1.0 + 1e-15));
  EXPECT_EQ(b.rejected_steps, 0);
}

// Steps of 0.05 from 0.9 sum to 1.2999999999999994 after eight: the step ends on 1.3 itself
// instead of leaving a step of 6e-16 to it (LL11 Alg. 2 once gave two levels at E = 1.3).
TEST(NaturalParameter, ASumOfStepsShortOfTheEndByRoundingEndsOnIt) {
  const CubicPath cubic;
  NaturalParameterOptions o;
  o.parameter_min = 0.9;
  o.parameter_max = 1.3;
  o.initial_step = 0.05;
  o.max_step = 0.05;
  o.grow = [](double h, int) { return h; };
  const Branch b = natural_parameter(newton_corrector(cubic), Eigen::VectorXd::Zero(1), 0.9, o);
  ASSERT_EQ(b.stop, StopReason::RangeReached) << b.message;
  EXPECT_EQ(b.points.size(), 9U);
  EXPECT_EQ(b.points.back().parameter, 1.3);
  for (size_t i = 1; i < b.points.size(); ++i) EXPECT_GT(b.points[i].parameter - b.points[i - 1].parameter, 0.04);
}

TEST(NaturalParameter, StepsDownwardWithDirectionMinusOne) {
  const CubicPath cubic;
  NaturalParameterOptions o;
  o.parameter_min = -1.0;
  o.parameter_max = 1.0;
  o.direction = -1;
  const Branch b = natural_parameter(newton_corrector(cubic), Eigen::VectorXd::Zero(1), 0.5, o);
  ASSERT_EQ(b.stop, StopReason::RangeReached) << b.message;
  EXPECT_EQ(b.points.back().parameter, -1.0);
  EXPECT_NEAR(b.points.back().x(0), cardano(-1.0), 1e-11);
  for (size_t i = 1; i < b.points.size(); ++i) EXPECT_LT(b.points[i].parameter, b.points[i - 1].parameter);
}

// Natural stepping cannot pass the fold of x² = 1 − λ: it stops short of λ = 1, says why and
// names the way on; pseudo-arclength, the other mode, passes it and locates it at λ = 1.
TEST(NaturalParameter, StopsAtAFoldThatPseudoArclengthPasses) {
  const Fold fold;
  NaturalParameterOptions o;
  o.parameter_min = 0.0;
  o.parameter_max = 2.0;
  o.min_step = 1e-8;
  const Branch b = natural_parameter(newton_corrector(fold), Eigen::VectorXd::Constant(1, 1.0), 0.0, o);
  ASSERT_EQ(b.stop, StopReason::StepBelowMinimum);
  EXPECT_LT(b.points.back().parameter, 1.0);
  EXPECT_GT(b.points.back().parameter, 0.99);
  EXPECT_NE(b.message.find("fold"), std::string::npos) << b.message;
  EXPECT_NE(b.message.find("pseudo-arclength"), std::string::npos) << b.message;
  EXPECT_GT(b.rejected_steps, 0);

  PseudoArclengthOptions pa;
  pa.parameter_min = 0.0;
  pa.parameter_max = 2.0;
  pa.max_step = 0.05;
  const Branch a = pseudo_arclength(fold, Eigen::VectorXd::Constant(1, 1.0), 0.0, pa);
  ASSERT_EQ(a.stop, StopReason::RangeReached) << a.message;
  ASSERT_EQ(a.folds.size(), 1U);
  EXPECT_NEAR(a.folds[0].parameter, 1.0, 1e-6);
}

// A corrector that fails beyond a wall at λ = 0.5: the branch ends within 2 min_step of it
// (a failure shrinks h by ½; the stop comes once h < min_step, so the last failed step was
// shorter than 2 min_step), with every accepted point before the wall.
TEST(NaturalParameter, StopsWithinTwoMinimumStepsOfAWall) {
  const CubicPath cubic;
  auto inner = newton_corrector(cubic);
  auto walled = [&](double lambda, Eigen::VectorXd guess) {
    if (lambda > 0.5) {
      return Correction{.x = guess, .status = SolveStatus::MaxIterations, .iterations = 8, .message = "beyond the wall"};
    }
    return inner(lambda, std::move(guess));
  };
  NaturalParameterOptions o;
  o.parameter_min = 0.0;
  o.parameter_max = 1.0;
  o.initial_step = 0.3;
  o.min_step = 1e-5;
  const Branch b = natural_parameter(walled, Eigen::VectorXd::Zero(1), 0.0, o);
  ASSERT_EQ(b.stop, StopReason::StepBelowMinimum);
  EXPECT_LE(b.points.back().parameter, 0.5);
  EXPECT_GT(b.points.back().parameter, 0.5 - 2.0 * o.min_step);
  EXPECT_NE(b.message.find("beyond the wall"), std::string::npos) << b.message;
}

TEST(NaturalParameter, GoalAndInitialFailureAndTimeBudgetAreStops) {
  const CubicPath cubic;
  NaturalParameterOptions o;
  o.parameter_min = 0.0;
  o.parameter_max = 2.0;
  o.goal = [](const BranchPoint& p) { return p.x(0) > 0.5; };
  const Branch goal = natural_parameter(newton_corrector(cubic), Eigen::VectorXd::Zero(1), 0.0, o);
  ASSERT_EQ(goal.stop, StopReason::GoalReached) << goal.message;
  EXPECT_GT(goal.points.back().x(0), 0.5);
  EXPECT_LE(goal.points[goal.points.size() - 2].x(0), 0.5);

  auto never = [](double, Eigen::VectorXd x) { return Correction{.x = x, .status = SolveStatus::Stagnated, .message = "no"}; };
  const Branch failed = natural_parameter(never, Eigen::VectorXd::Zero(1), 0.0, NaturalParameterOptions{.parameter_max = 1.0});
  EXPECT_EQ(failed.stop, StopReason::InitialPointFailed);
  EXPECT_TRUE(failed.points.empty());

  auto slow = [&](double lambda, Eigen::VectorXd guess) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    return newton_corrector(cubic)(lambda, std::move(guess));
  };
  NaturalParameterOptions timed{.parameter_max = 2.0, .initial_step = 1e-3, .min_step = 1e-6, .max_step = 1e-3};
  timed.max_wall_time_s = 0.02;
  const Branch t = natural_parameter(slow, Eigen::VectorXd::Zero(1), 0.0, timed);
  EXPECT_EQ(t.stop, StopReason::TimeBudget) << t.message;
  EXPECT_LT(t.points.size(), 2000U);
}

TEST(NaturalParameter, RefusesInvalidOptionsNamingTheField) {
  const CubicPath cubic;
  auto expect_names = [&](NaturalParameterOptions o, const std::string& field) {
    try {
      (void)natural_parameter(newton_corrector(cubic), Eigen::VectorXd::Zero(1), 0.0, o);
      ADD_FAILURE() << field << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  expect_names({.parameter_max = -1.0}, "parameter_max");
  expect_names({.parameter_max = 1.0, .shrink = 1.0}, "shrink");
  expect_names({.parameter_max = 1.0, .initial_step = 2.0, .max_step = 1.0}, "initial_step");
  expect_names({.parameter_max = 1.0, .min_step = 0.0}, "min_step");
  expect_names({.parameter_max = 1.0, .direction = 0}, "direction");
}

}  // namespace
