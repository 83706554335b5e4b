// The weighted residual with a Jenkins element on two tangents (ContactPoint::second_tangent,
// contact::JenkinsDiscLaw). Truths not produced by this code:
//   - the closed-form steady state of an isotropic point mass on a plane under a rotating force:
//     the orbit is a circle of radius a, the friction force turns with it at |f| = F_s, and
//     (k − m ω² + i ω c + k_t iβ/(1 + iβ)) A = F, β = F_s/(k_t r_s), r_s = √(a² − (F_s/k_t)²), a
//     scalar equation in a solved here by bisection;
//   - central differences of the residual, for Fourier:Fourier and two wavelet pairs, with the
//     normal load of a penalty spring;
//   - the explicit central-difference time stepping under that varying normal load;
//   - the validation of the pair, by name.
#include <cmath>
#include <complex>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <wbm/contact/jenkins_disc.hpp>
#include <wbm/contact/penalty.hpp>
#include <wbm/solvers/mechanical_system.hpp>
#include <wbm/solvers/post_processing.hpp>
#include <wbm/solvers/time_basis.hpp>
#include <wbm/solvers/time_integration.hpp>
#include <wbm/solvers/weighted_residual.hpp>

#include "testing.hpp"

namespace solvers = wbm::solvers;
namespace contact = wbm::contact;
using solvers::TimeBasis;

namespace {

using wbm::testing::kPi;

// A point mass m = 1 kg on springs k = (2π 10 Hz)² in x and y (DOFs 0, 1), 2 % damping, a Jenkins
// disc k_t = 2k, μ N = 0.3 · 1 N at the mass, and the rotating force F (cos ωt, sin ωt) at 9 Hz.
// With `normal`, DOF 2 (z, the same spring) is pressed by a penalty spring k_n = 5k with a
// static normal force of 1 N (the overlap n0 (1/k_n + 1/k) at rest, shared by the two springs in
// series), and the slip force follows it.
struct DiscOscillator {
  double m = 1.0, k = std::pow(2.0 * kPi * 10.0, 2), zeta = 0.02, kt = 2.0 * k, mu = 0.3, n0 = 1.0, force = 2.0;
  double f = 9.0;

  [[nodiscard]] solvers::MechanicalSystem system(int dofs) const {
    solvers::MechanicalSystem s;
    s.mass.resize(dofs, dofs);
    s.stiffness.resize(dofs, dofs);
    s.damping.resize(dofs, dofs);
    for (int i = 0; i < dofs; ++i) {
      s.mass.insert(i, i) = m;
      s.stiffness.insert(i, i) = k;
      s.damping.insert(i, i) = 2.0 * zeta * std::sqrt(k * m);
    }
    return s;
  }
  // F cos ωt on x and F cos(ωt − π/2) = F sin ωt on y; with normal, 0.5 N at 9 Hz on z too.
  [[nodiscard]] solvers::HarmonicForcing forcing(bool normal) const {
    solvers::HarmonicForcing h{0, force, f, {{1, force, -kPi / 2.0}}};
    if (normal) h.more.push_back({2, 0.5});
    return h;
  }
  // Contacts 0 and 1: the disc on x and y; with normal, contact 2 the normal spring on z.
  [[nodiscard]] std::vector<solvers::ContactPoint> contacts(bool normal) const {
    const auto law = std::make_shared<contact::JenkinsDiscLaw>(contact::JenkinsParameters{kt, mu, normal ? 0.0 : n0});
    std::vector<solvers::ContactPoint> c{{0, law}, {1, law}};
    c[0].second_tangent = 1;
    c[1].second_tangent = 0;
    if (normal) {
      c.push_back({2, std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{5.0 * k, -n0 * (1.0 / (5.0 * k) + 1.0 / k)})});
      c[0].normal = c[1].normal = 2;
    }
    return c;
  }
  // The closed-form orbit radius a [m]: a |D(a)| = F by bisection over the slipping radii.
  [[nodiscard]] double closed_form_radius() const {
    const double fs = mu * n0, w = 2.0 * kPi * f, c = 2.0 * zeta * std::sqrt(k * m);
    const auto residual = [&](double a) {
      const double rs = std::sqrt(a * a - (fs / kt) * (fs / kt)), beta = fs / (kt * rs);
      const std::complex<double> i(0.0, 1.0);
      const std::complex<double> d = k - m * w * w + i * w * c + kt * i * beta / (1.0 + i * beta);
      return a * std::abs(d) - force;
    };
    double lo = fs / kt * (1.0 + 1e-12), hi = 1.0;
    EXPECT_LT(residual(lo), 0.0);  // the force exceeds what full stick at the threshold needs
    EXPECT_GT(residual(hi), 0.0);
    for (int it = 0; it < 200; ++it) {
      const double mid = 0.5 * (lo + hi);
      (residual(mid) < 0.0 ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
  }
};

}  // namespace

// The rotating steady state: every sample of the computed orbit lies on the closed-form circle,
// to first order in 1/Q (the return map's own order on a curved slip path, test_jenkins_disc).
TEST(FrictionDisc, TheRotatingSteadyStateIsTheClosedFormCircle) {
  const DiscOscillator d;
  const double a = d.closed_form_radius();
  ASSERT_GT(a, 2.0 * d.mu * d.n0 / d.kt);  // well into slip
  const TimeBasis basis = TimeBasis::from_name("fourier", 8);
  std::vector<double> errors;
  for (int q : {512, 2048}) {
    const solvers::WeightedResidual w(d.system(2), d.forcing(false), d.contacts(false), basis, basis,
                                      {.time_samples = q});
    const auto sol = w.solve();
    ASSERT_TRUE(sol.converged()) << "Q = " << q << ": " << sol.brief();
    const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(64, 0.0, 63.0 / 64.0);
    const Eigen::MatrixXd u = sol.coefficients * basis.values(tau, 0).transpose();  // 2 × 64
    const Eigen::VectorXd radius = u.colwise().norm().transpose();
    errors.push_back((radius.array() - a).abs().maxCoeff() / a);
    std::printf("Q = %d: radius %.9g .. %.9g m against %.9g m (relative %.3e)\n", q, radius.minCoeff(),
                radius.maxCoeff(), a, errors.back());
  }
  EXPECT_LT(errors[0], 1.5e-3);
  EXPECT_NEAR(errors[0] / errors[1], 4.0, 0.6);  // first order in 1/Q
}

// The Jacobian of the weighted residual (the dense sample blocks of both tangents and of the
// normal spring) against central differences of its residual, at a state with stick and slip.
TEST(FrictionDisc, JacobianMatchesCentralDifferences) {
  const DiscOscillator d;
  for (const std::string pair : {"fourier", "db6", "bspline"}) {
    const int dimension = 16;
    const TimeBasis basis = TimeBasis::from_name(pair, dimension);
    const solvers::WeightedResidual w(d.system(3), d.forcing(true), d.contacts(true), basis, basis, {.time_samples = 64});
    const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(dimension, 0.0, (dimension - 1.0) / dimension);
    const Eigen::MatrixXd v = basis.values(tau, 0);
    const auto fit = [&](const Eigen::VectorXd& samples) -> Eigen::VectorXd { return v.colPivHouseholderQr().solve(samples); };
    const Eigen::ArrayXd t = 2.0 * kPi * tau.array();
    // An ellipse of 3 mm × 1 mm (k_t × 3 mm ≫ μ N: slips) and z ≈ 1e-5 sin: N = 6 ± 0.2 N (about
    // z = 0, not the rest position).
    const Eigen::VectorXd ax = fit(3e-3 * t.cos()), ay = fit(1e-3 * t.sin() + 2e-4 * (2.0 * t).cos()),
                          az = fit(1e-5 * t.sin());
    Eigen::VectorXd a(3 * dimension);
    for (int k = 0; k < dimension; ++k) a.segment<3>(3 * k) << ax(k), ay(k), az(k);
    const Eigen::MatrixXd j = w.jacobian(a);
    const double h = 1e-7 * a.cwiseAbs().maxCoeff();
    double worst = 0.0;
    for (int col = 0; col < 3 * dimension; ++col) {
      Eigen::VectorXd ap = a, am = a;
      ap(col) += h;
      am(col) -= h;
      const Eigen::VectorXd fd = (w.residual(ap) - w.residual(am)) / (2.0 * h);
      worst = std::max(worst, (fd - j.col(col)).cwiseAbs().maxCoeff());
    }
    EXPECT_LT(worst, 1e-6 * j.cwiseAbs().maxCoeff()) << pair;
    // The tangents couple: ∂R_x/∂a_y is not the frictionless zero.
    EXPECT_GT(std::abs(j(0, 1)) + std::abs(j(3, 4)), 0.0) << pair;
  }
}

// Under a varying normal load (the normal spring on z, N = 1 ± 0.48 N) against the explicit
// time-stepping reference, which steps both tangents' forces by the disc's projection with no
// basis, no sample grid and no period loop: the error falls at first order in 1/Q, the return
// map's order on a curved slip path.
TEST(FrictionDisc, UnderAVaryingNormalLoadItConvergesToTheTimeSteppingReference) {
  const DiscOscillator d;
  const auto ref = solvers::integrate_central_difference_to_periodic(
      d.system(3), d.forcing(true), d.contacts(true),
      {.steps_per_period = 16384, .samples_per_period = 512, .periodicity_tolerance = 1e-10});
  ASSERT_TRUE(ref.report.converged()) << ref.report.message;
  const double n_min = ref.contact_force.row(2).minCoeff(), n_max = ref.contact_force.row(2).maxCoeff();
  EXPECT_GT(n_max - n_min, 0.5 * d.n0);  // the normal load varies
  EXPECT_GT(n_min, 0.0);                 // and the contact stays closed
  const TimeBasis basis = TimeBasis::from_name("fourier", 16);
  std::vector<double> errors;
  for (int q : {256, 1024}) {
    const solvers::WeightedResidual w(d.system(3), d.forcing(true), d.contacts(true), basis, basis, {.time_samples = q});
    const auto sol = w.solve();
    ASSERT_TRUE(sol.converged()) << "Q = " << q << ": " << sol.brief();
    const Eigen::MatrixXd u = sol.coefficients * basis.values(ref.tau, 0).transpose();
    double e = 0.0;
    for (int dof : {0, 1}) {
      e = std::max(e, solvers::rms_relative_error(u.row(dof).transpose(), ref.displacement.row(dof).transpose()));
    }
    errors.push_back(e);
    std::printf("Q = %d: x, y within %.3e of the time stepping (N %.3f .. %.3f N)\n", q, e, n_min, n_max);
  }
  EXPECT_LT(errors[1], 1e-3);
  EXPECT_GT(errors[0] / errors[1], 3.0);
}

// A pair that is not one element, by name.
TEST(FrictionDisc, BadPairsAreRefusedByName) {
  const DiscOscillator d;
  auto c = d.contacts(false);
  c[1].second_tangent = -1;
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { solvers::ContactPoint::validate(c, 2); },
                                                         {"contact 1 names -1", "name each other"});
  c.pop_back();
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { solvers::ContactPoint::validate(c, 2); },
                                                         {"second_tangent = 1 (contact 0", "another contact in [0, 1)"});
  c[0].second_tangent = -1;
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { solvers::ContactPoint::validate(c, 2); },
                                                         {"second_tangent = -1 (contact 0", "needs the index"});
  c = d.contacts(false);
  c[1].law = std::make_shared<contact::JenkinsDiscLaw>(contact::JenkinsParameters{d.kt, d.mu, d.n0});
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { solvers::ContactPoint::validate(c, 2); },
                                                         {"share one contact::JenkinsDiscLaw"});
  c = d.contacts(false);
  c[0].along = {{0, 1.0}, {1, 0.5}};
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { solvers::ContactPoint::validate(c, 2); },
                                                         {"orthogonal directions of equal length"});
  c = d.contacts(false);
  c[0].second_tangent = 0;
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { solvers::ContactPoint::validate(c, 2); },
                                                         {"another contact in [0, 2)"});
}
