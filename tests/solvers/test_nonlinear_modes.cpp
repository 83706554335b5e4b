// Nonlinear modes with exact contact [LL11 Secs. 3–5.1]: the rod of Sec. 5.1 (E = 2.1e11 Pa,
// ρ = 7800 kg/m³, L = 1 m, A = 0.03 × 0.03 m², 20 elements, clamped-free, stop at the tip).
#include <cmath>

#include <gtest/gtest.h>

#include <wbm/fem/rod.hpp>
#include <wbm/solvers/nonlinear_modes.hpp>

#include "testing.hpp"

namespace {

using namespace wbm;

// [LL11 Sec. 5.1]
fem::Rod ll11_rod() { return fem::Rod({.young_modulus = 2.1e11, .density = 7800.0, .area = 9e-4, .length = 1.0, .elements = 20}); }

solvers::NonlinearModes modes(double gap) {
  const auto rod = ll11_rod();
  const solvers::MechanicalSystem system{rod.mass(), Eigen::SparseMatrix<double>(20, 20), rod.stiffness()};
  return solvers::NonlinearModes(system, {{rod.tip_dof(), gap}}, {.harmonics = 8, .samples = 256});
}

}  // namespace

// "The natural frequency of its linear counterpart with clamped-free boundary conditions is
// 1297.5 Hz" [LL11 Sec. 5.1].
TEST(NonlinearModes, LinearFrequencyIsThePapers) { EXPECT_NEAR(modes(1e-3).linear_frequency_hz(), 1297.5, 0.05); }

// Below contact (E < 1) the mode is the linear first mode scaled to the energy, at exactly the
// linear frequency; at E = 1 the tip just reaches the gap.
TEST(NonlinearModes, BelowContactTheModeIsLinear) {
  const auto nm = modes(1e-3);
  const auto level = nm.solve(0.7);
  ASSERT_TRUE(level.converged) << level.message;
  EXPECT_NEAR(level.frequency_hz, nm.linear_frequency_hz(), 1e-9 * nm.linear_frequency_hz());
  Eigen::MatrixXd expected = Eigen::MatrixXd::Zero(nm.dofs(), 2 * nm.harmonics() + 1);
  expected.col(1) = std::sqrt(0.7) * nm.onset_mode();
  EXPECT_LT((level.coefficients - expected).norm(), 1e-12 * expected.norm());
  EXPECT_NEAR(level.max_penetration, std::sqrt(0.7) - 1.0, 1e-12);  // tip amplitude √E g0
  const auto onset = nm.solve(1.0);
  ASSERT_TRUE(onset.converged);
  EXPECT_NEAR(onset.max_penetration, 0.0, 1e-12);
}

// Above contact: non-penetration and sign at every sample, complementarity and the energy
// normalization to the solver tolerance; the frequency rises (hardening [LL11 Fig. 3]); and the
// normalized result does not depend on the gap (hyper-elastic scaling [LL11 Sec. 5.1]).
TEST(NonlinearModes, AboveContactConstraintsHoldAndFrequencyHardens) {
  const auto nm = modes(1e-3);
  const auto level = nm.solve(1.2);
  ASSERT_TRUE(level.converged) << level.message;
  EXPECT_LE(level.max_penetration, 1e-8);
  EXPECT_LE(level.complementarity, 1e-8);
  EXPECT_LE(level.normalization_error, 1e-8);
  EXPECT_GE(level.multipliers.minCoeff(), 0.0);
  EXPECT_GT(level.multipliers.maxCoeff(), 0.0);  // the stop does push
  EXPECT_GT(level.frequency_hz, nm.linear_frequency_hz() * (1.0 + 1e-6));
  const auto tiny = modes(1e-6).solve(1.2);
  ASSERT_TRUE(tiny.converged) << tiny.message;
  EXPECT_NEAR(tiny.frequency_hz, level.frequency_hz, 1e-8 * level.frequency_hz);
  EXPECT_LT((tiny.coefficients * 1e3 - level.coefficients).norm(), 1e-6 * level.coefficients.norm());
}

TEST(NonlinearModes, RefusesInvalidInput) {
  const auto rod = ll11_rod();
  const solvers::MechanicalSystem system{rod.mass(), Eigen::SparseMatrix<double>(20, 20), rod.stiffness()};
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { solvers::NonlinearModes nm(system, {{rod.tip_dof(), 0.0}}, {}); }, {"gap 0", "must be > 0"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { solvers::NonlinearModes nm(system, {{rod.tip_dof(), 1e-3}}, {.harmonics = 16, .samples = 32}); },
      {"samples = 32", "must exceed 2N = 32"});
}
