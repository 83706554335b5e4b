// G(f) on the modal path with circulant time operators (a periodized wavelet basis with itself:
// DB6:DB6, B-spline:B-spline), each mode's block combined on the time operators' eigenvalues bin
// by bin (kronecker_factorization.cpp, Setup::mass_bins), and the other modal paths beside them.
// Truths from outside the code under test:
//  - the contact residual is smooth in the frequency near a resonance: its second difference over
//    f(1 ± 1e-12) is 1e-24 f² ∂²r/∂f², far below rounding, so what it shows is the rounding of
//    G(f) itself moving with f;
//  - bench_friction's Jenkins damper (issue #36) continued across its resonance in DB6:DB6 reaches
//    the range's end, and its peak is the closed form of the first-harmonic energy balance.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <wbm/contact/friction.hpp>
#include <wbm/solvers/mechanical_system.hpp>
#include <wbm/solvers/response_curve.hpp>
#include <wbm/solvers/weighted_residual.hpp>

#include "impact_oscillators.hpp"
#include "weighted_residual_fixtures.hpp"

namespace wbm::solvers {
namespace {

constexpr double kCirculantPi = std::numbers::pi;
const double kDamperStiffness = std::pow(2.0 * kCirculantPi * 10.0, 2);  // k [N/m]: 1 kg at f_n = 10 Hz

// bench/bench_friction's damper: 1 kg, f_n = 10 Hz, ζ = 0.5 %, 1 N at the DOF, a Jenkins element
// of k_t = 1000 k and slip force μN = 0.2 N.
MechanicalSystem friction_damper() {
  return wbm::testing::one_dof_system(1.0, 2.0 * 0.005 * 2.0 * kCirculantPi * 10.0, kDamperStiffness);
}

std::vector<ContactPoint> damper_jenkins() {
  return {{0, std::make_shared<contact::JenkinsLaw>(contact::JenkinsParameters{1e3 * kDamperStiffness, 0.2, 1.0})}};
}

TEST(CirculantBlocks, ContactResidualIsSmoothInTheFrequencyNearResonance) {
  // Every pair of [JL14 Table 2] in the distributional form, on the modal path: the circulant
  // blocks (B-spline:B-spline, DB6:DB6, Haar:B-spline), the Fourier-weighting factors (Haar:Fourier,
  // DB6:Fourier, which form λ − f² ω² per harmonic) and the components (Fourier:Fourier). 1e-4 Hz
  // below f_n, at 1.5 times the linear response. Before the circulant blocks were combined on the
  // eigenvalues (their first column formed per frequency and transformed), the second difference
  // was 2.3e-11 and 1.9e-10 of ‖r‖ for DB6:DB6 at M = 64 and 256, 9.3e-12 and 1.9e-10 for
  // B-spline:B-spline; 3.4e-14 to 6.8e-14 for every pair after.
  const double f0 = 9.9999;
  for (const auto& pair : wbm::testing::kTable2) {
    for (const int m : {64, 256}) {
      SCOPED_TRACE(std::string(pair.trial) + ":" + pair.weighting + " M = " + std::to_string(m));
      const auto trial = TimeBasis::from_name(pair.trial, m), weighting = TimeBasis::from_name(pair.weighting, m);
      const WeightedResidual w0(friction_damper(), {0, 1.0, 5.0}, damper_jenkins(), trial, weighting,
                                {.formulation = Formulation::Distributional, .time_samples = 1024});
      ASSERT_EQ(w0.linear_solver(), "modal");
      const WeightedResidual w = w0.at_frequency(f0);  // the same scale s_r
      const Eigen::VectorXd x = 1.5 * w.contact_unknowns(w.linear_response());
      const Eigen::VectorXd r0 = w.contact_residual(x);
      ASSERT_GT(r0.norm(), 0.0);
      const double delta = 1e-12;
      const Eigen::VectorXd second = w0.at_frequency(f0 * (1.0 + delta)).contact_residual(x) - 2.0 * r0 +
                                     w0.at_frequency(f0 * (1.0 - delta)).contact_residual(x);
      EXPECT_LE(second.norm(), 5e-13 * r0.norm());
    }
  }
}

double branch_peak(const ResponseCurve& curve) {
  double top = 0.0;
  for (const auto& p : curve.points) top = std::max(top, p.amplitude);
  return top;
}

TEST(CirculantBlocks, JenkinsDamperBranchCrossesItsResonanceInDb6) {
  // bench_friction's continuation from 5 to 20 Hz, at Q = 256 samples (1024 in the bench). With
  // the blocks formed on their first column, R moved by about 2e-9 when f moved by one ulp near
  // the resonance, twice the corrector's tolerance: the DB6:DB6 branch stopped on a step below
  // the minimum at 9.945 Hz, its amplitude 27 % below the peak. The peak is the first-harmonic
  // energy balance of a stiff Jenkins element (Coulomb friction as k_t → ∞, tests/scene's
  // SceneFriction.TheDamperPeakIsTheFirstHarmonicEnergyBalance): (P − 4μN/π)/(c ω_n).
  ResponseCurveOptions o;
  o.parameter_min = 5.0;
  o.parameter_max = 20.0;
  o.stability = false;
  o.max_points = 20000;
  const WeightedResidualOptions wo{.time_samples = 256, .contact_quadrature = ContactQuadrature::Midpoint};
  const auto db6 = TimeBasis::from_name("db6", 64);
  const MechanicalSystem s = friction_damper();
  const ResponseCurve curve = trace_response(WeightedResidual(s, {0, 1.0, 5.0}, damper_jenkins(), db6, db6, wo), o);
  ASSERT_EQ(curve.stop, StopReason::RangeReached) << curve.message;
  const double omega_n = std::sqrt(kDamperStiffness), c = s.damping.coeff(0, 0);
  const double closed_form = (1.0 - 4.0 * 0.2 / kCirculantPi) / (c * omega_n);
  EXPECT_NEAR(branch_peak(curve), closed_form, 1e-3 * closed_form);
}

}  // namespace
}  // namespace wbm::solvers
