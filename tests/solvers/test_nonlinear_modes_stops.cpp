// Nonlinear modes with stops along a direction, modal energy shares, and backbones started away
// from the linear mode ([LL11 Secs. 3–5.1] generalized): changes of coordinates, finite-difference
// Jacobians, the first stop to touch, a shifted orbit and a penalty homotopy that reach the same
// branch.
#include <cmath>
#include <memory>
#include <numbers>
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

namespace {

// The LL11 rod in coordinates v = Qᵀu, Q an orthogonal n × n matrix (a seeded random rotation):
// M_v = QᵀMQ, K_v = QᵀKQ. The tip stop u_tip ≤ g becomes a stop along the direction
// Σ_j Q(tip, j) v_j ≤ g over every DOF.
struct Rotated {
  solvers::MechanicalSystem system;
  Eigen::MatrixXd q;
  solvers::RigidStop stop;
};

Rotated rotated_rod(double gap) {
  const auto s = ll11_system();
  const int n = s.dofs();
  std::srand(7);
  const Eigen::MatrixXd q = Eigen::HouseholderQR<Eigen::MatrixXd>(Eigen::MatrixXd::Random(n, n)).householderQ();
  Rotated r{{}, q, {0, gap}};
  const Eigen::MatrixXd m = q.transpose() * Eigen::MatrixXd(s.mass) * q, k = q.transpose() * Eigen::MatrixXd(s.stiffness) * q;
  r.system.mass = (0.5 * (m + m.transpose())).sparseView();
  r.system.stiffness = (0.5 * (k + k.transpose())).sparseView();
  r.system.damping.resize(n, n);
  Eigen::Index big = 0;
  q.row(tip_dof()).cwiseAbs().maxCoeff(&big);
  r.stop.dof = static_cast<int>(big);
  for (int j = 0; j < n; ++j) r.stop.along.emplace_back(j, q(tip_dof(), j));
  return r;
}

// Harmonic amplitudes √(c_k² + s_k²) per DOF and harmonic (n × (N + 1)): independent of the time
// origin, which each problem fixes on its own phase DOF.
Eigen::MatrixXd harmonic_amplitudes(const Eigen::MatrixXd& y) {
  const Eigen::Index harmonics = (y.cols() - 1) / 2;
  Eigen::MatrixXd a(y.rows(), harmonics + 1);
  a.col(0) = y.col(0).cwiseAbs();
  for (Eigen::Index k = 1; k <= harmonics; ++k) a.col(k) = y.middleCols(2 * k - 1, 2).rowwise().norm();
  return a;
}

}  // namespace

// Backbone::converged is the one definition of a converged backbone (issue #41): the branch
// complete, and a converged level at every energy asked for. Before, `wbm run` checked the levels
// asked for and the Python module did not (complete alone). An energy that was not asked for has
// no level in `included`; a level that did not converge makes the backbone unconverged.
TEST(NonlinearModes, ConvergedNeedsAConvergedLevelAtEveryEnergyAskedFor) {
  const solvers::NonlinearModes modes(ll11_system(), {{tip_dof(), 1e-3}}, {.harmonics = 6, .samples = 96});
  auto b = modes.continue_backbone({.energy_min = 0.5, .energy_max = 1.5, .include = {0.8, 1.2}});
  ASSERT_TRUE(b.complete()) << b.message;
  EXPECT_TRUE(b.converged());
  EXPECT_TRUE(b.converged({0.8, 1.2}));
  EXPECT_FALSE(b.converged({0.8, 0.9}));  // 0.9 was not asked for: no level there
  ASSERT_EQ(b.included.size(), 2u);
  // The same energy to 1e-12 relative, as a scene's levels are read back from decimal text.
  EXPECT_EQ(b.included_at(1.2 * (1.0 + 5e-13)), &b.included[1]);
  EXPECT_EQ(b.included_at(1.2 * (1.0 + 5e-12)), nullptr);
  EXPECT_EQ(b.included_at(0.9), nullptr);
  b.included[1].status = solvers::SolveStatus::MaxIterations;
  EXPECT_FALSE(b.converged({0.8, 1.2}));
  EXPECT_TRUE(b.converged({0.8}));
  b.status = solvers::SolveStatus::PathEnded;  // the range not reached
  EXPECT_FALSE(b.converged());
}

// A stop along a direction is a change of coordinates [issue #15: radial contacts]: the rod
// written in rotated coordinates v = Qᵀu, with its tip stop along the direction Qᵀe_tip over all
// 20 DOFs, has the same backbone as the rod with the stop on the tip DOF — the same frequencies
// below and above contact and the same harmonic amplitudes of u = Q Y_v at every DOF — by the KKT
// continuation and by LL11 Alg. 1.
TEST(NonlinearModes, StopAlongADirectionIsAChangeOfCoordinates) {
  const double gap = 1e-3;
  const auto r = rotated_rod(gap);
  const solvers::NonlinearModeOptions o{.harmonics = 6, .samples = 96};
  const solvers::NonlinearModes plain(ll11_system(), {{tip_dof(), gap}}, o), turned(r.system, {r.stop}, o);
  EXPECT_NEAR(turned.linear_frequency_hz(), plain.linear_frequency_hz(), 1e-9 * plain.linear_frequency_hz());
  EXPECT_LT((r.q * turned.onset_mode() - plain.onset_mode()).norm(), 1e-9 * plain.onset_mode().norm());
  const std::vector<double> energies = {0.8, 1.2, 2.0};
  const auto a = plain.continue_backbone({.energy_min = 0.5, .energy_max = 2.1, .include = energies});
  const auto b = turned.continue_backbone({.energy_min = 0.5, .energy_max = 2.1, .include = energies});
  ASSERT_TRUE(a.complete()) << a.message;
  ASSERT_TRUE(b.complete()) << b.message;
  for (double e : energies) {
    const auto *la = included(a, e), *lb = included(b, e);
    ASSERT_NE(la, nullptr) << e;
    ASSERT_NE(lb, nullptr) << e;
    EXPECT_NEAR(lb->frequency_hz, la->frequency_hz, 1e-9 * la->frequency_hz) << "E = " << e;
    const Eigen::MatrixXd ha = harmonic_amplitudes(la->coefficients), hb = harmonic_amplitudes(r.q * lb->coefficients);
    EXPECT_LT((hb - ha).cwiseAbs().maxCoeff(), 1e-8 * ha.maxCoeff()) << "E = " << e;
    EXPECT_NEAR(lb->contact_force.maxCoeff(), la->contact_force.maxCoeff(), 1e-7 * la->contact_force.maxCoeff() + 1e-12);
    EXPECT_LE(lb->max_penetration, 1e-10);
  }
  EXPECT_GT(included(a, 2.0)->frequency_hz, plain.linear_frequency_hz() + 1.0);  // in contact: not the linear mode
  const auto alg1 = turned.solve(1.2);
  ASSERT_TRUE(alg1.converged()) << alg1.message;
  EXPECT_NEAR(alg1.frequency_hz, included(a, 1.2)->frequency_hz, 1e-7 * alg1.frequency_hz);
}

// The KKT and penalty Jacobians with a stop along a direction against central differences.
TEST(NonlinearModes, DirectionalStopJacobianMatchesFiniteDifferences) {
  const auto r = rotated_rod(1e-3);
  const solvers::NonlinearModes nm(r.system, {r.stop}, {.harmonics = 3, .samples = 24});
  for (double k : {0.0, 3e9}) {
    const solvers::NonlinearModes::BackboneSystem system(nm, k);
    Eigen::VectorXd x = system.linear_state(1.0) * 1.3;
    const Eigen::Index ny = x.size() - 1 - (k == 0.0 ? 24 : 0);
    x(ny) = 1.01;
    x.head(40) += 1e-2 * Eigen::VectorXd::LinSpaced(40, -1.0, 1.0);
    if (k == 0.0) {
      x.tail(24) = Eigen::VectorXd::LinSpaced(24, 0.0, 0.05);
      x(x.size() - 24 + 3) = 0.7;
    }
    const double energy = 1.4;
    const Eigen::MatrixXd j(system.linearize(x, energy).jacobian);
    const Eigen::MatrixXd fd = wbm::testing::fd_jacobian(
        [&](const Eigen::VectorXd& y) { return Eigen::VectorXd(system.residual(y, energy)); }, x, 1e-7, 1.0);
    EXPECT_LT((j - fd).cwiseAbs().maxCoeff(), 1e-6 * j.cwiseAbs().maxCoeff()) << "penalty " << k;
  }
}

// The exact-contact KKT Jacobian, built column by column in compressed storage
// (nonlinear_modes_kkt_jacobian.cpp), on the rotated rod with two stops whose directions span
// every DOF (each DOF in both), on a piece whose active set alternates:
//  - its values match central differences of the piece's residual, and each column's rows are
//    stored strictly ascending (what Eigen, KLU and the KKT solver's scan assume);
//  - at Y = 0, λ = 0 (the ∂/∂s column and the normalization row then vanish) the stored pattern is
//    that of the generic state, explicit zeros kept: it depends on the piece only, which the
//    reuse of SparseLu's symbolic analysis relies on;
//  - KKT symmetry: an active sample's row is minus its multiplier's column over the harmonic
//    balance (−∂g_s/∂Y = −(∂HB/∂λ_s)ᵀ, both Θ e_c), bit for bit, with nothing else in it; an inactive
//    sample's row is the unit row.
TEST(NonlinearModes, ExactBackboneJacobianHasTheKktStructure) {
  const auto r = rotated_rod(1e-3);
  const int n = static_cast<int>(r.system.dofs()), ms = 24;
  solvers::RigidStop mid{0, 2e-3, {}};
  Eigen::Index big = 0;
  r.q.row(tip_dof() - 6).cwiseAbs().maxCoeff(&big);
  mid.dof = static_cast<int>(big);
  for (int j = 0; j < n; ++j) mid.along.emplace_back(j, r.q(tip_dof() - 6, j));
  const solvers::NonlinearModes nm(r.system, {r.stop, mid}, {.harmonics = 3, .samples = ms});
  const solvers::NonlinearModes::BackboneSystem system(nm, 0.0);
  const Eigen::Index nl = 2 * ms, ny = system.size() - 1 - nl;
  Eigen::VectorXd x = system.linear_state(1.0) * 1.3;
  x(ny) = 1.01;
  x.head(40) += 1e-2 * Eigen::VectorXd::LinSpaced(40, -1.0, 1.0);
  x.tail(nl) = Eigen::VectorXd::LinSpaced(nl, 0.01, 0.05);
  const double energy = 1.4;
  solvers::ActiveSet piece(static_cast<size_t>(nl));
  for (size_t i = 0; i < piece.size(); ++i) piece[i] = static_cast<std::uint8_t>(i % 3 != 0);
  const Eigen::SparseMatrix<double> j = system.linearize(x, energy, piece).jacobian;
  const Eigen::MatrixXd fd = wbm::testing::fd_jacobian(
      [&](const Eigen::VectorXd& y) { return Eigen::VectorXd(system.residual(y, energy, piece)); }, x, 1e-7, 1.0);
  const Eigen::MatrixXd dense(j);
  EXPECT_LT((dense - fd).cwiseAbs().maxCoeff(), 1e-6 * dense.cwiseAbs().maxCoeff());
  ASSERT_TRUE(j.isCompressed());  // a valid compressed matrix: each column's rows strictly ascending
  for (Eigen::Index c = 0; c < j.cols(); ++c) {
    for (int e = j.outerIndexPtr()[c] + 1; e < j.outerIndexPtr()[c + 1]; ++e) {
      ASSERT_LT(j.innerIndexPtr()[e - 1], j.innerIndexPtr()[e]) << "column " << c;
    }
  }
  Eigen::VectorXd zero = x;
  zero.head(ny).setZero();
  zero.tail(nl).setZero();
  const Eigen::SparseMatrix<double> j0 = system.linearize(zero, energy, piece).jacobian;
  ASSERT_EQ(j0.nonZeros(), j.nonZeros());
  for (Eigen::Index c = 0; c <= j.cols(); ++c) ASSERT_EQ(j0.outerIndexPtr()[c], j.outerIndexPtr()[c]) << c;
  for (Eigen::Index e = 0; e < j.nonZeros(); ++e) ASSERT_EQ(j0.innerIndexPtr()[e], j.innerIndexPtr()[e]) << e;
  EXPECT_EQ(Eigen::MatrixXd(j0).col(ny).cwiseAbs().maxCoeff(), 0.0);  // stored, and zero
  EXPECT_EQ(Eigen::MatrixXd(j0).row(ny).cwiseAbs().maxCoeff(), 0.0);
  for (Eigen::Index i = 0; i < nl; ++i) {
    const Eigen::Index at = ny + 1 + i;
    if (piece[static_cast<size_t>(i)] != 0) {
      EXPECT_TRUE(dense.row(at).head(ny) == -dense.col(at).head(ny).transpose()) << "active sample " << i;
      EXPECT_EQ(dense.row(at).tail(dense.cols() - ny).cwiseAbs().maxCoeff(), 0.0) << "active sample " << i;
    } else {
      Eigen::RowVectorXd unit = Eigen::RowVectorXd::Zero(dense.cols());
      unit(at) = 1.0;
      EXPECT_TRUE(dense.row(at) == unit) << "inactive sample " << i;
    }
  }
}

// With several stops the energy is normalized by the first stop to touch in the linear mode
// (LL11 Fig. 7: "contact at 1"): a stop at mid-rod with a gap half the tip's touches first
// (the first mode moves the mid node by ~0.7 of the tip), whatever the order of the stops; and a
// tip stop too far to be reached changes nothing (the same frequencies as the mid stop alone).
TEST(NonlinearModes, TheFirstStopToTouchDefinesContactOnset) {
  const double gap = 1e-3;
  const int mid = 9;
  const solvers::NonlinearModeOptions o{.harmonics = 6, .samples = 96};
  const solvers::NonlinearModes both(ll11_system(), {{tip_dof(), 10 * gap}, {mid, 0.5 * gap}}, o);
  const solvers::NonlinearModes alone(ll11_system(), {{mid, 0.5 * gap}}, o);
  EXPECT_EQ(both.onset_stop(), 1);
  EXPECT_NEAR(both.onset_mode()(mid), 0.5 * gap, 1e-15);
  EXPECT_LT(both.onset_mode()(tip_dof()), 10 * gap);
  const auto a = both.continue_backbone({.energy_min = 0.5, .energy_max = 1.6, .include = {0.9, 1.5}});
  const auto b = alone.continue_backbone({.energy_min = 0.5, .energy_max = 1.6, .include = {0.9, 1.5}});
  ASSERT_TRUE(a.complete()) << a.message;
  ASSERT_TRUE(b.complete()) << b.message;
  for (double e : {0.9, 1.5}) {
    const auto *la = included(a, e), *lb = included(b, e);
    ASSERT_NE(la, nullptr);
    ASSERT_NE(lb, nullptr);
    EXPECT_NEAR(la->frequency_hz, lb->frequency_hz, 1e-10 * lb->frequency_hz) << "E = " << e;
    EXPECT_LT(la->coefficients.row(tip_dof()).cwiseAbs().sum(), 10 * gap);  // the far stop never reached
  }
  EXPECT_NEAR(included(a, 0.9)->frequency_hz, both.linear_frequency_hz(), 1e-9 * both.linear_frequency_hz());
  EXPECT_GT(included(a, 1.5)->frequency_hz, both.linear_frequency_hz() + 1.0);  // E = 1 is contact onset
}

TEST(NonlinearModes, RefusesBadDirectionsAndStopsTheModeDoesNotMove) {
  const auto s = ll11_system();
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { solvers::NonlinearModes nm(s, {{tip_dof(), 1e-3, {{3, 1.0}}}}, {}); },
      {"stops[0].along", "dof 19 is not among its DOFs"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { solvers::NonlinearModes nm(s, {{tip_dof(), 1e-3, {{tip_dof(), 0.0}}}}, {}); }, {"every weight is zero"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { solvers::NonlinearModes nm(s, {{tip_dof(), 1e-3, {{tip_dof(), 1.0}, {40, 1.0}}}}, {}); },
      {"DOF 40 must lie in [0, 20)"});
  solvers::MechanicalSystem two;  // decoupled: the first mode moves DOF 0 only
  two.mass = Eigen::MatrixXd::Identity(2, 2).sparseView();
  two.stiffness = Eigen::Vector2d(1.0, 4.0).asDiagonal().toDenseMatrix().sparseView();
  two.damping.resize(2, 2);
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { solvers::NonlinearModes nm(two, {{1, 1e-3}}, {.harmonics = 2, .samples = 8}); },
      {"no stop moves in the first linear mode"});
}

// Modal energy shares against a closed form: an orbit built from the linear modes φ_j (computed
// here by a dense generalized eigensolve, mass-normalized), Y = b φ₁ cos 2πτ + a φ₃ sin 4πτ + c
// (a mean, no kinetic energy), has m̂ = ½ b² + ½ · 4 a², so S(mode 1, h 1) = b²/(b² + 4a²) and
// S(mode 3, h 2) = 4a²/(b² + 4a²), every other entry zero. On the backbone the shares sum to 1;
// below contact the mode is the linear first mode (S(1, 1) = 1), above it other components appear.
TEST(NonlinearModes, ModalEnergySharesSplitTheEnergyOverModesAndHarmonics) {
  const auto s = ll11_system();
  const auto nm = modes(1e-3, 4, 64);
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig{Eigen::MatrixXd(s.stiffness),
                                                                      Eigen::MatrixXd(s.mass)};
  const Eigen::MatrixXd phi = eig.eigenvectors();
  const double a = 2e-4, b = 1e-3;
  solvers::ModeLevel l;
  l.coefficients = Eigen::MatrixXd::Zero(20, 9);
  l.coefficients.col(0).setConstant(3e-4);
  l.coefficients.col(1) = b * phi.col(0);
  l.coefficients.col(4) = a * phi.col(2);  // q_4 = sin 4πτ
  const Eigen::MatrixXd shares = nm.modal_energy_shares(l);
  ASSERT_EQ(shares.rows(), 20);
  ASSERT_EQ(shares.cols(), 5);
  const double total = b * b + 4 * a * a;
  EXPECT_NEAR(shares(0, 1), b * b / total, 1e-10);
  EXPECT_NEAR(shares(2, 2), 4 * a * a / total, 1e-10);
  EXPECT_NEAR(shares.cwiseAbs().sum(), 1.0, 1e-10);
  EXPECT_NEAR(nm.linear_frequencies_hz()(2), std::sqrt(eig.eigenvalues()(2)) / (2 * std::numbers::pi),
              1e-9 * nm.linear_frequencies_hz()(2));

  const auto bb = nm.continue_backbone({.energy_min = 0.5, .energy_max = 2.0, .include = {0.8, 2.0}});
  ASSERT_TRUE(bb.complete()) << bb.message;
  for (const auto& level : bb.levels) {
    const Eigen::MatrixXd sh = nm.modal_energy_shares(level);
    EXPECT_NEAR(sh.sum(), 1.0, 1e-12) << "E = " << level.energy;
    EXPECT_GE(sh.minCoeff(), 0.0);
  }
  EXPECT_NEAR(nm.modal_energy_shares(*included(bb, 0.8))(0, 1), 1.0, 1e-12);
  EXPECT_LT(nm.modal_energy_shares(*included(bb, 2.0))(0, 1), 1.0 - 1e-3);  // in contact: not the linear mode
  l.coefficients = Eigen::MatrixXd::Zero(20, 9);
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { (void)nm.modal_energy_shares(l); },
                                                         {"carries no kinetic energy"});
  l.coefficients = Eigen::MatrixXd::Ones(20, 7);
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { (void)nm.modal_energy_shares(l); },
                                                         {"coefficients 20 × 7", "need 20 × 9"});
}

// A backbone started from an orbit (BackboneContinuationOptions::start) at any time shift is the
// branch from the linear mode: a level at E = 1.5, shifted in time by 0.3 of a period (harmonic k
// rotated by 0.6πk, an equally valid orbit of the autonomous system), continued up and down,
// gives the same frequencies and harmonic amplitudes at E = 2.0 and 1.2 as the branch traced from
// the linear mode. The orbit's energy is invariant under the shift; a start outside the range and
// a bad direction are refused.
TEST(NonlinearModes, ABackboneStartedFromAShiftedOrbitIsTheSameBranch) {
  const auto nm = modes(1e-3, 6, 96);
  const auto ref = nm.continue_backbone({.energy_min = 0.5, .energy_max = 2.1, .include = {1.2, 1.5, 2.0}});
  ASSERT_TRUE(ref.complete()) << ref.message;
  const auto* mid = included(ref, 1.5);
  ASSERT_NE(mid, nullptr);
  Eigen::MatrixXd shifted = mid->coefficients;
  const double theta = 2.0 * std::numbers::pi * 0.3;
  for (int k = 1; k <= 6; ++k) {
    const Eigen::VectorXd c = shifted.col(2 * k - 1), s = shifted.col(2 * k);
    shifted.col(2 * k - 1) = c * std::cos(k * theta) + s * std::sin(k * theta);
    shifted.col(2 * k) = s * std::cos(k * theta) - c * std::sin(k * theta);
  }
  EXPECT_GT(std::abs(shifted(tip_dof(), 2)), 1e-2 * std::abs(mid->coefficients(tip_dof(), 1)));  // really shifted
  EXPECT_NEAR(nm.energy(shifted), 1.5, 1e-10);
  for (int direction : {+1, -1}) {
    const double target = direction > 0 ? 2.0 : 1.2;
    solvers::BackboneContinuationOptions o{.energy_min = 1.0, .energy_max = 2.1, .include = {target}};
    o.start = solvers::PeriodicOrbit{shifted, mid->frequency_hz};
    o.direction = direction;
    const auto b = nm.continue_backbone(o);
    ASSERT_TRUE(b.complete()) << b.message;
    const auto *got = included(b, target), *want = included(ref, target);
    ASSERT_NE(got, nullptr) << target;
    ASSERT_NE(want, nullptr) << target;
    EXPECT_NEAR(got->frequency_hz, want->frequency_hz, 1e-9 * want->frequency_hz) << "E = " << target;
    const Eigen::MatrixXd ha = harmonic_amplitudes(want->coefficients), hb = harmonic_amplitudes(got->coefficients);
    EXPECT_LT((hb - ha).cwiseAbs().maxCoeff(), 1e-7 * ha.maxCoeff()) << "E = " << target;
    EXPECT_NEAR(b.levels.front().energy, 1.5, 1e-9);  // the start, corrected at its own energy
    EXPECT_NEAR(b.levels.back().energy, direction > 0 ? 2.1 : 1.0, 1e-9);
  }
  solvers::BackboneContinuationOptions outside = range(1.6, 2.1);
  outside.start = solvers::PeriodicOrbit{shifted, mid->frequency_hz};
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { (void)nm.continue_backbone(outside); },
                                                         {"start", "E = 1.5", "widen the range"});
  outside.energy_min = 1.0;
  outside.direction = 0;
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { (void)nm.continue_backbone(outside); },
                                                         {"direction = 0", "+1 or -1"});
}

// The penalty homotopy to exact contact (BackboneContinuationOptions::start_penalty_stiffness):
// started from an orbit of soft penalty stops (k = 3e8 N/m, about 1.6 × the rod's static tip
// stiffness EA/L = 1.9e8 N/m, so the orbit penetrates the stop), at E = 4, the
// branch's first point is the exact-contact level at the orbit's energy that the continuation
// from the linear mode reaches independently: same frequency to 1e-9, same harmonic amplitudes
// to 1e-7, and the Signorini conditions hold at it. Refused: a homotopy without a start, with
// penalty stops, or with a negative stiffness.
TEST(NonlinearModes, APenaltyHomotopyFromASoftStopsOrbitReachesTheExactBranch) {
  const auto nm = modes(1e-3, 6, 96);
  const auto exact = nm.continue_backbone({.energy_min = 0.5, .energy_max = 4.5, .include = {4.0}});
  const auto soft = nm.continue_backbone({.energy_min = 0.5, .energy_max = 4.5, .penalty_stiffness = 3e8, .include = {4.0}});
  const auto *want = included(exact, 4.0), *orbit = included(soft, 4.0);
  ASSERT_NE(want, nullptr) << exact.message;
  ASSERT_NE(orbit, nullptr) << soft.message;
  EXPECT_GT(orbit->max_penetration, 1e-2);  // really a different orbit: it penetrates by 1 % of the gap or more
  EXPECT_GT(std::abs(orbit->frequency_hz / want->frequency_hz - 1.0), 1e-5);
  solvers::BackboneContinuationOptions o = range(3.0, 4.5);
  o.start = solvers::PeriodicOrbit{orbit->coefficients, orbit->frequency_hz};
  o.start_penalty_stiffness = 3e8;
  o.max_points = 3;  // the first point is the test
  const auto b = nm.continue_backbone(o);
  ASSERT_FALSE(b.levels.empty()) << b.message;
  const auto& got = b.levels.front();
  EXPECT_GE(b.homotopy_stages, 1);
  EXPECT_GE(b.homotopy_stiffness, 3e8);
  EXPECT_NE(b.message.find("penalty homotopy"), std::string::npos) << b.message;
  EXPECT_NEAR(got.energy, 4.0, 1e-9);
  EXPECT_NEAR(got.frequency_hz, want->frequency_hz, 1e-9 * want->frequency_hz);
  const Eigen::MatrixXd ha = harmonic_amplitudes(want->coefficients), hb = harmonic_amplitudes(got.coefficients);
  EXPECT_LT((hb - ha).cwiseAbs().maxCoeff(), 1e-7 * ha.maxCoeff());
  EXPECT_LT(got.max_penetration, 1e-10);
  EXPECT_LT(got.complementarity, 1e-10);
  EXPECT_GT(got.contact_force.maxCoeff(), 0.0);

  // Without the homotopy, semismooth Newton from the same orbit (zero multipliers) does not
  // converge: the case the option exists for.
  solvers::BackboneContinuationOptions direct = o;
  direct.start_penalty_stiffness = 0.0;
  EXPECT_EQ(nm.continue_backbone(direct).stop, solvers::StopReason::InitialPointFailed);
  solvers::BackboneContinuationOptions bad = range(3.0, 4.5);
  bad.start_penalty_stiffness = 1e9;
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { (void)nm.continue_backbone(bad); },
                                                         {"start_penalty_stiffness = 1e+09", "needs a start orbit"});
  bad.start = o.start;
  bad.penalty_stiffness = 1e10;
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { (void)nm.continue_backbone(bad); },
                                                         {"exact contact", "penalty_stiffness = 0, here 1e+10"});
  bad.penalty_stiffness = 0.0;
  bad.start_penalty_stiffness = -1.0;
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { (void)nm.continue_backbone(bad); },
                                                         {"start_penalty_stiffness = -1", ">= 0 [N/m]"});
}
