// Stability of forced responses with rigid stops (impact_stability, and trace_response with
// stability = true on rigid stops) against the closed forms of the 1-DOF impact oscillator: a free
// orbit's multipliers e^{(−ζω_n ± iω_d) T}, and the zero monodromy of an orbit whose plastic impact
// closes the stop (the state leaves the stop at the same (g0, 0) every period).
#include <wbm/solvers/impact_shooting.hpp>

#include <cmath>
#include <complex>
#include <memory>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include <wbm/contact/penalty.hpp>
#include <wbm/contact/signorini.hpp>
#include <wbm/solvers/response_curve.hpp>
#include <wbm/solvers/weighted_residual.hpp>

#include "impact_oscillators.hpp"

using namespace wbm;
using wbm::testing::stop_at;

namespace {

// The plastic oscillator's structure and stop (k g0/F = ½), forced at f [Hz].
struct Oscillator {
  wbm::testing::PlasticImpactOscillator o;
  [[nodiscard]] solvers::WeightedResidual problem(double f, int m) const {
    const auto trial = solvers::TimeBasis::fourier(m);
    return solvers::WeightedResidual(o.system(), {0, o.amplitude, f}, stop_at(0, o.gap), trial, trial);
  }
  // The free orbit's largest multiplier modulus over T = 1/f: e^{−ζω_n T}.
  [[nodiscard]] double free_modulus(double f) const { return std::exp(-o.zeta * o.wn / f); }
};

}  // namespace

// At the closed-form plastic orbit's frequency (8 Hz), the weighted residual solution's exact
// orbit is the closed form's and its monodromy is zero; above resonance (20 Hz) the response
// does not reach the stop and the multipliers are the linear oscillator's.
TEST(ImpactStability, ClosedFormMultipliersOfTheOneDofOscillator) {
  const Oscillator s;
  const auto touching = s.problem(s.o.f, 64).solve();
  ASSERT_TRUE(touching.converged()) << touching.report.message;
  const auto a = solvers::impact_stability(s.o.system(), {0, s.o.amplitude, s.o.f}, stop_at(0, s.o.gap),
                                           solvers::TimeBasis::fourier(64), touching.coefficients, 512);
  ASSERT_TRUE(a.available) << a.message;
  EXPECT_EQ(a.impacts, 1);
  EXPECT_LT(a.floquet.max_modulus, 1e-10);
  EXPECT_LT(a.distance, 2e-2);  // the truncation of M = 64 with a velocity jump
  const double t0 = a.orbit.start_s;
  EXPECT_NEAR(a.orbit.state(0), s.o.displacement(t0 * s.o.f), 1e-9 * s.o.gap);
  EXPECT_TRUE(a.floquet.settled());

  const double far = 20.0;
  const auto free = s.problem(far, 64).solve();
  ASSERT_TRUE(free.converged()) << free.report.message;
  const auto b = solvers::impact_stability(s.o.system(), {0, s.o.amplitude, far}, stop_at(0, s.o.gap),
                                           solvers::TimeBasis::fourier(64), free.coefficients, 512);
  ASSERT_TRUE(b.available) << b.message;
  EXPECT_EQ(b.impacts, 0);
  EXPECT_LT(b.distance, 1e-12);  // a linear orbit: the basis holds it exactly
  const std::complex<double> lambda(-s.o.zeta * s.o.wn, s.o.wd);
  const std::complex<double> mu = std::exp(lambda / far);
  ASSERT_EQ(b.floquet.multipliers.size(), 2);
  EXPECT_LT(std::min(std::abs(b.floquet.multipliers(0) - mu), std::abs(b.floquet.multipliers(0) - std::conj(mu))),
            1e-10);
  EXPECT_NEAR(b.floquet.max_modulus, s.free_modulus(far), 1e-10);
}

// A branch from 8 Hz up to 20 Hz: every point with a verdict has the closed-form multipliers of
// its kind (zero with a contact phase, e^{−ζω_n T} without an impact); the grazing point where
// the stop stops being reached is the only stretch allowed without a verdict.
TEST(ImpactStability, ForcedResponseBranchThroughGrazing) {
  const Oscillator s;
  const auto base = s.problem(s.o.f, 64);
  solvers::ResponseCurveOptions o;
  o.parameter_min = s.o.f;
  o.parameter_max = 20.0;
  o.max_step = 5e-2;
  o.stability = true;
  const auto curve = solvers::trace_response(base, o);
  ASSERT_TRUE(curve.converged()) << curve.message;
  int touching = 0, free = 0, other = 0;
  for (const auto& p : curve.points) {
    if (!p.stability_available) {
      EXPECT_FALSE(p.stability_message.empty());
      continue;
    }
    if (p.impacts == 0) {
      ++free;
      EXPECT_NEAR(p.max_multiplier, s.free_modulus(p.frequency_hz), 1e-9) << p.frequency_hz;
    } else if (p.max_multiplier < 1e-10) {
      ++touching;
    } else {
      ++other;  // an impact that does not close the stop (near grazing): no closed form
    }
  }
  // The sampled Signorini conditions fold the branch back and forth where every exact orbit has a
  // contact phase (Φ = 0): no multiplier crosses the unit circle there, so none of those folds is
  // confirmed (folds of the discretization, not of the dynamics).
  int folds_with_contact_phase = 0;
  for (size_t k = 0; k < curve.folds.size(); ++k) {
    if (curve.folds[k].parameter > 16.0) continue;  // the grazing region (17–17.7 Hz) may have true folds
    ++folds_with_contact_phase;
    EXPECT_FALSE(curve.fold_confirmed[k]) << curve.folds[k].parameter << " Hz";
  }
  EXPECT_GT(folds_with_contact_phase, 10);
  EXPECT_GT(touching, 5);
  EXPECT_GT(free, 5);
  EXPECT_EQ(curve.unavailable_points + touching + free + other, static_cast<int>(curve.points.size()));
  EXPECT_LE(curve.unavailable_points + other, static_cast<int>(curve.points.size()) / 4)
      << curve.unavailable_points << " without a verdict, " << other << " near grazing";
}

// A distance bound below the truncation makes every impacting point unavailable, with the reason;
// friction is still refused, and a contact that is not rigid is refused by name.
TEST(ImpactStability, UnavailableAndRefused) {
  const Oscillator s;
  const auto touching = s.problem(s.o.f, 64).solve();
  ASSERT_TRUE(touching.converged());
  solvers::ImpactStabilityOptions strict;
  strict.max_distance = 1e-8;
  const auto a = solvers::impact_stability(s.o.system(), {0, s.o.amplitude, s.o.f}, stop_at(0, s.o.gap),
                                           solvers::TimeBasis::fourier(64), touching.coefficients, 512, strict);
  EXPECT_FALSE(a.available);
  EXPECT_NE(a.message.find("max_distance"), std::string::npos) << a.message;
  EXPECT_TRUE(a.floquet.multipliers.size() == 0);
  strict.max_distance = 0.0;
  EXPECT_THROW((void)solvers::impact_stability(s.o.system(), {0, s.o.amplitude, s.o.f}, stop_at(0, s.o.gap),
                                               solvers::TimeBasis::fourier(64), touching.coefficients, 512, strict),
               std::invalid_argument);
  EXPECT_THROW((void)solvers::impact_stability(s.o.system(), {0, s.o.amplitude, s.o.f}, stop_at(0, s.o.gap),
                                               solvers::TimeBasis::fourier(64), touching.coefficients, 4),
               std::invalid_argument);
  const std::vector<solvers::ContactPoint> penalty{
      {0, std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{1e6, s.o.gap})}};
  EXPECT_THROW((void)solvers::impact_stability(s.o.system(), {0, s.o.amplitude, s.o.f}, penalty,
                                               solvers::TimeBasis::fourier(64), touching.coefficients, 512),
               std::invalid_argument);
}
