// Nonlinear modes with exact contact [LL11 Secs. 3–5.1]: the rod of Sec. 5.1 (E = 2.1e11 Pa,
// ρ = 7800 kg/m³, L = 1 m, A = 0.03 × 0.03 m², 20 elements, clamped-free, stop at the tip), read
// from reproduce/scenes/ll11_rod.toml. Truths not produced by this code: the paper's linear
// frequency, the linear mode below contact, the KKT conditions at every sample, agreement of
// three independent algorithms (LL11 Alg. 1 and 2 with Powell's augmented Lagrangian, and the
// semismooth-Newton continuation), finite-difference Jacobians, a free time simulation that stays
// on the computed orbit, first-order convergence of penalty backbones, and gap invariance.
#include <cmath>
#include <memory>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/QR>
#include <gtest/gtest.h>

#include <wbm/fem/rod.hpp>
#include <wbm/scene/analysis.hpp>
#include <wbm/solvers/nonlinear_modes.hpp>
#include <wbm/solvers/time_integration.hpp>

#include "shipped_scenes.hpp"
#include "nonlinear_modes_fixtures.hpp"
#include "testing.hpp"

using namespace wbm;
using namespace wbm::testing;

// "The natural frequency of its linear counterpart with clamped-free boundary conditions is
// 1297.5 Hz" [LL11 Sec. 5.1].
TEST(NonlinearModes, LinearFrequencyIsThePapers) { EXPECT_NEAR(modes(1e-3).linear_frequency_hz(), 1297.5, 0.05); }

// Below contact (E < 1) the mode is the linear first mode scaled to the energy, at exactly the
// linear frequency; at E = 1 the tip just reaches the gap.
TEST(NonlinearModes, BelowContactTheModeIsLinear) {
  const auto nm = modes(1e-3);
  const auto level = nm.solve(0.7);
  ASSERT_TRUE(level.converged()) << level.message;
  EXPECT_NEAR(level.frequency_hz, nm.linear_frequency_hz(), 1e-9 * nm.linear_frequency_hz());
  Eigen::MatrixXd expected = Eigen::MatrixXd::Zero(nm.dofs(), 2 * nm.harmonics() + 1);
  expected.col(1) = std::sqrt(0.7) * nm.onset_mode();
  EXPECT_LT((level.coefficients - expected).norm(), 1e-12 * expected.norm());
  EXPECT_NEAR(level.max_penetration, std::sqrt(0.7) - 1.0, 1e-12);  // tip amplitude √E g0
  const auto onset = nm.solve(1.0);
  ASSERT_TRUE(onset.converged());
  EXPECT_NEAR(onset.max_penetration, 0.0, 1e-12);
}

// Above contact: non-penetration and sign at every sample, complementarity and the energy
// normalization to the solver tolerance; the frequency rises (hardening [LL11 Fig. 3]); and the
// normalized result does not depend on the gap (hyper-elastic scaling [LL11 Sec. 5.1]).
TEST(NonlinearModes, AboveContactConstraintsHoldAndFrequencyHardens) {
  const auto nm = modes(1e-3);
  const auto level = nm.solve(1.2);
  ASSERT_TRUE(level.converged()) << level.message;
  EXPECT_LE(level.max_penetration, 1e-8);
  EXPECT_LE(level.complementarity, 1e-8);
  EXPECT_LE(level.normalization_error, 1e-8);
  EXPECT_GE(level.multipliers.minCoeff(), 0.0);
  EXPECT_GT(level.multipliers.maxCoeff(), 0.0);  // the stop does push
  EXPECT_GT(level.frequency_hz, nm.linear_frequency_hz() * (1.0 + 1e-6));
  const auto tiny = modes(1e-6).solve(1.2);
  ASSERT_TRUE(tiny.converged()) << tiny.message;
  EXPECT_NEAR(tiny.frequency_hz, level.frequency_hz, 1e-8 * level.frequency_hz);
  EXPECT_LT((tiny.coefficients * 1e3 - level.coefficients).norm(), 1e-6 * level.coefficients.norm());
}

TEST(NonlinearModes, RefusesInvalidInput) {
  const fem::Rod rod({.young_modulus = 2.1e11, .density = 7800.0, .area = 9e-4, .length = 1.0, .elements = 20});
  const solvers::MechanicalSystem system{rod.mass(), Eigen::SparseMatrix<double>(20, 20), rod.stiffness()};
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { solvers::NonlinearModes nm(system, {{rod.tip_dof(), 0.0}}, {}); }, {"gap 0", "must be > 0"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { solvers::NonlinearModes nm(system, {{rod.tip_dof(), 1e-3}}, {.harmonics = 16, .samples = 32}); },
      {"samples = 32", "must exceed 2N = 32"});
}

// The sparse Jacobian of the KKT system (exact contact) and of the penalty system against central
// differences, at a state with contact samples on both sides of the Signorini switch.
TEST(NonlinearModes, BackboneSystemJacobianMatchesFiniteDifferences) {
  const auto nm = modes(1e-3, 4, 32);
  for (double k : {0.0, 3e9}) {
    const solvers::NonlinearModes::BackboneSystem system(nm, k);
    Eigen::VectorXd x = wbm::testing::backbone_trial_state(system, k);
    x.head(20) += 1e-2 * Eigen::VectorXd::LinSpaced(20, -1.0, 1.0);
    if (k == 0.0) x(x.size() - 32 + 3) = 0.7;  // a sample whose min picks λ although g > 0
    const double energy = 1.4;
    const Eigen::MatrixXd j(system.linearize(x, energy).jacobian);
    const Eigen::MatrixXd fd = wbm::testing::fd_jacobian(
        [&](const Eigen::VectorXd& y) { return Eigen::VectorXd(system.residual(y, energy)); }, x, 1e-7, 1.0);
    EXPECT_LT((j - fd).cwiseAbs().maxCoeff(), 1e-6 * j.cwiseAbs().maxCoeff()) << "penalty " << k;
    const double h = 1e-7;
    Eigen::VectorXd dE = (system.residual(x, energy + h) - system.residual(x, energy - h)) / (2 * h);
    EXPECT_LT((system.linearize(x, energy).parameter_derivative - dE).norm(), 1e-8);
  }
}

// The penalty Jacobian reuses its sparsity pattern from one linearization to the next while the
// (row, column) sequence of its entries is unchanged (core/triplet_pattern.hpp), and keeps up to
// four patterns. Against Eigen's setFromTriplets (a new BackboneSystem assembles from scratch): on
// seven pieces, each linearized at two states in a row, the whole visited twice, so that patterns
// are reused, evicted and rebuilt, the entries are equal bit for bit and so are the patterns.
// (The exact-contact Jacobian is built without a pattern cache: ExactBackboneJacobianHasTheKktStructure.)
TEST(NonlinearModes, BackboneJacobianReusingItsPatternEqualsSetFromTriplets) {
  const auto nm = modes(1e-3, 4, 32);
  {
    const double k = 3e9;
    const solvers::NonlinearModes::BackboneSystem system(nm, k);
    Eigen::VectorXd x = wbm::testing::backbone_trial_state(system, k);
    const double energy = 1.4;
    const solvers::ActiveSet own = system.active_set(x, energy);
    for (int round = 0; round < 2; ++round) {
      for (size_t visit = 0; visit < 14; ++visit) {
        const size_t piece = visit / 2;
        solvers::ActiveSet a = own;
        for (size_t i = piece; i < a.size(); i += 7) a[i] ^= 1U;
        const Eigen::VectorXd xi =
            x + (1e-3 * static_cast<double>(2 * round + visit % 2 + 1)) * Eigen::VectorXd::LinSpaced(x.size(), -1.0, 1.0);
        const Eigen::SparseMatrix<double> reused = system.linearize(xi, energy, a).jacobian;
        const Eigen::SparseMatrix<double> fresh =
            solvers::NonlinearModes::BackboneSystem(nm, k).linearize(xi, energy, a).jacobian;
        ASSERT_EQ(reused.nonZeros(), fresh.nonZeros()) << "penalty " << k << ", piece " << piece;
        EXPECT_EQ(Eigen::MatrixXd(reused - fresh).cwiseAbs().maxCoeff(), 0.0) << "penalty " << k << ", piece " << piece;
        for (Eigen::Index i = 0; i < fresh.nonZeros(); ++i) {
          ASSERT_EQ(reused.innerIndexPtr()[i], fresh.innerIndexPtr()[i]) << "penalty " << k << ", piece " << piece;
        }
      }
    }
  }
}

// The pieces of the backbone system (PiecewiseSmoothSystem): on a fixed active set the residual
// is smooth, so its Jacobian matches central differences everywhere, also at samples where the
// nonsmooth min would pick the other branch; where the piece is the min's own, it is the nonsmooth
// system; the events are the piece's other quantity (λ where active, −g where inactive; ±g for a
// penalty), ≥ 0 on the piece the min picks.
TEST(NonlinearModes, BackbonePiecesAreSmoothAndTheirEventsMatchTheMin) {
  const auto nm = modes(1e-3, 4, 32);
  for (double k : {0.0, 3e9}) {
    const solvers::NonlinearModes::BackboneSystem system(nm, k);
    Eigen::VectorXd x = wbm::testing::backbone_trial_state(system, k);
    x.head(20) += 1e-2 * Eigen::VectorXd::LinSpaced(20, -1.0, 1.0);
    const double energy = 1.4;
    const solvers::ActiveSet own = system.active_set(x, energy);
    ASSERT_EQ(own.size(), 32U);
    EXPECT_LT((system.residual(x, energy, own) - system.residual(x, energy)).norm(), 1e-15) << "penalty " << k;
    int active = 0;
    for (auto a : own) active += a;
    EXPECT_GT(active, 0);
    EXPECT_LT(active, 32);
    // The min's own piece has every event ≥ 0 (λ ≥ 0 in this trial state).
    const Eigen::VectorXd e = system.events(x, energy, own);
    EXPECT_GE(e.minCoeff(), 0.0) << "penalty " << k;
    solvers::ActiveSet flipped = own;
    for (size_t i = 0; i < flipped.size(); i += 3) flipped[i] ^= 1U;  // a piece the min does not pick
    const Eigen::MatrixXd j(system.linearize(x, energy, flipped).jacobian);
    const Eigen::MatrixXd fd = wbm::testing::fd_jacobian(
        [&](const Eigen::VectorXd& y) { return system.residual(y, energy, flipped); }, x, 1e-7, 1.0);
    EXPECT_LT((j - fd).cwiseAbs().maxCoeff(), 1e-6 * j.cwiseAbs().maxCoeff()) << "penalty " << k;
    // Flipped samples trade their event for the other quantity: λ_s or −g_s (exact), −(±g_s) (penalty).
    const Eigen::VectorXd ef = system.events(x, energy, flipped);
    const Eigen::VectorXd lambda = x.tail(32);
    for (Eigen::Index i = 0; i < ef.size(); ++i) {
      const bool was_active = own[static_cast<size_t>(i)] != 0;
      if (i % 3 != 0) {
        EXPECT_EQ(ef(i), e(i)) << "sample " << i;
      } else if (k > 0.0) {
        EXPECT_EQ(ef(i), -e(i)) << "sample " << i;
      } else {
        EXPECT_EQ(was_active ? e(i) : ef(i), lambda(i)) << "sample " << i;
      }
    }
    EXPECT_THROW((void)system.events(x, energy, solvers::ActiveSet(31)), std::invalid_argument);
  }
}

// Independence from rounding (issue #35): the backbone of the LL11 rod with N = 12, m = 256 (it
// stopped at E = 2.48 on 18ad35a, whose corners were crossed by step halving), again with K
// scaled by (1 + k 1e-12), k = 1 … 3. Every run reaches E = 10, and the frequencies at the landed
// energies 1.8 and 10 agree to 1e-9 relative, the folds to 1e-6.
TEST(NonlinearModes, BackboneThroughItsCornersDoesNotDependOnRounding) {
  const auto problem = scene::mode_problem(scene::load_scene(models::scene_directory() / "ll11_rod.toml"));
  std::vector<double> f18, f10;
  std::vector<std::vector<double>> folds;
  for (int k = 0; k <= 3; ++k) {
    solvers::MechanicalSystem system = problem.system;
    system.stiffness *= 1.0 + k * 1e-12;
    const solvers::NonlinearModes nm(system, problem.stops, {.harmonics = 12, .samples = 256});
    auto o = range(0.5, 10.0);
    o.include = {1.8};
    const auto b = nm.continue_backbone(o);
    ASSERT_TRUE(b.complete()) << "k = " << k << ": " << b.message;
    ASSERT_EQ(b.included.size(), 1U);
    EXPECT_TRUE(b.included[0].converged());
    EXPECT_GT(b.kinks, 50);  // corners crossed as events, not by halving
    f18.push_back(b.included[0].frequency_hz);
    f10.push_back(b.levels.back().frequency_hz);
    folds.push_back(b.folds);
    EXPECT_NEAR(b.levels.back().energy, 10.0, 1e-12);
  }
  for (int k = 1; k <= 3; ++k) {
    EXPECT_NEAR(f18[k], f18[0], 1e-9 * f18[0]) << "k = " << k;
    EXPECT_NEAR(f10[k], f10[0], 1e-9 * f10[0]) << "k = " << k;
    // The same folds: samples τ_s and 1 − τ_s of the time-symmetric orbit reach their surfaces
    // together and must switch together (before, one switched alone with K × (1 + 1e-12) and
    // the branch folded twice more within 3.5e-6 of E near E = 1.98629).
    ASSERT_EQ(folds[k].size(), folds[0].size()) << "k = " << k;
    for (size_t i = 0; i < folds[0].size(); ++i) EXPECT_NEAR(folds[k][i], folds[0][i], 1e-6 * folds[0][i]) << "k = " << k;
  }
}

// The same rod with N = 10 harmonics and m = 128 samples: at E = 2.1493 samples τ = ±1/128 enter
// contact next to the active sample τ = 0, whose multiplier vanishes 1e-5 of arclength later.
// The piece beyond the first switch is ill-conditioned in the multipliers, so its solution through
// the located point has the new multipliers at −1.2e-8 (a band of 1e-10). The branch must go
// on through both switches, as the backbone of a conservative system does (before, the
// continuation took those multipliers for a crossing back, switched the samples back and
// retraced the backbone to the linear mode). Its frequency at E = 1.8 is the finer
// discretization's (N = 12, m = 256) to the discretization error, 1e-5 relative.
// N = 12, m = 512 is worse conditioned still: at E = 1.99207 samples τ = ±2/512 enter with
// multipliers −2.8e-7 on the new piece, known only to about 1e-9 (two corrector solves at the
// same arclength differed by that), while samples ±1/512 leave 3.5e-7 of arclength further on;
// a switching point moved to within the zero band of the new surfaces was never reached and the
// branch turned back there. It must reach E = 2.3 too, with the same frequency at E = 1.8.
TEST(NonlinearModes, BackboneEntersAnIllConditionedPieceWithoutTurningBack) {
  const auto problem = scene::mode_problem(scene::load_scene(models::scene_directory() / "ll11_rod.toml"));
  std::vector<double> f18;
  for (auto [harmonics, samples] : {std::pair{10, 128}, std::pair{12, 256}, std::pair{12, 512}}) {
    const solvers::NonlinearModes nm(problem.system, problem.stops, {.harmonics = harmonics, .samples = samples});
    auto o = range(0.5, 2.3);
    o.include = {1.8};
    const auto b = nm.continue_backbone(o);
    ASSERT_TRUE(b.complete()) << "N = " << harmonics << ", m = " << samples << ": " << b.message;
    EXPECT_EQ(b.stop, solvers::StopReason::RangeReached);
    EXPECT_TRUE(b.folds.empty()) << "N = " << harmonics;
    ASSERT_EQ(b.included.size(), 1U);
    ASSERT_TRUE(b.included[0].converged());
    f18.push_back(b.included[0].frequency_hz);
  }
  EXPECT_NEAR(f18[0], f18[1], 1e-5 * f18[1]);
  EXPECT_NEAR(f18[2], f18[1], 1e-5 * f18[1]);
}

// N = 4, m = 512, the most oversampled pair of the robustness grid (m/(2N + 1) = 57): at
// E = 1.4106 samples τ = ±1/512 release together on the time-symmetric orbit, but with only nine
// functions the constraint rows of the active samples 0, ±1, ±2 are nearly dependent and their
// multipliers come out up to 4 % apart, so their crossings lie 7e-5 of the step apart. One
// switched alone; the new piece then moved its event function at 3e-10 (the probe's rounding)
// against 13 on the old one, the orientation was left to that noise, and with K × (1 + 2e-12)
// or (1 + 3e-12) the branch zigzagged through 6 or 14 extra folds near E = 1.411, with the DOFs
// numbered in reverse it retraced itself there. A flip whose new piece is tangent to a flipped
// entry's surface takes the next crossing entry with it. Every run must reach E = 1.6 with no
// fold and the same frequency at E = 1.5 (the unperturbed run's path, which switched the pair
// together).
TEST(NonlinearModes, TwinSamplesWhoseMultipliersAreIllDeterminedSwitchTogether) {
  const auto problem = scene::mode_problem(scene::load_scene(models::scene_directory() / "ll11_rod.toml"));
  std::vector<double> f15;
  for (int k = 0; k <= 4; ++k) {
    solvers::MechanicalSystem system = problem.system;
    std::vector<solvers::RigidStop> stops = problem.stops;
    if (k < 4) {
      system.stiffness *= 1.0 + k * 1e-12;
    } else {  // the DOFs numbered in reverse
      const auto n = static_cast<int>(system.stiffness.rows());
      Eigen::VectorXi order(n);
      for (int i = 0; i < n; ++i) order(i) = n - 1 - i;
      const Eigen::PermutationMatrix<Eigen::Dynamic> perm(order);
      system.stiffness = (perm * system.stiffness * perm.transpose()).eval();
      system.mass = (perm * system.mass * perm.transpose()).eval();
      for (auto& stop : stops) stop.dof = n - 1 - stop.dof;
    }
    const solvers::NonlinearModes nm(system, stops, {.harmonics = 4, .samples = 512});
    auto o = range(0.5, 1.6);
    o.include = {1.5};
    const auto b = nm.continue_backbone(o);
    ASSERT_TRUE(b.complete()) << "run " << k << ": " << b.message;
    EXPECT_TRUE(b.folds.empty()) << "run " << k << ": " << b.folds.size() << " folds";
    ASSERT_EQ(b.included.size(), 1U);
    ASSERT_TRUE(b.included[0].converged());
    f15.push_back(b.included[0].frequency_hz);
  }
  for (size_t k = 1; k < f15.size(); ++k) EXPECT_NEAR(f15[k], f15[0], 1e-9 * f15[0]) << "run " << k;
}

// The structured KKT solver (block-diagonal harmonic balance + Schur complement on the active
// samples) against a slow reference path, full-pivoting LU of the dense J: three stops (the tip,
// and two along directions over two DOFs each, one of them through the phase DOF), samples on
// both sides of the Signorini switch, the plain and the continuation-bordered J. The penalty
// system of the same stops (harmonics coupled at the stops' DOFs: its Schur complement on the
// harmonics of the stops in contact), plain and bordered, against the same reference. The linear
// mode (A_1 = K̂ − M̂ singular at ω = ω₀) and penalty stops that share a DOF have no usable
// structure: they must go to SparseLu and still solve.
TEST(NonlinearModes, KktSolverSolvesLikeADenseLuAndFallsBackWithoutStructure) {
  const std::vector<solvers::RigidStop> stops{{tip_dof(), 1e-3},
                                              {10, 2e-3, {{10, 0.6}, {11, 0.8}}},
                                              {19, 1.5e-3, {{18, -0.8}, {19, 0.6}}}};
  const solvers::NonlinearModes nm(ll11_system(), stops, {.harmonics = 4, .samples = 32});
  const solvers::NonlinearModes::BackboneSystem system(nm, 0.0);
  // Below every gap, with λ = 0 (the min picks λ: an identity row) except on three samples per
  // stop (λ = 5 > −g: the min picks −g). More active samples than F = 2N + 1 per stop would make
  // J singular (their rows −θ_s e_cᵀ span at most F dimensions).
  Eigen::VectorXd x = system.linear_state(1.0) * 0.5;
  const Eigen::Index ny = system.size() - 3 * 32 - 1;
  x(ny) = 1.3;  // ω²/ω₀², away from every k² ω² = ω_j²
  x.head(ny) += 1e-3 * Eigen::VectorXd::LinSpaced(ny, -1.0, 1.0);
  for (int c = 0; c < 3; ++c) {
    for (int smp : {2, 9, 20 + c}) x(ny + 1 + 32 * c + smp) = 5.0;
  }
  // The plain J at `at` and its continuation-bordered form must both take the structured path
  // and solve as a full-pivoting LU of the dense J does; returns the solver's counts.
  auto solves_like_dense_lu = [](const solvers::NonlinearModes::BackboneSystem& sys, const Eigen::VectorXd& at,
                                 const std::string& label) {
    const auto lin = sys.linearize(at, 1.4);
    const Eigen::VectorXd tangent = Eigen::VectorXd::LinSpaced(sys.size() + 1, 0.5, -0.3);
    const Eigen::SparseMatrix<double> bordered = solvers::detail::bordered(lin, tangent, 1.0, 1.0);
    auto solver = sys.linear_solver();
    int expected_structured = 0;
    for (const Eigen::SparseMatrix<double>* j : {&lin.jacobian, &bordered}) {
      const Eigen::VectorXd rhs = Eigen::VectorXd::LinSpaced(j->rows(), 1.0, -2.0).array().sin();
      const Eigen::VectorXd reference = Eigen::MatrixXd(*j).fullPivLu().solve(rhs);
      EXPECT_TRUE(solver.factorize(*j)) << label << ", rows " << j->rows();
      EXPECT_EQ(solver.counts().structured, ++expected_structured) << label << ", rows " << j->rows();
      EXPECT_LT((solver.solve(rhs) - reference).norm(), 1e-10 * reference.norm()) << label << ", rows " << j->rows();
    }
    return solver.counts();
  };
  const auto c = solves_like_dense_lu(system, x, "exact");
  EXPECT_EQ(c.sparse_lu, 0);
  EXPECT_EQ(c.fallback_solves, 0);
  EXPECT_EQ(c.max_active, 9);  // the Schur complement held the active samples only

  // Penalty: three stops on disjoint DOFs (the one along DOFs 10 and 11 through the phase DOF),
  // amplitudes that press two of them on part of the period (checked by the Schur complement's
  // size: F = 9 unknowns per stop in contact).
  const std::vector<solvers::RigidStop> disjoint{{tip_dof(), 1e-3},
                                                 {10, 2e-3, {{10, 0.6}, {11, 0.8}}},
                                                 {17, 1.5e-3, {{16, -0.8}, {17, 0.6}}}};
  const solvers::NonlinearModes nm_disjoint(ll11_system(), disjoint, {.harmonics = 4, .samples = 32, .phase_dof = 11});
  const solvers::NonlinearModes::BackboneSystem penalty(nm_disjoint, 3e9);
  Eigen::VectorXd xp = x.head(penalty.size());
  xp.head(ny) *= 6.0;
  const auto cp = solves_like_dense_lu(penalty, xp, "penalty");
  EXPECT_EQ(cp.sparse_lu, 0);
  EXPECT_EQ(cp.fallback_solves, 0);
  EXPECT_EQ(cp.max_active, 2 * 9);

  const Eigen::SparseMatrix<double> linear = system.linearize(system.linear_state(0.8), 0.8).jacobian;
  const solvers::NonlinearModes::BackboneSystem penalty_sharing(nm, 3e9);  // the tip DOF in two stops
  const Eigen::SparseMatrix<double> soft = penalty_sharing.linearize(x.head(penalty_sharing.size()), 1.4).jacobian;
  for (const auto& [j, sys] : {std::pair{&linear, &system}, std::pair{&soft, &penalty_sharing}}) {
    auto s = sys->linear_solver();
    const Eigen::VectorXd rhs = Eigen::VectorXd::LinSpaced(j->rows(), 1.0, -2.0);
    const Eigen::VectorXd reference = Eigen::MatrixXd(*j).fullPivLu().solve(rhs);
    ASSERT_TRUE(s.factorize(*j));
    EXPECT_EQ(s.counts().sparse_lu, 1);
    EXPECT_EQ(s.counts().structured, 0);
    EXPECT_LT((s.solve(rhs) - reference).norm(), 1e-10 * reference.norm());
  }
}

// Three independent algorithms land on the same mode at E = 1.2: LL11 Alg. 1 (simultaneous) and
// Alg. 2 (sequential) with Powell's augmented Lagrangian, and the continuation of the KKT
// conditions by semismooth Newton. The orbit frequency √(r − μω₀²E) differs from the Rayleigh
// quotient √r (the paper's eigenvalue) once the stop pushes.
TEST(NonlinearModes, AugmentedLagrangianAndKktContinuationAgree) {
  const auto alg1 = modes(1e-3).solve(1.2);
  const auto alg2 = modes(1e-3, 8, 256, solvers::ModeAlgorithm::Sequential).solve(1.2);
  ASSERT_TRUE(alg1.converged()) << alg1.message;
  ASSERT_TRUE(alg2.converged()) << alg2.message;
  const auto nm = modes(1e-3);
  const auto b = nm.continue_backbone({.energy_min = 0.9, .energy_max = 1.3, .include = {1.2}});
  ASSERT_TRUE(b.complete()) << b.message;
  const auto* kkt = included(b, 1.2);
  ASSERT_NE(kkt, nullptr);
  for (const auto* l : {&alg1, &alg2}) {
    EXPECT_NEAR(l->frequency_hz, kkt->frequency_hz, 1e-7 * kkt->frequency_hz);
    EXPECT_NEAR(l->rayleigh_frequency_hz, kkt->rayleigh_frequency_hz, 1e-7 * kkt->frequency_hz);
    EXPECT_LT((l->coefficients - kkt->coefficients).norm(), 1e-5 * kkt->coefficients.norm());
  }
  EXPECT_GT(kkt->frequency_hz - kkt->rayleigh_frequency_hz, 0.5);  // Hz: not a rounding effect
}

// A stationarity tolerance below what ∇L_κ can be evaluated to: LL11 Alg. 1 converges within 10
// times the measured rounding floor of ∇L_κ, reports that tolerance and says so, and lands on
// the KKT continuation's mode (an independent formulation) as with the default tolerance.
TEST(NonlinearModes, AugmentedLagrangianBelowItsRoundingFloorConvergesAtTheFloorAndSaysSo) {
  const solvers::NonlinearModes strict(ll11_system(), {{tip_dof(), 1e-3}},
                                       {.harmonics = 8, .samples = 256, .stationarity_tolerance = 1e-17});
  const auto level = strict.solve(1.2);
  ASSERT_TRUE(level.converged()) << level.message;
  EXPECT_GT(level.tolerance, 1e-17);
  EXPECT_LT(level.tolerance, 1e-9);  // a rounding floor, not a loose tolerance
  EXPECT_LE(level.residual_norm, level.tolerance);
  EXPECT_NE(level.message.find("converged at the rounding floor"), std::string::npos) << level.message;
  const auto nm = modes(1e-3);
  const auto b = nm.continue_backbone({.energy_min = 0.9, .energy_max = 1.3, .include = {1.2}});
  ASSERT_TRUE(b.complete()) << b.message;
  const auto* kkt = included(b, 1.2);
  ASSERT_NE(kkt, nullptr);
  EXPECT_NEAR(level.frequency_hz, kkt->frequency_hz, 1e-7 * kkt->frequency_hz);
  EXPECT_LT((level.coefficients - kkt->coefficients).norm(), 1e-5 * kkt->coefficients.norm());
}

// Extremes: from below contact to 10 times the onset energy the branch is complete, and at every
// level the Signorini conditions hold at every sample (no penetration, non-negative forces,
// complementarity), the normalization holds, and the frequency never drops below the linear one.
TEST(NonlinearModes, BackboneToTenTimesOnsetKeepsTheKktConditions) {
  const auto nm = modes(1e-3, 8, 64);
  const auto b = nm.continue_backbone(range(0.5, 10.0));
  ASSERT_TRUE(b.complete()) << b.message;
  EXPECT_NEAR(b.levels.back().energy, 10.0, 1e-9);
  for (const auto& l : b.levels) {
    EXPECT_LE(l.max_penetration, 1e-10) << "E = " << l.energy;
    EXPECT_LE(l.complementarity, 1e-10) << "E = " << l.energy;
    EXPECT_LE(l.normalization_error, 1e-10) << "E = " << l.energy;
    EXPECT_GE(l.contact_force.minCoeff(), 0.0);
    EXPECT_GE(l.frequency_hz, nm.linear_frequency_hz() * (1.0 - 1e-12));
    if (l.energy < 1.0) {
      EXPECT_EQ(l.contact_force.maxCoeff(), 0.0);
    }
  }
  EXPECT_GT(b.levels.back().frequency_hz, nm.linear_frequency_hz() + 1.0);  // hardening
}

// A free, undamped time simulation (GSL msbdf, the stop as a 1e11 N/m spring) started from the
// mode at E = 1.2 stays on it for three periods of the orbit frequency, within the truncation to
// N = 8 harmonics (< 1 %), while with the period of the Rayleigh quotient the phase drifts and the
// deviation keeps growing past it.
TEST(NonlinearModes, FreeVibrationFromTheModeStaysOnTheOrbit) {
  const double gap = 1e-3;
  const auto nm = modes(gap);
  const auto b = nm.continue_backbone({.energy_min = 0.9, .energy_max = 1.3, .include = {1.2}});
  const auto* level = included(b, 1.2);
  ASSERT_NE(level, nullptr);
  const int p = 256, periods = 3;
  const Eigen::MatrixXd u = nm.displacement(*level, p), v = nm.velocity(*level, p);
  const std::vector<solvers::ContactPoint> spring = {
      {tip_dof(), std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{1e11, gap})}};
  auto deviation = [&](double f) {
    const auto t = solvers::integrate_free(ll11_system(), spring, u.col(0), v.col(0), 1.0 / f, periods,
                                           {.samples_per_period = p, .relative_tolerance = 1e-9, .absolute_tolerance = 1e-15});
    EXPECT_TRUE(t.report.converged()) << t.report.message;
    std::vector<double> d;
    for (int k = 0; k < periods; ++k) d.push_back((t.displacement.middleCols(k * p, p) - u).cwiseAbs().maxCoeff() / u.cwiseAbs().maxCoeff());
    return d;
  };
  const auto orbit = deviation(level->frequency_hz), rayleigh = deviation(level->rayleigh_frequency_hz);
  for (double d : orbit) EXPECT_LT(d, 1e-2);
  EXPECT_GT(rayleigh.back(), 1e-2);
  EXPECT_GT(rayleigh.back(), 1.5 * orbit.back());
}

// Free motion without contact equals the closed form u(t) = u0 cos ωt + v0/ω sin ωt of a
// 1-DOF oscillator (integrate_free itself).
TEST(NonlinearModes, FreeIntegrationMatchesTheClosedFormOscillator) {
  solvers::MechanicalSystem s;
  s.mass.resize(1, 1);
  s.mass.insert(0, 0) = 2.0;
  s.stiffness.resize(1, 1);
  s.stiffness.insert(0, 0) = 800.0;
  s.damping.resize(1, 1);
  const double w = 20.0, u0 = 1e-3, v0 = 0.05;
  const auto t = solvers::integrate_free(s, {}, Eigen::VectorXd::Constant(1, u0), Eigen::VectorXd::Constant(1, v0),
                                         0.1, 4, {.samples_per_period = 64, .relative_tolerance = 1e-10,
                                                  .absolute_tolerance = 1e-14});
  ASSERT_TRUE(t.report.converged()) << t.report.message;
  ASSERT_EQ(t.time_s.size(), 4 * 64 + 1);
  const double amplitude = std::hypot(u0, v0 / w);  // global error of the BDF (rtol 1e-10) over 1.3 periods
  for (Eigen::Index k = 0; k < t.time_s.size(); ++k) {
    const double tk = t.time_s(k);
    EXPECT_NEAR(t.displacement(0, k), u0 * std::cos(w * tk) + v0 / w * std::sin(w * tk), 5e-7 * amplitude);
    EXPECT_NEAR(t.velocity(0, k), -u0 * w * std::sin(w * tk) + v0 * std::cos(w * tk), 5e-7 * amplitude * w);
  }
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)solvers::integrate_free(s, {}, Eigen::VectorXd::Zero(2), Eigen::VectorXd::Zero(1), 0.1, 1); },
      {"u0 and v0 must be finite vectors of length 1"});
}

// Penalty backbones converge to the exact one at first order in 1/k (penetration O(1/k)).
TEST(NonlinearModes, PenaltyBackbonesConvergeAtFirstOrder) {
  const auto nm = modes(1e-3, 8, 64);
  auto f = [&](double k) {
    const auto b = nm.continue_backbone({.energy_min = 0.9, .energy_max = 1.3, .penalty_stiffness = k, .include = {1.2}});
    const auto* l = included(b, 1.2);
    EXPECT_NE(l, nullptr) << b.message;
    return l != nullptr ? l->frequency_hz : std::nan("");
  };
  const double exact = f(0.0), e10 = f(1e10), e12 = f(1e12);
  EXPECT_LT(e10, exact);  // a softer stop: a lower frequency
  const double ratio = (exact - e10) / (exact - e12);
  EXPECT_GT(ratio, 50.0);
  EXPECT_LT(ratio, 200.0);
}

// Gap → 0: the normalized backbone does not depend on the gap (homogeneity of the problem), from
// 1 mm to 1 nm, through the continuation as well.
TEST(NonlinearModes, ContinuationIsGapInvariant) {
  const auto a = modes(1e-3, 8, 64).continue_backbone({.energy_min = 0.9, .energy_max = 2.0, .include = {1.8}});
  const auto b = modes(1e-9, 8, 64).continue_backbone({.energy_min = 0.9, .energy_max = 2.0, .include = {1.8}});
  const auto *la = included(a, 1.8), *lb = included(b, 1.8);
  ASSERT_NE(la, nullptr);
  ASSERT_NE(lb, nullptr);
  EXPECT_NEAR(la->frequency_hz, lb->frequency_hz, 1e-9 * la->frequency_hz);
  EXPECT_LT((lb->coefficients * 1e6 - la->coefficients).norm(), 1e-8 * la->coefficients.norm());
}

// The 1-DOF impact oscillator has a closed-form nonlinear mode: harmonic arcs of amplitude A
// between elastic impacts at the stop g, period (2π − 2 arccos(g/A))/ωn, and normalized energy
// E = 2 mean(u̇²)/(ω² g²) (the functional of [LL11 Eq. (12)] over its value at onset). The orbit
// frequency of the truncated problem converges to it at first order in 1/N (the velocity jumps
// at impacts, so the Fourier coefficients decay as 1/k²); the Rayleigh quotient does not.
TEST(NonlinearModes, ImpactOscillatorFrequencyConvergesToTheClosedForm) {
  const double wn = 2 * std::numbers::pi * 10.0, g = 1e-3, energy = 1.5;
  solvers::MechanicalSystem s;
  s.mass.resize(1, 1);
  s.mass.insert(0, 0) = 1.0;
  s.stiffness.resize(1, 1);
  s.stiffness.insert(0, 0) = wn * wn;
  s.damping.resize(1, 1);
  auto closed_form = [&](double e) {  // f(E) by bisection on A
    auto normalized = [&](double a_amp) {
      const double a = std::acos(g / a_amp), span = 2 * std::numbers::pi - 2 * a;
      const double mean_v2 = a_amp * a_amp * wn * wn * ((std::numbers::pi - a) + std::sin(2 * a) / 2) / span;
      const double w = 2 * std::numbers::pi * wn / span;
      return 2 * mean_v2 / (w * w * g * g);
    };
    double lo = g, hi = 100 * g;
    for (int i = 0; i < 200; ++i) (normalized(0.5 * (lo + hi)) < e ? lo : hi) = 0.5 * (lo + hi);
    return wn / (2 * std::numbers::pi - 2 * std::acos(g / (0.5 * (lo + hi))));
  };
  const double exact = closed_form(energy);
  EXPECT_NEAR(exact, 13.7485, 1e-4);  // 37.5 % above the linear 10 Hz
  std::vector<double> error;
  for (int n : {8, 16, 32}) {
    const solvers::NonlinearModes nm(s, {{0, g}}, {.harmonics = n, .samples = 16 * n});
    const auto b = nm.continue_backbone({.energy_min = 0.9, .energy_max = 1.6, .include = {energy}});
    const auto* l = included(b, energy);
    ASSERT_NE(l, nullptr) << b.message;
    error.push_back(std::abs(l->frequency_hz - exact) / exact);
    EXPECT_GT(std::abs(l->rayleigh_frequency_hz - exact) / exact, 0.1);  // the paper's ω is not the frequency
  }
  EXPECT_LT(error.back(), 1e-2);
  for (size_t i = 1; i < error.size(); ++i) {
    EXPECT_GT(error[i - 1] / error[i], 1.7);  // first order in 1/N
    EXPECT_LT(error[i - 1] / error[i], 2.3);
  }
}

// Statuses come from verified residuals: a level stopped by the Powell limit, a state moved off
// the branch and a fixed-energy Newton given one iteration are each reported as not converged,
// with the residual and the tolerance it was tested against.
TEST(NonlinearModes, ANonConvergedLevelIsReportedAsSuch) {
  const solvers::NonlinearModes limited(ll11_system(), {{tip_dof(), 1e-3}},
                                        {.harmonics = 8, .samples = 256, .max_powell_iterations = 1});
  const auto level = limited.solve(1.2);
  EXPECT_FALSE(level.converged());
  EXPECT_NE(level.message.find("Powell iteration limit"), std::string::npos) << level.message;

  const auto nm = modes(1e-3, 4, 64);
  const solvers::NonlinearModes::BackboneSystem system(nm, 0.0);
  const auto b = nm.continue_backbone({.energy_min = 0.9, .energy_max = 1.3, .include = {1.2}});
  ASSERT_TRUE(b.complete()) << b.message;
  const auto* at = included(b, 1.2);
  ASSERT_NE(at, nullptr);
  EXPECT_LE(at->residual_norm, at->tolerance);
  // The linear mode at onset, moved by 1e-3 gaps in ten coefficients: not a mode at E = 1.2.
  Eigen::VectorXd x = system.linear_state(1.0);
  x(x.size() - 1) = 1.0;
  x.head(10).array() += 1e-3;
  const auto off = system.level(x, 1.2, 1e-10);
  EXPECT_FALSE(off.converged());
  EXPECT_GT(off.residual_norm, 1e-10);
  EXPECT_NE(off.message.find("tolerance 1e-10"), std::string::npos) << off.message;
  const auto one_step = nm.level_at(system, x, 1.2, {.include = {}, .tolerance = 1e-10, .max_newton_iterations = 1});
  EXPECT_FALSE(one_step.converged());
  EXPECT_EQ(one_step.status, solvers::SolveStatus::MaxIterations);
  EXPECT_NE(one_step.message.find("semismooth Newton at fixed E = 1.2"), std::string::npos) << one_step.message;
}

// Energy stepping (Alg. 1) with a wall-time budget: below contact onset every level is the linear
// mode, and the range is reached; with a budget already spent no level is attempted, and the
// backbone ends incomplete, saying so and naming the option; a negative budget is refused.
TEST(NonlinearModes, EnergySteppingHonoursItsWallTimeBudget) {
  const auto nm = modes(1e-3, 4, 64);
  const auto full = nm.backbone({.energy_min = 0.5, .energy_max = 0.9, .include = {}, .on_level = nullptr, .max_wall_time_s = 0.0});
  ASSERT_TRUE(full.complete()) << full.message;
  EXPECT_EQ(full.stop, solvers::StopReason::RangeReached);
  for (const auto& l : full.levels) EXPECT_NEAR(l.frequency_hz, nm.linear_frequency_hz(), 1e-9 * l.frequency_hz);
  const auto spent = nm.backbone({.energy_min = 0.5, .energy_max = 0.9, .include = {}, .on_level = nullptr, .max_wall_time_s = 1e-300});
  EXPECT_FALSE(spent.complete());
  EXPECT_TRUE(spent.levels.empty());
  EXPECT_EQ(spent.stop, solvers::StopReason::TimeBudget);
  EXPECT_NE(spent.message.find("max_wall_time_s"), std::string::npos) << spent.message;
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { (void)nm.backbone({.energy_min = 0.5, .energy_max = 0.9, .include = {}, .on_level = nullptr, .max_wall_time_s = -1.0}); },
                                           {"max_wall_time_s = -1", "must be >= 0"});
  // Invalid ranges and steps name the fields and their values (issue #41).
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] {
        (void)nm.backbone({.energy_min = 0.9, .energy_max = 0.5, .include = {}, .on_level = nullptr, .max_wall_time_s = 0.0});
      },
      {"BackboneOptions.energy_min = 0.9, energy_max = 0.5", "0 < energy_min < energy_max"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] {
        (void)nm.backbone({.energy_min = 0.5, .energy_max = 0.9, .initial_step = 1e-5, .min_step = 1e-4, .max_step = 0.1,
                           .include = {}, .on_level = nullptr, .max_wall_time_s = 0.0});
      },
      {"BackboneOptions.min_step = 0.0001, initial_step = 1e-05", "min_step <= initial_step <= max_step"});
}

// The modal eigensolver reads one triangle: a non-symmetric K is refused, naming the entry.
TEST(NonlinearModes, RefusesANonSymmetricStiffness) {
  auto system = ll11_system();
  system.stiffness.coeffRef(3, 4) *= 1.01;
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { solvers::NonlinearModes nm(system, {{tip_dof(), 1e-3}}, {.harmonics = 4, .samples = 64}); },
      {"stiffness is not symmetric", "(3, 4)", "(X + X^T)/2"});
}
