// Augmented Lagrangian terms and Powell's updates [LL11 Eqs. (18), (21), (25), Alg. 3] on
// problems whose KKT points are known in closed form.
#include <cmath>

#include <gtest/gtest.h>

#include <wbm/contact/augmented_lagrangian.hpp>

#include "testing.hpp"

namespace {
using wbm::contact::AugmentedLagrangian;
}

// ∂φ/∂g and ∂φ/∂h against central differences of φ (Eq. 18), off the kinks of (·)₊.
TEST(AugmentedLagrangian, DerivativesMatchFiniteDifferences) {
  AugmentedLagrangian al(3);
  Eigen::VectorXd lambda(3);
  lambda << 0.0, 5.0, 20.0;
  al.warm_start(lambda, -3.0);
  Eigen::VectorXd g(3);
  g << -0.7, 0.2, -0.9;  // inactive, active, active through its shift θ = 2
  const double h = 0.1, step = 1e-6;
  const Eigen::VectorXd grad = al.inequality_gradient(g);
  for (int k = 0; k < 3; ++k) {
    Eigen::VectorXd gp = g, gm = g;
    gp(k) += step;
    gm(k) -= step;
    EXPECT_NEAR(grad(k), (al.value(gp, h) - al.value(gm, h)) / (2 * step), 1e-6) << k;
  }
  EXPECT_NEAR(al.equality_gradient(h), (al.value(g, h + step) - al.value(g, h - step)) / (2 * step), 1e-6);
  const Eigen::VectorXd curvature = al.inequality_curvature(g);
  EXPECT_EQ(curvature(0), 0.0);
  EXPECT_EQ(curvature(1), al.inequality_penalties()(1));
}

// min (x − 2)² subject to x ≤ 1: KKT x = 1, λ = 2 (2(x − 2) + λ = 0). Primal minimization in
// closed form for each (κ, θ); Powell's updates drive the multiplier to 2.
TEST(AugmentedLagrangian, PowellUpdatesReachTheInequalityKktPoint) {
  AugmentedLagrangian al(1, {.tolerance = 1e-10, .initial_inequality_penalty = 1.0});
  double x = 0.0;
  wbm::contact::PowellUpdate last;
  for (int j = 0; j < 100 && !last.measures_met; ++j) {
    const double kappa = al.inequality_penalties()(0), theta = al.inequality_shifts()(0);
    // Stationarity 2(x − 2) + κ (x − 1 + θ)₊ = 0 on the active side.
    x = (4.0 + kappa * (1.0 - theta)) / (2.0 + kappa);
    if (x - 1.0 + theta <= 0.0) x = 2.0;
    Eigen::VectorXd g(1);
    g << x - 1.0;
    last = al.update(g, 0.0);
  }
  ASSERT_TRUE(last.measures_met);
  EXPECT_NEAR(x, 1.0, 1e-9);
  Eigen::VectorXd g(1);
  g << x - 1.0;
  EXPECT_NEAR(al.inequality_gradient(g)(0), 2.0, 1e-8);
}

// min x² + y² subject to x + y = 1: KKT x = y = ½, μ = −1 (2x + μ = 0).
TEST(AugmentedLagrangian, PowellUpdatesReachTheEqualityKktPoint) {
  AugmentedLagrangian al(0, {.tolerance = 1e-10, .initial_equality_penalty = 1.0});
  double x = 0.0;
  wbm::contact::PowellUpdate last;
  for (int j = 0; j < 100 && !last.measures_met; ++j) {
    // Stationarity 2x + κ_e (2x − 1 + θ_e) = 0 (x = y by symmetry).
    const double kappa = al.equality_penalty(), theta = al.equality_shift();
    x = kappa * (1.0 - theta) / (2.0 + 2.0 * kappa);
    last = al.update(Eigen::VectorXd(0), 2.0 * x - 1.0);
  }
  ASSERT_TRUE(last.measures_met);
  EXPECT_NEAR(x, 0.5, 1e-9);
  EXPECT_NEAR(al.equality_gradient(2.0 * x - 1.0), -1.0, 1e-8);
}

// Alg. 3 followed by hand on one inequality (α = 4, β = 10, κ₀ = 1, κ_max = 50), each pass's
// report against the branch the algorithm must take.
TEST(AugmentedLagrangian, UpdateReportsWhatAlgorithm3Did) {
  AugmentedLagrangian al(1, {.alpha = 4.0, .beta = 10.0, .initial_inequality_penalty = 1.0, .max_penalty = 50.0});
  Eigen::VectorXd g(1);
  g << 0.5;
  // G_i = 0.5 < G* = ∞: θ ← 0 + 0.5 (Eq. 21a); 0.5 < ∞/α, so no penalty is raised.
  auto u = al.update(g, 0.0);
  EXPECT_DOUBLE_EQ(u.inequality_measure, 0.5);
  EXPECT_EQ(u.equality_measure, 0.0);
  EXPECT_FALSE(u.measures_met);
  EXPECT_EQ(u.multiplier_updates, 1);
  EXPECT_EQ(u.penalties_raised, 0);
  EXPECT_DOUBLE_EQ(al.inequality_shifts()(0), 0.5);
  // Same G_i again: no improvement (l. 12), κ ← 10, θ ← 0.05, the multiplier κθ = 0.5 kept.
  u = al.update(g, 0.0);
  EXPECT_EQ(u.multiplier_updates, 0);
  EXPECT_EQ(u.penalties_raised, 1);
  EXPECT_DOUBLE_EQ(al.inequality_penalties()(0), 10.0);
  EXPECT_DOUBLE_EQ(al.inequality_shifts()(0), 0.05);
  // G_i = 0.2 improves on 0.5 but not by α (0.2 ≥ 0.5/4): θ ← 0.25, and κ ← 100 is refused by κ_max.
  g << 0.2;
  u = al.update(g, 0.0);
  EXPECT_EQ(u.multiplier_updates, 1);
  EXPECT_EQ(u.penalties_raised, 0);
  EXPECT_EQ(u.penalties_capped, 1);
  EXPECT_DOUBLE_EQ(al.inequality_penalties()(0), 10.0);
  EXPECT_DOUBLE_EQ(al.inequality_shifts()(0), 0.25);
  // A satisfied inactive constraint (g = −1, θ = 0) and h = 0 meet both measures: nothing changes.
  AugmentedLagrangian fresh(1);
  g << -1.0;
  u = fresh.update(g, 0.0);
  EXPECT_TRUE(u.measures_met);
  EXPECT_EQ(u.multiplier_updates + u.penalties_raised + u.penalties_capped, 0);
  EXPECT_EQ(fresh.inequality_shifts()(0), 0.0);
}

TEST(AugmentedLagrangian, RefusesInvalidParameters) {
  wbm::testing::expect_throw_with<std::invalid_argument>([] { AugmentedLagrangian al(1, {.alpha = 1.0}); },
                                                         {"alpha = 1", "must be > 1"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [] { AugmentedLagrangian al(1, {.initial_equality_penalty = -1.0}); },
      {"PowellParameters.initial_equality_penalty = -1", "> 0"});
  wbm::testing::expect_throw_with<std::invalid_argument>([] { AugmentedLagrangian al(1, {.max_penalty = 5.0}); },
                                                         {"PowellParameters.max_penalty = 5", ">= both initial penalties"});
  AugmentedLagrangian al(2);
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { al.warm_start(Eigen::VectorXd(3), 0.0); },
                                                         {"3 multipliers for 2 constraints"});
}
