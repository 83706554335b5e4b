#include <wbm/solvers/weighted_residual.hpp>

#include <cmath>
#include <complex>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>
#include <gsl/gsl_integration.h>
#include <gtest/gtest.h>

#include <wbm/contact/penalty.hpp>
#include <wbm/solvers/post_processing.hpp>
#include <wbm/solvers/time_integration.hpp>
#include <wbm/spectral/layout.hpp>

#include "shipped_scenes.hpp"
#include "testing.hpp"
#include "weighted_residual_fixtures.hpp"

using namespace wbm;
using solvers::Formulation;
using solvers::TimeBasis;
using wbm::testing::case1;
using wbm::testing::kTable2;
using wbm::testing::Pair;

namespace {

Eigen::VectorXd uniform_tau(int p) {
  Eigen::VectorXd tau(p);
  for (int k = 0; k < p; ++k) tau(k) = static_cast<double>(k) / p;
  return tau;
}

// Tip displacement of the direct (no-contact) frequency response on the samples tau.
Eigen::VectorXd direct_tip(const scene::Scene& s, const Eigen::VectorXd& tau) {
  const Eigen::VectorXcd u = solvers::frequency_response(s.system(), s.harmonic_forcing());
  Eigen::VectorXd out(tau.size());
  for (Eigen::Index p = 0; p < tau.size(); ++p) {
    out(p) = std::real(u(s.harmonic_forcing().dof) * std::exp(std::complex<double>(0.0, 2.0 * std::numbers::pi * tau(p))));
  }
  return out;
}

double linear_tip_error(const scene::Scene& s, const Pair& pair, int m, Formulation f, int samples = 0) {
  const auto trial = TimeBasis::from_name(pair.trial, m);
  const auto sol = solvers::solve_weighted_residual(s.system(), s.harmonic_forcing(), {}, trial,
                                                    TimeBasis::from_name(pair.weighting, m),
                                                    {.formulation = f, .time_samples = samples});
  const Eigen::VectorXd tau = uniform_tau(1024);
  return solvers::rms_relative_error(
      solvers::evaluate_trial(trial, sol.coefficients, s.harmonic_forcing().dof, tau, s.forcing->frequency_hz), direct_tip(s, tau));
}

}  // namespace

// Without contact the response is one harmonic. Derived orders of the rms error against the
// direct frequency response: the Galerkin/Petrov–Galerkin solution of this shift-invariant
// problem lies within a constant of the best approximation in the trial space (the discrete
// Rayleigh-quotient symbol error is O(h^{2p}), squared), so the error is the trial space's
// approximation order p: cubic B-spline 4 (Strang–Fix), DB6 3 (vanishing moments), Haar 1.
// Fourier trial functions contain the solution: exact to rounding.
class LinearConvergence : public ::testing::TestWithParam<Pair> {};

TEST_P(LinearConvergence, ConvergesToDirectFrequencyResponseAtTheDerivedOrder) {
  const Pair pair = GetParam();
  const auto s = case1();
  const std::string trial = pair.trial;
  if (trial == "fourier") {
    // M = 2^J and M = 2H + 1 (H = 3, 15) alike
    for (int m : {8, 32, 7, 31}) EXPECT_LT(linear_tip_error(s, pair, m, Formulation::Distributional), 1e-11) << m;
    return;
  }
  const double expected = trial == "bspline" ? 4.0 : trial == "db6" ? 3.0 : 1.0;
  std::vector<double> h, e;
  for (int m : {16, 32, 64}) {
    h.push_back(1.0 / m);
    e.push_back(linear_tip_error(s, pair, m, Formulation::Distributional));
  }
  EXPECT_NEAR(wbm::testing::observed_order(h, e), expected, 0.25) << pair.trial << ":" << pair.weighting;
}

INSTANTIATE_TEST_SUITE_P(Table2, LinearConvergence, ::testing::ValuesIn(kTable2),
                         [](const auto& info) {
                           return std::string(info.param.trial) + "_" + info.param.weighting;
                         });

// A Fourier trial space contains the exact solution; with derivatives on the trial functions
// (strong form) any weighting reproduces it exactly, but the distributional form moves the
// derivatives onto a discretely integrated weighting, leaving the midpoint rule's O(Q⁻²) error.
TEST(WeightedResidual, DistributionalPetrovGalerkinErrorIsSecondOrderInQuadrature) {
  const auto s = case1();
  const Pair pair{"fourier", "bspline"};
  EXPECT_LT(linear_tip_error(s, pair, 16, Formulation::Strong, 256), 1e-11);
  std::vector<double> h, e;
  for (int q : {128, 256, 512}) {
    h.push_back(1.0 / q);
    e.push_back(linear_tip_error(s, pair, 16, Formulation::Distributional, q));
  }
  EXPECT_NEAR(wbm::testing::observed_order(h, e), 2.0, 0.15);
}

// Integration by parts on the circle: with exact operators (Fourier analytic, B-spline and DB6
// connection coefficients) the strong, weak and distributional time operators coincide
// (Γ^{0,2} = −Γ^{1,1} = Γ^{2,0}, Γ^{0,1} = −Γ^{1,0}); with discrete inner products (B-spline:
// Fourier) they agree to the quadrature error, and so do the Case 1 solutions with contact.
TEST(WeightedResidual, StrongWeakAndDistributionalAgreeWhereAllAreDefined) {
  const auto s = case1();
  for (const Pair pair : {Pair{"fourier", "fourier"}, Pair{"bspline", "bspline"}, Pair{"db6", "db6"}}) {
    const auto make = [&](Formulation f) {
      return solvers::WeightedResidual(s.system(), s.harmonic_forcing(), s.contact_points(), TimeBasis::from_name(pair.trial, 16),
                                       TimeBasis::from_name(pair.weighting, 16), {.formulation = f});
    };
    const auto strong = make(Formulation::Strong), weak = make(Formulation::Weak),
               dist = make(Formulation::Distributional);
    const double scale = strong.time_operators().mass.cwiseAbs().maxCoeff();
    EXPECT_LT((strong.time_operators().mass - weak.time_operators().mass).cwiseAbs().maxCoeff(), 1e-9 * scale);
    EXPECT_LT((strong.time_operators().mass - dist.time_operators().mass).cwiseAbs().maxCoeff(), 1e-9 * scale);
    EXPECT_LT((strong.time_operators().damping - dist.time_operators().damping).cwiseAbs().maxCoeff(), 1e-9 * scale);
  }
  // B-spline:Fourier (discrete): the forms differ by quadrature only, shrinking as O(Q⁻²).
  double spread[2];
  int qi = 0;
  for (int q : {256, 1024}) {
    Eigen::VectorXd tip[3];
    int i = 0;
    for (Formulation f : {Formulation::Strong, Formulation::Weak, Formulation::Distributional}) {
      const auto trial = TimeBasis::from_name("bspline", 32);
      const auto sol = solvers::solve_weighted_residual(s.system(), s.harmonic_forcing(), s.contact_points(), trial,
                                                        TimeBasis::from_name("fourier", 32),
                                                        {.formulation = f, .time_samples = q});
      ASSERT_TRUE(sol.converged()) << sol.report.message;
      tip[i++] = solvers::evaluate_trial(trial, sol.coefficients, s.harmonic_forcing().dof, uniform_tau(512), s.forcing->frequency_hz);
    }
    spread[qi++] = std::max(solvers::rms_relative_error(tip[1], tip[0]), solvers::rms_relative_error(tip[2], tip[0]));
  }
  EXPECT_LT(spread[0], 1e-3);
  EXPECT_LT(spread[1], spread[0] / 8.0) << "not second order in Q: " << spread[0] << " -> " << spread[1];
}

namespace {
// ∫₀¹ p_j^{(dw)} q_k^{(dt)} for all j, k by GSL's 20-point Gauss–Legendre rule on each of 128
// subintervals (every basis breakpoint k/M, M ≤ 8, is an interval end): exact for polynomial
// pieces of degree < 40, spectrally accurate for trigonometric ones.
Eigen::MatrixXd brute_force(const TimeBasis& w, const TimeBasis& t, int dw, int dt) {
  constexpr int kIntervals = 128, kNodes = 20;
  gsl_integration_glfixed_table* table = gsl_integration_glfixed_table_alloc(kNodes);
  Eigen::VectorXd tau(kIntervals * kNodes), weight(kIntervals * kNodes);
  for (int i = 0; i < kIntervals; ++i) {
    for (int n = 0; n < kNodes; ++n) {
      gsl_integration_glfixed_point(static_cast<double>(i) / kIntervals, (i + 1.0) / kIntervals, n,
                                    &tau(i * kNodes + n), &weight(i * kNodes + n), table);
    }
  }
  gsl_integration_glfixed_table_free(table);
  return w.values(tau, dw).transpose() * weight.asDiagonal() * t.values(tau, dt);
}
}  // namespace

// Assembled time operators against brute-force Gauss–Legendre quadrature of their definition
// [JL14 Eqs. (14)–(16)] at M = 8: exact operators (Fourier:Fourier analytic, B-spline:B-spline
// connection coefficients) to 1e-9; discrete ones (Q = 256 midpoints) to the midpoint rule's
// O((πM/Q)²) relative error. (DB6 connection coefficients are checked against the published
// tables in tests/wavelets; DB6' is only Hölder-0.08, too rough for pointwise quadrature.)
TEST(WeightedResidual, TimeOperatorsMatchBruteForceQuadrature) {
  const auto s = case1();
  struct Case {
    Pair pair;
    Formulation f;
    double tol;
  };
  for (const Case c : {Case{{"fourier", "fourier"}, Formulation::Weak, 1e-9},
                       Case{{"bspline", "bspline"}, Formulation::Distributional, 1e-9},
                       Case{{"bspline", "bspline"}, Formulation::Weak, 1e-9},
                       Case{{"haar", "fourier"}, Formulation::Distributional, 2e-3},
                       Case{{"db6", "fourier"}, Formulation::Distributional, 2e-3},
                       Case{{"haar", "bspline"}, Formulation::Distributional, 2e-3},
                       Case{{"fourier", "haar"}, Formulation::Strong, 2e-3}}) {
    const auto trial = TimeBasis::from_name(c.pair.trial, 8), weighting = TimeBasis::from_name(c.pair.weighting, 8);
    const solvers::WeightedResidual wr(s.system(), s.harmonic_forcing(), {}, trial, weighting, {.formulation = c.f});
    const Eigen::MatrixXd* ops[3] = {&wr.time_operators().mass, &wr.time_operators().damping,
                                     &wr.time_operators().stiffness};
    // (weighting order, trial order, sign) of the mass, damping, stiffness terms.
    const int orders[3][3][3] = {{{0, 2, 1}, {0, 1, 1}, {0, 0, 1}},
                                 {{1, 1, -1}, {0, 1, 1}, {0, 0, 1}},
                                 {{2, 0, 1}, {1, 0, -1}, {0, 0, 1}}};
    const int fi = static_cast<int>(c.f);
    for (int t = 0; t < 3; ++t) {
      const auto& o = orders[fi][t];
      const Eigen::MatrixXd bf = o[2] * brute_force(weighting, trial, o[0], o[1]);
      EXPECT_LT((*ops[t] - bf).cwiseAbs().maxCoeff(), c.tol * bf.cwiseAbs().maxCoeff())
          << c.pair.trial << ":" << c.pair.weighting << " term " << t << " (" << wr.time_operators().rule << ")";
    }
  }
}

// Analytic condensed Jacobian (I + H N)/s against central differences for Petrov–Galerkin pairs,
// Galerkin pairs and Fourier with 2H + 1 functions (M = 15), at a state in contact over part of
// the period.
TEST(WeightedResidual, CondensedJacobianMatchesFiniteDifferences) {
  const auto s = case1();
  struct Case {
    Pair pair;
    int m;
  };
  for (const auto& [pair, m] : {Case{{"db6", "fourier"}, 16}, Case{{"haar", "bspline"}, 16}, Case{{"bspline", "bspline"}, 16},
                                Case{{"fourier", "fourier"}, 16}, Case{{"haar", "fourier"}, 16}, Case{{"fourier", "fourier"}, 15}}) {
    const solvers::WeightedResidual wr(s.system(), s.harmonic_forcing(), s.contact_points(), TimeBasis::from_name(pair.trial, m),
                                       TimeBasis::from_name(pair.weighting, m));
    const Eigen::VectorXd x = wr.contact_unknowns(wr.linear_response()) * 1.02;
    struct Condensed {
      const solvers::WeightedResidual* wr;
      Eigen::VectorXd residual(const Eigen::VectorXd& y) const { return wr->contact_residual(y); }
      Eigen::MatrixXd jacobian(const Eigen::VectorXd& y) const { return wr->contact_jacobian(y); }
    };
    wbm::testing::expect_jacobian_matches_fd(Condensed{&wr}, x, 1e-5, 1e-7, 1e-6);
  }
}

// Slow reference path for the FFTW transforms in the residual: the contact term
// n(a) = R(a) − R_no-contact(a) against the direct sum (1/Q) Σ_q p_j(τ_q) f_c(u_c(τ_q)) on the
// midpoints τ_q = (q + ½)/Q with u_c = Σ_k a_{c,k} q_k(τ_q), for Q = M (the Nyquist bin), Q < 2M
// and Q not a power of two.
TEST(WeightedResidual, ContactTermMatchesTheDirectSumOverSamples) {
  const auto s = case1();
  struct Case {
    Pair pair;
    int m;
  };
  for (const auto& [pair, m] : {Case{{"fourier", "fourier"}, 32}, Case{{"haar", "fourier"}, 32},
                                Case{{"fourier", "bspline"}, 32}, Case{{"fourier", "fourier"}, 31}}) {
    for (const int q : {m, 48, 100}) {
      const auto trial = TimeBasis::from_name(pair.trial, m), weighting = TimeBasis::from_name(pair.weighting, m);
      const solvers::WeightedResidualOptions options{.time_samples = q};
      const solvers::WeightedResidual with(s.system(), s.harmonic_forcing(), s.contact_points(), trial, weighting, options);
      const solvers::WeightedResidual without(s.system(), s.harmonic_forcing(), {}, trial, weighting, options);
      const Eigen::VectorXd a = with.linear_response() * 1.05;
      const Eigen::VectorXd contact_term = with.residual(a) - without.residual(a);

      Eigen::VectorXd tau(q);
      for (int k = 0; k < q; ++k) tau(k) = (k + 0.5) / q;
      const Eigen::MatrixXd coefficients = spectral::as_coefficients(a, with.dofs());
      Eigen::VectorXd expected = Eigen::VectorXd::Zero(a.size());
      for (const auto& contact : s.contact_points()) {
        const Eigen::VectorXd u = trial.values(tau) * coefficients.row(contact.dof).transpose();
        Eigen::VectorXd force(q), stiffness(q);
        contact.law->evaluate(u, force, stiffness);
        const Eigen::VectorXd projected = weighting.values(tau).transpose() * force / q;
        for (int j = 0; j < m; ++j) expected(spectral::stacked_index(j, contact.dof, with.dofs())) += projected(j);
      }
      ASSERT_GT(expected.lpNorm<Eigen::Infinity>(), 0.0) << "the state must be in contact";
      EXPECT_LT((contact_term - expected).lpNorm<Eigen::Infinity>(), 1e-9 * expected.lpNorm<Eigen::Infinity>())
          << pair.trial << ":" << pair.weighting << " M = " << m << " Q = " << q;
    }
  }
}

// The modal block solve and the sparse LU of the assembled Kronecker sum are two independent
// factorizations of G: same Case 1 solution; and the condition estimate against the exact κ₁
// of the dense G (Higham's estimator is a lower bound, exact in most cases).
TEST(WeightedResidual, ModalAndSparseLuPathsAgreeAndConditionIsEstimated) {
  // DB6:Fourier and Haar:Fourier take the factored modal blocks of the Fourier weighting
  // (Sherman–Morrison, and last-row replacement for Haar, whose A_K is singular); DB6:DB6 the
  // banded sparse blocks. The sparse LU of the whole Kronecker sum is the slow reference.
  const auto s = case1();
  for (const char* name : {"db6", "haar"}) {
    for (const char* w : {"fourier", "db6"}) {
      if (std::string(name) == "haar" && std::string(w) == "db6") continue;  // no form admits Haar:DB6 at M = 16
      const auto trial = TimeBasis::from_name(name, 16), weighting = TimeBasis::from_name(w, 16);
      const auto modal = solvers::solve_weighted_residual(s.system(), s.harmonic_forcing(), s.contact_points(), trial,
                                                          weighting, {.linear_solver = solvers::LinearSolverPath::Modal});
      const auto sparse = solvers::solve_weighted_residual(s.system(), s.harmonic_forcing(), s.contact_points(), trial,
                                                           weighting, {.linear_solver = solvers::LinearSolverPath::SparseLU});
      ASSERT_TRUE(modal.converged() && sparse.converged()) << name << ":" << w;
      EXPECT_EQ(modal.linear_solver, "modal");
      EXPECT_EQ(sparse.linear_solver, "sparse-lu");
      EXPECT_LT((modal.coefficients - sparse.coefficients).norm(), 1e-9 * sparse.coefficients.norm()) << name << ":" << w;
    }
  }

  // ‖G‖₁ from dense time operators (Haar:Fourier) and from sparse ones (Fourier:Fourier), on the
  // modal path and on the assembled one (Haar:Fourier's dense operators take SupernodalLu,
  // Fourier:Fourier's KLU: the estimate's solves with Gᵀ go through both policies).
  for (const auto path : {solvers::LinearSolverPath::Modal, solvers::LinearSolverPath::SparseLU}) {
    for (const char* name : {"haar", "fourier"}) {
      const solvers::WeightedResidual wr(s.system(), s.harmonic_forcing(), {}, TimeBasis::from_name(name, 8),
                                         TimeBasis::from_name("fourier", 8), {.linear_solver = path});
      const Eigen::MatrixXd g = wr.jacobian(Eigen::VectorXd::Zero(25 * 8));  // no contact: J = G
      const double exact = g.cwiseAbs().colwise().sum().maxCoeff() * g.inverse().cwiseAbs().colwise().sum().maxCoeff();
      EXPECT_LE(wr.condition_number(), exact * (1 + 1e-9)) << name;
      EXPECT_GE(wr.condition_number(), exact / 3.0) << name;
      const Eigen::VectorXd a = wr.linear_response();
      const Eigen::VectorXd b = wr.residual(Eigen::VectorXd::Zero(a.size())) * -1.0;  // R(0) = −b
      EXPECT_LT((g * a - b).norm(), 1e-12 * b.norm()) << name;
    }
  }
}

// Every combination of [JL14 Table 2] on Case 1 at M = 128 against the BDF reference. The
// tolerance is quasi-optimality: the weighted-residual error may exceed the best approximation
// of the reference in the trial space (discrete least squares on the 1024 reference samples, a
// quantity this solver does not produce) by a factor 2 (measured 1.03–1.46), plus 1e-5 for the
// reference's own error. Galerkin B-spline gets a factor 10 (measured 7.9): the paper reports
// its "localized error ... at the end of the contact plateau" that keeps it above HBM as M
// grows [JL14 Sec. 5.5], and we see the same with exact operators.
TEST(WeightedResidual, Table2CombinationsMatchTimeSteppingAtM128) {
  const auto s = case1();
  const auto ref = solvers::integrate_to_periodic(s.system(), s.harmonic_forcing(), s.contact_points(), {.samples_per_period = 1024});
  ASSERT_TRUE(ref.report.converged());
  const Eigen::VectorXd u_ref = ref.displacement.row(s.harmonic_forcing().dof).transpose();
  for (const Pair& pair : kTable2) {
    const auto trial = TimeBasis::from_name(pair.trial, 128);
    const auto sol = solvers::solve_weighted_residual(s.system(), s.harmonic_forcing(), s.contact_points(), trial,
                                                      TimeBasis::from_name(pair.weighting, 128));
    ASSERT_TRUE(sol.converged()) << pair.trial << ":" << pair.weighting << ": " << sol.report.message;
    EXPECT_LT(sol.relative_residual, 1e-8);
    const Eigen::MatrixXd v = trial.values(ref.tau, 0);
    const Eigen::VectorXd best = v * v.colPivHouseholderQr().solve(u_ref);
    const double best_error = solvers::rms_relative_error(best, u_ref);
    const double error = solvers::rms_relative_error(
        solvers::evaluate_trial(trial, sol.coefficients, s.harmonic_forcing().dof, ref.tau, s.forcing->frequency_hz), u_ref);
    const double factor = std::string(pair.trial) == "bspline" ? 10.0 : 2.0;
    EXPECT_LT(error, factor * best_error + 1e-5)
        << pair.trial << ":" << pair.weighting << " error " << error << ", best approximation " << best_error;
  }
}

// Pairs that need a derivative a basis lacks are refused, naming the basis, the order, the term
// and the formulation that works [JL14 Secs. 2.1–2.3].
TEST(WeightedResidual, RefusesInadmissiblePairs) {
  using wbm::testing::expect_throw_with;
  const auto s = case1();
  const auto build = [&](const char* t, const char* w, Formulation f, int mt = 16, int mw = 16) {
    return solvers::WeightedResidual(s.system(), s.harmonic_forcing(), s.contact_points(), TimeBasis::from_name(t, mt),
                                     TimeBasis::from_name(w, mw), {.formulation = f});
  };
  expect_throw_with<std::invalid_argument>([&] { (void)build("haar", "fourier", Formulation::Strong); },
                                           {"Haar", "no pointwise derivative of order 2", "distributional"});
  expect_throw_with<std::invalid_argument>([&] { (void)build("haar", "fourier", Formulation::Weak); },
                                           {"order 1", "Eq. 15", "distributional"});
  expect_throw_with<std::invalid_argument>([&] { (void)build("db6", "fourier", Formulation::Strong); },
                                           {"DB6", "order 2", "largest: 1"});
  expect_throw_with<std::invalid_argument>([&] { (void)build("fourier", "haar", Formulation::Distributional); },
                                           {"weighting basis Haar", "strong form"});
  expect_throw_with<std::invalid_argument>([&] { (void)build("haar", "haar", Formulation::Distributional); },
                                           {"connection coefficients up to order 0", "no formulation admits"});
  expect_throw_with<std::invalid_argument>([&] { (void)build("db6", "fourier", Formulation::Distributional, 16, 32); },
                                           {"M = 16", "32"});
  expect_throw_with<std::invalid_argument>([&] { (void)TimeBasis::from_name("db7", 16); }, {"L = 7"});
  expect_throw_with<std::invalid_argument>([&] { (void)TimeBasis::from_name("morlet", 16); },
                                           {"'morlet'", "fourier, haar"});
  expect_throw_with<std::invalid_argument>([&] { (void)TimeBasis::from_name("haar", 24); }, {"M = 24", "power of two"});
  expect_throw_with<std::invalid_argument>([&] { (void)solvers::parse_formulation("mixed"); },
                                           {"'mixed'", "distributional"});
}

// "Converged" needs the full residual ‖G a − b + n(a)‖ recomputed from the solution below the
// stated bound, not only the condensed Newton: Case 1 (Fourier, M = 32) is verified at the default
// 1e-8 and reported as not verified against an unattainable 1e-20.
TEST(WeightedResidual, ConvergedRequiresTheVerifiedFullResidual) {
  const auto s = case1();
  const auto basis = TimeBasis::from_name("fourier", 32);
  const auto ok = solvers::solve_weighted_residual(s.system(), s.harmonic_forcing(), s.contact_points(), basis, basis);
  ASSERT_TRUE(ok.converged()) << ok.report.message;
  EXPECT_LE(ok.relative_residual, 1e-8);
  EXPECT_EQ(ok.residual_tolerance, 1e-8);
  const auto strict = solvers::solve_weighted_residual(s.system(), s.harmonic_forcing(), s.contact_points(), basis,
                                                       basis, {.residual_tolerance = 1e-20});
  EXPECT_EQ(strict.report.status, solvers::SolveStatus::ResidualNotVerified);
  EXPECT_NE(strict.report.message.find("residual_tolerance = 1e-20"), std::string::npos) << strict.report.message;
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] {
        (void)solvers::solve_weighted_residual(s.system(), s.harmonic_forcing(), s.contact_points(), basis, basis,
                                               {.residual_tolerance = 0.0});
      },
      {"residual_tolerance = 0", "must be > 0"});
}

// M, C and K must be symmetric (the modal path factorizes from one triangle).
TEST(WeightedResidual, RefusesANonSymmetricStiffness) {
  const auto s = case1();
  auto system = s.system();
  system.stiffness.coeffRef(2, 3) += 1e-6 * system.stiffness.coeffRef(2, 3);
  const auto basis = TimeBasis::from_name("fourier", 8);
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)solvers::solve_weighted_residual(system, s.harmonic_forcing(), s.contact_points(), basis, basis); },
      {"MechanicalSystem.stiffness is not symmetric", "(2, 3)"});
}

// The Haar delta-pair velocity [JL14 Sec. 5.2] in its box form is the difference quotient of
// neighbouring cells: second order at the jumps τ = k/M for the cell averages of sin 2πτ.
TEST(PostProcessing, HaarDeltaPairVelocityIsSecondOrderAtTheJumps) {
  std::vector<double> h, e;
  for (int m : {16, 32, 64}) {
    const auto haar = TimeBasis::from_name("haar", m);
    // Orthonormal Haar coefficient of the cell average: ∫ sin 2πτ φ_{J,k} = √M ∫_cell sin.
    Eigen::MatrixXd a(1, m);
    for (int k = 0; k < m; ++k) {
      a(0, k) = std::sqrt(m) * (std::cos(2 * std::numbers::pi * k / m) - std::cos(2 * std::numbers::pi * (k + 1) / m)) /
                (2 * std::numbers::pi);
    }
    Eigen::VectorXd tau(m);
    for (int k = 0; k < m; ++k) tau(k) = static_cast<double>(k) / m;
    const Eigen::VectorXd v = solvers::evaluate_trial(haar, a, 0, tau, 1.0, 1);
    double err = 0.0;
    for (int k = 0; k < m; ++k) err = std::max(err, std::abs(v(k) - 2 * std::numbers::pi * std::cos(2 * std::numbers::pi * tau(k))));
    h.push_back(1.0 / m);
    e.push_back(err);
  }
  EXPECT_NEAR(wbm::testing::observed_order(h, e), 2.0, 0.1);
}

// Energy conservation [JL14 Eq. (35)]: a free undamped mode u = φ cos ωt (Kφ = ω²Mφ, φᵀMφ = 1)
// has E(t) = ω²/2 at every t.
TEST(PostProcessing, SystemEnergyOfAFreeModeIsConstant) {
  const auto s = case1();
  const auto sys = s.system();
  const Eigen::MatrixXd k = Eigen::MatrixXd(sys.stiffness), mm = Eigen::MatrixXd(sys.mass);
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(k, mm);
  const Eigen::VectorXd phi = eig.eigenvectors().col(0);
  const double omega = std::sqrt(eig.eigenvalues()(0));
  const Eigen::VectorXd tau = uniform_tau(64);
  Eigen::MatrixXd u(25, 64), v(25, 64);
  for (int p = 0; p < 64; ++p) {
    u.col(p) = phi * std::cos(2 * std::numbers::pi * tau(p));
    v.col(p) = -omega * phi * std::sin(2 * std::numbers::pi * tau(p));
  }
  const Eigen::VectorXd e = solvers::system_energy(sys, {}, u, v);
  EXPECT_LT((e.array() - 0.5 * omega * omega).abs().maxCoeff(), 1e-10 * omega * omega);
}
