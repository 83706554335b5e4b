// FloquetAnalysis's modal path (issue #39, item 2): the monodromy stepping in the undamped modes'
// coordinates, set up once per branch. Truths: each mode's 2 × 2 transition matrix in closed form
// from its characteristic roots (long double, another formula than the path's cos/cosh one), and
// floquet_multipliers, the balanced dense path that never uses modes, as the slow reference
// (the same scheme in other coordinates: the same multipliers and Φ up to rounding).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>
#include <unsupported/Eigen/MatrixFunctions>

#include <wbm/contact/penalty.hpp>
#include <wbm/contact/signorini.hpp>
#include <wbm/fem/rod.hpp>
#include <wbm/solvers/floquet.hpp>
#include <wbm/solvers/mechanical_system.hpp>

#include "shipped_scenes.hpp"
#include "testing.hpp"

namespace {

using namespace wbm;
using solvers::FloquetAnalysis;
using solvers::FloquetPath;

// The unit rod of NLvib (E = ρ = A = L = 1, clamped at x = 0) with 1 % modal damping.
solvers::MechanicalSystem nlvib_rod(int elements) {
  fem::RodParameters p;
  p.young_modulus = p.density = p.area = p.length = 1.0;
  p.elements = elements;
  auto s = solvers::beta_damped(fem::Rod(p), 0.0);
  s.damping = solvers::modal_damping(s, 0.01);
  return s;
}

// A prescribed contact displacement u_c(τ_p) = g + a cos 2πτ_p + b sin 6πτ_p (n_c = rows): any
// periodic samples define the linearized system, so no solve is needed to compare two paths.
Eigen::MatrixXd orbit(int contacts, int samples, double gap, double amplitude) {
  Eigen::MatrixXd u(contacts, samples);
  for (int c = 0; c < contacts; ++c) {
    for (int p = 0; p < samples; ++p) {
      const double tau = static_cast<double>(p) / samples;
      u(c, p) = gap + amplitude * (std::cos(2.0 * M_PI * (tau + 0.1 * c)) + 0.3 * std::sin(6.0 * M_PI * tau));
    }
  }
  return u;
}

// Both paths' stepping on one orbit: the same multipliers (sorted by modulus; matched to the nearest, as a
// complex pair's order is arbitrary), error estimates and monodromy matrix.
void expect_paths_agree(const solvers::MechanicalSystem& system, const std::vector<solvers::ContactPoint>& contacts,
                        const Eigen::MatrixXd& u, double hz, double tolerance) {
  // The stepping on both paths (exact_flights off: linear stops would take the exact flights).
  const FloquetAnalysis modal(system, contacts, {.path = FloquetPath::Modal, .exact_flights = false});
  ASSERT_TRUE(modal.modal());
  const auto fast = modal(u, hz);
  const auto slow = solvers::floquet_multipliers(system, contacts, u, hz);
  ASSERT_EQ(fast.multipliers.size(), slow.multipliers.size());
  EXPECT_NEAR(fast.max_modulus, slow.max_modulus, tolerance * std::max(1.0, slow.max_modulus));
  for (Eigen::Index i = 0; i < slow.multipliers.size(); ++i) {
    double nearest = 1e300;
    for (Eigen::Index j = 0; j < fast.multipliers.size(); ++j) {
      nearest = std::min(nearest, std::abs(fast.multipliers(j) - slow.multipliers(i)));
    }
    EXPECT_LT(nearest, tolerance * std::max(1.0, std::abs(slow.multipliers(i))))
        << "multiplier " << slow.multipliers(i);
  }
  // The estimates are first-order perturbations of an O(h²) difference: equal to a few digits.
  EXPECT_NEAR(fast.multiplier_errors.maxCoeff(), slow.multiplier_errors.maxCoeff(),
              1e-3 * slow.multiplier_errors.maxCoeff() + tolerance);
  EXPECT_LT((fast.monodromy - slow.monodromy).norm(), tolerance * slow.monodromy.norm());
  EXPECT_EQ(fast.steps, slow.steps);
}

// Without contact Φ = e^{A₀T}: each mode's transition matrix from its roots s_{1,2} = −ζω ± ω√(ζ² − 1),
// overdamped modes included (C = βK on the JL14 rod: ζ > 1 above 40 kHz, where the path takes
// cosh and its overflow-free branch), Φ = S blockdiag(Φ_i) S⁻¹. The balanced path reaches 1e-9
// here (test_continuation.cpp); one exact flight per period is ~1e-13.
TEST(FloquetModal, LinearRodMonodromyIsTheModalTransitionMatrixToRounding) {
  const auto s = models::load_scene("jl14_case2");
  const auto sys = s.system();
  const Eigen::Index n = sys.dofs();
  const double f = 1275.0;
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(Eigen::MatrixXd(sys.stiffness),
                                                                      Eigen::MatrixXd(sys.mass));
  const Eigen::MatrixXd psi = eig.eigenvectors(), psi_inv = psi.transpose() * Eigen::MatrixXd(sys.mass);
  std::array<Eigen::VectorXd, 4> modal;  // entries (1,1), (1,2), (2,1), (2,2) per mode
  for (auto& v : modal) v.resize(n);
  using C = std::complex<long double>;
  for (Eigen::Index i = 0; i < n; ++i) {
    const long double w = std::sqrt(static_cast<long double>(eig.eigenvalues()(i))), zeta = 0.5L * s.damping.beta * w;
    const C root = std::sqrt(C(zeta * zeta - 1.0L)), s1 = -zeta * w + w * root, s2 = -zeta * w - w * root;
    const C e1 = std::exp(s1 / static_cast<long double>(f)), e2 = std::exp(s2 / static_cast<long double>(f));
    const C d = s1 - s2;
    modal[0](i) = static_cast<double>(std::real((s1 * e2 - s2 * e1) / d));
    modal[1](i) = static_cast<double>(std::real((e1 - e2) / d));
    modal[2](i) = static_cast<double>(std::real(s1 * s2 * (e2 - e1) / d));
    modal[3](i) = static_cast<double>(std::real((s1 * e1 - s2 * e2) / d));
  }
  const FloquetAnalysis floquet(sys, {});
  ASSERT_TRUE(floquet.modal());  // C = βK: Rayleigh
  for (const int steps : {64, 8192}) {
    const auto result = floquet(Eigen::MatrixXd(0, steps), f);
    for (int b = 0; b < 4; ++b) {
      const Eigen::MatrixXd expected = psi * modal[static_cast<size_t>(b)].asDiagonal() * psi_inv;
      const Eigen::MatrixXd got = result.monodromy.block((b / 2) * n, (b % 2) * n, n, n);
      EXPECT_LT((got - expected).norm(), 1e-12 * expected.norm()) << "P = " << steps << ", block " << b;
    }
    EXPECT_TRUE(result.stable());
  }
}

// The JL14 rod against its exponential stop (Case 2's law), an orbit crossing the gap twice per
// period: contact runs, crossing splits and the overdamped modes together.
TEST(FloquetModal, RodWithAnExponentialStopAgreesWithTheBalancedPath) {
  const auto s = models::load_scene("jl14_case2");
  const auto contacts = s.contact_points();
  const double gap = contacts.front().law->gap();
  for (const int samples : {64, 256}) {
    expect_paths_agree(s.system(), contacts, orbit(1, samples, gap, 0.5 * gap), 1300.0, 1e-8);
  }
}

// NLvib's rod with 1 % modal damping (classical, not Rayleigh: each mode's (Φᵀ C Φ)_ii) and its
// linear stop of 10 EA/L, and two stops on the same rod (n_c = 2, different phases).
TEST(FloquetModal, ModallyDampedRodWithLinearStopsAgreesWithTheBalancedPath) {
  const auto rod = nlvib_rod(20);
  const auto law = std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{10.0, 0.1});
  expect_paths_agree(rod, {{19, law}}, orbit(1, 256, 0.1, 0.15), 0.3, 1e-9);
  expect_paths_agree(rod, {{19, law}, {9, law}}, orbit(2, 128, 0.1, 0.15), 0.3, 1e-9);
}

// A free-free pair of masses with a stop between them (a relative contact): the rigid-body mode
// (ω = 0, flight [[1, t], [0, 1]]) gives a double multiplier 1 with one eigenvector (a Jordan
// block: translation and drift). Its computed value moves by √eps under rounding in Φ: 9e-8 on
// the balanced path; the modal path keeps the mode uncoupled and exact. The other multipliers and Φ
// agree.
TEST(FloquetModal, FreeFreeBodiesWithARelativeStopKeepTheRigidBodyMultiplierExact) {
  solvers::MechanicalSystem s;
  const Eigen::Matrix2d m{{2.0, 0.0}, {0.0, 1.0}}, k{{1e4, -1e4}, {-1e4, 1e4}};
  s.mass = m.sparseView();
  s.stiffness = k.sparseView();
  s.damping = (1e-3 * k).sparseView();
  const auto law = std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{5e4, 1e-3});
  const std::vector<solvers::ContactPoint> between = {{1, law, 0}};
  const Eigen::MatrixXd u = orbit(1, 128, 1e-3, 2e-3);
  const FloquetAnalysis modal(s, between);
  ASSERT_TRUE(modal.modal());
  const auto fast = modal(u, 20.0);
  const auto slow = solvers::floquet_multipliers(s, between, u, 20.0);
  EXPECT_LT((fast.monodromy - slow.monodromy).norm(), 1e-9 * slow.monodromy.norm());
  int at_one = 0;
  for (Eigen::Index i = 0; i < fast.multipliers.size(); ++i) {
    if (std::abs(fast.multipliers(i) - 1.0) < 1e-12) {
      ++at_one;
      continue;
    }
    double nearest = 1e300;
    for (Eigen::Index j = 0; j < slow.multipliers.size(); ++j) {
      nearest = std::min(nearest, std::abs(slow.multipliers(j) - fast.multipliers(i)));
    }
    EXPECT_LT(nearest, 1e-9) << fast.multipliers(i);
  }
  EXPECT_EQ(at_one, 2);
  for (Eigen::Index i = 0; i < slow.multipliers.size(); ++i) {
    if (std::abs(slow.multipliers(i) - 1.0) < 1e-3) {
      EXPECT_LT(std::abs(slow.multipliers(i) - 1.0), 1e-6);
    }
  }
}

// A damper on one DOF of a chain is not classical (C M⁻¹ K ≠ K M⁻¹ C): Automatic takes the
// balanced path (the same bits as floquet_multipliers), Modal is refused with the way out.
TEST(FloquetModal, NonClassicalDampingTakesTheBalancedPathOrIsRefused) {
  solvers::MechanicalSystem s;
  const Eigen::Matrix3d m = Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d k{{2e4, -1e4, 0.0}, {-1e4, 2e4, -1e4}, {0.0, -1e4, 1e4}};
  Eigen::Matrix3d c = Eigen::Matrix3d::Zero();
  c(2, 2) = 3.0;
  s.mass = m.sparseView();
  s.stiffness = k.sparseView();
  s.damping = c.sparseView();
  const auto law = std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{1e5, 1e-3});
  const std::vector<solvers::ContactPoint> stop = {{2, law}};
  const FloquetAnalysis automatic(s, stop);
  EXPECT_FALSE(automatic.modal());
  const Eigen::MatrixXd u = orbit(1, 64, 1e-3, 2e-3);
  const auto a = automatic(u, 15.0), b = solvers::floquet_multipliers(s, stop, u, 15.0);
  EXPECT_EQ(a.multipliers, b.multipliers);
  EXPECT_EQ(a.monodromy, b.monodromy);
  try {
    (void)FloquetAnalysis(s, stop, {.path = FloquetPath::Modal});
    ADD_FAILURE() << "a non-classical C was accepted on the modal path";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("FloquetPath::Automatic"), std::string::npos) << e.what();
  }
  // With C = 2e-4 K the same chain is Rayleigh, hence modal.
  s.damping = (2e-4 * k).sparseView();
  EXPECT_TRUE(FloquetAnalysis(s, stop).modal());
}

// The same refusals as floquet_multipliers, at construction or per point.
TEST(FloquetModal, RefusesWhatFloquetMultipliersRefuses) {
  const auto rod = nlvib_rod(4);
  const auto law = std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{10.0, 0.1});
  const FloquetAnalysis floquet(rod, {{3, law}});
  ASSERT_TRUE(floquet.modal());
  EXPECT_THROW((void)floquet(orbit(1, 4, 0.1, 0.1), 0.3), std::invalid_argument);   // P < 8
  EXPECT_THROW((void)floquet(orbit(2, 64, 0.1, 0.1), 0.3), std::invalid_argument);  // a row per contact
  EXPECT_THROW((void)floquet(orbit(1, 64, 0.1, 0.1), 0.0), std::invalid_argument);  // f > 0
  Eigen::MatrixXd bad = orbit(1, 64, 0.1, 0.1);
  bad(0, 3) = std::nan("");
  EXPECT_THROW((void)floquet(bad, 0.3), std::invalid_argument);
  EXPECT_THROW((void)FloquetAnalysis(rod, {{3, std::make_shared<contact::RigidStop>(0.1)}}), std::invalid_argument);
}

}  // namespace

namespace {

// Above FloquetOptions::dense_states the modal path computes the multipliers of largest modulus
// by Arnoldi on products Φ v: against every multiplier of the formed Φ (the dense modal path),
// on NLvib's rod with two stops. The ones it returns are the largest, down to one below 0.9, and
// each agrees with the dense one to Arnoldi's tolerance; the error estimates are Richardson's too.
TEST(FloquetModal, ArnoldiFindsTheDominantMultipliersOfTheFormedMonodromy) {
  const auto rod = nlvib_rod(40);  // 80 states
  const auto law = std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{10.0, 0.1});
  const std::vector<solvers::ContactPoint> stops = {{39, law}, {19, law}};
  const Eigen::MatrixXd u = orbit(2, 256, 0.1, 0.15);
  for (const double hz : {0.3, 3.0}) {  // at 3 Hz twenty multipliers lie above 0.9: nev doubles
    const auto dense = FloquetAnalysis(rod, stops, {.dense_states = 1000})(u, hz);
    const auto arnoldi = FloquetAnalysis(rod, stops, {.monodromy = false, .dense_states = 0})(u, hz);
    ASSERT_FALSE(dense.dominant_only);
    ASSERT_TRUE(arnoldi.dominant_only);
    EXPECT_EQ(arnoldi.monodromy.size(), 0);
    const Eigen::Index found = arnoldi.multipliers.size();
    ASSERT_GE(found, 8);
    if (hz > 1.0) {
      EXPECT_GT(found, 8) << "nev did not double";
    }
    ASSERT_LT(found, dense.multipliers.size());
    EXPECT_LT(std::abs(arnoldi.multipliers(found - 1)), 0.9);
    // Every dense multiplier above the smallest found is found, in the same order of modulus.
    for (Eigen::Index i = 0; i < found; ++i) {
      EXPECT_NEAR(std::abs(arnoldi.multipliers(i)), std::abs(dense.multipliers(i)), 1e-9) << hz << " Hz, " << i;
      double nearest = 1e300;
      for (Eigen::Index j = 0; j < found; ++j) {
        nearest = std::min(nearest, std::abs(arnoldi.multipliers(j) - dense.multipliers(i)));
      }
      EXPECT_LT(nearest, 1e-9) << hz << " Hz, " << dense.multipliers(i);
    }
    EXPECT_GE(std::abs(arnoldi.multipliers(found - 1)), std::abs(dense.multipliers(found)) - 1e-9);
    EXPECT_NEAR(arnoldi.max_modulus, dense.max_modulus, 1e-9);
    EXPECT_EQ(arnoldi.stable(), dense.stable());
    // Richardson per multiplier against the eigenvector-mapped estimate: the same size (both
    // estimate |μ_P − μ|, first-order), within a factor of 3 for the largest.
    EXPECT_GT(arnoldi.multiplier_errors(0), dense.multiplier_errors(0) / 3.0);
    EXPECT_LT(arnoldi.multiplier_errors(0), dense.multiplier_errors(0) * 3.0);
  }
}

// When more than 2n − 2 multipliers lie above 0.9 (an undamped structure) Arnoldi cannot stop
// below it: the path forms Φ instead, and says so (dominant_only false, every multiplier).
TEST(FloquetModal, AnUndampedStructureFallsBackToTheFormedMonodromy) {
  auto rod = nlvib_rod(10);
  rod.damping = solvers::modal_damping(rod, 0.0);
  const auto law = std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{10.0, 0.1});
  const auto result = FloquetAnalysis(rod, {{9, law}}, {.dense_states = 0})(orbit(1, 128, 0.1, 0.15), 0.3);
  EXPECT_FALSE(result.dominant_only);
  EXPECT_EQ(result.multipliers.size(), 20);
  EXPECT_EQ(result.monodromy.rows(), 20);
}

}  // namespace

namespace {

// A 1-DOF oscillator: mass m [kg], damping c [N·s/m], stiffness k [N/m].
solvers::MechanicalSystem oscillator(double m, double c, double k) {
  solvers::MechanicalSystem s;
  const Eigen::Matrix<double, 1, 1> one{1.0};
  s.mass = (m * one).sparseView();
  s.stiffness = (k * one).sparseView();
  s.damping = (c * one).sparseView();
  return s;
}

// The exact monodromy of a 1-DOF oscillator (m, c, k) against a linear stop k_c on an orbit in
// contact for |τ| < τ₁ (symmetric about τ = 0): Φ = F_c(τ₁T) F_f((1 − 2τ₁)T) F_c(τ₁T), each
// flight of [[0, 1], [−κ/m, −c/m]] from the closed form e^{−ct/2m}(cos νt I + sin νt/ν (A + c/2m I))
// in long double (Eigen's Padé exponential is off by 1.7e-7 at the stop of the next test: 125 rad
// of its vibration per contact phase take many squarings). Its spectral radius.
double piecewise_linear_radius(double m, double c, double k, double kc, double period, double tau1) {
  using L = long double;
  using F = std::array<L, 4>;  // (1,1), (1,2), (2,1), (2,2)
  auto flight = [&](L stiffness, L t) {
    const L d = c / static_cast<L>(m), w2 = stiffness / m, nu = std::sqrt(w2 - d * d / 4.0L);
    const L e = std::exp(-d * t / 2.0L), ch = std::cos(nu * t), sh = std::sin(nu * t) / nu;
    return F{e * (ch + d / 2.0L * sh), e * sh, -e * w2 * sh, e * (ch - d / 2.0L * sh)};
  };
  auto times = [](const F& x, const F& y) {
    return F{x[0] * y[0] + x[1] * y[2], x[0] * y[1] + x[1] * y[3], x[2] * y[0] + x[3] * y[2], x[2] * y[1] + x[3] * y[3]};
  };
  const F contact = flight(static_cast<L>(k) + kc, static_cast<L>(tau1) * period);
  const F phi = times(contact, times(flight(k, (1.0L - 2.0L * tau1) * period), contact));
  const L half_trace = (phi[0] + phi[3]) / 2.0L, det = phi[0] * phi[3] - phi[1] * phi[2];
  const L disc = half_trace * half_trace - det;
  if (disc < 0.0L) return static_cast<double>(std::sqrt(det));
  return static_cast<double>(std::max(std::abs(half_trace + std::sqrt(disc)), std::abs(half_trace - std::sqrt(disc))));
}

// A stop 10⁴ times stiffer than its spring (m = 1 kg, k = 4e4 N/m, c = 5 N·s/m, k_c = 4e8 N/m at
// g0 = 2 mm; ω_c = 2e4 rad/s) on the orbit u = g0 + 1 mm cos 2πτ at 40 Hz, given at P = 64 samples:
// h ω_c = 7.8, where the kick scheme is unstable. The stepping refines the samples (by 16, to
// h ω_c = 0.49) and its spectral radius agrees with the exact piecewise-linear monodromy (in
// contact for |τ| < 1/4, by the orbit's symmetry) within twice its own error estimate, on both
// paths. The exact flights (the default for linear stops) take the 64 samples as they are and give
// the closed form to rounding: the crossings sit at samples here.
TEST(FloquetModal, AStiffStopIsResolvedByRefinedSamplesOnBothPaths) {
  const double m = 1.0, k = 4e4, c = 5.0, kc = 4e8, g0 = 2e-3, hz = 40.0;
  const solvers::MechanicalSystem s = oscillator(m, c, k);
  const auto law = std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{kc, g0});
  const std::vector<solvers::ContactPoint> stop = {{0, law}};
  auto samples = [&](int count) {
    Eigen::MatrixXd u(1, count);
    for (int p = 0; p < count; ++p) u(0, p) = g0 + 1e-3 * std::cos(2.0 * M_PI * p / count);
    return u;
  };
  const double radius = piecewise_linear_radius(m, c, k, kc, 1.0 / hz, 0.25);
  const FloquetAnalysis stepping(s, stop, {.exact_flights = false}), exact(s, stop);
  ASSERT_TRUE(stepping.modal());
  // 125 rad of the stop's vibration per contact phase: at h ω_c = 0.49 the phase error is large,
  // and the estimate says so; at 4 times the steps it is below 2 %.
  for (const int count : {64, 4096}) {
    const Eigen::MatrixXd u = samples(count);
    for (const auto& result : {stepping(u, hz), solvers::floquet_multipliers(s, stop, u, hz)}) {
      EXPECT_EQ(result.steps, std::max(count, 1024));
      EXPECT_LE(std::abs(result.max_modulus - radius), 2.0 * result.multiplier_errors.maxCoeff())
          << result.max_modulus << " against the exact " << radius << " at P = " << count;
      if (count == 4096) {
        EXPECT_LT(std::abs(result.max_modulus - radius), 0.02 * radius) << result.max_modulus << " against " << radius;
      }
    }
    const auto flights = exact(u, hz);
    EXPECT_EQ(flights.steps, count);
    EXPECT_EQ(exact.resolved_steps(u, hz), count);
    EXPECT_LT(std::abs(flights.max_modulus - radius), 1e-9 * radius) << flights.max_modulus << " against " << radius;
  }
}

// The exact flights where the crossings fall between the samples: u = g0 + a (cos 2πτ − 0.3), in
// contact for |τ| < τ₁ = acos(0.3)/2π, on the stiff stop above. The crossings are located on the
// cubic through the four nearest samples, so the spectral radius converges at fourth order in
// 1/P to the closed form, and the error estimate (Richardson's second-order one) bounds the error.
TEST(FloquetModal, ExactFlightsConvergeAtFourthOrderWhereCrossingsFallBetweenSamples) {
  const double m = 1.0, k = 4e4, c = 5.0, kc = 4e8, g0 = 2e-3, hz = 40.0;
  const solvers::MechanicalSystem s = oscillator(m, c, k);
  const auto law = std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{kc, g0});
  const FloquetAnalysis exact(s, {{0, law}});
  const double radius = piecewise_linear_radius(m, c, k, kc, 1.0 / hz, std::acos(0.3) / (2.0 * M_PI));
  std::vector<double> h, err;
  for (const int count : {64, 128, 256, 512}) {
    Eigen::MatrixXd u(1, count);
    for (int p = 0; p < count; ++p) u(0, p) = g0 + 1e-3 * (std::cos(2.0 * M_PI * p / count) - 0.3);
    const auto result = exact(u, hz);
    ASSERT_EQ(result.steps, count);
    const double e = std::abs(result.max_modulus - radius);
    std::printf("P = %d: |mu| %.12f, exact %.12f, error %.2e, estimate %.2e\n", count, result.max_modulus, radius, e,
                result.multiplier_errors.maxCoeff());
    EXPECT_LE(e, 2.0 * result.multiplier_errors.maxCoeff() + 1e-12) << "P = " << count;
    h.push_back(1.0 / count);
    err.push_back(e);
  }
  EXPECT_NEAR(wbm::testing::observed_order(h, err), 4.0, 0.5);
  EXPECT_LT(err.back(), 1e-6 * radius);
}

// A stop that would need more than kMaxResolvedSteps steps of the stepping (k_c = 4e14 N/m:
// h ω_c = 7.8e3 at P = 64) is refused there, with the stiffness named and the way out, rather than
// answered wrong. (The exact flights, the default for linear stops, need no steps: the closed
// forms of the two tests above.)
TEST(FloquetModal, AStopTooStiffToResolveIsRefusedWithTheWayOut) {
  solvers::MechanicalSystem s;
  const Eigen::Matrix<double, 1, 1> one{1.0};
  s.mass = one.sparseView();
  s.stiffness = (4e4 * one).sparseView();
  s.damping = (5.0 * one).sparseView();
  const auto law = std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{4e14, 2e-3});
  const Eigen::MatrixXd u = orbit(1, 64, 2e-3, 1e-3);
  for (const bool modal : {true, false}) {
    try {
      if (modal) {
        (void)FloquetAnalysis(s, {{0, law}}, {.exact_flights = false})(u, 40.0);
      } else {
        (void)solvers::floquet_multipliers(s, {{0, law}}, u, 40.0);
      }
      ADD_FAILURE() << "an unresolved stop was answered";
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("lower the penalty stiffness"), std::string::npos) << what;
      EXPECT_NE(what.find("k = 4"), std::string::npos) << what;
    }
  }
}

}  // namespace
