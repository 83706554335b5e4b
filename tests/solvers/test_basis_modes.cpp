// Nonlinear modes in a time basis (basis_modes.hpp) against truths this code did not produce: the
// 1-DOF oscillator against a stop in closed form, the central-difference frequency of Haar's
// linear mode, the Fourier KKT backbone of NonlinearModes (an independent code for the same
// equations), and finite differences of the Jacobian.
#include <wbm/solvers/basis_modes.hpp>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "impact_oscillators.hpp"
#include "nonlinear_modes_fixtures.hpp"
#include "testing.hpp"

using namespace wbm;

namespace {

// The 1-DOF oscillator m ü + k u = 0 against a stop at u = g with elastic impacts: between
// impacts u = −A cos ω_n t (A > g), T = 2θ/ω_n with θ = π − arccos(g/A), and
// ∫₀ᵀ u̇² dt = A² ω_n (θ − sin 2θ / 2). Its E = m̂/m̂_c with m̂ = (m/T) ∫ u̇² dt / ω², ω = 2π/T,
// and m̂_c = ½ m g² (the linear mode at onset): E(A) grows with A from E(g) = 1.
struct OneDofOrbit {
  double energy, frequency_hz;
};
OneDofOrbit one_dof_orbit(double wn, double gap, double amplitude) {
  const double theta = std::numbers::pi - std::acos(gap / amplitude), period = 2.0 * theta / wn;
  const double w = 2.0 * std::numbers::pi / period;
  const double msr = amplitude * amplitude * wn * (theta - 0.5 * std::sin(2.0 * theta)) / period / (w * w);
  return {msr / (0.5 * gap * gap), 1.0 / period};
}
// The closed-form frequency at energy E > 1 (bisection on A).
double one_dof_frequency(double wn, double gap, double energy) {
  double lo = gap, hi = 10.0 * gap;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (one_dof_orbit(wn, gap, mid).energy < energy ? lo : hi) = mid;
  }
  return one_dof_orbit(wn, gap, 0.5 * (lo + hi)).frequency_hz;
}

solvers::TimeBasis basis(const std::string& name, int dimension) { return solvers::TimeBasis::from_name(name, dimension); }

// `call` throws std::invalid_argument whose message holds every one of `parts`.
template <class F>
void expect_refused(F call, const std::vector<std::string>& parts) {
  try {
    call();
    ADD_FAILURE() << "no exception; expected one naming " << parts.front();
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    for (const auto& p : parts) EXPECT_NE(what.find(p), std::string::npos) << "'" << p << "' not in: " << what;
  }
}

}  // namespace

// The 1-DOF oscillator at E = 1.5 (one impact per period) against the closed form. The impact of
// the exact orbit falls between two Signorini instants, and the discrete orbit may rest on the
// stop from one to the next: its period is longer by up to about 1/m of itself, so every basis
// converges at first order in M here (measured: Fourier 3.0e-2 at M = 16, 8.1e-3 at 64; Haar
// observed order 0.99 from 32 to 256), not at the order of its approximation of smooth functions.
TEST(BasisModes, OneDofLevelsConvergeToTheClosedForm) {
  const double m = 2.0, k = 8.0e4, gap = 1e-3, wn = std::sqrt(k / m), energy = 1.5;
  const double exact = one_dof_frequency(wn, gap, energy);
  const solvers::NonlinearModes problem(wbm::testing::one_dof_system(m, 0.0, k), {{0, gap}}, {.harmonics = 1, .samples = 3});
  auto error = [&](const std::string& name, int dim, double offset) {
    const solvers::BasisModes modes(problem, basis(name, dim), {.samples = 0, .sample_offset = offset});
    auto o = wbm::testing::range(0.5, 1.6);
    o.include = {energy};
    const auto b = modes.continue_backbone(o);
    EXPECT_TRUE(b.complete()) << name << " M = " << dim << ": " << b.message;
    const auto* l = b.included_at(energy);
    if (l == nullptr || !l->level.converged()) {
      ADD_FAILURE() << name << " M = " << dim << ": no converged level at E = " << energy;
      return 1.0;
    }
    const double e = std::abs(l->level.frequency_hz / exact - 1.0);
    EXPECT_LE(e, 2.0 / dim) << name << " M = " << dim;
    return e;
  };
  for (const std::string name : {"fourier", "bspline", "db6"}) {
    const double coarse = error(name, 16, 0.0), fine = error(name, 64, 0.0);
    EXPECT_LT(fine, coarse / 3.0) << name;
  }
  std::vector<double> h, errors;
  for (int dim : {32, 64, 128, 256}) {
    h.push_back(1.0 / dim);
    errors.push_back(error("haar", dim, 0.5));
  }
  const double order = wbm::testing::observed_order(h, errors);
  EXPECT_GT(order, 0.8);
  EXPECT_LT(order, 1.2);
}

// Below contact the Haar Galerkin system is the periodic central-difference scheme with M steps:
// with B's eigenvalue M² · 4 sin²(π/M)/4π² on the fundamental, f = f₁ (π/M)/sin(π/M) exactly.
TEST(BasisModes, HaarLinearModeIsTheCentralDifferenceScheme) {
  const auto problem = wbm::testing::modes(1e-3, 1, 3);
  for (int dim : {16, 64}) {
    const solvers::BasisModes modes(problem, basis("haar", dim));
    auto o = wbm::testing::range(0.5, 0.9);
    o.include = {0.7};
    const auto b = modes.continue_backbone(o);
    ASSERT_TRUE(b.complete()) << b.message;
    const auto* l = b.included_at(0.7);
    ASSERT_NE(l, nullptr);
    const double x = std::numbers::pi / dim;
    EXPECT_NEAR(l->level.frequency_hz, problem.linear_frequency_hz() * x / std::sin(x), 1e-10 * problem.linear_frequency_hz()) << dim;
    EXPECT_NEAR(l->level.normalization_error, 0.0, 1e-10);
    EXPECT_EQ(l->level.contact_force.maxCoeff(), 0.0);
  }
}

// With the Fourier functions of NonlinearModes (harmonics 0 … N, samples τ_s = s/m) BasisModes
// solves the equations of NonlinearModes::continue_backbone, written and solved by another code
// (harmonic-balance blocks, the phase coefficient removed, the structured KKT solver): the same
// levels in contact.
TEST(BasisModes, FourierBasisGivesTheLevelsOfNonlinearModes) {
  const auto problem = wbm::testing::modes(1e-3, 8, 64);
  const solvers::BasisModes modes(problem, solvers::TimeBasis::fourier_harmonics(8), {.samples = 64, .sample_offset = 0.0});
  auto o = wbm::testing::range(0.5, 1.3);
  o.include = {1.1, 1.2};
  const auto reference = problem.continue_backbone(o);
  const auto b = modes.continue_backbone(o);
  ASSERT_TRUE(reference.complete()) << reference.message;
  ASSERT_TRUE(b.complete()) << b.message;
  for (double e : o.include) {
    const auto* r = wbm::testing::included(reference, e);
    const auto* l = b.included_at(e);
    ASSERT_NE(r, nullptr);
    ASSERT_NE(l, nullptr);
    EXPECT_NEAR(l->level.frequency_hz, r->frequency_hz, 1e-9 * r->frequency_hz) << e;
    EXPECT_GT(r->contact_force.sum(), 0.0);
    EXPECT_NEAR(l->level.contact_force.sum(), r->contact_force.sum(), 1e-6 * r->contact_force.sum()) << e;
    EXPECT_NEAR(l->phase_multiplier, 0.0, 1e-12);  // a shift-invariant span
  }
}

// The Jacobian of every piece against central differences of its residual, for each basis, at a
// state with the tip beyond its gap over part of the period and multipliers of both signs.
TEST(BasisModes, JacobianMatchesFiniteDifferences) {
  const auto problem = wbm::testing::modes(1e-3, 1, 3);
  for (const std::string name : {"fourier", "bspline", "db6", "haar"}) {
    const solvers::BasisModes modes(problem, basis(name, 16));
    Eigen::VectorXd x = modes.linear_guess(1.4);
    const Eigen::Index ny = modes.size() - 2 - modes.samples();
    x.segment(ny + 1, modes.samples()) = Eigen::VectorXd::LinSpaced(modes.samples(), -0.02, 0.05);
    x(x.size() - 1) = 0.01;
    const auto active = modes.active_set(x, 1.4);
    int on = 0;
    for (auto a : active) on += a;
    EXPECT_GT(on, 0) << name;
    EXPECT_LT(on, modes.samples()) << name;
    const Eigen::MatrixXd j(modes.linearize(x, 1.4, active).jacobian);
    const Eigen::MatrixXd fd =
        wbm::testing::fd_jacobian([&](const Eigen::VectorXd& z) { return modes.residual(z, 1.4, active); }, x, 1e-6, 1e-3);
    EXPECT_LE((j - fd).norm(), 1e-7 * fd.norm()) << name;
    EXPECT_EQ(modes.linearize(x, 1.4, active).parameter_derivative(ny), -1.0);
  }
}

TEST(BasisModes, RefusesBadInput) {
  const auto problem = wbm::testing::modes(1e-3, 1, 3);
  expect_refused([&] { (void)solvers::BasisModes(problem, basis("db4", 16)); }, {"DB4", "Haar"});
  expect_refused([&] { (void)solvers::BasisModes(problem, basis("haar", 1)); }, {"M = 1", "M >= 2"});
  expect_refused(
      [&] { (void)solvers::BasisModes(problem, basis("haar", 16), {.samples = 8, .sample_offset = 0.5}); },
      {"samples = 8", "M = 16"});
  expect_refused(
      [&] { (void)solvers::BasisModes(problem, basis("haar", 16), {.samples = 0, .sample_offset = 1.0}); },
      {"sample_offset = 1", "[0, 1)"});
  const solvers::BasisModes modes(problem, basis("haar", 16));
  expect_refused([&] { (void)modes.continue_backbone(wbm::testing::range(1.2, 2.0)); },
                                        {"energy_min = 1.2", "energy_min < 1"});
  auto o = wbm::testing::range(0.5, 2.0);
  o.penalty_stiffness = 1e6;
  expect_refused([&] { (void)modes.continue_backbone(o); }, {"penalty", "NonlinearModes::continue_backbone"});
}
