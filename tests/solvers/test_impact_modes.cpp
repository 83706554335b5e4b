// Exact conservative orbits with elastic impacts (impact_modes.hpp) against truths this code did
// not produce: the 1-DOF oscillator against a stop in closed form (period, m̂), central
// differences of the flow, the symplecticity of a conservative monodromy, and the Fourier KKT
// backbone of [LL11 Sec. 5.1], which converges to these orbits as N grows.
#include <wbm/solvers/impact_modes.hpp>

#include <cmath>
#include <numbers>
#include <vector>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <wbm/solvers/nonlinear_modes.hpp>

#include "impact_oscillators.hpp"
#include "nonlinear_modes_fixtures.hpp"
#include "testing.hpp"

using namespace wbm;
using wbm::testing::stop_at;

namespace {

// Two masses on springs (ground–k1–m1–k2–m2), a stop on m2: a non-classical 2-DOF chain.
solvers::MechanicalSystem two_mass_chain_undamped() {
  Eigen::MatrixXd m(2, 2), k(2, 2);
  m << 1.0, 0.0, 0.0, 0.5;
  k << 3000.0, -1200.0, -1200.0, 1200.0;
  solvers::MechanicalSystem s;
  s.mass = m.sparseView();
  s.stiffness = k.sparseView();
  s.damping = Eigen::SparseMatrix<double>(2, 2);
  return s;
}

}  // namespace

// u = −A cos ω_n t between impacts at u = g (A > g): T = 2θ/ω_n with θ = π − arccos(g/A), and
// ∫ u̇² dt = A² ω_n (θ − sin 2θ / 2) over a period; the 2 × 2 monodromy has only the trivial pair.
TEST(ImpactModes, OneDofOscillatorMatchesTheClosedForm) {
  const double m = 2.0, k = 8.0e4, gap = 1e-3, amplitude = 1.6e-3;
  const double wn = std::sqrt(k / m), theta = std::numbers::pi - std::acos(gap / amplitude);
  const double period = 2.0 * theta / wn;
  const auto system = wbm::testing::one_dof_system(m, 0.0, k);
  const Eigen::Vector2d guess(-amplitude * 1.02, 0.0);
  const double h = 0.5 * k * amplitude * amplitude;
  const auto orbit = solvers::shoot_conservative_orbit(system, stop_at(0, gap), guess, 1.05 * period, 0,
                                                       solvers::OrbitLevel::Energy, h, {}, 4096);
  ASSERT_TRUE(orbit.converged()) << orbit.report.message;
  EXPECT_NEAR(orbit.period_s, period, 1e-12 * period);
  EXPECT_NEAR(orbit.state(0), -amplitude, 1e-10 * amplitude);
  EXPECT_EQ(orbit.state(1), 0.0);
  ASSERT_EQ(orbit.period.events.size(), 1U);
  const double w = 2.0 * std::numbers::pi / period;
  const double msr = m * amplitude * amplitude * wn * (theta - 0.5 * std::sin(2.0 * theta)) / period / (w * w);
  EXPECT_NEAR(orbit.mean_square_rate, msr, 1e-6 * msr);  // trapezoid on 4096 samples, kink at the impact
  EXPECT_EQ(orbit.nontrivial_multipliers.size(), 0);
  for (Eigen::Index i = 0; i < 2; ++i) EXPECT_NEAR(std::abs(orbit.multipliers(i) - 1.0), 0.0, 1e-6) << i;
  EXPECT_TRUE(orbit.stable);
  // The same orbit fixed by its period instead.
  const auto by_period = solvers::shoot_conservative_orbit(system, stop_at(0, gap), guess, 1.05 * period, 0,
                                                           solvers::OrbitLevel::Period, period);
  ASSERT_TRUE(by_period.converged()) << by_period.report.message;
  EXPECT_NEAR(by_period.state(0), -amplitude, 1e-9 * amplitude);
}

// The saltation monodromy against central differences of the flow over the exact period, and the
// identities of a conservative monodromy: symplectic, the trivial eigenvector f(x₀), reciprocal
// nontrivial multipliers (det R = 1).
TEST(ImpactModes, ChainMonodromyMatchesCentralDifferencesAndIsSymplectic) {
  const auto system = two_mass_chain_undamped();
  const Eigen::MatrixXd m(system.mass), k(system.stiffness);
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(k, m);
  const Eigen::VectorXd phi = eig.eigenvectors().col(0) / eig.eigenvectors().col(0)(1);
  const double gap = 1e-3, w1 = std::sqrt(eig.eigenvalues()(0));
  Eigen::VectorXd guess(4);
  guess << -1.3 * gap * phi, 0.0, 0.0;
  const double h = 0.5 * guess.head(2).dot(k * guess.head(2));
  const auto orbit = solvers::shoot_conservative_orbit(system, stop_at(1, gap), guess, 2.0 * std::numbers::pi / w1, 1,
                                                       solvers::OrbitLevel::Energy, h);
  ASSERT_TRUE(orbit.converged()) << orbit.report.message;
  ASSERT_GE(orbit.period.events.size(), 1U);
  solvers::ImpactFlowOptions fo;
  fo.restitution = 1.0;
  const solvers::ImpactFlow flow(system, {0, 0.0, orbit.frequency_hz}, stop_at(1, gap), fo);
  const Eigen::MatrixXd fd = solvers::finite_difference_monodromy(flow, orbit.state, 0.0, 1e-6);
  const Eigen::MatrixXd& salt = orbit.period.monodromy;
  EXPECT_LT((salt - fd).norm(), 1e-6 * salt.norm());
  EXPECT_LT(orbit.symplectic_defect, 1e-10);
  ASSERT_EQ(orbit.nontrivial_multipliers.size(), 2);
  EXPECT_NEAR(std::abs(orbit.nontrivial_multipliers(0) * orbit.nontrivial_multipliers(1)), 1.0, 1e-9);
}

// [LL11 Sec. 5.1] rod: below contact the level is the linear mode, an exact orbit (stable, zero
// distance); above it the Fourier KKT level at E = 1.2 has an exact orbit with elastic impacts
// within a few % of it, at the same frequency to 1e-5 and the same E to 1e-4 (two independent
// methods: harmonic balance with Signorini conditions at m instants, and event-driven shooting),
// and that orbit's saltation monodromy agrees with central differences of the flow.
TEST(ImpactModes, Ll11RodLevelsHaveExactOrbitsNearThem) {
  const auto system = wbm::testing::ll11_system();
  const double gap = 1e-3;
  const auto modes = wbm::testing::modes(gap, 16, 256);
  auto o = wbm::testing::range(0.5, 1.3);
  o.include = {0.8, 1.2};
  const auto b = modes.continue_backbone(o);
  const auto* linear = wbm::testing::included(b, 0.8);
  const auto* level = wbm::testing::included(b, 1.2);
  ASSERT_NE(linear, nullptr);
  ASSERT_NE(level, nullptr);
  const auto lin = modes.stability(*linear);
  ASSERT_TRUE(lin.available) << lin.message;
  EXPECT_TRUE(lin.stable);
  EXPECT_EQ(lin.impacts, 0);
  EXPECT_LT(lin.distance, 1e-10);
  EXPECT_NEAR(lin.frequency_hz, modes.linear_frequency_hz(), 1e-9 * modes.linear_frequency_hz());
  for (Eigen::Index i = 0; i < lin.multipliers.size(); ++i) EXPECT_NEAR(std::abs(lin.multipliers(i)), 1.0, 1e-8) << i;
  const auto st = modes.stability(*level);
  ASSERT_TRUE(st.available) << st.message;
  EXPECT_GE(st.impacts, 1);
  EXPECT_LT(st.distance, 0.1);
  EXPECT_NEAR(st.frequency_hz, level->frequency_hz, 1e-5 * level->frequency_hz);
  EXPECT_NEAR(st.energy, 1.2, 1e-4);
  EXPECT_LT(st.symplectic_defect, 1e-10);
  // det of the reduced map is 1 (symplectic): the product of the nontrivial multipliers' moduli.
  double product = 1.0;
  for (Eigen::Index i = 0; i < st.multipliers.size(); ++i) product *= std::abs(st.multipliers(i));
  EXPECT_NEAR(product, 1.0, 1e-6);
  EXPECT_EQ(st.stable, st.max_modulus <= 1.0 + solvers::ConservativeOrbitOptions{}.stability_tolerance);
  solvers::ImpactFlowOptions fo;
  fo.restitution = 1.0;
  solvers::MechanicalSystem undamped = system;
  undamped.damping = Eigen::SparseMatrix<double>(system.dofs(), system.dofs());
  const solvers::ImpactFlow flow(undamped, {0, 0.0, st.orbit.frequency_hz}, stop_at(wbm::testing::tip_dof(), gap), fo);
  const Eigen::MatrixXd fd = solvers::finite_difference_monodromy(flow, st.orbit.state, 0.0, 1e-6);
  const Eigen::MatrixXd& salt = st.orbit.period.monodromy;
  // In the shooting's scaling (velocities by ω), where both blocks are O(1).
  const Eigen::Index n = system.dofs();
  const double w = 2.0 * std::numbers::pi * st.orbit.frequency_hz;
  Eigen::VectorXd d = Eigen::VectorXd::Ones(2 * n);
  d.tail(n) /= w;
  const Eigen::MatrixXd diff = d.asDiagonal() * (salt - fd) * d.cwiseInverse().asDiagonal();
  const Eigen::MatrixXd ref = d.asDiagonal() * salt * d.cwiseInverse().asDiagonal();
  EXPECT_LT(diff.norm(), 1e-6 * ref.norm());
  // The monodromy carried in the free phase's eigen-coordinates against the dense products of
  // every transition and saltation matrix (the slow path): the flow itself (events, end state)
  // does not depend on it, bit for bit.
  fo.dense_monodromy = true;
  const solvers::ImpactFlow dense(undamped, {0, 0.0, st.orbit.frequency_hz}, stop_at(wbm::testing::tip_dof(), gap), fo);
  const auto slow = dense.flow(st.orbit.state, 0.0, 1.0 / st.orbit.frequency_hz);
  const auto fast = flow.flow(st.orbit.state, 0.0, 1.0 / st.orbit.frequency_hz);
  ASSERT_EQ(fast.events.size(), slow.events.size());
  for (size_t e = 0; e < fast.events.size(); ++e) EXPECT_EQ(fast.events[e].time_s, slow.events[e].time_s) << e;
  EXPECT_EQ(fast.state, slow.state);
  const Eigen::MatrixXd gap_fast = d.asDiagonal() * (fast.monodromy - slow.monodromy) * d.cwiseInverse().asDiagonal();
  EXPECT_LT(gap_fast.norm(), 1e-11 * ref.norm());  // measured: 1.6e-13
}

// Bad input names the parameter.
TEST(ImpactModes, RefusesBadInput) {
  const auto system = wbm::testing::one_dof_system(1.0, 0.0, 1.0e4);
  const Eigen::Vector2d guess(-2e-3, 0.0);
  EXPECT_THROW((void)solvers::shoot_conservative_orbit(system, stop_at(0, 1e-3), guess, -1.0, 0,
                                                       solvers::OrbitLevel::Energy, 1.0),
               std::invalid_argument);
  EXPECT_THROW((void)solvers::shoot_conservative_orbit(system, stop_at(0, 1e-3), guess, 0.05, 3,
                                                       solvers::OrbitLevel::Energy, 1.0),
               std::invalid_argument);
  EXPECT_THROW((void)solvers::shoot_conservative_orbit(system, stop_at(0, 1e-3), guess, 0.05, 0,
                                                       solvers::OrbitLevel::Period, 0.0),
               std::invalid_argument);
  solvers::ConservativeOrbitOptions bad;
  bad.stability_tolerance = -1.0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

// The verdict against the exact flow itself: a perturbation δ of the exact orbit's start on its
// energy surface (∇Hᵀ δ = 0, so the period does not drift) grows like max|μ|^k over k periods
// when the orbit is unstable, and stays of its size when it is stable. The 2-DOF chain of
// examples/scenes/two_dof_nnm.toml (wall–k–a–k–b, a stop on b), at E = 1.5 and 2.8.
TEST(ImpactModes, PerturbationsGrowAsTheLargestMultiplierSays) {
  solvers::MechanicalSystem chain;
  Eigen::MatrixXd k(2, 2);
  k << 2000.0, -1000.0, -1000.0, 1000.0;
  chain.mass = Eigen::MatrixXd::Identity(2, 2).sparseView();
  chain.stiffness = k.sparseView();
  chain.damping = Eigen::SparseMatrix<double>(2, 2);
  const double gap = 1e-3;
  const solvers::NonlinearModes modes(chain, {{1, gap}}, {.harmonics = 8, .samples = 64});
  auto o = wbm::testing::range(0.5, 3.0);
  o.include = {1.5, 2.8};
  const auto b = modes.continue_backbone(o);
  solvers::ImpactFlowOptions fo;
  fo.restitution = 1.0;
  for (double e : {1.5, 2.8}) {
    const auto* level = wbm::testing::included(b, e);
    ASSERT_NE(level, nullptr) << e;
    const auto st = modes.stability(*level);
    ASSERT_TRUE(st.available) << st.message;
    const Eigen::VectorXd x0 = st.orbit.state;
    Eigen::VectorXd grad(4);
    grad << k * x0.head(2), x0.tail(2);  // ∇H = (K u, M u̇)
    Eigen::VectorXd delta(4);
    delta << 0.3, -0.7, 0.5 * st.orbit.frequency_hz, 0.2 * st.orbit.frequency_hz;  // m, m/s of like size
    delta -= grad * (grad.dot(delta) / grad.squaredNorm());
    delta *= 1e-9 * x0.norm() / delta.norm();
    const solvers::ImpactFlow flow(chain, {0, 0.0, st.orbit.frequency_hz}, stop_at(1, gap), fo);
    auto deviation = [&](int periods) {
      const double t = periods * st.orbit.period_s;
      return (flow.flow(x0 + delta, 0.0, t).state - flow.flow(x0, 0.0, t).state).norm() / delta.norm();
    };
    const double d8 = deviation(8), d16 = deviation(16);
    if (st.stable) {
      EXPECT_LT(d16, 20.0) << "E = " << e << ": a stable orbit's perturbation grew by " << d16;
    } else {
      const double rate = std::pow(d16 / d8, 1.0 / 8.0);
      EXPECT_NEAR(rate, st.max_modulus, 0.05 * st.max_modulus) << "E = " << e;
    }
  }
}
