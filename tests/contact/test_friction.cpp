// The Jenkins element over one period (contact/friction.hpp). Truths not produced by this code:
// the closed-form hysteresis loop of a Jenkins element under w = A cos θ [G80] at the samples,
// its dissipated energy 4 F_s (A − F_s/k_t) per cycle and first-harmonic stiffness
// (k_t/π)(β − sin 2β / 2), cos β = 1 − 2 F_s/(k_t A), with the rectangle rule's second order;
// full stick f = k_t w; the Coulomb limit k_t → ∞ (energy 4 F_s A); central differences of the
// force in every sample of w and of the slip force; invariance under a shift of the period. Exact
// Coulomb friction (CoulombProjection): the roots of the projection equation are the normal-cone
// inclusion of the discrete Coulomb law, whatever the compliance.
#include <wbm/contact/friction.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "testing.hpp"

using wbm::contact::jenkins_loop;
using wbm::contact::JenkinsLoop;

namespace {

using wbm::testing::kPi;

Eigen::VectorXd angles(int q) { return Eigen::VectorXd::LinSpaced(q, 0.0, 2.0 * kPi * (q - 1) / q); }

// [G80]'s loop for w = A cos θ: from the reversal at θ = 0 (f = F_s) the element sticks,
// f = F_s − k_t A (1 − cos θ), until f reaches −F_s at θ = β; it then slips at −F_s up to θ = π;
// the second half mirrors the first, f(θ + π) = −f(θ).
double griffin_force(double theta, double kt, double fs, double a) {
  if (theta > kPi) return -griffin_force(theta - kPi, kt, fs, a);
  return std::max(fs - kt * a * (1.0 - std::cos(theta)), -fs);
}

// The dense Jacobians ∂f/∂w and ∂f/∂F_s from the loop's sparse description.
Eigen::MatrixXd displacement_jacobian(const JenkinsLoop& l, double kt) {
  const auto n = l.force.size();
  Eigen::MatrixXd j = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index q = 0; q < n; ++q) {
    j(q, q) += l.stiffness(q);
    if (l.anchor(q) >= 0) j(q, l.anchor(q)) -= kt;
  }
  return j;
}

Eigen::MatrixXd slip_force_jacobian(const JenkinsLoop& l) {
  const auto n = l.force.size();
  Eigen::MatrixXd j = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index q = 0; q < n; ++q) {
    if (l.stiffness(q) == 0.0) {
      j(q, q) = l.slip_sensitivity(q);  // slip: f_q = σ_q F_s,q
    } else if (l.anchor(q) >= 0) {
      j(q, l.anchor(q)) = l.slip_sensitivity(q);  // stick after the slip at the anchor
    }
  }
  return j;
}

// The loop's derivatives ∂f/∂w and ∂f/∂F_s (displacement_jacobian, slip_force_jacobian of
// loop_at(w, F_s)) against central differences of loop_at's force in every sample of w (step hw)
// and of F_s (step hf).
template <class LoopAt>
void expect_derivatives_match_central_differences(const LoopAt& loop_at, double kt, const Eigen::VectorXd& w,
                                                  const Eigen::VectorXd& fs, double hw, double hf) {
  const JenkinsLoop l = loop_at(w, fs);
  const Eigen::MatrixXd jw = displacement_jacobian(l, kt), jf = slip_force_jacobian(l);
  for (Eigen::Index r = 0; r < w.size(); ++r) {
    Eigen::VectorXd wp = w, wm = w, fp = fs, fm = fs;
    wp(r) += hw;
    wm(r) -= hw;
    fp(r) += hf;
    fm(r) -= hf;
    const Eigen::VectorXd dw = (loop_at(wp, fs).force - loop_at(wm, fs).force) / (2.0 * hw);
    const Eigen::VectorXd df = (loop_at(w, fp).force - loop_at(w, fm).force) / (2.0 * hf);
    EXPECT_LT((dw - jw.col(r)).cwiseAbs().maxCoeff(), 1e-6 * kt) << "w sample " << r;
    EXPECT_LT((df - jf.col(r)).cwiseAbs().maxCoeff(), 1e-6) << "slip force sample " << r;
  }
}

}  // namespace

// The loop at the samples equals [G80]'s closed form (rounding of the increments only), the
// slip starts at the first sample past β, the state is periodic after two periods, and the slider
// dissipates exactly 4 F_s (A − F_s/k_t) per cycle: with Q even the samples hit both reversals.
TEST(JenkinsLoop, EqualsGriffinsClosedFormLoopUnderHarmonicDisplacement) {
  const double kt = 1e6, fs = 10.0, a = 5e-5;  // k_t A = 50 N > F_s: the element slips
  const int q = 256;
  const Eigen::VectorXd theta = angles(q);
  const Eigen::VectorXd w = a * theta.array().cos();
  const JenkinsLoop l = jenkins_loop(kt, w, Eigen::VectorXd::Constant(q, fs));
  EXPECT_EQ(l.periods, 2);
  const double beta = std::acos(1.0 - 2.0 * fs / (kt * a));
  int slipping = 0;
  for (int i = 0; i < q; ++i) {
    EXPECT_NEAR(l.force(i), griffin_force(theta(i), kt, fs, a), 1e-12 * kt * a) << "sample " << i;
    const double phase = 2.0 * kPi * (i % (q / 2)) / q;  // θ from the last reversal (i = 0 or Q/2)
    const bool slip = i % (q / 2) == 0 || phase > beta;
    EXPECT_EQ(l.stiffness(i), slip ? 0.0 : kt) << "sample " << i;
    slipping += slip ? 1 : 0;
    if (!slip) {
      EXPECT_EQ(l.anchor(i), i < q / 2 ? 0 : q / 2) << "sample " << i;  // the last reversal
    }
  }
  EXPECT_EQ(l.slipping_samples, slipping);
  EXPECT_NEAR(l.dissipated_energy, 4.0 * fs * (a - fs / kt), 1e-12 * fs * a);
}

// The first harmonic of the loop, by the rectangle rule over Q samples, tends to [G80]'s
// equivalent stiffness (k_t/π)(β − sin 2β / 2) and damping term W/(πA) at second order in 1/Q:
// the loop is continuous with a kink at each slip onset, so the error times Q² stays bounded
// (it oscillates with where the kink falls between samples: measured 0.05 … 7 from Q = 64 to
// 16 384), while a first-order error would grow it 256-fold over that range.
TEST(JenkinsLoop, FirstHarmonicTendsToGriffinsEquivalentStiffnessAndDampingAtSecondOrder) {
  const double kt = 1e6, fs = 10.0, a = 5e-5;
  const double beta = std::acos(1.0 - 2.0 * fs / (kt * a));
  const double stiffness = kt / kPi * (beta - 0.5 * std::sin(2.0 * beta));
  const double damping = 4.0 * fs * (a - fs / kt) / (kPi * a);
  for (int q = 64; q <= 16384; q *= 2) {
    const Eigen::VectorXd theta = angles(q);
    const JenkinsLoop l = jenkins_loop(kt, a * theta.array().cos(), Eigen::VectorXd::Constant(q, fs));
    const double a1 = 2.0 / q * l.force.dot(theta.array().cos().matrix());
    const double b1 = 2.0 / q * l.force.dot(theta.array().sin().matrix());
    const double error = std::max(std::abs(a1 / a - stiffness) / stiffness, std::abs(-b1 - damping) / damping);
    EXPECT_LT(error * q * q, 10.0) << "Q = " << q;
  }
}

// Below the slip threshold (k_t A < F_s) the element sticks: f = k_t w, the slider at the origin,
// no energy dissipated, the Jacobian k_t I.
TEST(JenkinsLoop, FullStickIsTheSpringAlone) {
  const double kt = 1e6, fs = 10.0, a = 5e-6;
  const int q = 64;
  const Eigen::VectorXd theta = angles(q);
  const Eigen::VectorXd w = a * (theta.array().cos() + 0.3 * (3.0 * theta.array()).sin());
  const JenkinsLoop l = jenkins_loop(kt, w, Eigen::VectorXd::Constant(q, fs));
  EXPECT_EQ(l.slipping_samples, 0);
  EXPECT_EQ(l.periods, 2);
  EXPECT_EQ(l.dissipated_energy, 0.0);
  EXPECT_LT((l.force - kt * w).cwiseAbs().maxCoeff(), 1e-12 * kt * a);
  EXPECT_TRUE((l.anchor.array() == -1).all());
  EXPECT_TRUE((l.stiffness.array() == kt).all());
}

// The Coulomb limit: as k_t → ∞ the energy per cycle tends to 4 F_s A with the relative defect
// F_s/(k_t A), and the force to F_s sign(dw/dt) = −F_s sign(sin θ) away from the reversals.
TEST(JenkinsLoop, TendsToCoulombFrictionAsTheTangentialStiffnessGrows) {
  const double fs = 10.0, a = 5e-5;
  const int q = 512;
  const Eigen::VectorXd theta = angles(q);
  double previous = 0.0;
  for (double ratio : {1e1, 1e2, 1e3, 1e4}) {  // k_t A / F_s
    const double kt = ratio * fs / a;
    const JenkinsLoop l = jenkins_loop(kt, a * theta.array().cos(), Eigen::VectorXd::Constant(q, fs));
    EXPECT_NEAR(l.dissipated_energy / (4.0 * fs * a), 1.0 - 1.0 / ratio, 1e-12) << ratio;
    double distance = 0.0;  // mean |f − f_Coulomb| over the samples
    for (int i = 0; i < q; ++i) {
      const double s = std::sin(theta(i));
      const double coulomb = s > 0.0 ? -fs : s < 0.0 ? fs : l.force(i);
      distance += std::abs(l.force(i) - coulomb) / q;
    }
    if (previous > 0.0) {
      EXPECT_LT(distance, previous) << ratio;
    }
    previous = distance;
  }
  EXPECT_LT(previous, 0.02 * fs);  // k_t A = 1e4 F_s: one sample of stick per reversal
}

// ∂f/∂w and ∂f/∂F_s against central differences, for a multi-harmonic w and a slip force that
// varies over the period (a varying normal load): at most two entries a row, exact away from the
// switching samples. Shifting the period's samples shifts the steady state (no transient left).
TEST(JenkinsLoop, JacobiansMatchCentralDifferencesAndTheStateIsPeriodic) {
  const double kt = 1e6, f0 = 10.0, a = 5e-5;
  const int q = 96;
  const Eigen::VectorXd theta = angles(q);
  const Eigen::VectorXd w =
      a * (theta.array().cos() + 0.3 * (3.0 * theta.array()).sin() + 0.1 * (5.0 * theta.array() + 0.2).cos());
  const Eigen::VectorXd fs = f0 * (1.0 + 0.4 * (2.0 * theta.array() + 0.3).cos());
  const JenkinsLoop l = jenkins_loop(kt, w, fs);
  ASSERT_GT(l.slipping_samples, 0);
  ASSERT_LT(l.slipping_samples, q);
  EXPECT_LE(l.periods, 3);
  expect_derivatives_match_central_differences(
      [&](const Eigen::VectorXd& ws, const Eigen::VectorXd& f) { return jenkins_loop(kt, ws, f); }, kt, w, fs,
      1e-7 * a, 1e-7 * f0);
  for (int shift : {1, 17, q / 2}) {
    Eigen::VectorXd ws(q), fss(q);
    for (int i = 0; i < q; ++i) {
      ws(i) = w((i + shift) % q);
      fss(i) = fs((i + shift) % q);
    }
    const JenkinsLoop s = jenkins_loop(kt, ws, fss);
    for (int i = 0; i < q; ++i) EXPECT_NEAR(s.force(i), l.force((i + shift) % q), 1e-12 * kt * a) << shift << " " << i;
    EXPECT_NEAR(s.dissipated_energy, l.dissipated_energy, 1e-12 * f0 * a) << shift;
  }
}

TEST(JenkinsLoop, RefusesBadInputNamingTheArgument) {
  using wbm::testing::expect_throw_with;
  const Eigen::VectorXd w = Eigen::VectorXd::Constant(4, 1e-5), fs = Eigen::VectorXd::Constant(4, 1.0);
  expect_throw_with<std::invalid_argument>([&] { (void)jenkins_loop(0.0, w, fs); },
                                           {"tangential_stiffness (k_t) = 0 must be finite and > 0 [N/m]"});
  expect_throw_with<std::invalid_argument>([&] { (void)jenkins_loop(1e6, Eigen::VectorXd(), Eigen::VectorXd()); },
                                           {"w is empty"});
  expect_throw_with<std::invalid_argument>([&] { (void)jenkins_loop(1e6, w, Eigen::VectorXd::Constant(3, 1.0)); },
                                           {"slip_force has 3 samples, w 4"});
  Eigen::VectorXd negative = fs;
  negative(2) = -1.0;
  expect_throw_with<std::invalid_argument>([&] { (void)jenkins_loop(1e6, w, negative); },
                                           {"slip_force[2] = -1 must be finite and >= 0 [N]"});
  Eigen::VectorXd nan = w;
  nan(1) = std::nan("");
  expect_throw_with<std::invalid_argument>([&] { (void)jenkins_loop(1e6, nan, fs); }, {"w[1] is not finite"});
  expect_throw_with<std::invalid_argument>([&] { (void)jenkins_loop(1e6, w, fs, 1); }, {"max_periods = 1 must be >= 2"});
}

// The projection equation's roots are exactly the discrete Coulomb law Δ ∈ N_[−F, F](λ) — stick
// (|λ| ≤ F, Δ = 0), or slip at the bound in the direction of the slip (λ = ±F, ±Δ > 0) — for any
// compliance c, and its branch derivatives equal central differences off the switching set.
TEST(CoulombProjection, RootsAreTheNormalConeInclusionAndDerivativesMatchDifferences) {
  using wbm::contact::coulomb_projection;
  const double f = 0.3;
  for (double c : {1e-6, 1.0, 1e3}) {
    for (double lambda : {-0.5, -0.3, -0.1, 0.0, 0.2, 0.3, 0.4}) {
      for (double delta : {-1e-3, -1e-9, 0.0, 1e-9, 1e-3}) {
        const bool law = (std::abs(lambda) <= f && delta == 0.0) || (lambda == f && delta > 0.0) ||
                         (lambda == -f && delta < 0.0);
        EXPECT_EQ(coulomb_projection(c * lambda, delta, c * f).value == 0.0, law)
            << "c = " << c << " lambda = " << lambda << " delta = " << delta;
      }
    }
  }
  // Derivatives: stick ∂φ/∂Δ = −1, ∂φ/∂a = 0; slip ∂φ/∂a = 1, ∂φ/∂b = −σ.
  const double h = 1e-8;
  for (const auto& [a, delta] : std::vector<std::pair<double, double>>{{0.1, 0.05}, {0.25, 0.2}, {-0.2, -0.3}}) {
    const double b = 0.3;
    const auto p = coulomb_projection(a, delta, b);
    const double da = (coulomb_projection(a + h, delta, b).value - coulomb_projection(a - h, delta, b).value) / (2 * h);
    const double dd = (coulomb_projection(a, delta + h, b).value - coulomb_projection(a, delta - h, b).value) / (2 * h);
    const double db = (coulomb_projection(a, delta, b + h).value - coulomb_projection(a, delta, b - h).value) / (2 * h);
    EXPECT_NEAR(da, p.stick ? 0.0 : 1.0, 1e-7);
    EXPECT_NEAR(dd, p.stick ? -1.0 : 0.0, 1e-7);
    EXPECT_NEAR(db, p.stick ? 0.0 : -p.sigma, 1e-7);
  }
  EXPECT_TRUE(coulomb_projection(0.1, 0.05, 0.3).stick);
  EXPECT_FALSE(coulomb_projection(0.25, 0.2, 0.3).stick);
}

// CoulombFriction is an exact (multiplier) law that is also hysteretic, has no f(u), and refuses
// a bad μ or N naming the field.
TEST(CoulombFriction, IsAMultiplierLawAndRefusesBadParameters) {
  using wbm::contact::CoulombFriction;
  using wbm::testing::expect_throw_with;
  const CoulombFriction law({0.3, 2.0});
  EXPECT_TRUE(law.rigid());
  EXPECT_TRUE(law.hysteretic());
  EXPECT_DOUBLE_EQ(law.slip_force(), 0.6);
  EXPECT_EQ(law.gap(), 0.0);
  EXPECT_EQ(law.potential(1.0), 0.0);
  EXPECT_THROW((void)law.force(0.0), std::logic_error);
  EXPECT_THROW((void)law.stiffness(0.0), std::logic_error);
  EXPECT_NE(law.describe().find("mu = 0.3, N = 2 N"), std::string::npos) << law.describe();
  expect_throw_with<std::invalid_argument>([] { (void)CoulombFriction({-0.1, 1.0}); },
                                           {"CoulombParameters.friction_coefficient (mu) = -0.1", ">= 0"});
  expect_throw_with<std::invalid_argument>([] { (void)CoulombFriction({0.1, std::nan("")}); },
                                           {"CoulombParameters.normal_load (N) = nan", "finite and >= 0 [N]"});
}

// A counter-surface that slides by (period_shift δ: the next period's samples are w + δ). The
// slow reference is the return map itself, f ← proj_[−F_s, F_s](f + k_t Δw), stepped sample by
// sample over the unrolled sequence w_q + p δ from the unstretched spring until a period repeats:
// the loop agrees with its last period to rounding, stick samples included (a slide of 0.3 of the
// loop's width: the element sticks after each reversal). Under a slide wider than the loop,
// f = sign(δ) F_s at every sample and the period dissipates F_s |δ| (the slider travels δ).
TEST(JenkinsLoop, ASlidingCounterSurfaceCarriesTheSliderAcrossPeriods) {
  const double kt = 2e5, fs = 0.5, a = 1e-5;  // loop width 2 (a − F_s/k_t) = 1.5e-5 m
  const int q = 64;
  const Eigen::VectorXd slip = Eigen::VectorXd::Constant(q, fs);
  // w = a cos θ + δ θ/2π over a period, then the next period's samples w + δ.
  const auto samples = [&](double delta) {
    return Eigen::VectorXd(a * angles(q).array().cos() + delta * angles(q).array() / (2.0 * kPi));
  };
  for (double delta : {4.5e-6, -4.5e-6}) {
    const Eigen::VectorXd w = samples(delta);
    const JenkinsLoop l = jenkins_loop(kt, w, slip, 16, delta);
    EXPECT_GT(l.slipping_samples, 0);
    EXPECT_LT(l.slipping_samples, q);  // it sticks at the reversals
    double f = 0.0, w_prev = 0.0;
    Eigen::VectorXd reference(q);
    for (int period = 0; period < 64; ++period) {
      for (int k = 0; k < q; ++k) {
        const double wk = w(k) + period * delta;
        f = std::clamp(f + kt * (wk - w_prev), -fs, fs);
        w_prev = wk;
        reference(k) = f;
      }
    }
    EXPECT_LT((l.force - reference).cwiseAbs().maxCoeff(), 1e-12 * fs) << "delta = " << delta;
  }
  for (double delta : {-1e-3, 1e-3}) {
    const JenkinsLoop l = jenkins_loop(kt, samples(delta), slip, 8, delta);
    EXPECT_EQ(l.slipping_samples, q);
    EXPECT_LT((l.force.array() - std::copysign(fs, delta)).abs().maxCoeff(), 1e-15) << "delta = " << delta;
    EXPECT_NEAR(l.dissipated_energy, fs * std::abs(delta), 1e-12 * fs * std::abs(delta)) << "delta = " << delta;
  }
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)jenkins_loop(kt, samples(0.0), slip, 8, std::nan("")); }, {"period_shift", "finite"});
}

// A stick/slip pattern names one piece of the piecewise-linear return map (jenkins_loop with a
// pattern). Truths: the return map's own pattern is the map itself; the pieces meet continuously
// (at the amplitude where one sample's margin F_s − |f*| vanishes, its stick and its slip piece
// give the same forces, whatever the rest of the loop); and a piece's derivatives equal central
// differences of that piece's force even where its pattern is not the return map's (its affine
// extension beyond the piece).
TEST(JenkinsLoop, APatternIsAPieceTheReturnMapMeetsContinuously) {
  const double kt = 1e6, fs = 10.0;
  const int q = 64;
  const Eigen::VectorXd theta = angles(q);
  const Eigen::VectorXd shape = theta.array().cos() + 0.2 * (3.0 * theta.array() + 0.4).sin();
  const Eigen::VectorXd slip = Eigen::VectorXd::Constant(q, fs);
  auto pattern_of = [](const JenkinsLoop& l) {
    std::vector<std::uint8_t> p(static_cast<size_t>(l.force.size()));
    for (Eigen::Index i = 0; i < l.force.size(); ++i) p[static_cast<size_t>(i)] = l.stiffness(i) == 0.0 ? 1 : 0;
    return p;
  };
  const double a0 = 3.0 * fs / kt;
  const JenkinsLoop free = jenkins_loop(kt, a0 * shape, slip);
  const std::vector<std::uint8_t> own = pattern_of(free);
  const JenkinsLoop same = jenkins_loop(kt, a0 * shape, slip, 8, 0.0, &own);
  EXPECT_EQ(same.force, free.force);
  for (int i = 0; i < q; ++i) EXPECT_EQ(same.margin(i) >= 0.0, own[static_cast<size_t>(i)] == 0) << i;
  // As the amplitude grows on the piece of a0, the first stick sample whose margin turns negative
  // (the piece's boundary), and bisection on its margin for where it vanishes.
  int switching = -1;
  double hi = a0;
  while (switching < 0 && hi < 100.0 * a0) {
    hi *= 1.05;
    const Eigen::VectorXd m = jenkins_loop(kt, hi * shape, slip, 8, 0.0, &own).margin;
    for (int i = 0; i < q && switching < 0; ++i) {
      if (own[static_cast<size_t>(i)] == 0 && m(i) < 0.0) switching = i;
    }
  }
  ASSERT_GE(switching, 0);
  double lo = hi / 1.05;
  auto margin_at = [&](double a) { return jenkins_loop(kt, a * shape, slip, 8, 0.0, &own).margin(switching); };
  ASSERT_GT(margin_at(lo), 0.0);
  ASSERT_LT(margin_at(hi), 0.0);
  for (int k = 0; k < 200 && hi - lo > 1e-15 * a0; ++k) (margin_at(0.5 * (lo + hi)) > 0.0 ? lo : hi) = 0.5 * (lo + hi);
  std::vector<std::uint8_t> flipped = own;
  flipped[static_cast<size_t>(switching)] = 1;
  const JenkinsLoop stick = jenkins_loop(kt, lo * shape, slip, 8, 0.0, &own);
  const JenkinsLoop slipping = jenkins_loop(kt, lo * shape, slip, 8, 0.0, &flipped);
  EXPECT_LT((stick.force - slipping.force).cwiseAbs().maxCoeff(), 1e-9 * fs);
  EXPECT_EQ(slipping.stiffness(switching), 0.0);
  // Beyond the piece (amplitude 2 a0 on the pattern of a0, where the return map would slip
  // elsewhere): the piece's derivatives against central differences of the piece.
  const Eigen::VectorXd w = 2.0 * a0 * shape;
  ASSERT_NE(pattern_of(jenkins_loop(kt, w, slip)), own);
  expect_derivatives_match_central_differences(
      [&](const Eigen::VectorXd& ws, const Eigen::VectorXd& f) { return jenkins_loop(kt, ws, f, 8, 0.0, &own); }, kt,
      w, slip, 1e-7 * a0, 1e-7 * fs);
  const std::vector<std::uint8_t> short_pattern(3, 0);
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)jenkins_loop(kt, w, slip, 8, 0.0, &short_pattern); }, {"pattern has 3 entries, w 64 samples"});
}
