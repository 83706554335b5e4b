// Several loads (HarmonicForcing::more): F_j cos(2π h_j f t + φ_j) on DOF j. On a linear system
// the periodic response is the superposition of closed-form complex responses, one per load:
//   u(t) = Σ_j Re(H(h_j ω) e_{dof_j} F_j e^{i(h_j ω t + φ_j)}),  H(Ω) = (K − Ω² M + iΩ C)⁻¹,
// with h_j = 0 the static K⁻¹ e F cos φ. The weighted residual (three pairs), the BDF and the
// Moreau–Jean integrators must all give it; frequency_response sums harmonic-1 loads with their
// phases and refuses other harmonics.
// A load above the highest harmonic the basis or the output samples resolve is refused (issue #40).
#include <wbm/solvers/mechanical_system.hpp>

#include <cmath>
#include <complex>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <wbm/contact/signorini.hpp>
#include <wbm/solvers/post_processing.hpp>
#include <wbm/solvers/time_integration.hpp>
#include <wbm/solvers/weighted_residual.hpp>

#include "testing.hpp"

using namespace wbm;

namespace {

// Two masses on springs (a chain with a ground spring at each end), Rayleigh-free damping.
solvers::MechanicalSystem two_dofs() {
  Eigen::MatrixXd m(2, 2), k(2, 2), c(2, 2);
  m << 1.0, 0.0, 0.0, 2.0;
  k << 3e4, -1e4, -1e4, 2e4;
  c << 3.0, -1.0, -1.0, 1.5;
  return {m.sparseView(), c.sparseView(), k.sparseView()};
}

// 40 N cos ωt on DOF 0, 15 N cos(3ωt + 60°) on DOF 1, 25 N cos(ωt − 30°) on DOF 1, and a
// constant 10 N cos(20°) on DOF 0, at f = 7 Hz.
solvers::HarmonicForcing loads() {
  const double deg = std::numbers::pi / 180.0;
  return {0, 40.0, 7.0, {{1, 15.0, 60.0 * deg, 3}, {1, 25.0, -30.0 * deg, 1}, {0, 10.0, 20.0 * deg, 0}}};
}

Eigen::MatrixXd closed_form(const solvers::MechanicalSystem& s, const solvers::HarmonicForcing& f,
                            const Eigen::VectorXd& tau) {
  const Eigen::MatrixXd m(s.mass), k(s.stiffness), c(s.damping);
  Eigen::MatrixXd u = Eigen::MatrixXd::Zero(2, tau.size());
  const double w = 2.0 * std::numbers::pi * f.frequency_hz;
  for (const auto& l : f.loads()) {
    const double big_w = l.harmonic * w;
    const Eigen::MatrixXcd d = k.cast<std::complex<double>>() - big_w * big_w * m.cast<std::complex<double>>() +
                               std::complex<double>(0.0, big_w) * c.cast<std::complex<double>>();
    Eigen::VectorXcd rhs = Eigen::VectorXcd::Zero(2);
    rhs(l.dof) = l.amplitude * std::polar(1.0, l.phase_rad);
    const Eigen::VectorXcd x = d.partialPivLu().solve(rhs);
    for (Eigen::Index p = 0; p < tau.size(); ++p) {
      u.col(p) += (x * std::polar(1.0, 2.0 * std::numbers::pi * l.harmonic * tau(p))).real();
    }
  }
  return u;
}

}  // namespace

TEST(SeveralLoads, WeightedResidualAndTimeSteppingGiveTheSuperposedClosedForm) {
  const auto system = two_dofs();
  const auto forcing = loads();
  const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(64, 0.0, 63.0 / 64.0);
  const Eigen::MatrixXd exact = closed_form(system, forcing, tau);
  const double scale = exact.cwiseAbs().maxCoeff();
  ASSERT_GT(scale, 1e-4);
  struct Pair {
    solvers::TimeBasis trial, weighting;
    double tolerance;
  };
  const std::vector<Pair> pairs = {
      {solvers::TimeBasis::fourier_harmonics(4), solvers::TimeBasis::fourier_harmonics(4), 1e-12},
      {solvers::TimeBasis::from_name("bspline", 64), solvers::TimeBasis::from_name("bspline", 64), 1e-5},
      {solvers::TimeBasis::from_name("db6", 256), solvers::TimeBasis::fourier(256), 1e-4}};
  for (const auto& p : pairs) {
    const auto s = solvers::solve_weighted_residual(system, forcing, {}, p.trial, p.weighting);
    ASSERT_TRUE(s.report.converged()) << p.trial.name();
    const auto fields = solvers::evaluate_fields(p.trial, s.coefficients, tau, forcing.frequency_hz);
    EXPECT_LT((fields.displacement - exact).cwiseAbs().maxCoeff(), p.tolerance * scale) << p.trial.name();
  }
  solvers::TimeIntegrationOptions bdf;
  bdf.samples_per_period = 64;
  bdf.periodicity_tolerance = 1e-8;  // the slowest mode decays ~20 % per period: the error is ~5δ
  const auto b = solvers::integrate_to_periodic(system, forcing, {}, bdf);
  ASSERT_TRUE(b.report.converged()) << b.report.message;
  EXPECT_LT((b.displacement - exact).cwiseAbs().maxCoeff(), 1e-6 * scale);
  solvers::MoreauJeanOptions mj;
  mj.samples_per_period = 64;
  mj.steps_per_period = 4096;
  mj.periodicity_tolerance = 1e-11;
  const auto j = solvers::integrate_moreau_jean_to_periodic(system, forcing, {}, mj);
  ASSERT_TRUE(j.report.converged()) << j.report.message;
  EXPECT_LT((j.displacement - exact).cwiseAbs().maxCoeff(), 1e-4 * scale);  // θ = ½: second order in h
  // Energy balance of the integrator: the loads' power equals the damping power over a period.
  EXPECT_NEAR(j.input_power, j.damping_power, 1e-6 * j.input_power);
}

TEST(SeveralLoads, FrequencyResponseSumsPhasedLoadsAndRefusesOtherHarmonics) {
  const auto system = two_dofs();
  const double deg = std::numbers::pi / 180.0;
  const solvers::HarmonicForcing phased{0, 40.0, 7.0, {{1, 25.0, -30.0 * deg, 1}}};
  const Eigen::VectorXcd u = solvers::frequency_response(system, phased);
  const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(8, 0.0, 7.0 / 8.0);
  const Eigen::MatrixXd exact = closed_form(system, phased, tau);
  for (Eigen::Index p = 0; p < tau.size(); ++p) {
    const Eigen::VectorXd at = (u * std::polar(1.0, 2.0 * std::numbers::pi * tau(p))).real();
    EXPECT_LT((at - exact.col(p)).norm(), 1e-12 * exact.norm());
  }
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)solvers::frequency_response(system, loads()); },
      {"frequency_response: the load on DOF 1 has harmonic 3"});
  solvers::HarmonicForcing bad = loads();
  bad.more[0].harmonic = -1;
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { bad.validate(2); },
                                                         {"HarmonicForcing.more[0].harmonic = -1: must be >= 0"});
  bad = loads();
  bad.more[2].dof = 2;
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { bad.validate(2); },
                                                         {"HarmonicForcing.more[2].dof = 2: must lie in [0, 2)"});
}

// Issue #40, item 1: a load at harmonic h needs 2h < M functions (or P output samples); above,
// its samples alias it to a lower harmonic (harmonic 250 on H = 32 came out at harmonic 6, and
// the run said "converged"). The highest resolved harmonic, H for M = 2H + 1, still gives the
// closed-form amplitude F/|k − Ω²m + iΩc| with Ω = 2π H f; one more is refused with the fix.
TEST(SeveralLoads, ALoadAboveTheHighestResolvedHarmonicIsRefusedNotAliased) {
  Eigen::MatrixXd m(1, 1), k(1, 1), c(1, 1);
  m << 1.0;
  k << 4e4;
  c << 5.0;  // α = 5 s⁻¹, C = αM
  const solvers::MechanicalSystem system{m.sparseView(), c.sparseView(), k.sparseView()};
  const double f = 10.0;
  const auto at = [&](int h) { return solvers::HarmonicForcing{0, 0.0, f, {{0, 5.0, 0.0, h}}}; };
  EXPECT_EQ(solvers::highest_resolved_harmonic(65), 32);
  EXPECT_EQ(solvers::highest_resolved_harmonic(64), 31);  // cos 32·2πτ has no sine partner at M = 64

  const auto basis = solvers::TimeBasis::fourier_harmonics(32);
  const auto top = solvers::solve_weighted_residual(system, at(32), {}, basis, basis);
  ASSERT_TRUE(top.report.converged()) << top.report.message;
  const double w = 2.0 * std::numbers::pi * 32 * f;
  const double exact = 5.0 / std::abs(std::complex<double>(4e4 - w * w, w * 5.0));
  const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(256, 0.0, 255.0 / 256.0);
  const Eigen::MatrixXd u = solvers::evaluate_fields(basis, top.coefficients, tau, f).displacement;
  EXPECT_NEAR(std::sqrt(2.0 * u.squaredNorm() / 256.0), exact, 1e-9 * exact);  // rms of one harmonic: A/√2

  for (const int h : {33, 250, 1000}) {
    wbm::testing::expect_throw_with<std::invalid_argument>(
        [&] { (void)solvers::solve_weighted_residual(system, at(h), {}, basis, basis); },
        {"HarmonicForcing.more[0] acts at harmonic " + std::to_string(h), "highest harmonic 32",
         "raise the basis dimension to more than " + std::to_string(2 * h)});
  }
  const auto haar = solvers::TimeBasis::from_name("haar", 64);  // wavelets alias the same way: M box averages
  const auto fourier = solvers::TimeBasis::fourier(64);
  EXPECT_THROW((void)solvers::solve_weighted_residual(system, at(32), {}, haar, fourier), std::invalid_argument);
  EXPECT_TRUE(solvers::solve_weighted_residual(system, at(31), {}, haar, fourier).report.converged());
  // The forcing's own harmonic-1 load needs M ≥ 3: M = 2 (1 and cos 2πτ, no sine) cannot carry it.
  const auto two = solvers::TimeBasis::fourier(2);
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)solvers::solve_weighted_residual(system, {0, 1.0, f}, {}, two, two); },
      {"HarmonicForcing (the load F cos 2πft) acts at harmonic 1", "highest harmonic 0"});

  solvers::TimeIntegrationOptions bdf;
  bdf.samples_per_period = 64;
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)solvers::integrate_to_periodic(system, at(32), {}, bdf); },
      {"P = 64 output samples", "raise TimeIntegrationOptions.samples_per_period"});
  solvers::MoreauJeanOptions mj;
  mj.samples_per_period = 64;
  mj.steps_per_period = 4096;
  const std::vector<solvers::ContactPoint> stop = {{0, std::make_shared<contact::RigidStop>(1.0)}};
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)solvers::integrate_moreau_jean_to_periodic(system, at(40), stop, mj); },
      {"P = 64 output samples", "raise MoreauJeanOptions.samples_per_period"});
}
