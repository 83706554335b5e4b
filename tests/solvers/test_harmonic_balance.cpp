#include <wbm/solvers/harmonic_balance.hpp>

#include <cmath>
#include <numbers>
#include <stdexcept>

#include <gtest/gtest.h>

#include <wbm/solvers/time_integration.hpp>
#include <wbm/spectral/layout.hpp>

#include "shipped_scenes.hpp"
#include "testing.hpp"

using namespace wbm;
using solvers::HarmonicBalance;
using solvers::HarmonicBalanceOptions;

namespace {
scene::Scene hb_case1() { return models::load_scene("jl14_case1"); }
scene::Scene hb_case2() { return models::load_scene("jl14_case2"); }
}  // namespace

// Published values [JL14 Sec. 4]: fundamental ≈ 1273 Hz; no-contact tip amplitudes ≈ 1.4 mm at
// 150 Hz and 29 mm at 1275 Hz, with F at the tip. This checks the forcing placement.
TEST(HarmonicBalance, NoContactAmplitudesMatchThePaper) {
  const auto s1 = hb_case1();
  EXPECT_NEAR(fem::Rod(s1.structure->rod).natural_frequencies_hz(1)(0), 1273.0, 1.0);
  const Eigen::VectorXcd u1 = solvers::frequency_response(s1.system(), s1.harmonic_forcing());
  EXPECT_NEAR(std::abs(u1(s1.harmonic_forcing().dof)), 1.4e-3, 0.05e-3);
  const auto s2 = hb_case2();
  const Eigen::VectorXcd u2 = solvers::frequency_response(s2.system(), s2.harmonic_forcing());
  EXPECT_NEAR(std::abs(u2(s2.harmonic_forcing().dof)), 29e-3, 0.5e-3);
}

// Without contact, harmonic balance is exact on the first harmonic: coefficient of cos 2πτ is
// Re U and of sin 2πτ is −Im U, with U from (K − ω²M + iωC) U = F e_tip; all others vanish.
TEST(HarmonicBalance, LinearResponseEqualsDirectFrequencyResponse) {
  for (const auto& s : {hb_case1(), hb_case2()}) {
    const auto sol = solvers::solve_harmonic_balance(s.system(), s.harmonic_forcing(), {}, {.dimension = 16});
    ASSERT_TRUE(sol.converged());
    const Eigen::VectorXcd u = solvers::frequency_response(s.system(), s.harmonic_forcing());
    const double scale = u.cwiseAbs().maxCoeff();
    EXPECT_LT((sol.coefficients.col(1) - u.real()).cwiseAbs().maxCoeff(), 1e-10 * scale);
    EXPECT_LT((sol.coefficients.col(2) + u.imag()).cwiseAbs().maxCoeff(), 1e-10 * scale);
    EXPECT_LT(sol.coefficients.col(0).cwiseAbs().maxCoeff(), 1e-12 * scale);
    EXPECT_LT(sol.coefficients.rightCols(13).cwiseAbs().maxCoeff(), 1e-12 * scale);
  }
}

// Analytic Jacobian of the full residual against central differences, M = 8, at a state in
// contact over part of the period (the no-contact response, whose tip exceeds g0).
TEST(HarmonicBalance, FullJacobianMatchesFiniteDifferences) {
  const auto s = hb_case1();
  const HarmonicBalance hb(s.system(), s.harmonic_forcing(), s.contact_points(), {.dimension = 8});
  const Eigen::VectorXd a = hb.linear_response() * 1.05;
  // Step 1e-7 of the coefficient scale (~1 mm): truncation O(h²·f''') ≪ rounding ~ eps·‖R‖/h.
  wbm::testing::expect_jacobian_matches_fd(hb, a, 1e-6, 1e-4, 1e-6);
}

// Same for the condensed system on the contact unknowns, which Newton actually solves.
TEST(HarmonicBalance, CondensedJacobianMatchesFiniteDifferences) {
  for (const auto& s : {hb_case1(), hb_case2()}) {
    const HarmonicBalance hb(s.system(), s.harmonic_forcing(), s.contact_points(), {.dimension = 16});
    const Eigen::VectorXd x = hb.contact_unknowns(hb.linear_response());
    struct View {
      const HarmonicBalance* hb;
      Eigen::VectorXd residual(const Eigen::VectorXd& y) const { return hb->contact_residual(y); }
      Eigen::MatrixXd jacobian(const Eigen::VectorXd& y) const { return hb->contact_jacobian(y); }
    };
    wbm::testing::expect_jacobian_matches_fd(View{&hb}, x, 1e-6, 1e-4, 1e-6);
  }
}

// Newton converges on both cases of Table 1 at M = 64 and the recomputed full residual is at
// rounding level relative to the forcing.
TEST(HarmonicBalance, NewtonConvergesOnBothCases) {
  for (const auto& s : {hb_case1(), hb_case2()}) {
    const auto sol = solvers::solve_harmonic_balance(s.system(), s.harmonic_forcing(), s.contact_points(), {.dimension = 64});
    ASSERT_TRUE(sol.converged()) << s.name << ": " << sol.report.message;
    EXPECT_LT(sol.relative_residual, 1e-9) << s.name;
    EXPECT_LE(sol.report.iterations, 20) << s.name;
    EXPECT_GT(sol.max_penetration, 0.0) << s.name << " should be in contact";
    EXPECT_TRUE(sol.coefficients.allFinite());
  }
}

// Condensation is exact: the full residual of the expanded solution vanishes, and Newton on
// the full system from the same start reaches the same coefficients.
TEST(HarmonicBalance, CondensedSolutionSolvesTheFullSystem) {
  const auto s = hb_case1();
  const HarmonicBalance hb(s.system(), s.harmonic_forcing(), s.contact_points(), {.dimension = 16});
  const auto condensed = hb.solve();
  ASSERT_TRUE(condensed.converged());
  const auto full = solvers::newton(hb, hb.linear_response(), {.tolerance = 1e-6});  // [N]
  ASSERT_TRUE(full.report.converged()) << full.report.message;
  const Eigen::VectorXd a = spectral::stacked(condensed.coefficients);
  EXPECT_LT((full.x - a).cwiseAbs().maxCoeff(), 1e-9 * a.cwiseAbs().maxCoeff());
}

// Against the BDF time-stepping reference [JL14 Sec. 4], M = 128. The tip velocity jumps at
// impact, so the Fourier coefficients of u decay like m⁻² and the L² truncation error like
// (M/2)^{-3/2} ≈ 2e-3; measured 5e-4 (Case 1) and 8e-5 (Case 2). The reference itself is
// periodic to 1e-7 and integrated at rtol 1e-10. The error must also shrink from M = 32.
TEST(HarmonicBalance, AgreesWithTimeSteppingAtM128) {
  for (const auto& s : {hb_case1(), hb_case2()}) {
    const auto ref = solvers::integrate_to_periodic(s.system(), s.harmonic_forcing(), s.contact_points(),
                                                    {.samples_per_period = 256});
    ASSERT_TRUE(ref.report.converged()) << ref.report.message;
    const Eigen::VectorXd u_ref = ref.displacement.row(s.harmonic_forcing().dof).transpose();
    double previous = 1.0;
    for (int m : {32, 128}) {
      const auto sol = solvers::solve_harmonic_balance(s.system(), s.harmonic_forcing(), s.contact_points(), {.dimension = m});
      ASSERT_TRUE(sol.converged());
      const Eigen::VectorXd u = solvers::evaluate_dof(sol.coefficients, s.harmonic_forcing().dof, ref.tau, s.forcing->frequency_hz);
      const double err = (u - u_ref).norm() / u_ref.norm();
      EXPECT_LT(err, previous) << s.name << " M=" << m;
      previous = err;
    }
    EXPECT_LT(previous, 2e-3) << s.name;
  }
}

// Time derivative in physical time: for the linear response, u̇_tip = Re(iω U e^{iωt}).
TEST(HarmonicBalance, VelocityEvaluationMatchesAnalyticDerivative) {
  const auto s = hb_case1();
  const auto sol = solvers::solve_harmonic_balance(s.system(), s.harmonic_forcing(), {}, {.dimension = 8});
  const Eigen::VectorXcd u = solvers::frequency_response(s.system(), s.harmonic_forcing());
  const double w = 2 * std::numbers::pi * s.forcing->frequency_hz;
  const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(7, 0.0, 0.9);
  const Eigen::VectorXd v = solvers::evaluate_dof(sol.coefficients, s.harmonic_forcing().dof, tau, s.forcing->frequency_hz, 1);
  for (int p = 0; p < tau.size(); ++p) {
    const std::complex<double> e(std::cos(2 * std::numbers::pi * tau(p)), std::sin(2 * std::numbers::pi * tau(p)));
    const double exact = (std::complex<double>(0, w) * u(s.harmonic_forcing().dof) * e).real();
    EXPECT_NEAR(v(p), exact, 1e-9 * w * std::abs(u(s.harmonic_forcing().dof)));
  }
}

TEST(HarmonicBalance, RejectsInvalidInput) {
  using wbm::testing::expect_throw_with;
  const auto s = hb_case1();
  auto f = s.harmonic_forcing();
  f.frequency_hz = 0.0;
  expect_throw_with<std::invalid_argument>([&] { HarmonicBalance hb(s.system(), f, s.contact_points(), {}); },
                                           {"frequency_hz = 0", "> 0"});
  f = s.harmonic_forcing();
  f.dof = 99;
  expect_throw_with<std::invalid_argument>([&] { HarmonicBalance hb(s.system(), f, {}, {}); },
                                           {"dof = 99", "[0, 25)"});
  expect_throw_with<std::invalid_argument>(
      [&] { HarmonicBalance hb(s.system(), s.harmonic_forcing(), {}, {.dimension = 48}); }, {"M = 48", "power of two"});
  expect_throw_with<std::invalid_argument>(
      [&] { HarmonicBalance hb(s.system(), s.harmonic_forcing(), {}, {.dimension = 64, .time_samples = 32}); },
      {"Q = 32", ">= M"});
  expect_throw_with<std::invalid_argument>([&] { (void)solvers::beta_damped(fem::Rod(s.structure->rod), -1.0); },
                                           {"beta = -1", ">= 0"});
}
