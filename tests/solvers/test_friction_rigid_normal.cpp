// Exact Coulomb friction on a rigid normal stop in the weighted residual (a 2D contact: the slip
// force is μ times the stop's multiplier of the same cell, ContactPoint::normal). Truths not
// produced by this code: the physics of a normal DOF held on a rigid plane by a static load,
// whose reaction is that load (so the tangential response is the constant-load Coulomb one);
// Moreau–Jean time stepping with the 2D contact solved by Siconos Numerics (fc2d, Lemke), under a
// normal load that lifts the point off the plane for part of the period; central differences of
// the complementarity residual.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <wbm/contact/friction.hpp>
#include <wbm/contact/signorini.hpp>
#include <wbm/solvers/mechanical_system.hpp>
#include <wbm/solvers/post_processing.hpp>
#include <wbm/solvers/time_basis.hpp>
#include <wbm/solvers/time_integration.hpp>
#include <wbm/solvers/weighted_residual.hpp>
#include <wbm/spectral/layout.hpp>

#include "testing.hpp"

namespace solvers = wbm::solvers;
namespace contact = wbm::contact;
using solvers::TimeBasis;

namespace {

using wbm::testing::kPi;

// A point mass (1 kg) on two springs of 10 Hz, x tangential and y normal, ζ = 2 % on each. A rigid
// plane at y = 0 (the stop, contact 0; y > 0 would penetrate), exact Coulomb friction with μ on x
// (contact 1) whose normal load is the plane's reaction. x is driven by 1 N at `hz`; y is pressed
// on the plane by a static n0 [N] plus `py` cos ωt.
struct PointOnPlane {
  double mu = 0.3, n0 = 1.0, py = 0.0, hz = 12.0;

  [[nodiscard]] static solvers::MechanicalSystem system() {
    const double k = std::pow(2.0 * kPi * 10.0, 2);
    solvers::MechanicalSystem s;
    s.mass = Eigen::MatrixXd::Identity(2, 2).sparseView();
    s.stiffness = (k * Eigen::MatrixXd::Identity(2, 2)).sparseView();
    s.damping = (2.0 * 0.02 * std::sqrt(k) * Eigen::MatrixXd::Identity(2, 2)).sparseView();
    return s;
  }
  [[nodiscard]] solvers::HarmonicForcing forcing() const {
    solvers::HarmonicForcing f{0, 1.0, hz, {{1, n0, 0.0, 0}}};
    if (py != 0.0) f.more.push_back({1, py});
    return f;
  }
  [[nodiscard]] std::vector<solvers::ContactPoint> contacts() const {
    solvers::ContactPoint friction{0, std::make_shared<contact::CoulombFriction>(contact::CoulombParameters{mu, 0.0})};
    friction.normal = 0;
    return {{1, std::make_shared<contact::RigidStop>(0.0)}, friction};
  }
};

// u_dof(τ_p) of a weighted-residual solution at the P = 1024 samples τ_p = p/P of Moreau–Jean.
Eigen::VectorXd at_samples(const TimeBasis& basis, const Eigen::MatrixXd& coefficients, int dof) {
  const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(1024, 0.0, 1023.0 / 1024.0);
  return basis.values(tau, 0) * coefficients.row(dof).transpose();
}

}  // namespace

// A static load n0 holds y on the plane at every instant, so the stop's multiplier is n0 and the
// tangential problem is the Coulomb contact under a constant load n0: the two solutions agree to
// the solver's tolerance. Fourier (odd and even M: the instants are the midpoints, and k/M where
// the top function vanishes at them) projects the constant load exactly with the impulses'
// M-point rule, so λ_n = n0 to rounding; a wavelet pair projects the load with the Q-point rule
// and the impulses with the M-point one (test_friction: full stick), so λ_n = n0 and the tangential
// response agree to 1e-3 there.
TEST(FrictionRigidNormal, AStaticallyPressedPointRubsAsUnderAConstantNormalLoad) {
  const PointOnPlane p;
  for (const std::string pair : {"fourier-odd", "fourier", "db6", "bspline"}) {
    const TimeBasis basis = pair == "fourier-odd" ? TimeBasis::fourier_harmonics(16) : TimeBasis::from_name(pair, 32);
    const solvers::WeightedResidual paired(PointOnPlane::system(), p.forcing(), p.contacts(), basis, basis);
    const solvers::WeightedResidual plain(
        PointOnPlane::system(), {0, 1.0, p.hz},
        {{0, std::make_shared<contact::CoulombFriction>(contact::CoulombParameters{p.mu, p.n0})}}, basis, basis);
    const auto a = paired.solve();
    const auto b = plain.solve();
    ASSERT_TRUE(a.converged()) << pair << ": " << a.brief();
    ASSERT_TRUE(b.converged()) << pair << ": " << b.brief();
    const double tolerance = pair.starts_with("fourier") ? 1e-9 : 1e-3;
    const double scale = b.coefficients.row(0).cwiseAbs().maxCoeff();
    EXPECT_LT((a.coefficients.row(0) - b.coefficients.row(0)).cwiseAbs().maxCoeff(), tolerance * scale) << pair;
    EXPECT_LT((a.contact_force_samples.row(0).array() - p.n0).abs().maxCoeff(), tolerance * p.n0) << pair;
    EXPECT_LT(a.coefficients.row(1).cwiseAbs().maxCoeff(), tolerance * scale) << pair << ": y stays on the plane";
    // The friction force reaches μ n0 where it slips, and slips somewhere (1 N against 0.3 N).
    EXPECT_NEAR(a.contact_force_samples.row(1).cwiseAbs().maxCoeff(), p.mu * p.n0, tolerance * p.mu * p.n0) << pair;
  }
}

// The normal load n0 + py cos ωt (0.2 … 1.8 N) keeps the point on the plane and swings the slip
// force with it: x slips throughout, under μ λ_n. The weighted residual tends to the Moreau–Jean
// reference (Siconos fc2d, T/16384; its own error against T/32768 is 1.4e-5): with the instants
// at k/M (Fourier of even M, B-splines) from 2.6e-2 at M = 64 to 4.6e-3 at M = 256 (1.1e-3 at
// 512); with the midpoints (DB6) 4.7e-3 and 4.6e-3, the irregular first-order convergence of exact
// friction on this motion (the constant-load contact, py = 0, gives 4.6e-3 … 2.6e-2 over the same
// M for these pairs). |λ_t| ≤ μ λ_n at every instant, and y stays on the plane.
// (A swing above n0 lifts the point mass off the plane: the rigid normal stop of a point mass is
// then the position-level impact problem of issue #38, item 3, whose iteration may not converge.)
TEST(FrictionRigidNormal, ConvergesToMoreauJeanUnderAVaryingNormalLoad) {
  PointOnPlane p;
  p.py = 0.8;
  solvers::MoreauJeanOptions o;
  o.steps_per_period = 16384;
  o.samples_per_period = 1024;
  o.periodicity_tolerance = 1e-10;
  const auto reference =
      solvers::integrate_moreau_jean_to_periodic(PointOnPlane::system(), p.forcing(), p.contacts(), o);
  ASSERT_TRUE(reference.report.converged()) << reference.report.message;
  ASSERT_EQ(reference.report.unsettled_lcp_steps, 0);
  const Eigen::VectorXd x_ref = reference.displacement.row(0).transpose();
  ASSERT_NEAR(reference.contact_force.row(0).minCoeff(), p.n0 - p.py, 1e-3);  // the normal load's swing
  for (const std::string pair : {"fourier", "db6", "bspline"}) {
    std::vector<double> errors;
    for (int m : {64, 256}) {
      const TimeBasis basis = TimeBasis::from_name(pair, m);
      const solvers::WeightedResidual w(PointOnPlane::system(), p.forcing(), p.contacts(), basis, basis);
      const auto s = w.solve();
      ASSERT_TRUE(s.converged()) << pair << " M = " << m << ": " << s.brief();
      EXPECT_LT(s.complementarity, 1e-9 * w.residual_scale()) << pair << " M = " << m;
      const double ex = solvers::rms_relative_error(at_samples(basis, s.coefficients, 0), x_ref);
      const double ey = at_samples(basis, s.coefficients, 1).cwiseAbs().maxCoeff();  // y stays on the plane
      errors.push_back(ex);
      std::printf("%s M = %d: x %.3e, max|y| %.1e m (%s)\n", pair.c_str(), m, ex, ey,
                  solvers::to_string(s.path).data());
      EXPECT_LT(ey, 1e-9) << pair << " M = " << m;
      // The friction force within the cone of the plane's reaction: |λ_t| ≤ μ λ_n⁺ at every instant.
      for (int k = 0; k < m; ++k) {
        const double ln = std::max(s.contact_force_samples(0, k), 0.0);
        EXPECT_LE(std::abs(s.contact_force_samples(1, k)), p.mu * ln + 1e-9) << pair << " M = " << m << " k = " << k;
      }
    }
    if (pair != "db6") {
      EXPECT_LT(errors[1], errors[0] / 3.0) << pair;
    }
    EXPECT_LT(errors[1], 1e-2) << pair;
  }
}

// The generalized Jacobian of the 2D contact's rows (the slip rows on a pushing stop carry
// −σμc in the stop's column) equals central differences of the residual away from a switch.
TEST(FrictionRigidNormal, JacobianMatchesCentralDifferences) {
  PointOnPlane p;
  p.py = 0.8;
  for (const std::string pair : {"fourier", "db6"}) {
    const TimeBasis basis = TimeBasis::from_name(pair, 32);
    const solvers::WeightedResidual w(PointOnPlane::system(), p.forcing(), p.contacts(), basis, basis);
    const auto s = w.solve();
    ASSERT_TRUE(s.converged()) << pair << ": " << s.brief();
    Eigen::VectorXd x = wbm::spectral::stacked(s.contact_force_samples);  // rows k·2 + c
    // Off every switch: a stop that barely pushes is opened (λ_n = −1e-3 N: the force branch, no
    // slip force), and a friction impulse on its bound moved 0.1 % beyond it (as test_friction).
    int coupled = 0;
    for (Eigen::Index k = 0; k < x.size(); k += 2) {
      if (x(k) <= 1e-4) x(k) = -1e-3;
      const double bound = p.mu * std::max(x(k), 0.0);
      if (x(k) > 0.0 && std::abs(x(k + 1)) >= bound * (1.0 - 1e-9)) {
        x(k + 1) *= 1.001;
        ++coupled;
      }
    }
    ASSERT_GT(coupled, 0) << pair << ": some slip row must sit on a pushing stop";
    const Eigen::MatrixXd j = w.signorini_jacobian(x).dense();
    const double h = 1e-7 * p.n0;
    for (Eigen::Index i = 0; i < x.size(); ++i) {
      Eigen::VectorXd xp = x, xm = x;
      xp(i) += h;
      xm(i) -= h;
      const Eigen::VectorXd fd = (w.signorini_residual(xp) - w.signorini_residual(xm)) / (2.0 * h);
      EXPECT_LT((fd - j.col(i)).cwiseAbs().maxCoeff(), 1e-6 * j.cwiseAbs().maxCoeff()) << pair << " column " << i;
    }
  }
}

// A Coulomb contact under a normal that is not a rigid stop, with its own preload beside one, or
// two of them on one stop, is refused by name (ContactPoint::validate, shared with Moreau–Jean).
TEST(FrictionRigidNormal, PairingsThatAreNotA2DContactAreRefusedByName) {
  const PointOnPlane p;
  const TimeBasis basis = TimeBasis::fourier_harmonics(8);
  const auto build = [&](const std::vector<solvers::ContactPoint>& contacts) {
    (void)solvers::WeightedResidual(PointOnPlane::system(), p.forcing(), contacts, basis, basis);
  };
  auto contacts = p.contacts();
  contacts[0].law = std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{1e6, 0.0});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { build(contacts); }, {"ContactPoint.normal = 0 (contact 1", "from a rigid stop", "Jenkins element"});
  contacts = p.contacts();
  contacts[1].law = std::make_shared<contact::CoulombFriction>(contact::CoulombParameters{0.3, 0.5});
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { build(contacts); }, {"normal_load = 0.5"});
  contacts = p.contacts();
  solvers::ContactPoint second{1, contacts[1].law, -1, {{0, 1.0}, {1, 1.0}}};
  second.normal = 0;
  contacts.push_back(second);
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { build(contacts); }, {"already takes its normal load"});
}
