// Piecewise-smooth continuation (continuation.hpp, detail/continuation_events.hpp) against closed
// forms: a spring against a stop (one event, the branch bends), a branch that turns back at the
// corner (a fold located at the event), two symmetric samples that switch together, and the same
// with the symmetry broken at the rounding level (the branch must not change), an entry that
// crosses and returns within a step, a crossing beside an entry that creeps to its stop, and
// (an identity of the corrector) no Jacobian formed that is not factorized.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <wbm/solvers/continuation.hpp>

namespace {

using namespace wbm;
using solvers::ActiveSet;
using solvers::Linearization;

// DOFs u_i with springs k_i to ground and c between neighbours, a load λ on each, a stop at gap g
// on each DOF with its contact force f_i as an unknown (Signorini), x = [u; f]:
//   R_i     = k_i u_i + Σ_j c (u_i − u_j) + a f_i − p_i(λ)  (a = 1: the stop pushes back;
//                                                              a < 0: the branch turns back)
// with the load p_i(λ) = λ, or, where `bump` gives its entry a value, a parabola
// p_i(λ) = b + d − q (λ − l)² + r (λ − l) (bump_load; with r = 0 it meets the stop over
// |λ − l| < √(d/q) only).
//   R_(n+i) = min(f_i, g − u_i)
// Pieces: active entry i → g − u_i = 0, event f_i; inactive → f_i = 0, event g − u_i.
struct SpringsAgainstStops {
  Eigen::VectorXd k;
  double c = 0.0, a = 1.0, g = 1.0;
  struct Bump {
    Eigen::Index entry = -1;  // −1: every load is λ
    double base = 0.0, depth = 0.0, curvature = 0.0, centre = 0.0, slope = 0.0;
  } bump;
  [[nodiscard]] double load(Eigen::Index i, double lambda) const {
    if (i != bump.entry) return lambda;
    return bump.base + bump.depth - bump.curvature * (lambda - bump.centre) * (lambda - bump.centre) +
           bump.slope * (lambda - bump.centre);
  }
  [[nodiscard]] double load_derivative(Eigen::Index i, double lambda) const {
    return i != bump.entry ? 1.0 : -2.0 * bump.curvature * (lambda - bump.centre) + bump.slope;
  }
  mutable int evaluations = 0;  // calls of eval(): residuals and linearizations
  [[nodiscard]] Eigen::Index n() const { return k.size(); }
  [[nodiscard]] Linearization eval(const Eigen::VectorXd& x, double lambda, const ActiveSet* piece) const {
    ++evaluations;
    const Eigen::Index m = n();
    Linearization l;
    l.residual = Eigen::VectorXd::Zero(2 * m);
    l.jacobian = Eigen::MatrixXd::Zero(2 * m, 2 * m);
    l.parameter_derivative = Eigen::VectorXd::Zero(2 * m);
    for (Eigen::Index i = 0; i < m; ++i) {
      l.residual(i) = k(i) * x(i) + a * x(m + i) - load(i, lambda);
      l.jacobian(i, i) = k(i);
      l.jacobian(i, m + i) = a;
      for (Eigen::Index j : {i - 1, i + 1}) {
        if (j < 0 || j >= m) continue;
        l.residual(i) += c * (x(i) - x(j));
        l.jacobian(i, i) += c;
        l.jacobian(i, j) -= c;
      }
      l.parameter_derivative(i) = -load_derivative(i, lambda);
      const double f = x(m + i), gap = g - x(i);
      const bool active = piece ? (*piece)[static_cast<size_t>(i)] != 0 : !(f <= gap);
      l.residual(m + i) = piece ? (active ? gap : f) : std::min(f, gap);
      if (active) {
        l.jacobian(m + i, i) = -1.0;
      } else {
        l.jacobian(m + i, m + i) = 1.0;
      }
    }
    return l;
  }
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x, double p) const { return eval(x, p, nullptr).residual; }
  [[nodiscard]] Linearization linearize(const Eigen::VectorXd& x, double p) const { return eval(x, p, nullptr); }
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x, double p, const ActiveSet& s) const {
    return eval(x, p, &s).residual;
  }
  [[nodiscard]] Linearization linearize(const Eigen::VectorXd& x, double p, const ActiveSet& s) const {
    return eval(x, p, &s);
  }
  [[nodiscard]] ActiveSet active_set(const Eigen::VectorXd& x, double /*p*/) const {
    ActiveSet s(static_cast<size_t>(n()));
    for (Eigen::Index i = 0; i < n(); ++i) s[static_cast<size_t>(i)] = !(x(n() + i) <= g - x(i));
    return s;
  }
  [[nodiscard]] Eigen::VectorXd events(const Eigen::VectorXd& x, double /*p*/, const ActiveSet& s) const {
    Eigen::VectorXd e(n());
    for (Eigen::Index i = 0; i < n(); ++i) e(i) = s[static_cast<size_t>(i)] ? x(n() + i) : g - x(i);
    return e;
  }
};
static_assert(solvers::PiecewiseSmoothSystem<SpringsAgainstStops>);

solvers::PseudoArclengthOptions options(double lambda_min, double lambda_max, int direction = +1) {
  solvers::PseudoArclengthOptions o;
  o.parameter_min = lambda_min;
  o.parameter_max = lambda_max;
  o.direction = direction;
  o.initial_step = 0.05;
  o.max_step = 0.3;
  o.corrector_tolerance = 1e-12;
  return o;
}

// One spring, k = 2, g = 1: u = min(λ/k, g), f = max(0, λ − k g); the corner at λ = k g = 2.
TEST(PiecewiseContinuation, SpringAgainstAStopFollowsTheClosedFormThroughOneEvent) {
  SpringsAgainstStops s;
  s.k = Eigen::VectorXd::Constant(1, 2.0);
  const auto b = solvers::pseudo_arclength(s, Eigen::VectorXd::Zero(2), 0.0, options(-0.1, 5.0));
  ASSERT_EQ(b.stop, solvers::StopReason::RangeReached) << b.message;
  EXPECT_EQ(b.events, 1);
  EXPECT_EQ(b.switches, 1);
  EXPECT_EQ(b.rejected_steps, 0);
  int corners = 0;
  for (const auto& p : b.points) {
    EXPECT_NEAR(p.x(0), std::min(p.parameter / 2.0, 1.0), 1e-12) << "λ = " << p.parameter;
    EXPECT_NEAR(p.x(1), std::max(0.0, p.parameter - 2.0), 1e-12) << "λ = " << p.parameter;
    if (p.event) {
      ++corners;
      EXPECT_NEAR(p.parameter, 2.0, 1e-12);  // located on the switching surface u = g
    }
  }
  EXPECT_EQ(corners, 1);
  EXPECT_TRUE(b.folds.empty());
}

// a = −1: the contact piece u = g, f = k g − λ exists for λ ≤ k g only, so the branch comes up
// the free piece to λ = k g and turns back along the contact piece: a fold at the corner, where
// a step-halving corrector finds no hyperplane normal to the old tangent that meets the branch.
TEST(PiecewiseContinuation, BranchTurningBackAtTheCornerIsFollowedAndTheFoldSitsAtTheEvent) {
  SpringsAgainstStops s;
  s.k = Eigen::VectorXd::Constant(1, 2.0);
  s.a = -1.0;
  const auto b = solvers::pseudo_arclength(s, Eigen::VectorXd::Zero(2), 0.0, options(-0.1, 5.0));
  ASSERT_EQ(b.stop, solvers::StopReason::RangeReached) << b.message;
  EXPECT_LT(b.points.back().parameter, -0.1);  // left by the lower end, after the turn
  EXPECT_EQ(b.events, 1);
  ASSERT_EQ(b.folds.size(), 1U);
  EXPECT_NEAR(b.folds[0].parameter, 2.0, 1e-12);
  bool turned = false;
  for (const auto& p : b.points) {
    turned = turned || p.event;
    // Free piece u = λ/k, f = 0; contact piece u = g, f = k g − λ.
    EXPECT_NEAR(p.x(0), turned ? 1.0 : p.parameter / 2.0, 1e-12) << "λ = " << p.parameter;
    EXPECT_NEAR(p.x(1), turned ? 2.0 - p.parameter : 0.0, 1e-12) << "λ = " << p.parameter;
    EXPECT_GE(p.x(1), -1e-12);
  }
}

// Two equal DOFs coupled by c: both reach the stop at λ = k g at once and switch in one event;
// with k₂ = k₁ (1 + 1e-12) they reach it 1e-12 apart. Either way every point lies on the closed
// form (u = min(λ/k, g) on each, f = max(0, λ − k g)) and the branch ends at the same place.
TEST(PiecewiseContinuation, SimultaneousCrossingsSwitchTogetherWhateverTheirLastBits) {
  for (double perturbation : {0.0, 1e-12, -3e-12}) {
    SpringsAgainstStops s;
    s.k = Eigen::Vector2d(2.0, 2.0 * (1.0 + perturbation));
    s.c = 0.5;
    const auto b = solvers::pseudo_arclength(s, Eigen::VectorXd::Zero(4), 0.0, options(-0.1, 5.0));
    ASSERT_EQ(b.stop, solvers::StopReason::RangeReached) << b.message << " (perturbation " << perturbation << ")";
    EXPECT_GE(b.events, 1);
    EXPECT_LE(b.events, 2);
    EXPECT_EQ(b.switches, 2);
    for (const auto& p : b.points) {
      for (int i = 0; i < 2; ++i) {
        EXPECT_NEAR(p.x(i), std::min(p.parameter / 2.0, 1.0), 1e-10) << "λ = " << p.parameter;
        EXPECT_NEAR(p.x(2 + i), std::max(0.0, p.parameter - s.k(i)), 1e-10) << "λ = " << p.parameter;
      }
    }
    EXPECT_GT(b.points.back().parameter, 5.0);
  }
}

// Checks every point of a branch of two unit springs against u_i = min(p_i, g), f_i = max(0, p_i − g)
// (g = 1); returns the parameters of its events.
std::vector<double> on_closed_form(const SpringsAgainstStops& s, const solvers::Branch& b) {
  std::vector<double> corners;
  for (const auto& p : b.points) {
    for (Eigen::Index i = 0; i < 2; ++i) {
      EXPECT_NEAR(p.x(i), std::min(s.load(i, p.parameter), 1.0), 1e-10) << "λ = " << p.parameter;
      EXPECT_NEAR(p.x(2 + i), std::max(0.0, s.load(i, p.parameter) - 1.0), 1e-10) << "λ = " << p.parameter;
    }
    if (p.event) corners.push_back(p.parameter);
  }
  return corners;
}

// Two unit springs, g = 1, one step from λ = 0.9 to about 1.2: DOF 0 under p₀ = λ reaches the
// stop at λ = 1, DOF 1 under p₁ = 1 + 0.0025 − (λ − 1)² touches it only over 0.95 < λ < 1.05.
// DOF 1's gap crosses 0 and comes back within the step, so the step's end shows only DOF 0's
// crossing; locating it finds DOF 1's entry first. Only DOF 1 may switch there: DOF 0 is 0.05
// from the stop (before, the step-position rule measured simultaneity from DOF 0's crossing,
// DOF 1 having no crossing of its own by the step's mean rate, and switched DOF 0 with it: on
// the LL11 rod at N = 10, m = 512, E = 2.497 that put two samples with multipliers 3.5e-3 out
// of contact, the corrector jumped to another orbit and the backbone retraced itself). Three
// events at λ = 0.95, 1 and 1.05, every point on the closed form u_i = min(p_i, g).
TEST(PiecewiseContinuation, AnEntryThatCrossesAndReturnsWithinAStepSwitchesAloneWhereItCrosses) {
  SpringsAgainstStops s;
  s.k = Eigen::Vector2d(1.0, 1.0);
  s.bump = {.entry = 1, .base = 1.0, .depth = 0.0025, .curvature = 1.0, .centre = 1.0};
  const double lambda0 = 0.9;
  const Eigen::Vector4d x0(lambda0, s.load(1, lambda0), 0.0, 0.0);
  auto o = options(0.0, 1.5);
  o.initial_step = o.max_step = 0.34;  // the first step spans DOF 1's contact and DOF 0's onset
  const auto b = solvers::pseudo_arclength(s, Eigen::VectorXd(x0), lambda0, o);
  ASSERT_EQ(b.stop, solvers::StopReason::RangeReached) << b.message;
  EXPECT_EQ(b.events, 3);
  EXPECT_EQ(b.switches, 3);
  const std::vector<double> corners = on_closed_form(s, b);
  ASSERT_EQ(corners.size(), 3U);
  EXPECT_NEAR(corners[0], 0.95, 1e-9);
  EXPECT_NEAR(corners[1], 1.0, 1e-9);
  EXPECT_NEAR(corners[2], 1.05, 1e-9);
}

// Two unit springs, g = 1, one step from λ = 0.9: DOF 0 under p₀ = λ reaches the stop at λ = 1
// at unit rate; DOF 1 under p₁ = 1 + r (λ − 1.1), r = 5e-7, creeps to it, 1e-7 away at the
// start, and reaches it at λ = 1.1. Both cross within the step, so the minimum of their event
// functions has a kink just before DOF 0's crossing, where DOF 1's gap stops being the smaller.
// The crossing of DOF 0 is still located to 1e-9 in λ, and DOF 1's to twice the zero band over
// its rate (2 · 1e-12 / 5e-7 = 4e-6). Regula falsi on the minimum instead of on each entry crept
// towards the first crossing: 52 evaluations of the system for this branch, against 18 now.
TEST(PiecewiseContinuation, ACrossingBesideACreepingEntryIsLocatedWithoutCreeping) {
  SpringsAgainstStops s;
  s.k = Eigen::Vector2d(1.0, 1.0);
  const double rate = 5e-7;
  s.bump = {.entry = 1, .base = 1.0, .centre = 1.1, .slope = rate};
  const double lambda0 = 0.9;
  const Eigen::Vector4d x0(lambda0, s.load(1, lambda0), 0.0, 0.0);
  auto o = options(0.0, 1.5);
  o.initial_step = o.max_step = 0.34;
  const auto b = solvers::pseudo_arclength(s, Eigen::VectorXd(x0), lambda0, o);
  ASSERT_EQ(b.stop, solvers::StopReason::RangeReached) << b.message;
  const std::vector<double> corners = on_closed_form(s, b);
  ASSERT_EQ(corners.size(), 2U);
  EXPECT_NEAR(corners[0], 1.0, 1e-9);
  EXPECT_NEAR(corners[1], 1.1, 2.0 * o.corrector_tolerance / rate);
  EXPECT_LE(s.evaluations, 26);
}

// A release: from contact at λ = 5 downwards, the contact force vanishes at λ = k g and the DOF
// leaves the stop (an active entry's event, f, through 0).
TEST(PiecewiseContinuation, ReleaseFromTheStopIsAnEventOnTheMultiplier) {
  SpringsAgainstStops s;
  s.k = Eigen::VectorXd::Constant(1, 2.0);
  const auto b = solvers::pseudo_arclength(s, Eigen::Vector2d(1.0, 3.0), 5.0, options(-1.0, 5.5, -1));
  ASSERT_EQ(b.stop, solvers::StopReason::RangeReached) << b.message;
  EXPECT_EQ(b.events, 1);
  EXPECT_LT(b.points.back().parameter, -1.0);
  for (const auto& p : b.points) {
    EXPECT_NEAR(p.x(0), std::min(p.parameter / 2.0, 1.0), 1e-12);
    EXPECT_NEAR(p.x(1), std::max(0.0, p.parameter - 2.0), 1e-12);
  }
}

// Every Jacobian the continuation forms is factorized, in a Newton step or a tangent. The event
// location's trials end at converged points that take no tangent, so the corrector evaluates R
// alone at its iterates and forms J only where a step or a tangent follows (it formed one at
// every iterate before: 11 538 linearizations for 8 070 factorizations on the LL11 rod backbone
// at N = 10, m = 512, now 8 069). Three springs against their stops at different loads, so that
// steps cross events and trials locate them; the factorizations are counted by the system's own
// linear solver.
struct CountingLu {
  int* count;
  solvers::DenseLu lu;
  bool factorize(const Eigen::MatrixXd& j) {
    ++*count;
    return lu.factorize(j);
  }
  [[nodiscard]] Eigen::VectorXd solve(const Eigen::VectorXd& r) const { return lu.solve(r); }
  [[nodiscard]] std::optional<double> rcond() const { return lu.rcond(); }
};

struct CountedSprings : SpringsAgainstStops {
  mutable int linearizations = 0, factorizations = 0;
  [[nodiscard]] Linearization linearize(const Eigen::VectorXd& x, double p) const {
    ++linearizations;
    return eval(x, p, nullptr);
  }
  [[nodiscard]] Linearization linearize(const Eigen::VectorXd& x, double p, const ActiveSet& s) const {
    ++linearizations;
    return eval(x, p, &s);
  }
  [[nodiscard]] CountingLu linear_solver() const { return CountingLu{&factorizations, {}}; }
};
static_assert(solvers::PiecewiseSmoothSystem<CountedSprings>);

TEST(PiecewiseContinuation, EveryJacobianFormedIsFactorized) {
  CountedSprings s;
  s.k = Eigen::Vector3d(1.0, 2.0, 4.0);
  s.c = 0.5;
  const auto b = solvers::pseudo_arclength(s, Eigen::VectorXd::Zero(6), 0.0, options(-0.1, 8.0));
  ASSERT_EQ(b.stop, solvers::StopReason::RangeReached) << b.message;
  ASSERT_GE(b.events, 3);
  ASSERT_GT(s.factorizations, 0);
  EXPECT_EQ(s.linearizations, s.factorizations);
}

}  // namespace

namespace {

// A closed branch in two pieces: the unit circle x² + λ² = 1, the same residual on both, piece 1
// where x > 0 (event x) and piece 0 where x ≤ 0 (event −x). Pieces that close a loop.
struct SplitCircle {
  [[nodiscard]] Linearization eval(const Eigen::VectorXd& x, double lambda) const {
    Linearization l;
    l.residual = Eigen::VectorXd::Constant(1, x(0) * x(0) + lambda * lambda - 1.0);
    l.jacobian = Eigen::MatrixXd::Constant(1, 1, 2.0 * x(0));
    l.parameter_derivative = Eigen::VectorXd::Constant(1, 2.0 * lambda);
    return l;
  }
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x, double p) const { return eval(x, p).residual; }
  [[nodiscard]] Linearization linearize(const Eigen::VectorXd& x, double p) const { return eval(x, p); }
  [[nodiscard]] ActiveSet active_set(const Eigen::VectorXd& x, double /*p*/) const { return {x(0) > 0.0 ? std::uint8_t{1} : std::uint8_t{0}}; }
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x, double p, const ActiveSet& /*a*/) const {
    return eval(x, p).residual;
  }
  [[nodiscard]] Linearization linearize(const Eigen::VectorXd& x, double p, const ActiveSet& /*a*/) const { return eval(x, p); }
  [[nodiscard]] Eigen::VectorXd events(const Eigen::VectorXd& x, double /*p*/, const ActiveSet& a) const {
    return Eigen::VectorXd::Constant(1, a[0] != 0 ? x(0) : -x(0));
  }
};

}  // namespace

// The continuation goes round the circle once, switching at λ = 1 and λ = −1, and stops when it
// reaches its first switching point again (Retraced), instead of going round until max_points.
TEST(PiecewiseContinuation, AClosedLoopOfPiecesEndsTheBranchAtItsFirstRepeatedSwitchingPoint) {
  static_assert(solvers::PiecewiseSmoothSystem<SplitCircle>);
  const SplitCircle s;
  auto o = options(-2.0, 2.0);
  o.max_points = 5000;
  const auto b = solvers::pseudo_arclength(s, Eigen::VectorXd::Constant(1, 1.0), 0.0, o);
  EXPECT_EQ(b.stop, solvers::StopReason::Retraced) << b.message;
  EXPECT_EQ(b.events, 3) << b.message;  // λ = 1, λ = −1, λ = 1 again
  EXPECT_LT(b.points.size(), 1000U);
  for (const auto& p : b.points) EXPECT_NEAR(p.x(0) * p.x(0) + p.parameter * p.parameter, 1.0, 1e-8);
  EXPECT_NE(b.message.find("closed loop"), std::string::npos) << b.message;
}
