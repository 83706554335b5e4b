// Contacts between two DOFs (a relative gap, two bodies): every solver against the same problem
// written in other coordinates. With u = T y and T = I + e_a e_bᵀ, the relative displacement
// u_a − u_b is the coordinate y_a, so a contact on u_a − u_b in (M, C, K) is an ordinary contact
// on y_a against a fixed obstacle in (TᵀMT, TᵀCT, TᵀKT), whose solution mapped back by T must be
// the same periodic state. The transformed problem never goes through the relative-contact code.
#include <wbm/solvers/weighted_residual.hpp>

#include <algorithm>
#include <complex>
#include <limits>
#include <numbers>
#include <utility>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <wbm/contact/penalty.hpp>
#include <wbm/contact/signorini.hpp>
#include <wbm/solvers/floquet.hpp>
#include <wbm/solvers/post_processing.hpp>
#include <wbm/solvers/time_integration.hpp>
#include <wbm/spectral/layout.hpp>

#include "shipped_scenes.hpp"
#include "testing.hpp"

using namespace wbm;
using solvers::TimeBasis;

namespace {

// Two bodies: the clamped-free rod of [JL14 Table 1, Case 1] and, beyond its tip, a mass on a
// spring (the rod's mass, tuned to 0.8 × the forcing frequency) that is forced and hammers the
// tip through a contact on u_tip − u_mass at the Case 1 gap: free, it would move 1.5 gaps.
struct TwoBodies {
  scene::Scene scene = models::load_scene("jl14_case1");
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

namespace {

// A mass in a plane (DOFs x1, y1) on anisotropic springs, forced along y, carrying a light
// contact node (x2, y2; 1e-4 of its mass, on springs 100 times stiffer) that meets a wall along
// the unit normal n = (cos 30°, sin 30°): g = g0 − n·u₂ (along = {(x2, cos), (y2, sin)}). A
// point mass alone has no local compliance and is a known limit of the rigid law (docs/design.md).
// With T⁻¹ = I + e_a (n − e_a)ᵀ, a = x2 (row a of T⁻¹ is nᵀ), y_a = n·u₂, and Tᵀ e_y1 = e_y1
// (Sherman–Morrison), so the same problem is a wall contact on y_a with the same forcing.
struct SlantedStop {
  double m = 1.0, kx = std::pow(2.0 * std::numbers::pi * 10.0, 2), ky = std::pow(2.0 * std::numbers::pi * 14.0, 2);
  double alpha = 6.0, f = 12.0, gap = 1e-3;
  Eigen::Vector2d n{std::cos(std::numbers::pi / 6.0), std::sin(std::numbers::pi / 6.0)};
  Eigen::Matrix4d t;  // u = T y
  solvers::MechanicalSystem along, transformed;
  solvers::HarmonicForcing forcing;

  SlantedStop() {
    const double kc = 100.0 * kx;
    Eigen::Matrix4d mm = Eigen::Vector4d(m, m, 1e-4 * m, 1e-4 * m).asDiagonal(), kk = Eigen::Matrix4d::Zero();
    kk(0, 0) = kx + kc;
    kk(1, 1) = ky + kc;
    kk(2, 2) = kk(3, 3) = kc;
    kk(0, 2) = kk(2, 0) = kk(1, 3) = kk(3, 1) = -kc;
    Eigen::Matrix4d t_inv = Eigen::Matrix4d::Identity();
    t_inv(2, 2) = n(0);
    t_inv(2, 3) = n(1);
    t = t_inv.inverse();
    auto system = [&](const Eigen::Matrix4d& ms, const Eigen::Matrix4d& ks) {
      solvers::MechanicalSystem s;
      s.mass = Eigen::MatrixXd(ms).sparseView();
      s.stiffness = Eigen::MatrixXd(ks).sparseView();
      s.damping = Eigen::MatrixXd(alpha * ms).sparseView();
      return s;
    };
    along = system(mm, kk);
    transformed = system(t.transpose() * mm * t, t.transpose() * kk * t);
    // Free, the contact node would move about 3 gaps along n.
    const Eigen::VectorXcd free = solvers::frequency_response(along, {1, 1.0, f});
    forcing = {1, 3.0 * gap / std::abs(n(0) * free(2) + n(1) * free(3)), f};
  }
  [[nodiscard]] std::vector<solvers::ContactPoint> slanted(std::shared_ptr<const contact::ContactLaw> law) const {
    return {{2, std::move(law), -1, {{2, n(0)}, {3, n(1)}}}};
  }
  [[nodiscard]] std::vector<solvers::ContactPoint> on_y(std::shared_ptr<const contact::ContactLaw> law) const {
    return {{2, std::move(law)}};
  }
  [[nodiscard]] Eigen::VectorXd normal_displacement(const TimeBasis& trial, const Eigen::MatrixXd& a,
                                                    const Eigen::VectorXd& tau) const {
    return n(0) * solvers::evaluate_trial(trial, a, 2, tau, f) + n(1) * solvers::evaluate_trial(trial, a, 3, tau, f);
  }
};

}  // namespace

// Every solver on a contact along a unit normal equals the wall contact in the coordinates
// whose first axis is n: the weighted residual method (three pairs, penalty and rigid) and
// Moreau–Jean. BDF and the monodromy matrix use the same ContactPoint::terms() and are checked
// by the two-body tests above: this light, stiff contact node costs BDF seconds per run and is
// beyond the fixed-step monodromy integration at P = 256.
TEST(ContactDirection, ANormalContactEqualsTheTransformedWallContact) {
  const SlantedStop s;
  const std::shared_ptr<const contact::ContactLaw> penalty = std::make_shared<contact::LinearPenalty>(
      contact::LinearPenaltyParameters{100.0 * s.kx, s.gap});
  const std::shared_ptr<const contact::ContactLaw> rigid = std::make_shared<contact::RigidStop>(s.gap);
  const int m = 64;
  for (const char* name : {"fourier", "haar", "db6"}) {
    const auto trial = TimeBasis::from_name(name, m);
    const auto weighting = TimeBasis::from_name(std::string(name) == "haar" ? "fourier" : name, m);
    for (const auto& law : {penalty, rigid}) {
      SCOPED_TRACE(std::string(name) + " " + law->describe());
      const auto a = solvers::solve_weighted_residual(s.along, s.forcing, s.slanted(law), trial, weighting);
      const auto b = solvers::solve_weighted_residual(s.transformed, s.forcing, s.on_y(law), trial, weighting);
      ASSERT_TRUE(a.report.converged()) << a.report.message;
      ASSERT_TRUE(b.report.converged()) << b.report.message;
      EXPECT_LT(relative_difference(a.coefficients, s.t * b.coefficients), 1e-8);
      EXPECT_GT(a.max_contact_force, 0.0);
      // n·u₂ meets the stop: at g0 at the instants for the rigid law, within the penalty's
      // penetration otherwise.
      const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(256, 0.0, 255.0 / 256.0);
      const double reach = s.normal_displacement(trial, a.coefficients, tau).maxCoeff();
      EXPECT_GT(reach, 0.99 * s.gap);
      if (law->rigid()) {
        EXPECT_LT(a.collocation_penetration, 1e-12 * s.gap);
      } else {
        EXPECT_LT(reach, 1.5 * s.gap);
      }
    }
  }
  solvers::MoreauJeanOptions mj;
  mj.steps_per_period = 1 << 12;
  mj.max_periods = 300;
  const auto c = solvers::integrate_moreau_jean_to_periodic(s.along, s.forcing, s.slanted(rigid), mj);
  const auto d = solvers::integrate_moreau_jean_to_periodic(s.transformed, s.forcing, s.on_y(rigid), mj);
  ASSERT_EQ(c.report.periods, d.report.periods);
  EXPECT_LT(relative_difference(c.displacement, s.t * d.displacement), 1e-8);
  EXPECT_GT(c.contact_force.maxCoeff(), 0.0);
}

// A stop on the −x side is the direction −e_x: the mirror image of the +x stop under u → −u
// (with the forcing mirrored too), for the penalty and the rigid law.
TEST(ContactDirection, AStopOnTheNegativeSideMirrorsThePositiveOne) {
  const TwoBodies b;  // its rod only: the Case 1 rod with its stop at the tip
  const solvers::MechanicalSystem rod = b.scene.system();
  const solvers::HarmonicForcing forcing = b.scene.harmonic_forcing();
  solvers::HarmonicForcing mirrored = forcing;
  mirrored.amplitude = -forcing.amplitude;
  const auto trial = TimeBasis::from_name("bspline", 64);
  for (const auto& law : {b.penalty, b.rigid}) {
    SCOPED_TRACE(law->describe());
    const auto plus = solvers::solve_weighted_residual(rod, forcing, {{b.tip, law}}, trial, trial);
    const auto minus = solvers::solve_weighted_residual(rod, mirrored, {{b.tip, law, -1, {{b.tip, -1.0}}}}, trial, trial);
    ASSERT_TRUE(plus.report.converged() && minus.report.converged());
    EXPECT_LT(relative_difference(minus.coefficients, -plus.coefficients), 1e-9);
    EXPECT_GT(plus.max_contact_force, 0.0);
  }
}

TEST(ContactDirection, RefusesAnImpossibleDirection) {
  const SlantedStop s;
  const auto trial = TimeBasis::from_name("fourier", 8);
  const std::shared_ptr<const contact::ContactLaw> law = std::make_shared<contact::RigidStop>(s.gap);
  using Terms = std::vector<std::pair<int, double>>;
  const auto build = [&](int dof, int other, const Terms& along) {
    (void)solvers::WeightedResidual(s.along, s.forcing, {{dof, law, other, along}}, trial, trial);
  };
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { build(0, -1, {{0, 0.0}, {1, 0.0}}); },
                                                         {"ContactPoint.along", "every weight is zero"});
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { build(0, -1, {{0, 1.0}, {7, 1.0}}); },
                                                         {"ContactPoint.along", "DOF 7 must lie in [0, 4)"});
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { build(0, -1, {{0, 1.0}, {0, 1.0}}); },
                                                         {"DOF 0 appears twice"});
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { build(0, -1, {{1, 1.0}}); },
                                                         {"dof 0 is not among its DOFs"});
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { build(0, 1, {{0, 1.0}}); },
                                                         {"other = 1 beside a direction"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { build(0, -1, {{0, std::numeric_limits<double>::quiet_NaN()}}); }, {"weight of DOF 0 is not finite"});
}
