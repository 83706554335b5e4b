// Stick/slip switches of Jenkins elements as located events (JenkinsResponseFamily,
// StickSlipEvents). Truths not produced by this code:
//  - central differences of a piece's residual in x and in λ (μ and f), on a piece that is not
//    the return map's at that point (its affine extension);
//  - the definition of a piece's events: on the return map's own piece they are all ≥ 0 and the
//    piece's residual is the nonsmooth one;
//  - full stick: once μN exceeds the largest elastic force, the damper is the linear oscillator
//    with k + k_t, whose amplitude is P/|k + k_t − mω² + icω|.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <memory>
#include <vector>

#include <Eigen/Dense>

#include <wbm/contact/friction.hpp>
#include <wbm/solvers/mechanical_system.hpp>
#include <wbm/solvers/response_curve.hpp>
#include <wbm/solvers/time_basis.hpp>
#include <wbm/solvers/weighted_residual.hpp>
#include <wbm/spectral/layout.hpp>

#include "impact_oscillators.hpp"
#include "testing.hpp"

namespace wbm::solvers {
namespace {

using wbm::testing::kPi;

// The friction damper of examples/scenes/friction_damper_load.toml: 1 kg on k at f_n = 10 Hz,
// C = 0.2π M (ζ = 0.5 %), a Jenkins element k_t = 1000 k under N = 1 N, 1 N at 10 Hz; Fourier
// H = 32 with Q = 256 samples, where the nonsmooth corrector stalls near the onset of full stick.
struct Damper {
  double k = std::pow(2.0 * kPi * 10.0, 2), kt = 1000.0 * k, c = 0.2 * kPi;
  [[nodiscard]] WeightedResidual problem(double mu, int samples = 256) const {
    const TimeBasis basis = TimeBasis::fourier_harmonics(32);
    return {wbm::testing::one_dof_system(1.0, c, k),
            {0, 1.0, 10.0},
            {{0, std::make_shared<contact::JenkinsLaw>(contact::JenkinsParameters{kt, mu, 1.0})}},
            basis,
            basis,
            {.time_samples = samples}};
  }
};

// On a solved stick–slip state (μ = 0.9, 134 of the 256 samples slip): the return map's own
// piece has every event ≥ 0 and the nonsmooth residual; a neighbouring piece (the first stick
// sample after each of the 4 slip runs made to slip) has its Jacobian, ∂r/∂μ and ∂r/∂f equal to
// central differences of that piece's residual (measured: 1.2e-10 of max |J|; 2.1e-11 of max
// |∂r/∂μ|, 4.0e-8 of max |∂r/∂f|).
TEST(StickSlipEvents, APieceIsSmoothWithExactDerivativesAndTheReturnMapsPieceHoldsItsEvents) {
  const Damper d;
  const WeightedResidual base = d.problem(0.9);
  const auto solved = base.solve();
  ASSERT_TRUE(solved.converged()) << solved.brief();
  for (const ContinuationParameter parameter :
       {ContinuationParameter::FrictionCoefficient, ContinuationParameter::Frequency}) {
    const ForcedResponseFamily family(base, parameter);
    const JenkinsResponseFamily pieces(family);
    const double lambda = parameter == ContinuationParameter::Frequency ? 10.0 : 0.9;
    const Eigen::VectorXd x = base.contact_unknowns(spectral::stacked(solved.coefficients));
    const ActiveSet own = pieces.active_set(x, lambda);
    ASSERT_EQ(own.size(), 256U);
    int slipping = 0;
    for (auto s : own) slipping += s;
    EXPECT_GT(slipping, 20);
    EXPECT_LT(slipping, 236);
    EXPECT_EQ(pieces.residual(x, lambda, own), family.residual(x, lambda));
    EXPECT_GE(pieces.events(x, lambda, own).minCoeff(), 0.0);
    ActiveSet next = own;
    int flipped = 0;
    for (size_t q = 0; q < own.size(); ++q) {
      if (own[q] == 0 && own[(q + own.size() - 1) % own.size()] == 1) next[q] = 1, ++flipped;
    }
    ASSERT_GT(flipped, 0);
    EXPECT_LT(pieces.events(x, lambda, next).minCoeff(), 0.0);  // x lies outside that piece
    EXPECT_NE(pieces.residual(x, lambda, next), family.residual(x, lambda));
    const LowRankLinearization l = pieces.linearize(x, lambda, next);
    const Eigen::MatrixXd jac = l.jacobian.dense();
    const double h = 1e-6 * x.cwiseAbs().maxCoeff();
    Eigen::MatrixXd fd(x.size(), x.size());
    for (Eigen::Index j = 0; j < x.size(); ++j) {
      Eigen::VectorXd xp = x, xm = x;
      xp(j) += h;
      xm(j) -= h;
      fd.col(j) = (pieces.residual(xp, lambda, next) - pieces.residual(xm, lambda, next)) / (2.0 * h);
    }
    EXPECT_LT((jac - fd).cwiseAbs().maxCoeff(), 1e-7 * jac.cwiseAbs().maxCoeff());
    const double dl = 1e-6 * lambda;
    const Eigen::VectorXd dr =
        (pieces.residual(x, lambda + dl, next) - pieces.residual(x, lambda - dl, next)) / (2.0 * dl);
    EXPECT_LT((l.parameter_derivative - dr).cwiseAbs().maxCoeff(), 1e-6 * dr.cwiseAbs().maxCoeff())
        << (parameter == ContinuationParameter::Frequency ? "frequency" : "mu");
  }
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)base.jenkins_events(Eigen::VectorXd::Zero(65), ActiveSet(3, 0)); },
      {"the stick/slip piece has 3 entries", "Q = 256 per Jenkins element"});
}

// The damper in μ from 0.99 to 1.2 at Q = 256: the nonsmooth corrector alone stalls at the onset
// of full stick (StickSlipEvents::Never: step below minimum near μ = 0.998); on events the branch
// crosses it and reaches 1.2, and every point past the onset is the linear oscillator with
// k + k_t (measured 5.0e-11 relative: the amplitude is read at the P = 512 output samples).
TEST(StickSlipEvents, TheDamperCrossesTheOnsetOfFullStickOnEvents) {
  const Damper d;
  const WeightedResidual base = d.problem(0.99);
  ResponseCurveOptions o;
  o.parameter = ContinuationParameter::FrictionCoefficient;
  o.parameter_min = 0.0;
  o.parameter_max = 1.2;
  o.stability = false;
  o.stick_slip_events = StickSlipEvents::Never;
  const ResponseCurve stalled = trace_response(base, o);
  EXPECT_EQ(stalled.stop, StopReason::StepBelowMinimum) << stalled.brief();
  ASSERT_FALSE(stalled.points.empty());
  EXPECT_LT(stalled.points.back().parameter, 0.999);
  o.stick_slip_events = StickSlipEvents::OnStall;
  const ResponseCurve curve = trace_response(base, o);
  ASSERT_TRUE(curve.converged()) << curve.brief() << ": " << curve.message;
  EXPECT_GT(curve.events, 0);
  EXPECT_DOUBLE_EQ(curve.points.back().parameter, 1.2);
  const double omega = 2.0 * kPi * 10.0;
  const double exact = 1.0 / std::abs(std::complex<double>(d.k + d.kt - omega * omega, d.c * omega));
  int stuck = 0;
  for (const ResponsePoint& p : curve.points) {
    if (p.parameter < 1.0005) continue;  // μN above k_t max|u| ≈ 1.00 N: every sample sticks
    ++stuck;
    EXPECT_NEAR(p.amplitude / exact, 1.0, 1e-9) << "mu = " << p.parameter;
  }
  EXPECT_GE(stuck, 5);
  // The points before the stall are those of the nonsmooth corrector: the same path.
  for (size_t i = 0; i + 1 < stalled.points.size(); ++i) {
    EXPECT_EQ(curve.points[i].parameter, stalled.points[i].parameter) << i;
  }
}

}  // namespace
}  // namespace wbm::solvers
