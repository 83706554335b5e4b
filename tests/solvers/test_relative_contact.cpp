// Contacts between two DOFs (a relative gap, two bodies): every solver against the same problem
// written in other coordinates. With u = T y and T = I + e_a e_bᵀ, the relative displacement
// u_a − u_b is the coordinate y_a, so a contact on u_a − u_b in (M, C, K) is an ordinary contact
// on y_a against a fixed obstacle in (TᵀMT, TᵀCT, TᵀKT), whose solution mapped back by T must be
// the same periodic state. The transformed problem never goes through the relative-contact code.
#include <wbm/solvers/weighted_residual.hpp>

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <wbm/contact/signorini.hpp>
#include <wbm/solvers/floquet.hpp>
#include <wbm/solvers/post_processing.hpp>
#include <wbm/solvers/time_integration.hpp>
#include <wbm/spectral/layout.hpp>

#include "scene.hpp"
#include "testing.hpp"

using namespace wbm;
using solvers::TimeBasis;

namespace {

// Two bodies: the clamped-free rod of [JL14 Table 1, Case 1] and, beyond its tip, a mass on a
// spring (the rod's mass, tuned to 0.8 × the forcing frequency) that is forced and hammers the
// tip through a contact on u_tip − u_mass at the Case 1 gap: free, it would move 1.5 gaps.
struct TwoBodies {
  scene::Scene scene = reproduce::load_scene("jl14_case1");
  int tip = 0, mass = 0, n = 0;
  double gap = 0.0;
  Eigen::MatrixXd t;                         // u = T y
  solvers::MechanicalSystem relative, transformed;
  solvers::HarmonicForcing forcing;          // on the mass in both (Tᵀ e_mass = e_mass)
  std::shared_ptr<const contact::ContactLaw> penalty, rigid;

  TwoBodies() {
    const solvers::MechanicalSystem rod = scene.system();
    const auto case1 = scene.contact_points().front();
    penalty = case1.law;
    gap = penalty->gap();
    tip = case1.dof;
    mass = rod.dofs();
    n = rod.dofs() + 1;
    const double f = scene.harmonic_forcing().frequency_hz, omega = 2.0 * std::numbers::pi * f;
    const double m2 = Eigen::MatrixXd(rod.mass).sum();
    const double k2 = m2 * std::pow(0.8 * omega, 2);
    Eigen::MatrixXd m = Eigen::MatrixXd::Zero(n, n), k = m;
    m.topLeftCorner(n - 1, n - 1) = Eigen::MatrixXd(rod.mass);
    k.topLeftCorner(n - 1, n - 1) = Eigen::MatrixXd(rod.stiffness);
    m(mass, mass) = m2;
    k(mass, mass) = k2;
    const double beta = scene.damping.beta;
    t = Eigen::MatrixXd::Identity(n, n);
    t(tip, mass) = 1.0;
    auto system = [&](const Eigen::MatrixXd& mm, const Eigen::MatrixXd& kk) {
      solvers::MechanicalSystem s;
      s.mass = mm.sparseView();
      s.stiffness = kk.sparseView();
      s.damping = (beta * kk).sparseView();
      return s;
    };
    relative = system(m, k);
    transformed = system(t.transpose() * m * t, t.transpose() * k * t);
    forcing = {mass, 1.5 * gap * std::abs(k2 - m2 * omega * omega), f};
    rigid = std::make_shared<contact::RigidStop>(gap);
  }
  [[nodiscard]] std::vector<solvers::ContactPoint> between(std::shared_ptr<const contact::ContactLaw> law) const {
    return {{tip, std::move(law), mass}};
  }
  [[nodiscard]] std::vector<solvers::ContactPoint> on_y(std::shared_ptr<const contact::ContactLaw> law) const {
    return {{tip, std::move(law)}};
  }
};

double relative_difference(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) { return (a - b).norm() / b.norm(); }

}  // namespace

// The weighted residual method, penalty and rigid laws, three pairs of [JL14 Table 2]: the
// coefficients of the relative-contact problem are T times those of the transformed one.
TEST(RelativeContact, WeightedResidualEqualsTheTransformedObstacleProblem) {
  const TwoBodies b;
  const int m = 64;
  for (const char* name : {"fourier", "haar", "db6"}) {
    const auto trial = TimeBasis::from_name(name, m);
    const auto weighting = TimeBasis::from_name(std::string(name) == "haar" ? "fourier" : name, m);
    for (const auto& law : {b.penalty, b.rigid}) {
      SCOPED_TRACE(std::string(name) + " " + law->describe());
      const auto rel = solvers::solve_weighted_residual(b.relative, b.forcing, b.between(law), trial, weighting);
      const auto abs = solvers::solve_weighted_residual(b.transformed, b.forcing, b.on_y(law), trial, weighting);
      ASSERT_TRUE(rel.report.converged()) << rel.report.message;
      ASSERT_TRUE(abs.report.converged()) << abs.report.message;
      EXPECT_LT(relative_difference(rel.coefficients, b.t * abs.coefficients), 1e-8);
      EXPECT_GT(rel.max_contact_force, 0.0);  // the bodies do touch
      // A contact between the bodies, not of the tip against a wall: the gap closes while the
      // tip itself stays far from g0.
      const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(256, 0.0, 255.0 / 256.0);
      EXPECT_LT(solvers::evaluate_trial(trial, rel.coefficients, b.tip, tau, b.forcing.frequency_hz).maxCoeff(),
                0.5 * b.gap);
      if (law->rigid()) {
        EXPECT_LT(relative_difference(rel.contact_force_samples, abs.contact_force_samples), 1e-8);
        EXPECT_LT(rel.complementarity, 1e-9 * b.gap);
      }
    }
  }
}

// The dense Jacobian of the relative-contact residual (PᵀNP with rows e_tip − e_mass) against
// central differences of the residual, at the solution and off it.
TEST(RelativeContact, JacobianMatchesFiniteDifferences) {
  const TwoBodies b;
  const int m = 16;
  const solvers::WeightedResidual wr(b.relative, b.forcing, b.between(b.penalty), TimeBasis::from_name("bspline", m),
                                     TimeBasis::from_name("bspline", m));
  const auto s = wr.solve();
  ASSERT_TRUE(s.report.converged()) << s.report.message;
  const Eigen::VectorXd a = spectral::stacked(s.coefficients);
  wbm::testing::expect_jacobian_matches_fd(wr, a, 1e-6, 1e-6, b.gap);
  // The coupling between the two DOFs, which only the contact creates (M, C, K are block
  // diagonal): nonzero where the bodies touch.
  const Eigen::MatrixXd j = wr.jacobian(a);
  double coupling = 0.0;
  for (int k = 0; k < m; ++k) {
    for (int l = 0; l < m; ++l) {
      coupling = std::max(coupling, std::abs(j(spectral::stacked_index(k, b.tip, b.n), spectral::stacked_index(l, b.mass, b.n))));
    }
  }
  EXPECT_GT(coupling, 1e-3 * j.cwiseAbs().maxCoeff());
}

// The time-stepping references: BDF with the penalty law and Moreau–Jean with the rigid stop.
TEST(RelativeContact, TimeSteppingEqualsTheTransformedObstacleProblem) {
  const TwoBodies b;
  solvers::TimeIntegrationOptions bdf;
  bdf.samples_per_period = 256;
  const auto rel = solvers::integrate_to_periodic(b.relative, b.forcing, b.between(b.penalty), bdf);
  const auto abs = solvers::integrate_to_periodic(b.transformed, b.forcing, b.on_y(b.penalty), bdf);
  ASSERT_TRUE(rel.report.converged()) << rel.report.message;
  ASSERT_TRUE(abs.report.converged()) << abs.report.message;
  EXPECT_LT(relative_difference(rel.displacement, b.t * abs.displacement), 1e-5);

  solvers::MoreauJeanOptions mj;
  mj.steps_per_period = 1 << 12;
  mj.max_periods = 300;
  const auto rel_mj = solvers::integrate_moreau_jean_to_periodic(b.relative, b.forcing, b.between(b.rigid), mj);
  const auto abs_mj = solvers::integrate_moreau_jean_to_periodic(b.transformed, b.forcing, b.on_y(b.rigid), mj);
  ASSERT_TRUE(rel_mj.report.converged()) << rel_mj.report.message;
  ASSERT_TRUE(abs_mj.report.converged()) << abs_mj.report.message;
  EXPECT_LT(relative_difference(rel_mj.displacement, b.t * abs_mj.displacement), 1e-8);
  EXPECT_LT(relative_difference(rel_mj.contact_force, abs_mj.contact_force), 1e-8);
  EXPECT_GT(rel_mj.contact_force.maxCoeff(), 0.0);
  // Energy: the stop's absorption is the impulse times the relative velocity, the same in both.
  EXPECT_NEAR(rel_mj.stop_power, abs_mj.stop_power, 1e-8 * abs_mj.input_power);
}

// Floquet multipliers are invariant under the change of coordinates.
TEST(RelativeContact, FloquetMultipliersEqualThoseOfTheTransformedProblem) {
  const TwoBodies b;
  const int m = 64;
  const auto trial = TimeBasis::from_name("fourier", m);
  const auto s = solvers::solve_weighted_residual(b.relative, b.forcing, b.between(b.penalty), trial, trial);
  ASSERT_TRUE(s.report.converged()) << s.report.message;
  const int p = 256;
  const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(p, 0.0, (p - 1.0) / p);
  const Eigen::VectorXd u = solvers::evaluate_trial(trial, s.coefficients, b.tip, tau, b.forcing.frequency_hz) -
                            solvers::evaluate_trial(trial, s.coefficients, b.mass, tau, b.forcing.frequency_hz);
  const Eigen::MatrixXd contact_displacement = u.transpose();
  const auto rel = solvers::floquet_multipliers(b.relative, b.between(b.penalty), contact_displacement, b.forcing.frequency_hz);
  const auto abs = solvers::floquet_multipliers(b.transformed, b.on_y(b.penalty), contact_displacement, b.forcing.frequency_hz);
  ASSERT_EQ(rel.multipliers.size(), abs.multipliers.size());
  EXPECT_NEAR(rel.max_modulus, abs.max_modulus, 1e-8);
  for (Eigen::Index i = 0; i < rel.multipliers.size(); ++i) {
    EXPECT_NEAR(std::abs(rel.multipliers(i)), std::abs(abs.multipliers(i)), 1e-8) << i;
  }
}

TEST(RelativeContact, RefusesAContactAgainstItselfOrAMissingDof) {
  const TwoBodies b;
  const auto trial = TimeBasis::from_name("fourier", 8);
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)solvers::WeightedResidual(b.relative, b.forcing, {{b.tip, b.penalty, b.tip}}, trial, trial); },
      {"ContactPoint.other = " + std::to_string(b.tip), "another DOF"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)solvers::WeightedResidual(b.relative, b.forcing, {{b.tip, b.penalty, b.n}}, trial, trial); },
      {"ContactPoint.other = " + std::to_string(b.n), "[0, " + std::to_string(b.n) + ")"});
  // The same pair twice is one law twice; a second contact of the tip against the wall is not.
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] {
        (void)solvers::WeightedResidual(b.relative, b.forcing, {{b.tip, b.penalty, b.mass}, {b.tip, b.penalty, b.mass}},
                                        trial, trial);
      },
      {"appears twice"});
  EXPECT_NO_THROW((void)solvers::WeightedResidual(b.relative, b.forcing, {{b.tip, b.penalty, b.mass}, {b.tip, b.penalty}},
                                                  trial, trial));
}
