// Pseudo-arclength continuation, forced-response curves and Floquet multipliers, against closed
// forms: the single-harmonic Duffing response (folds, middle branch unstable), the linear rod's
// direct frequency response, the multipliers e^{sT} of a linear system; and finite differences.
#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <memory>
#include <numbers>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>
#include <unsupported/Eigen/MatrixFunctions>

#include <wbm/contact/penalty.hpp>
#include <wbm/solvers/continuation.hpp>
#include <wbm/solvers/floquet.hpp>
#include <wbm/solvers/response_curve.hpp>
#include <wbm/scene/analysis.hpp>
#include <wbm/scene/scene.hpp>

#include "shipped_scenes.hpp"
#include "testing.hpp"

namespace {

using namespace wbm;
using solvers::ContinuationParameter;
using solvers::TimeBasis;

using wbm::testing::kPi;

// Cubic spring f(u) = k3 u³ on one DOF: the Duffing oscillator's nonlinearity through the
// contact-law interface (a law is any scalar restoring force of the DOF's displacement).
class CubicSpring final : public contact::ContactLaw {
 public:
  explicit CubicSpring(double k3) : k3_(k3) {}
  [[nodiscard]] double force(double u) const override { return k3_ * u * u * u; }
  [[nodiscard]] double stiffness(double u) const override { return 3.0 * k3_ * u * u; }
  [[nodiscard]] double potential(double u) const override { return 0.25 * k3_ * u * u * u * u; }
  [[nodiscard]] double gap() const override { return 0.0; }
  [[nodiscard]] std::string describe() const override { return "cubic spring"; }

 private:
  double k3_;
};

// One DOF: mass m [kg], damping c [N·s/m], stiffness k [N/m].
solvers::MechanicalSystem one_dof(double m, double c, double k) {
  solvers::MechanicalSystem s;
  s.mass.resize(1, 1);
  s.mass.insert(0, 0) = m;
  s.stiffness.resize(1, 1);
  s.stiffness.insert(0, 0) = k;
  s.damping.resize(1, 1);
  s.damping.insert(0, 0) = c;
  return s;
}

// Duffing m ü + c u̇ + k u + k3 u³ = F cos ωt: f_n = 10 Hz, ζ = 1 %, F = 1 N, k3 = 1e7 N/m³.
struct Duffing {
  double m = 1.0, k = std::pow(2 * kPi * 10.0, 2), c = 2 * 0.01 * 2 * kPi * 10.0, k3 = 1e7, f = 1.0;

  [[nodiscard]] solvers::MechanicalSystem system() const { return one_dof(m, c, k); }
  // Harmonic balance with {1, cos, sin, cos 2ωt}: for the odd cubic the constant and cos 2ωt
  // stay zero and u³ projects exactly on cos, sin, so this is the single-harmonic balance.
  [[nodiscard]] solvers::WeightedResidual problem(double hz, int dimension = 4) const {
    return {system(), {0, f, hz}, {{0, std::make_shared<CubicSpring>(k3)}}, TimeBasis::fourier(dimension),
            TimeBasis::fourier(dimension)};
  }
  // Single-harmonic closed form: A² [(K_A − mω²)² + c²ω²] = F², K_A = k + ¾ k3 A², i.e.
  //   m²W² − (2mK_A − c²) W + K_A² − F²/A² = 0 in W = ω².
  // The two roots meet at the peak amplitude A_max (4m²F²/A² = c²(4mK_A − c²)); the larger one,
  // f₊(A), falls from ∞ (A → 0) to a local minimum (the jump-up fold), rises to a local maximum
  // (the jump-down fold, just below A_max for light damping) and falls again to A_max.
  [[nodiscard]] double ka(double a) const { return k + 0.75 * k3 * a * a; }
  [[nodiscard]] double upper_hz(double a) const {
    const double kk = ka(a), b = 2 * m * kk - c * c;
    const double disc = b * b - 4 * m * m * (kk * kk - f * f / (a * a));
    return std::sqrt((b + std::sqrt(std::max(0.0, disc))) / (2 * m * m)) / (2 * kPi);
  }
  [[nodiscard]] double peak_amplitude() const {
    auto g = [&](double a) { return 4 * m * m * f * f / (a * a) - c * c * (4 * m * ka(a) - c * c); };
    double lo = 1e-4, hi = 1.0;  // g(lo) > 0 > g(hi)
    for (int i = 0; i < 200; ++i) {
      const double mid = 0.5 * (lo + hi);
      (g(mid) > 0 ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
  }
  // Golden-section extremum of f₊ on [lo, hi] (sign = +1 maximum, −1 minimum): its amplitude A.
  [[nodiscard]] double extremum_amplitude(double lo, double hi, double sign) const {
    const double r = (std::sqrt(5.0) - 1) / 2;
    for (int i = 0; i < 200; ++i) {
      const double x1 = hi - r * (hi - lo), x2 = lo + r * (hi - lo);
      if (sign * upper_hz(x1) > sign * upper_hz(x2)) {
        hi = x2;
      } else {
        lo = x1;
      }
    }
    return 0.5 * (lo + hi);
  }
  // {jump-up, jump-down} fold amplitudes A [m]: the local minimum and maximum of f₊ on a fine
  // grid, refined by golden section on the neighbouring cells.
  [[nodiscard]] std::pair<double, double> fold_amplitudes() const {
    const double a_max = peak_amplitude();
    const int n = 20000;
    std::vector<double> a(n), fa(n);
    for (int i = 0; i < n; ++i) {
      a[i] = a_max * std::pow(1e-3, 1.0 - static_cast<double>(i) / (n - 1));
      fa[i] = upper_hz(a[i]);
    }
    int imin = -1, imax = -1;
    for (int i = 1; i + 1 < n; ++i) {
      if (imin < 0 && fa[i] < fa[i - 1] && fa[i] <= fa[i + 1]) imin = i;
      if (imin >= 0 && fa[i] > fa[i - 1] && fa[i] >= fa[i + 1]) imax = i;
    }
    return {extremum_amplitude(a[imin - 1], a[imin + 1], -1.0), extremum_amplitude(a[imax - 1], a[imax + 1], +1.0)};
  }
  // {jump-up, jump-down} fold frequencies [Hz].
  [[nodiscard]] std::pair<double, double> folds_hz() const {
    const auto [a_up, a_down] = fold_amplitudes();
    return {upper_hz(a_up), upper_hz(a_down)};
  }
};

solvers::ResponseCurveOptions duffing_options(int direction) {
  solvers::ResponseCurveOptions o;
  o.parameter_min = 8.0;
  o.parameter_max = 14.0;
  o.direction = direction;
  o.max_step = 5e-2;
  o.corrector_tolerance = 1e-12;
  return o;
}

// Raw pseudo-arclength options over the Duffing range 8–14 Hz, scaled by the start frequency and
// the residual scale.
solvers::PseudoArclengthOptions duffing_arclength(const solvers::WeightedResidual& base) {
  solvers::PseudoArclengthOptions o;
  o.parameter_min = 8.0;
  o.parameter_max = 14.0;
  o.parameter_scale = 8.0;
  o.state_scale = base.residual_scale();
  o.max_step = 5e-2;
  o.corrector_tolerance = 1e-12;
  return o;
}

}  // namespace

// ∂r/∂f against central differences of the condensed residual through at_frequency, for a
// Galerkin and a Petrov–Galerkin pair with the Case 2 stop active.
TEST(Continuation, FrequencyDerivativeMatchesFiniteDifferences) {
  const auto s = models::load_scene("jl14_case2");
  for (const auto& [tr, we] : {std::pair{"fourier", "fourier"}, std::pair{"haar", "fourier"}, std::pair{"db6", "db6"}}) {
    const solvers::WeightedResidual wr(s.system(), s.harmonic_forcing(1300.0), s.contact_points(),
                                       TimeBasis::from_name(tr, 16), TimeBasis::from_name(we, 16));
    const Eigen::VectorXd x = 1.3 * wr.contact_unknowns(wr.linear_response());  // deep in contact
    const double h = 1e-3;                                                     // Hz
    const Eigen::VectorXd fd =
        (wr.at_frequency(1300.0 + h).contact_residual(x) - wr.at_frequency(1300.0 - h).contact_residual(x)) / (2 * h);
    const Eigen::VectorXd analytic = wr.contact_residual_frequency_derivative(x);
    EXPECT_LE((analytic - fd).norm(), 1e-6 * fd.norm()) << tr << ":" << we;
  }
}

// The contact unknowns of the linear response, x_lin = P G⁻¹ b, read through the modal blocks on
// the forced and contact DOFs only (gathered_solve, issue #39 item 5), against the full solve
// G⁻¹ b gathered (linear_response, the slow path): with the stop out of reach n(x) = 0, so the
// condensed residual r(x) = (x − x_lin)/s vanishes at the full solve's x to rounding, against
// |r(0)| = |x_lin|/s. Modal pairs (Fourier:Fourier, DB6:DB6) and a pair that takes the full
// solve either way (Haar:Fourier, Fourier weighting), at a frequency off the first used.
TEST(Continuation, GatheredLinearResponseEqualsTheFullSolve) {
  const auto s = models::load_scene("jl14_case2");
  const std::vector<solvers::ContactPoint> far = {
      {s.forcing->dof, std::make_shared<contact::ExponentialPenalty>(contact::ExponentialPenaltyParameters{1e8, 20.0, 1.0})}};
  for (const auto& [tr, we] : {std::pair{"fourier", "fourier"}, std::pair{"db6", "db6"}, std::pair{"haar", "fourier"}}) {
    const solvers::WeightedResidual base(s.system(), s.harmonic_forcing(1250.0), far, TimeBasis::from_name(tr, 32),
                                         TimeBasis::from_name(we, 32));
    for (const double f : {1250.0, 1290.0}) {
      const solvers::WeightedResidual wr = base.at_frequency(f);
      const Eigen::VectorXd x = wr.contact_unknowns(wr.linear_response());
      const Eigen::VectorXd r0 = wr.contact_residual(Eigen::VectorXd::Zero(x.size()));
      EXPECT_GT(r0.norm(), 0.0);
      EXPECT_LE(wr.contact_residual(x).norm(), 1e-12 * r0.norm()) << tr << ":" << we << " at " << f << " Hz";
    }
  }
}

// With the stop out of reach (g0 = 1 m) the rod is linear: every point of the branch through
// the first resonance (1273 Hz) equals the direct solve (K − ω²M + iωC) U = F e_tip.
TEST(Continuation, LinearRodFollowsTheDirectFrequencyResponse) {
  const auto s = models::load_scene("jl14_case2");
  const std::vector<solvers::ContactPoint> far = {
      {s.forcing->dof, std::make_shared<contact::ExponentialPenalty>(contact::ExponentialPenaltyParameters{1e8, 20.0, 1.0})}};
  const solvers::WeightedResidual wr(s.system(), s.harmonic_forcing(1000.0), far, TimeBasis::fourier(8),
                                     TimeBasis::fourier(8));
  solvers::ResponseCurveOptions o;
  o.parameter_min = 1000.0;
  o.parameter_max = 1500.0;
  o.corrector_tolerance = 1e-13;  // on r = (x − …)/g0 with g0 = 1 m: 1e-13 m
  const auto curve = solvers::trace_response(wr, o);
  ASSERT_EQ(curve.stop, solvers::StopReason::RangeReached) << curve.message;
  EXPECT_TRUE(curve.folds.empty());
  EXPECT_GT(curve.points.size(), 20u);
  EXPECT_EQ(curve.points.back().frequency_hz, o.parameter_max) << "the branch stops on the range end (landed there)";
  for (const auto& p : curve.points) {
    auto forcing = s.harmonic_forcing(p.frequency_hz);
    const double exact = std::abs(solvers::frequency_response(s.system(), forcing)(forcing.dof));
    // Fourier ordering {1, cos, sin, ...}: the first-harmonic amplitude is √(a₁² + a₂²).
    EXPECT_NEAR(std::hypot(p.contact_unknowns(1), p.contact_unknowns(2)), exact, 1e-10 * exact + 1e-12) << p.frequency_hz;
    EXPECT_TRUE(p.stable) << p.frequency_hz;  // a damped linear system
  }
}

// Duffing, single harmonic: both folds of the closed form, with their states, and the same folds
// traced from either end of the range. The first-harmonic amplitude at each fold is the closed
// form's A at the extremum of f₊(A): the curve is multivalued there, so the nearest point in
// frequency can lie on the other sheet, and the fold's state must be its own.
TEST(Continuation, DuffingFoldsMatchClosedFormFromEitherEnd) {
  const Duffing d;
  const auto [jump_up, jump_down] = d.folds_hz();
  const auto [a_up, a_down] = d.fold_amplitudes();
  const auto up = solvers::trace_response(d.problem(8.0), duffing_options(+1));
  ASSERT_EQ(up.stop, solvers::StopReason::RangeReached) << up.message;
  ASSERT_EQ(up.folds.size(), 2u);
  EXPECT_NEAR(up.folds[0].parameter, jump_down, 1e-6 * jump_down);
  EXPECT_NEAR(up.folds[1].parameter, jump_up, 1e-6 * jump_up);
  ASSERT_EQ(up.fold_points.size(), 2u);
  const double expected[2] = {a_down, a_up};  // traced upward: the jump-down fold comes first
  for (size_t k = 0; k < 2; ++k) {
    const auto& f = up.fold_points[k];
    EXPECT_EQ(f.frequency_hz, up.folds[k].parameter);
    const double a = std::hypot(f.contact_unknowns(1), f.contact_unknowns(2));
    EXPECT_NEAR(a, expected[k], 1e-4 * expected[k]) << "fold " << k << " at " << f.frequency_hz << " Hz";
    EXPECT_NEAR(f.amplitude, a, 1e-3 * a) << "the sampled amplitude of the observed DOF (P = 512 samples)";
  }
  const auto down = solvers::trace_response(d.problem(14.0), duffing_options(-1));
  ASSERT_EQ(down.folds.size(), 2u) << down.message;
  EXPECT_NEAR(down.folds[0].parameter, up.folds[1].parameter, 1e-6 * jump_up);
  EXPECT_NEAR(down.folds[1].parameter, up.folds[0].parameter, 1e-6 * jump_down);
}

// Duffing with 8 harmonics (an accurate orbit): the monodromy matrix of the ODE about it finds
// the middle branch unstable and the others stable, and a multiplier crossing +1 at each fold.
// (About the single-harmonic orbit the crossings sit ~0.5 % away from its folds: the missing
// third harmonic.)
TEST(Continuation, DuffingMiddleBranchIsUnstable) {
  const Duffing d;
  const auto curve = solvers::trace_response(d.problem(8.0, 16), duffing_options(+1));
  ASSERT_EQ(curve.stop, solvers::StopReason::RangeReached) << curve.message;
  ASSERT_EQ(curve.folds.size(), 2u);
  const size_t first = curve.folds[0].after, second = curve.folds[1].after;
  for (size_t i = 0; i < curve.points.size(); ++i) {
    const auto& p = curve.points[i];
    if (i > first + 1 && i < second) {
      EXPECT_FALSE(p.stable) << i << " at " << p.frequency_hz << " Hz";
    }
    if (i + 1 < first || i > second + 2) {
      EXPECT_TRUE(p.stable) << i << " at " << p.frequency_hz << " Hz, |mu| = " << p.max_multiplier;
    }
  }
  int crossings = 0;
  for (const auto& p : curve.points) crossings += p.crossing == solvers::Bifurcation::Fold ? 1 : 0;
  EXPECT_EQ(crossings, 2);
  ASSERT_EQ(curve.fold_confirmed.size(), 2u);
  EXPECT_TRUE(curve.fold_confirmed[0] && curve.fold_confirmed[1]);
  // stability_crossings locates both between their two points, at the continuation's folds (found
  // by the tangent's sign, not by the multipliers) to within two steps of the curve in λ: the
  // jump-down fold is met first going up in frequency, so stability is lost at the first and
  // regained at the second.
  const auto located = solvers::stability_crossings(curve);
  ASSERT_EQ(located.size(), 2u);
  for (size_t j = 0; j < 2; ++j) {
    const auto& c = located[j];
    EXPECT_EQ(c.kind, solvers::Bifurcation::Fold);
    EXPECT_EQ(c.stability_lost, j == 0);
    const double lo = std::min(curve.points[c.before].parameter, curve.points[c.after].parameter);
    const double hi = std::max(curve.points[c.before].parameter, curve.points[c.after].parameter);
    EXPECT_GE(c.parameter, lo);
    EXPECT_LE(c.parameter, hi);
    const double step = std::abs(curve.points[c.after].parameter - curve.points[c.before].parameter);
    EXPECT_NEAR(c.parameter, curve.folds[j].parameter, 2.0 * step) << j;  // 1e-5 and 1e-4 Hz of 11.17 and 10.44
    EXPECT_NEAR(std::abs(c.multiplier), 1.0, 0.02) << j;                  // 1.002 and 1.006
  }
}

// stability_crossings' interpolation, on a curve written by hand: |μ| 0.9 -> 1.3 between λ = 10
// and 12 passes 1 at t = 1/4, λ = 10.5; a point without a verdict between them is skipped.
TEST(Continuation, StabilityCrossingsInterpolateTheSpectralRadius) {
  solvers::ResponseCurve curve;
  auto point = [](double lambda, double mu, bool available) {
    solvers::ResponsePoint p;
    p.parameter = p.frequency_hz = lambda;
    p.amplitude = 2.0 * lambda;
    p.max_multiplier = mu;
    p.leading_multiplier = {-mu, 0.0};
    p.stable = mu < 1.0;
    p.stability_available = available;
    return p;
  };
  curve.points = {point(10.0, 0.9, true), point(11.0, 0.0, false), point(12.0, 1.3, true), point(13.0, 0.5, true)};
  curve.points[2].crossing = solvers::Bifurcation::PeriodDoubling;
  curve.points[3].crossing = solvers::Bifurcation::PeriodDoubling;
  const auto c = solvers::stability_crossings(curve);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c[0].before, 0u);
  EXPECT_EQ(c[0].after, 2u);
  EXPECT_DOUBLE_EQ(c[0].t, 0.25);
  EXPECT_DOUBLE_EQ(c[0].parameter, 10.5);
  EXPECT_DOUBLE_EQ(c[0].amplitude, 21.0);
  EXPECT_TRUE(c[0].stability_lost);
  EXPECT_EQ(c[0].multiplier, std::complex<double>(-1.3, 0.0));
  // 1.3 -> 0.5 passes 1 at t = 0.3/0.8.
  EXPECT_DOUBLE_EQ(c[1].parameter, 12.0 + 0.375);
  EXPECT_FALSE(c[1].stability_lost);
  EXPECT_EQ(c[1].multiplier, std::complex<double>(-1.3, 0.0));
  EXPECT_EQ(c[1].kind, solvers::Bifurcation::PeriodDoubling);
}

// The stability of the points runs on threads: the multipliers, their error estimates, the
// verdicts and the crossings are bit-identical to the serial run (each point's monodromy matrix
// is computed alone), with 1, 2 and 3 threads. With two or more, the points start on a worker
// during the continuation (point_stability.hpp), and the branch's last point, replaced by its
// landing on the range's end (not a point the continuation accepted), is computed afterwards:
// both kinds meet the serial run's bits.
TEST(Continuation, StabilityOnThreadsIsBitIdenticalToTheSerialRun) {
  const Duffing d;
  auto o = duffing_options(+1);
  o.threads = 1;
  const auto serial = solvers::trace_response(d.problem(8.0, 16), o);
  ASSERT_GT(serial.points.size(), 20u);
  ASSERT_EQ(serial.points.back().parameter, o.parameter_max);  // the landing, not a queued point
  EXPECT_EQ(serial.stability_points_beside, 0);
  for (int threads : {2, 3}) {
    o.threads = threads;
    const auto parallel = solvers::trace_response(d.problem(8.0, 16), o);
    ASSERT_EQ(parallel.points.size(), serial.points.size());
    for (size_t i = 0; i < serial.points.size(); ++i) {
      const auto &a = serial.points[i], &b = parallel.points[i];
      EXPECT_EQ(a.max_multiplier, b.max_multiplier) << i;
      EXPECT_EQ(a.max_multiplier_error, b.max_multiplier_error) << i;
      EXPECT_EQ(a.monodromy_steps, b.monodromy_steps) << i;
      EXPECT_EQ(a.stable, b.stable) << i;
      EXPECT_EQ(a.crossing, b.crossing) << i;
      EXPECT_EQ(a.leading_multiplier, b.leading_multiplier) << i;
    }
    EXPECT_GT(parallel.stability_work_s, 0.0);
    // Every accepted point was taken from the worker; the landed end alone was computed after.
    EXPECT_EQ(parallel.stability_points_beside, static_cast<int>(parallel.points.size()) - 1);
    EXPECT_EQ(parallel.fold_confirmed, serial.fold_confirmed);
    EXPECT_EQ(parallel.unsettled_points, serial.unsettled_points);
  }
}

// A corrector that fails (non-finite residual) the first times it is asked inside a window is
// retried with halved steps; the branch then reaches the end with the same folds.
TEST(Continuation, StepAdaptationRecoversFromAForcedCorrectorFailure) {
  const Duffing d;
  const auto base = d.problem(8.0);
  const solvers::ForcedResponseFamily family(base, ContinuationParameter::Frequency);
  struct Flaky {
    const solvers::ForcedResponseFamily* family;
    mutable int failures_left = 6;  // evaluations in the window fail, residual() and linearize() alike
    [[nodiscard]] bool fails(double f) const { return f > 10.5 && f < 11.0 && failures_left > 0 && failures_left--; }
    [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x, double f) const {
      return fails(f) ? Eigen::VectorXd(Eigen::VectorXd::Constant(x.size(), NAN)) : family->residual(x, f);
    }
    [[nodiscard]] solvers::LowRankLinearization linearize(const Eigen::VectorXd& x, double f) const {
      solvers::LowRankLinearization l = family->linearize(x, f);
      if (fails(f)) l.residual.setConstant(std::nan(""));
      return l;
    }
  };
  const Flaky flaky{&family};
  const solvers::PseudoArclengthOptions o = duffing_arclength(base);
  const Eigen::VectorXd x0 = base.contact_unknowns(base.linear_response());
  const auto clean = solvers::pseudo_arclength(family, x0, 8.0, o);
  const auto recovered = solvers::pseudo_arclength(flaky, x0, 8.0, o);
  EXPECT_EQ(flaky.failures_left, 0);
  EXPECT_GE(recovered.rejected_steps, clean.rejected_steps + 1);
  ASSERT_EQ(recovered.stop, solvers::StopReason::RangeReached) << recovered.message;
  ASSERT_EQ(recovered.folds.size(), 2u);
  for (size_t i = 0; i < 2; ++i) EXPECT_NEAR(recovered.folds[i].parameter, clean.folds[i].parameter, 1e-5);
}

// The same branch through the sparse path (SparseLinearization, sparse LU of the bordered system)
// as through the dense one: Duffing's folds agree to the corrector tolerance.
TEST(Continuation, SparseJacobianPathEqualsTheDensePath) {
  const Duffing d;
  const auto base = d.problem(8.0);
  const solvers::ForcedResponseFamily family(base, ContinuationParameter::Frequency);
  struct Sparse {
    const solvers::ForcedResponseFamily* family;
    [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x, double f) const { return family->residual(x, f); }
    [[nodiscard]] solvers::SparseLinearization linearize(const Eigen::VectorXd& x, double f) const {
      const solvers::LowRankLinearization l = family->linearize(x, f);
      return {l.residual, l.jacobian.dense().sparseView(), l.parameter_derivative};
    }
  };
  const solvers::PseudoArclengthOptions o = duffing_arclength(base);
  const Eigen::VectorXd x0 = base.contact_unknowns(base.linear_response());
  const auto dense = solvers::pseudo_arclength(family, x0, 8.0, o);
  const auto sparse = solvers::pseudo_arclength(Sparse{&family}, x0, 8.0, o);
  ASSERT_EQ(sparse.stop, solvers::StopReason::RangeReached) << sparse.message;
  ASSERT_EQ(sparse.folds.size(), 2u);
  EXPECT_EQ(sparse.points.size(), dense.points.size());
  for (size_t i = 0; i < 2; ++i) EXPECT_NEAR(sparse.folds[i].parameter, dense.folds[i].parameter, 1e-9);
}

// A complementarity branch that turns back at a corner: x − λ + a μ = 0, min(μ, 1 − x) = 0 with
// a = −0.1 (state (x, μ), parameter λ). Free piece x = λ up to λ = 1; then the stop x = 1 is
// active, μ = (λ − 1)/a ≥ 0 needs λ ≤ 1: the branch turns back by 180° − 5.7°, and no hyperplane
// normal to the old tangent meets the new piece. Without corner restarts the corrector fails for
// every step (StepBelowMinimum at λ = 1); with them the continuation follows the new piece to
// μ = 1 (λ = 0.9) exactly.
TEST(Continuation, CornerRestartFollowsAComplementarityBranchThatTurnsBack) {
  struct Stop {
    double a = -0.1;
    [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x, double lambda) const {
      return Eigen::Vector2d(x(0) - lambda + a * x(1), std::min(x(1), 1.0 - x(0)));
    }
    [[nodiscard]] solvers::Linearization linearize(const Eigen::VectorXd& x, double lambda) const {
      Eigen::Matrix2d j;
      j << 1.0, a, 0.0, 0.0;
      if (x(1) <= 1.0 - x(0)) j(1, 1) = 1.0; else j(1, 0) = -1.0;  // the min picks μ, else 1 − x
      return {residual(x, lambda), j, Eigen::Vector2d(-1.0, 0.0)};
    }
  };
  solvers::PseudoArclengthOptions o;
  o.parameter_min = 0.0;
  o.parameter_max = 2.0;
  o.initial_step = 0.05;
  o.max_step = 0.05;
  o.max_points = 400;
  o.corrector_tolerance = 1e-12;
  const auto plain = solvers::pseudo_arclength(Stop{}, Eigen::Vector2d(0.5, 0.0), 0.5, o);
  EXPECT_EQ(plain.stop, solvers::StopReason::StepBelowMinimum);
  EXPECT_NEAR(plain.points.back().parameter, 1.0, 0.06);
  o.corner_restart = true;
  const auto turned = solvers::pseudo_arclength(Stop{}, Eigen::Vector2d(0.5, 0.0), 0.5, o);
  EXPECT_EQ(turned.kinks, 1);
  ASSERT_EQ(turned.folds.size(), 1u);
  EXPECT_NEAR(turned.folds[0].parameter, 1.0, 1e-2);  // Hermite interpolation across a corner: within a step
  bool reached = false;
  for (const auto& p : turned.points) {
    EXPECT_LE(std::abs(Stop{}.residual(p.x, p.parameter).norm()), 1e-12);
    EXPECT_GE(p.x(1), -1e-12);           // μ ≥ 0
    EXPECT_LE(p.x(0), 1.0 + 1e-12);      // x ≤ 1
    EXPECT_LE(p.parameter, 1.0 + 1e-12);  // the branch never passes the corner
    if (p.x(1) >= 1.0) {
      reached = true;
      EXPECT_NEAR(p.parameter, 1.0 + (-0.1) * p.x(1), 1e-12);  // on the new piece, λ = 1 + a μ
    }
  }
  EXPECT_TRUE(reached);
  // corner_bisection: the corrector beyond the corner cycles between the two pieces (|·| + 1 in
  // disguise); stopping it and bisecting toward its hyperplane reaches the same corner and the
  // same new piece with fewer rejected steps (one attempt per halving).
  o.corner_bisection = true;
  const auto bisected = solvers::pseudo_arclength(Stop{}, Eigen::Vector2d(0.5, 0.0), 0.5, o);
  EXPECT_EQ(bisected.kinks, 1);
  ASSERT_EQ(bisected.folds.size(), 1u);
  EXPECT_NEAR(bisected.folds[0].parameter, 1.0, 1e-2);
  EXPECT_LT(bisected.rejected_steps, turned.rejected_steps);
  bool new_piece = false;
  for (const auto& p : bisected.points) {
    EXPECT_LE(Stop{}.residual(p.x, p.parameter).norm(), 1e-12);
    EXPECT_LE(p.parameter, 1.0 + 1e-12);
    if (p.x(1) >= 1.0) {
      new_piece = true;
      EXPECT_NEAR(p.parameter, 1.0 + (-0.1) * p.x(1), 1e-12);
    }
  }
  EXPECT_TRUE(new_piece);
}

// Linear system: Φ = e^{A₀T} exactly, so the multipliers are e^{sT} with the modal eigenvalues
// s = −ζω ± ω√(ζ² − 1), ω² = λ_i, 2ζω = β λ_i (C = βK) of the rod.
TEST(Floquet, LinearRodMultipliersAreExponentialsOfModalEigenvalues) {
  const auto s = models::load_scene("jl14_case2");
  const auto sys = s.system();
  const double f = 1275.0, beta = s.damping.beta;
  const auto result = solvers::floquet_multipliers(sys, {}, Eigen::MatrixXd(0, 64), f);
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(Eigen::MatrixXd(sys.stiffness),
                                                                      Eigen::MatrixXd(sys.mass));
  ASSERT_EQ(result.multipliers.size(), 2 * sys.dofs());
  for (Eigen::Index i = 0; i < eig.eigenvalues().size(); ++i) {
    // High modes are overdamped (ζ > 1): s is then real, hence the complex square root.
    const double w = std::sqrt(eig.eigenvalues()(i)), zeta = 0.5 * beta * w;
    const std::complex<double> s_i = -zeta * w + w * std::sqrt(std::complex<double>(zeta * zeta - 1.0));
    const std::complex<double> mu = std::exp(s_i / f);
    double best = 1e300;
    for (Eigen::Index j = 0; j < result.multipliers.size(); ++j) best = std::min(best, std::abs(result.multipliers(j) - mu));
    EXPECT_LT(best, 1e-9) << "mode " << i;
  }
  EXPECT_TRUE(result.stable());
}

// Φ itself against the modal closed form: with ψ mass-normalized, Φ = S blockdiag(Φ_i) S⁻¹, each
// mode's 2 × 2 transition matrix from s_{1,2} = −ζω ± ω√(ζ² − 1) (long double). ‖M⁻¹K‖₁ h is
// 2.9e6 at P = 64 here; the unbalanced exponential had blocks wrong by 3.5e-8, the balanced one
// (floquet.cpp) by at most 8.4e-11.
TEST(Floquet, LinearRodMonodromyIsTheModalTransitionMatrix) {
  const auto s = models::load_scene("jl14_case2");
  const auto sys = s.system();
  const Eigen::Index n = sys.dofs();
  const double f = 1275.0;
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(Eigen::MatrixXd(sys.stiffness), Eigen::MatrixXd(sys.mass));
  const Eigen::MatrixXd psi = eig.eigenvectors(), psi_inv = psi.transpose() * Eigen::MatrixXd(sys.mass);
  std::array<Eigen::VectorXd, 4> modal;  // Φ_i's entries (1,1), (1,2), (2,1), (2,2) per mode
  for (auto& v : modal) v.resize(n);
  using C = std::complex<long double>;
  for (Eigen::Index i = 0; i < n; ++i) {
    const long double w = std::sqrt(static_cast<long double>(eig.eigenvalues()(i))), zeta = 0.5L * s.damping.beta * w;
    const C root = std::sqrt(C(zeta * zeta - 1.0L)), s1 = -zeta * w + w * root, s2 = -zeta * w - w * root;
    const C e1 = std::exp(s1 / static_cast<long double>(f)), e2 = std::exp(s2 / static_cast<long double>(f)), d = s1 - s2;
    modal[0](i) = static_cast<double>(std::real((s1 * e2 - s2 * e1) / d));
    modal[1](i) = static_cast<double>(std::real((e1 - e2) / d));
    modal[2](i) = static_cast<double>(std::real(s1 * s2 * (e2 - e1) / d));
    modal[3](i) = static_cast<double>(std::real((s1 * e1 - s2 * e2) / d));
  }
  for (const int steps : {64, 8192}) {
    const auto result = solvers::floquet_multipliers(sys, {}, Eigen::MatrixXd(0, steps), f);
    for (int b = 0; b < 4; ++b) {
      const Eigen::MatrixXd expected = psi * modal[static_cast<size_t>(b)].asDiagonal() * psi_inv;
      const Eigen::MatrixXd got = result.monodromy.block((b / 2) * n, (b % 2) * n, n, n);
      EXPECT_LT((got - expected).norm(), 1e-9 * expected.norm()) << "P = " << steps << ", block " << b;
    }
  }
}

// The contact part is integrated by the trapezoidal rule: second order in the step T/P (Duffing
// point on the resonant branch, smooth k(t) = 3 k3 u(t)²; reference P = 16384).
TEST(Floquet, MonodromyConvergesAtSecondOrder) {
  const Duffing d;
  const auto wr = d.problem(10.8);
  const auto sol = wr.solve();
  ASSERT_TRUE(sol.converged());
  auto multipliers = [&](int p) {
    const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(p, 0.0, 1.0 - 1.0 / p);
    const Eigen::MatrixXd u = (TimeBasis::fourier(4).values(tau, 0) * sol.coefficients.transpose()).transpose();
    return solvers::floquet_multipliers(d.system(), wr.contacts(), u, 10.8).monodromy;
  };
  const Eigen::MatrixXd reference = multipliers(16384);
  std::vector<double> h, err;
  for (int p : {64, 128, 256, 512}) {
    h.push_back(1.0 / p);
    err.push_back((multipliers(p) - reference).norm());
  }
  EXPECT_NEAR(wbm::testing::observed_order(h, err), 2.0, 0.15);
}

// Regression (issue #19): the stability verdicts along the branch of an oscillator against a
// stop 100 times stiffer than its spring (m = 1 kg, k = 4e4 N/m, c = 5 N·s/m, k_c = 4e6 N/m at
// g0 = 2 mm, F = 5 N; examples/scenes/stiff_stop_continuation.toml) against its exact monodromy.
// The law f = k_c (u − g0)⁺ is continuous, so the saltation matrix at a switch is I and
// Φ = Π_i e^{A_i Δt_i}: the exact exponential of each linear piece (A_free, A_contact) between the
// orbit's gap crossings, found by bisection on u*(τ) = Σ a_k q_k(τ). Before the crossing split
// the switch sat at a sample: |μ| reached 1.6 where the exact value is 0.94, and runs of
// "unstable" points broke the attracting upper branch. Near the collision of two real
// multipliers on the middle branch (45.21 Hz) P = 512 gave a complex pair of modulus 0.946 for
// the exact 1.029 and 0.870: the error estimate sends such points to 4P.
TEST(Floquet, StiffStopVerdictsAgreeWithTheExactPiecewiseLinearMonodromy) {
  const double m = 1.0, k = 4e4, c = 5.0, kc = 4e6, g0 = 2e-3;
  const solvers::MechanicalSystem system = one_dof(m, c, k);
  const auto law = std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{kc, g0});
  const auto basis = TimeBasis::fourier_harmonics(32);
  const solvers::WeightedResidual base(system, {0, 5.0, 15.0}, {{0, law}}, basis, basis,
                                       {.contact_quadrature = solvers::ContactQuadrature::CellAverage});
  solvers::ResponseCurveOptions o;
  o.parameter_min = 15.0;
  o.parameter_max = 60.0;
  o.samples = 512;
  const auto curve = solvers::trace_response(base, o);
  ASSERT_EQ(curve.stop, solvers::StopReason::RangeReached) << curve.message;
  ASSERT_EQ(curve.folds.size(), 2u);
  auto exact_spectral_radius = [&](const Eigen::VectorXd& a, double hz) {
    auto u = [&](double tau) {
      Eigen::VectorXd t(1);
      t << tau;
      return (basis.values(t, 0) * a)(0);
    };
    const int grid = 4096;
    std::vector<double> switches;  // τ of each gap crossing, in order
    for (int i = 0; i < grid; ++i) {
      double lo = static_cast<double>(i) / grid, hi = static_cast<double>(i + 1) / grid;
      if ((u(lo) > g0) == (u(hi) > g0)) continue;
      const bool rising = u(lo) <= g0;
      for (int it = 0; it < 60; ++it) {
        const double mid = 0.5 * (lo + hi);
        ((u(mid) > g0) == rising ? hi : lo) = mid;
      }
      switches.push_back(0.5 * (lo + hi));
    }
    auto a_matrix = [&](bool contact) {
      Eigen::Matrix2d a;
      a << 0.0, 1.0, -(k + (contact ? kc : 0.0)) / m, -c / m;
      return a;
    };
    Eigen::Matrix2d phi = Eigen::Matrix2d::Identity();
    double from = 0.0;
    bool contact = u(0.0) > g0;
    switches.push_back(1.0);
    for (double to : switches) {
      phi = (a_matrix(contact) * ((to - from) / hz)).exp() * phi;
      from = to;
      contact = !contact;
    }
    return Eigen::EigenSolver<Eigen::Matrix2d>(phi, false).eigenvalues().cwiseAbs().maxCoeff();
  };
  int compared = 0, verdicts = 0;
  double worst = 0.0;
  for (size_t i = 0; i < curve.points.size(); i += 3) {
    const auto& p = curve.points[i];
    const double exact = exact_spectral_radius(p.contact_unknowns, p.frequency_hz);
    worst = std::max(worst, std::abs(p.max_multiplier - exact));
    // The reported accuracy is honest: the error is within twice its estimate (+1e-4 for the
    // oracle's own switching times, from the truncated orbit).
    EXPECT_LE(std::abs(p.max_multiplier - exact), 2.0 * p.max_multiplier_error + 1e-4)
        << p.frequency_hz << " Hz, P = " << p.monodromy_steps;
    ++compared;
    if (std::abs(exact - 1.0) > 0.02) {  // away from the folds, where the verdict is delicate
      ++verdicts;
      EXPECT_EQ(p.stable, exact < 1.0) << p.frequency_hz << " Hz: |μ| " << p.max_multiplier << ", exact " << exact;
    }
  }
  EXPECT_GT(verdicts, 50);
  EXPECT_GT(compared, 100);
  EXPECT_LT(worst, 0.05);  // measured 0.026, on the middle (unstable) branch at P = 512
  EXPECT_EQ(curve.unsettled_points, 0);
}

// Bad input is refused with the parameter named.
TEST(Continuation, RefusesInvalidOptions) {
  const Duffing d;
  auto o = duffing_options(+1);
  o.parameter_min = 9.0;
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { (void)solvers::trace_response(d.problem(8.0), o); },
                                                    {"start 8", "outside [9"});
  o = duffing_options(+1);
  o.threads = -1;
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { (void)solvers::trace_response(d.problem(8.0), o); },
                                                    {"threads = -1", ">= 0"});
  solvers::PseudoArclengthOptions p;
  p.parameter_min = 1.0;
  p.parameter_max = 2.0;
  p.direction = 0;
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { p.validate(); }, {"direction = 0"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)solvers::floquet_multipliers(d.system(), {}, Eigen::MatrixXd(0, 4), 10.0); }, {"need P >= 8"});
}

// Extremes of issue #6 on the Case 2 rod: a stiff penalty (α = 500 1/m), very light damping
// (β = 1e-7 s, a sharp fold) and a zero gap. Each branch completes or stops with a reason, and
// every point it holds is a converged, finite solution (the residual is checked again here).
TEST(Continuation, ExtremesCompleteOrStopWithAReasonAndValidPoints) {
  const auto s = models::load_scene("jl14_case2");
  const auto& c = s.contacts.front();
  struct Extreme {
    const char* what;
    double exponent, beta, gap;
  };
  for (const Extreme e : {Extreme{"alpha = 500", 500.0, s.damping.beta, c.gap}, Extreme{"beta = 1e-7", c.exponent, 1e-7, c.gap},
                          Extreme{"gap = 0", c.exponent, s.damping.beta, 0.0}}) {
    const fem::Rod rod(s.structure->rod);
    const std::vector<solvers::ContactPoint> contacts = {
        {rod.tip_dof(), std::make_shared<contact::ExponentialPenalty>(
                            contact::ExponentialPenaltyParameters{c.coefficient, e.exponent, e.gap})}};
    const solvers::WeightedResidual base(solvers::beta_damped(rod, e.beta), s.harmonic_forcing(1000.0), contacts,
                                         TimeBasis::fourier(16), TimeBasis::fourier(16));
    solvers::ResponseCurveOptions o;
    o.parameter_min = 1000.0;
    o.parameter_max = 1700.0;
    o.max_points = 800;
    const auto curve = solvers::trace_response(base, o);
    EXPECT_FALSE(curve.message.empty()) << e.what;
    EXPECT_NE(curve.stop, solvers::StopReason::InitialPointFailed) << e.what << ": " << curve.message;
    ASSERT_FALSE(curve.points.empty()) << e.what;
    const solvers::ForcedResponseFamily family(base, ContinuationParameter::Frequency);
    for (size_t i = 0; i < curve.points.size(); i += 25) {
      const auto& p = curve.points[i];
      ASSERT_TRUE(p.contact_unknowns.allFinite() && std::isfinite(p.amplitude) && std::isfinite(p.max_multiplier))
          << e.what;
      EXPECT_LE(family.residual(p.contact_unknowns, p.frequency_hz).norm(), 1e-8) << e.what << " at " << p.frequency_hz;
    }
    std::printf("[ extreme  ] %s: %zu points, %zu folds, stop: %s (%s)\n", e.what, curve.points.size(),
                curve.folds.size(), std::string(solvers::to_string(curve.stop)).c_str(), curve.message.c_str());
  }
}

// The fold of a step is the extremum of the cubic Hermite interpolant of λ̂(s): exact for a cubic.
// λ(s) = 1 − (s − 0.3)² + 0.5 (s − 0.3)³ on [0, 1] has λ'(0.3) = 0, λ(0.3) = 1, and λ' changes sign
// there only (λ'(s) = −2u + 1.5u², u = s − 0.3, zero again at u = 4/3, outside the step).
TEST(Continuation, FoldIsTheExtremumOfTheHermiteCubic) {
  const auto lambda = [](double s) { return 1.0 - std::pow(s - 0.3, 2) + 0.5 * std::pow(s - 0.3, 3); };
  const auto slope = [](double s) { return -2.0 * (s - 0.3) + 1.5 * std::pow(s - 0.3, 2); };
  EXPECT_NEAR(wbm::solvers::detail::fold_parameter(lambda(0.0), lambda(1.0), slope(0.0), slope(1.0), 1.0), 1.0, 1e-14);
  // A quadratic over a step of length 2 with its top at s = 1.5: λ = 3 − (s − 1.5)².
  EXPECT_NEAR(wbm::solvers::detail::fold_parameter(3.0 - 2.25, 3.0 - 0.25, 3.0, -1.0, 2.0), 3.0, 1e-14);
}

// The undamped top function (issue #19). A peer's nondimensional rod (E = ρ = S = L = 1, C = βK
// with β = 0.04/π, tip force 0.01, linear stop k = 10 at g0 = 0.1), 0.2–0.4 Hz across its first
// resonance (0.25 Hz). With M = 2^J the lone top function cos πMτ has no damping; for 20 elements
// and M = 32, 16 f meets the 8th mode near 0.2486 Hz and the branch follows that undamped
// resonance (hundreds of gaps, point limit) unless cut where that function takes over, as
// trace_response does (StopReason::UndampedResonance). With H harmonics (2H + 1 functions, every harmonic
// damped) the branch crosses the range; its peak amplitude is converged in H (H = 16 against 32,
// and M = 128 where (M/2)f meets no mode in the range), so it is not a truncation artefact.
TEST(Continuation, HarmonicFourierBasisTracesTheBranchTheUndampedTopFunctionDerails) {
  // Largest tip amplitude along the branch [gaps], as `wbm run` traces it; `stop` as it reports it.
  std::string message;  // of the last run
  const auto peak = [&message](const std::string& basis, int max_points, std::string& stop) {
    const auto s = scene::parse_scene(R"(
[structure]
young_modulus = 1.0
density = 1.0
area = 1.0
length = 1.0
elements = 20
[damping]
beta = 0.012732395447351627
[forcing]
amplitude = 0.01
frequency_hz = [0.2, 0.4]
[contact]
law = "linear"
stiffness = 10.0
gap = 0.1
[analysis]
type = "continuation"
stability = false
max_points = )" + std::to_string(max_points) + R"(
[basis]
trial = "fourier"
)" + basis + "\n",
                                      "peer_rod.toml");
    const auto result = scene::run_analysis(s);
    stop = result.diagnostics["continuation"]["stop"].get<std::string>();
    message = result.diagnostics["continuation"]["message"].get<std::string>();
    const auto& branch = result.tables.front();
    EXPECT_EQ(branch.header[3], "amplitude_node20 [m]");
    if (basis == "harmonics = 16") {
      // The same branch with ResponseCurveOptions' defaults: a predictor there overshoots to f < 0,
      // which must be a failed step (halved), not an exception out of the continuation.
      solvers::ResponseCurveOptions o;
      o.parameter_min = 0.2;
      o.parameter_max = 0.4;
      o.stability = false;
      const solvers::WeightedResidual base(s.system(), s.harmonic_forcing(0.2), s.contact_points(), s.trial(), s.weighting());
      const auto curve = solvers::trace_response(base, o);
      EXPECT_EQ(curve.stop, solvers::StopReason::RangeReached) << curve.message;
      double best = 0.0;
      for (const auto& p : curve.points) best = std::max(best, p.amplitude);
      EXPECT_NEAR(best, branch.columns[3].maxCoeff(), 2e-3 * best);
    }
    return branch.columns[3].maxCoeff() / 0.1;
  };
  std::string stop16, stop32, stop128, stop_top;
  const double h16 = peak("harmonics = 16", 2000, stop16), h32 = peak("harmonics = 32", 2000, stop32);
  const double m128 = peak("dimension = 128", 2000, stop128);
  EXPECT_EQ(stop16, "range reached");
  EXPECT_EQ(stop32, "range reached");
  EXPECT_EQ(stop128, "range reached");
  EXPECT_NEAR(h16, h32, 2e-3 * h32);
  EXPECT_NEAR(m128, h32, 2e-3 * h32);
  EXPECT_LT(h32, 2.0);  // the stop limits the tip to about 1.3 gaps
  // M = 32: the branch is cut where the top function takes over, naming the 8th mode (its
  // frequency, 16 f, from the FE model: 3.97 Hz), before the runaway (hundreds of gaps).
  const double top = peak("dimension = 32", 1000, stop_top);
  EXPECT_EQ(stop_top, "undamped resonance of the top Fourier function");
  EXPECT_NE(message.find("resonates with mode 8"), std::string::npos) << message;
  EXPECT_LT(top, 2.0);
}
