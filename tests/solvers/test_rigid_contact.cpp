// Exact unilateral contact (rigid stops) in the weighted residual method, against independent
// references: the Moreau–Jean time stepping with a plastic impact law, the impulse response of
// the full system, finite differences, and the penalty laws as their stiffness grows.
#include <wbm/solvers/weighted_residual.hpp>

#include <cmath>
#include <complex>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <wbm/contact/friction.hpp>
#include <wbm/contact/penalty.hpp>
#include <wbm/contact/signorini.hpp>
#include <wbm/solvers/floquet.hpp>
#include <wbm/solvers/post_processing.hpp>
#include <wbm/solvers/response_curve.hpp>
#include <wbm/solvers/time_integration.hpp>
#include <wbm/spectral/layout.hpp>

#include "shipped_scenes.hpp"
#include "testing.hpp"
#include "impact_oscillators.hpp"
#include "weighted_residual_fixtures.hpp"

using namespace wbm;
using solvers::TimeBasis;
using wbm::testing::kTable2;  // the six combinations of [JL14 Table 2]
using wbm::testing::Pair;

namespace {

// Case 1 of [JL14 Table 1] with its exponential penalty replaced by a rigid stop at the same gap.
struct RigidCase1 {
  scene::Scene scene = models::load_scene("jl14_case1");
  solvers::MechanicalSystem system = scene.system();
  solvers::HarmonicForcing forcing = scene.harmonic_forcing();
  double gap = scene.contact_points().front().law->gap();
  int tip = scene.contact_points().front().dof;
  std::vector<solvers::ContactPoint> stop{{tip, std::make_shared<contact::RigidStop>(gap)}};
};

Eigen::VectorXd grid(int p) {
  Eigen::VectorXd tau(p);
  for (int k = 0; k < p; ++k) tau(k) = static_cast<double>(k) / p;
  return tau;
}

// The tip displacement of the Moreau–Jean steady state (P = 1024 samples at τ = p/P).
Eigen::VectorXd moreau_jean_tip(const RigidCase1& c, int steps, double restitution = 0.0) {
  solvers::MoreauJeanOptions o;
  o.steps_per_period = steps;
  o.restitution = restitution;
  const auto r = solvers::integrate_moreau_jean_to_periodic(c.system, c.forcing, c.stop, o);
  EXPECT_TRUE(r.report.converged()) << r.report.message;
  return r.displacement.row(c.forcing.dof).transpose();
}

}  // namespace

// Without contact the scheme is the trapezoidal rule (θ = ½) on the linear rod: second order in
// the step against the direct frequency response.
TEST(MoreauJean, WithoutContactConvergesAtSecondOrderToTheFrequencyResponse) {
  const RigidCase1 c;
  const Eigen::VectorXcd amplitude = solvers::frequency_response(c.system, c.forcing);
  const Eigen::VectorXd tau = grid(256);
  Eigen::VectorXd exact(tau.size());
  for (Eigen::Index p = 0; p < tau.size(); ++p) {
    exact(p) = std::real(amplitude(c.forcing.dof) * std::exp(std::complex<double>(0.0, 2.0 * std::numbers::pi * tau(p))));
  }
  std::vector<double> h, errors;
  for (int steps : {512, 1024, 2048}) {
    solvers::MoreauJeanOptions o;
    o.steps_per_period = steps;
    o.samples_per_period = 256;
    const auto r = solvers::integrate_moreau_jean_to_periodic(c.system, c.forcing, {}, o);
    ASSERT_TRUE(r.report.converged()) << r.report.message;
    h.push_back(1.0 / steps);
    errors.push_back(solvers::rms_relative_error(r.displacement.row(c.forcing.dof).transpose(), exact));
  }
  EXPECT_NEAR(wbm::testing::observed_order(h, errors), 2.0, 0.15);
  EXPECT_LT(errors.back(), 1e-4);
}

// With the rigid stop the velocity jumps at impacts make the scheme first order: the
// differences between runs with 4× more steps shrink about 4× (Richardson), and the
// penetration, which the velocity-level law allows within a step, shrinks with the step.
TEST(MoreauJean, RigidStopConvergesAtFirstOrderInTheStep) {
  const RigidCase1 c;
  std::vector<Eigen::VectorXd> tips;
  for (int steps : {1 << 12, 1 << 14, 1 << 16}) tips.push_back(moreau_jean_tip(c, steps));
  const double d1 = solvers::rms_relative_error(tips[0], tips[1]);
  const double d2 = solvers::rms_relative_error(tips[1], tips[2]);
  EXPECT_GT(d1 / d2, 3.0) << d1 << " " << d2;
  EXPECT_LT(d1 / d2, 6.0) << d1 << " " << d2;
  double before = std::numeric_limits<double>::infinity();
  for (const auto& t : tips) {
    const double penetration = t.maxCoeff() - c.gap;
    EXPECT_LT(penetration, before);
    before = penetration;
  }
  EXPECT_LT(before, 1e-4 * c.gap);
  EXPECT_GT(tips.back().maxCoeff(), c.gap - 1e-4 * c.gap);  // it does reach the stop
}

// The θ = ½ scheme's energy identity over a periodic period: input − damping − stop = 0, and an
// elastic stop (e = 1) absorbs nothing while a plastic one (e = 0) absorbs a positive share.
TEST(MoreauJean, EnergyBalanceClosesOverAPeriod) {
  const RigidCase1 c;
  for (double e : {0.0, 1.0}) {
    solvers::MoreauJeanOptions o;
    o.steps_per_period = 1 << 12;
    o.restitution = e;
    const auto r = solvers::integrate_moreau_jean_to_periodic(c.system, c.forcing, c.stop, o);
    ASSERT_TRUE(r.report.converged()) << r.report.message;
    EXPECT_NEAR(r.input_power - r.damping_power - r.stop_power, 0.0, 1e-9 * r.input_power) << "e = " << e;
    if (e == 1.0) {
      EXPECT_NEAR(r.stop_power, 0.0, 1e-9 * r.input_power);
    } else {
      EXPECT_GT(r.stop_power, 1e-5 * r.input_power);
    }
  }
}

// The weighted residual solution with the rigid stop converges, for the six pairs of Table 2,
// to the Moreau–Jean steady state with a plastic impact law (e = 0): the Signorini conditions at
// the instants τ_{k+1} with the impulse of τ_k are the periodic analogue of its position-to-
// velocity pairing. Haar trial functions converge at first order (piecewise constants), the
// others at about second order (the kinks of the response at impacts).
TEST(RigidContact, SixPairsConvergeToTheMoreauJeanReference) {
  const RigidCase1 c;
  const Eigen::VectorXd reference = moreau_jean_tip(c, 1 << 16);
  const Eigen::VectorXd tau = grid(1024);
  for (const Pair& pair : kTable2) {
    std::vector<double> errors;
    for (int m : {64, 256}) {
      const auto trial = TimeBasis::from_name(pair.trial, m);
      const solvers::WeightedResidual wr(c.system, c.forcing, c.stop, trial, TimeBasis::from_name(pair.weighting, m));
      const auto s = wr.solve();
      ASSERT_TRUE(s.converged()) << pair.trial << ":" << pair.weighting << " M = " << m << ": " << s.report.message;
      errors.push_back(solvers::rms_relative_error(
          solvers::evaluate_trial(trial, s.coefficients, c.forcing.dof, tau, c.forcing.frequency_hz), reference));
    }
    const double order = std::log(errors[0] / errors[1]) / std::log(4.0);
    const bool haar = std::string(pair.trial) == "haar";
    SCOPED_TRACE(std::string(pair.trial) + ":" + pair.weighting + " errors " + std::to_string(errors[0]) + ", " +
                 std::to_string(errors[1]));
    if (haar) {
      EXPECT_NEAR(order, 1.0, 0.25);
      EXPECT_LT(errors[1], 1e-2);
    } else {
      EXPECT_GT(order, 1.5);
      EXPECT_LT(errors[1], 5e-4);
    }
  }
}

// "Perfectly flat contact plateaus" [JL14 Sec. 6]: at every collocation instant the tip is at
// the stop to rounding wherever the stop pushes, and never beyond it. Haar trial functions are
// constant on each cell, so the whole plateau is flat; smooth bases overshoot between the
// instants (Gibbs), by much less than the gap.
TEST(RigidContact, PlateausAreFlat) {
  const RigidCase1 c;
  const int m = 64;
  for (const Pair& pair : kTable2) {
    const auto trial = TimeBasis::from_name(pair.trial, m);
    const solvers::WeightedResidual wr(c.system, c.forcing, c.stop, trial, TimeBasis::from_name(pair.weighting, m));
    const auto s = wr.solve();
    ASSERT_TRUE(s.converged()) << s.report.message;
    SCOPED_TRACE(std::string(pair.trial) + ":" + pair.weighting);
    EXPECT_LE(s.collocation_penetration, 1e-12 * c.gap);
    EXPECT_LE(s.complementarity, 1e-12 * c.gap);
    EXPECT_GE(s.contact_force_samples.minCoeff(), -1e-9 * s.max_contact_force);
    // The displacement at the instants τ_{k+1} whose impulse λ_k pushes: at g0.
    const Eigen::VectorXd times = wr.collocation_times();
    Eigen::VectorXd next(m);
    for (int k = 0; k < m; ++k) next(k) = times((k + 1) % m);
    const Eigen::VectorXd u = solvers::evaluate_trial(trial, s.coefficients, c.tip, next, c.forcing.frequency_hz);
    int pushing = 0;
    for (int k = 0; k < m; ++k) {
      if (s.contact_force_samples(0, k) > 1e-6 * s.max_contact_force) {
        ++pushing;
        EXPECT_NEAR(u(k), c.gap, 1e-12 * c.gap) << "instant " << k + 1;
      }
    }
    EXPECT_GE(pushing, 5);  // a plateau, not a touch
    if (std::string(pair.trial) == "haar") {
      EXPECT_LE(s.max_penetration, 1e-12 * c.gap);  // flat between the instants too
    } else {
      EXPECT_LT(s.max_penetration, 2e-2 * c.gap);
    }
  }
}

// D = V H W against the impulse responses of the full system: column j is minus the change of
// the contact displacements at the instants τ_{k+1} when a unit impulse λ_j acts, computed by a
// full solve with G (expand_forces), not through the condensed compliance H. Two contacts, so
// that the cross terms and the ordering k·n_c + c are checked.
TEST(RigidContact, DelassusOperatorIsTheImpulseResponseOfTheFullSystem) {
  const RigidCase1 c;
  const int m = 16;
  std::vector<solvers::ContactPoint> stops{{c.tip, std::make_shared<contact::RigidStop>(1.0)},
                                           {c.tip - 5, std::make_shared<contact::RigidStop>(2.0)}};
  for (const Pair& pair : {Pair{"fourier", "fourier"}, Pair{"haar", "fourier"}, Pair{"db6", "db6"}}) {
    const auto trial = TimeBasis::from_name(pair.trial, m);
    const solvers::WeightedResidual wr(c.system, c.forcing, stops, trial, TimeBasis::from_name(pair.weighting, m));
    const Eigen::VectorXd times = wr.collocation_times();
    Eigen::VectorXd next(m);
    for (int k = 0; k < m; ++k) next(k) = times((k + 1) % m);
    auto samples = [&](const Eigen::VectorXd& lambda) {  // u at τ_{k+1}, ordering k·n_c + c
      const Eigen::MatrixXd a = spectral::as_coefficients(wr.expand_forces(lambda), wr.dofs());
      Eigen::VectorXd u(2 * m);
      for (int s = 0; s < 2; ++s) {
        const Eigen::VectorXd us = solvers::evaluate_trial(trial, a, stops[static_cast<size_t>(s)].dof, next, 1.0);
        for (int k = 0; k < m; ++k) u(2 * k + s) = us(k);
      }
      return u;
    };
    const Eigen::VectorXd base = samples(Eigen::VectorXd::Zero(2 * m));
    Eigen::MatrixXd d(2 * m, 2 * m);
    for (int j = 0; j < 2 * m; ++j) d.col(j) = base - samples(Eigen::VectorXd::Unit(2 * m, j));
    EXPECT_LE((d - wr.delassus()).norm(), 1e-9 * d.norm()) << pair.trial << ":" << pair.weighting;
  }
}

// The same with exact Coulomb friction on the second contact: its rows are the slips
// u(τ_{k+1}) − u(τ_k) per unit impulse, again from full solves with G. Fourier:Fourier forms D
// from its first block column (H commutes with time shifts: set_delassus_circulant), the other
// pairs by the dense products; both against the same impulse responses. Fourier with M even puts
// the impulses at k/M (its top function vanishes at the midpoints), so the circulant path is
// checked on both grids by these two tests.
TEST(RigidContact, DelassusOperatorWithFrictionIsTheImpulseResponseOfTheFullSystem) {
  const RigidCase1 c;
  const int m = 16;
  std::vector<solvers::ContactPoint> contacts{
      {c.tip, std::make_shared<contact::RigidStop>(1.0)},
      {c.tip - 5, std::make_shared<contact::CoulombFriction>(contact::CoulombParameters{0.3, 2.0})}};
  for (const Pair& pair : {Pair{"fourier", "fourier"}, Pair{"db6", "db6"}}) {
    const auto trial = TimeBasis::from_name(pair.trial, m);
    const solvers::WeightedResidual wr(c.system, c.forcing, contacts, trial, TimeBasis::from_name(pair.weighting, m));
    const Eigen::VectorXd times = wr.collocation_times();
    Eigen::VectorXd next(m);
    for (int k = 0; k < m; ++k) next(k) = times((k + 1) % m);
    auto rows = [&](const Eigen::VectorXd& lambda) {  // gap displacement (stop), slip (friction)
      const Eigen::MatrixXd a = spectral::as_coefficients(wr.expand_forces(lambda), wr.dofs());
      const Eigen::VectorXd u0 = solvers::evaluate_trial(trial, a, contacts[0].dof, next, 1.0);
      const Eigen::VectorXd u1 = solvers::evaluate_trial(trial, a, contacts[1].dof, next, 1.0) -
                                 solvers::evaluate_trial(trial, a, contacts[1].dof, times, 1.0);
      Eigen::VectorXd u(2 * m);
      for (int k = 0; k < m; ++k) {
        u(2 * k) = u0(k);
        u(2 * k + 1) = u1(k);
      }
      return u;
    };
    const Eigen::VectorXd base = rows(Eigen::VectorXd::Zero(2 * m));
    Eigen::MatrixXd d(2 * m, 2 * m);
    for (int j = 0; j < 2 * m; ++j) d.col(j) = base - rows(Eigen::VectorXd::Unit(2 * m, j));
    EXPECT_LE((d - wr.delassus()).norm(), 1e-9 * d.norm()) << pair.trial << ":" << pair.weighting;
  }
}

// The generalized Jacobian of φ(λ) = min(cλ, g0 − u(λ))/s_r against central differences, at
// states away from the kinks (each row is then linear in λ), on both branches.
TEST(RigidContact, SignoriniJacobianMatchesFiniteDifferences) {
  const RigidCase1 c;
  const int m = 32;
  for (const Pair& pair : {Pair{"fourier", "fourier"}, Pair{"haar", "bspline"}}) {
    const solvers::WeightedResidual wr(c.system, c.forcing, c.stop, TimeBasis::from_name(pair.trial, m),
                                       TimeBasis::from_name(pair.weighting, m));
    const auto s = wr.solve();
    ASSERT_TRUE(s.converged());
    // Shift the converged forces so that neither branch ties: half the pushing instants get
    // more force (gap rows), the rest of the instants a small negative or positive force.
    Eigen::VectorXd lambda = spectral::stacked(s.contact_force_samples);
    for (Eigen::Index i = 0; i < lambda.size(); ++i) lambda(i) += (i % 2 == 0 ? 0.1 : -0.05) * s.max_contact_force;
    struct System {
      const solvers::WeightedResidual* wr;
      Eigen::VectorXd residual(const Eigen::VectorXd& l) const { return wr->signorini_residual(l); }
      Eigen::MatrixXd jacobian(const Eigen::VectorXd& l) const { return wr->signorini_jacobian(l).dense(); }
    };
    const solvers::LowRankJacobian j = wr.signorini_jacobian(lambda);
    EXPECT_GT(j.rank(), 0);
    EXPECT_FALSE(j.dense_form());
    wbm::testing::expect_jacobian_matches_fd(System{&wr}, lambda, 1e-7, 1e-6, s.max_contact_force);
  }
}

// The penalty laws approach the rigid stop as their stiffness grows: the linear penalty
// solution (another code path: sampled law, condensed coefficients, Woodbury Newton) moves
// towards the rigid solution by a factor of at least 3 per decade of stiffness.
TEST(RigidContact, PenaltySolutionsConvergeToTheRigidOne) {
  const RigidCase1 c;
  const int m = 256;
  const auto trial = TimeBasis::fourier(m);
  const Eigen::VectorXd tau = grid(1024);
  const auto rigid = solvers::WeightedResidual(c.system, c.forcing, c.stop, trial, trial).solve();
  ASSERT_TRUE(rigid.converged());
  const Eigen::VectorXd u_rigid = solvers::evaluate_trial(trial, rigid.coefficients, c.tip, tau, c.forcing.frequency_hz);
  std::vector<double> differences;
  for (double k : {1e8, 1e9, 1e10}) {
    solvers::WeightedResidualOptions o;
    o.time_samples = 4 * m;
    const auto penalty = solvers::WeightedResidual(
        c.system, c.forcing, {{c.tip, std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{k, c.gap})}},
        trial, trial, o).solve();
    ASSERT_TRUE(penalty.converged()) << penalty.report.message;
    differences.push_back(solvers::rms_relative_error(
        solvers::evaluate_trial(trial, penalty.coefficients, c.tip, tau, c.forcing.frequency_hz), u_rigid));
  }
  EXPECT_GT(differences[0] / differences[1], 3.0) << differences[0] << " " << differences[1];
  EXPECT_GT(differences[1] / differences[2], 3.0) << differences[1] << " " << differences[2];
  EXPECT_LT(differences[2], 1e-2);
}

// What the rigid law does not do is refused by name, never computed wrong.
TEST(RigidContact, RefusesWhatItCannotDo) {
  const RigidCase1 c;
  const auto fourier = TimeBasis::fourier(16);
  auto penalty = std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{1e9, c.gap});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] {
        (void)solvers::WeightedResidual(c.system, c.forcing, {c.stop[0], {c.tip - 1, penalty}}, fourier, fourier);
      },
      {"1 of the 2 contacts are exact", "make every contact exact", "the rigid ones a stiff LinearPenalty"});
  solvers::WeightedResidualOptions cell;
  cell.contact_quadrature = solvers::ContactQuadrature::CellAverage;
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)solvers::WeightedResidual(c.system, c.forcing, c.stop, fourier, fourier, cell); },
      {"cell-average", "Midpoint"});
  const solvers::WeightedResidual wr(c.system, c.forcing, c.stop, fourier, fourier);
  const Eigen::VectorXd x = Eigen::VectorXd::Zero(16);
  wbm::testing::expect_throw_with<std::logic_error>([&] { (void)wr.contact_residual(x); }, {"rigid stops", "signorini_residual"});
  wbm::testing::expect_throw_with<std::logic_error>([&] { (void)wr.residual(wr.linear_response()); }, {"rigid stops"});
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { (void)wr.signorini_residual(Eigen::VectorXd::Zero(3)); },
                                                    {"length 3", "n_c*M = 16"});
  // Stability with exact friction (rigid stops alone have it: test_impact_stability).
  const solvers::WeightedResidual friction(
      c.system, c.forcing,
      {c.stop[0], {c.tip - 5, std::make_shared<contact::CoulombFriction>(contact::CoulombParameters{0.3, 2.0})}},
      fourier, fourier);
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)solvers::trace_response(friction, {}); },
      {"exact Coulomb friction", "rigid-plastic", "stability = false", "stiff Jenkins element"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)solvers::integrate_to_periodic(c.system, c.forcing, c.stop); }, {"integrate_moreau_jean_to_periodic"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)solvers::integrate_moreau_jean_to_periodic(c.system, c.forcing, {{c.tip, penalty}}); },
      {"rigid stops", "integrate_to_periodic"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)solvers::floquet_multipliers(c.system, c.stop, Eigen::MatrixXd::Zero(1, 16), c.forcing.frequency_hz); },
      {"saltation", "not computed"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)solvers::contact_force(c.stop, Eigen::MatrixXd::Zero(c.system.dofs(), 4)); }, {"contact_force_samples"});
  solvers::MoreauJeanOptions o;
  o.steps_per_period = 1000;
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { o.validate(); }, {"steps_per_period = 1000", "multiple"});
  o = {};
  o.theta = 0.3;
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { o.validate(); }, {"theta", "[0.5, 1]"});
  const solvers::WeightedResidual penalised(c.system, c.forcing, {{c.tip, penalty}}, fourier, fourier);
  EXPECT_FALSE(penalised.rigid());
  wbm::testing::expect_throw_with<std::logic_error>([&] { (void)penalised.delassus(); }, {"penalty laws"});
}

// Over a period M ü + C u̇ averages to zero, so the mean contact force balances the static load
// of the mean displacement: f̄ e_tip = −K ū (the forcing has zero mean). Checked on the
// Moreau–Jean steady state (its impulses) and on the weighted residual solution (its
// multipliers, Fourier:Fourier), which also agree with each other.
TEST(RigidContact, MeanContactForceBalancesTheMeanStaticLoad) {
  const RigidCase1 c;
  solvers::MoreauJeanOptions o;
  o.steps_per_period = 1 << 16;
  const auto mj = solvers::integrate_moreau_jean_to_periodic(c.system, c.forcing, c.stop, o);
  ASSERT_TRUE(mj.report.converged());
  const Eigen::VectorXd mean_u = mj.displacement.rowwise().mean();
  const Eigen::VectorXd static_load = -(c.system.stiffness * mean_u);
  const double f_mj = mj.contact_force.row(0).mean();
  EXPECT_GT(f_mj, 0.0);
  // To the rectangle rule of the 1024 output samples on the kinked trajectory (the identity is
  // exact over the 65536 steps).
  EXPECT_NEAR(static_load(c.tip), f_mj, 1e-4 * f_mj);
  EXPECT_LE(static_load.head(c.tip).cwiseAbs().maxCoeff(), 1e-4 * f_mj);  // no load elsewhere

  const auto trial = TimeBasis::fourier(256);
  const auto s = solvers::WeightedResidual(c.system, c.forcing, c.stop, trial, trial).solve();
  ASSERT_TRUE(s.converged());
  const double f_wr = s.contact_force_samples.row(0).mean();
  const Eigen::VectorXd mean_a = s.coefficients.col(0);  // the constant function's coefficient
  EXPECT_NEAR(-(c.system.stiffness * mean_a)(c.tip), f_wr, 1e-9 * f_wr);
  EXPECT_NEAR(f_wr, f_mj, 2e-3 * f_mj);
}

// Near resonance (Case 2, 1275 Hz) the active-set iteration from λ = 0 cycles for DB6:DB6; the
// penalty homotopy then reaches the rigid solution, whose Signorini conditions hold when
// recomputed from the coefficients.
TEST(RigidContact, PenaltyHomotopyRescuesACyclingActiveSet) {
  const auto sc = models::load_scene("jl14_case2");
  const auto cp = sc.contact_points();
  const double g0 = cp.front().law->gap();
  const std::vector<solvers::ContactPoint> stop{{cp.front().dof, std::make_shared<contact::RigidStop>(g0)}};
  const auto db6 = TimeBasis::from_name("db6", 8);
  solvers::WeightedResidualOptions direct_only;
  direct_only.contact_homotopy = false;
  const auto direct = solvers::WeightedResidual(sc.system(), sc.harmonic_forcing(), stop, db6, db6, direct_only).solve();
  EXPECT_FALSE(direct.converged());  // the reason for the fallback
  const auto s = solvers::WeightedResidual(sc.system(), sc.harmonic_forcing(), stop, db6, db6).solve();
  ASSERT_TRUE(s.converged()) << s.report.message;
  EXPECT_EQ(s.path, solvers::SolutionPath::ContactHomotopy);
  EXPECT_TRUE(s.homotopy.reached());
  EXPECT_LE(s.complementarity, 1e-12 * g0);
  EXPECT_LE(s.collocation_penetration, 1e-12 * g0);
  EXPECT_GE(s.contact_force_samples.minCoeff(), -1e-9 * s.max_contact_force);
}

// ∂φ/∂f and ∂φ/∂s of the Signorini conditions against central differences through
// at_frequency (a new factorization of G) and the load argument.
TEST(RigidContact, ParameterDerivativesMatchFiniteDifferences) {
  const RigidCase1 c;
  const auto trial = TimeBasis::from_name("haar", 32);
  const auto weighting = TimeBasis::fourier(32);
  const solvers::WeightedResidual wr(c.system, c.forcing, c.stop, trial, weighting);
  const auto s = wr.solve();
  ASSERT_TRUE(s.converged());
  Eigen::VectorXd lambda = spectral::stacked(s.contact_force_samples);
  for (Eigen::Index i = 0; i < lambda.size(); ++i) lambda(i) += (i % 2 == 0 ? 0.1 : -0.05) * s.max_contact_force;
  const double f = c.forcing.frequency_hz, hf = 1e-4 * f;
  const Eigen::VectorXd fd_f =
      (wr.at_frequency(f + hf).signorini_residual(lambda) - wr.at_frequency(f - hf).signorini_residual(lambda)) / (2 * hf);
  const Eigen::VectorXd df = wr.signorini_frequency_derivative(lambda);
  EXPECT_GT(df.norm(), 0.0);
  EXPECT_LE((df - fd_f).norm(), 1e-6 * fd_f.norm());
  const double hs = 1e-6;
  const Eigen::VectorXd fd_s = (wr.signorini_residual(lambda, 1 + hs) - wr.signorini_residual(lambda, 1 - hs)) / (2 * hs);
  EXPECT_LE((wr.signorini_load_derivative(lambda) - fd_s).norm(), 1e-6 * fd_s.norm());
}

// The frequency response with the rigid stop by pseudo-arclength continuation (through the
// corners of the nonsmooth branch) passes through the points that solve() finds on its own at
// fixed frequencies, where the branch has one point per frequency.
TEST(RigidContact, ContinuationPassesThroughTheFixedFrequencySolves) {
  const RigidCase1 c;
  const auto trial = TimeBasis::fourier(32);
  const solvers::WeightedResidual base(c.system, c.forcing, c.stop, trial, trial);
  solvers::ResponseCurveOptions o;
  o.parameter_min = c.forcing.frequency_hz;
  o.parameter_max = 400.0;
  o.stability = false;
  o.max_parameter_step = 10.0;
  const auto curve = solvers::trace_response(base, o);
  ASSERT_EQ(curve.stop, solvers::StopReason::RangeReached) << curve.message;
  ASSERT_GE(curve.points.size(), 20U);
  EXPECT_DOUBLE_EQ(curve.points.back().frequency_hz, 400.0);
  for (double f : {200.0, 300.0, 400.0}) {
    const auto wr = base.at_frequency(f);
    const auto s = wr.solve();
    ASSERT_TRUE(s.converged());
    const Eigen::VectorXd u = solvers::evaluate_trial(trial, s.coefficients, c.tip, grid(1024), f);
    const double amplitude = 0.5 * (u.maxCoeff() - u.minCoeff());
    // The branch between its first two points around f, linearly.
    EXPECT_NEAR(wbm::testing::branch_amplitude_at(curve, f), amplitude, 2e-3 * amplitude) << f << " Hz";
  }
}

// The closed-form orbit exists for these parameters (the mass leaves, stays below the stop in
// flight, and lands within the sticking window), and Moreau–Jean with e = 0 converges to it at
// first order in the step (the velocity jump at the impact). The discrete orbit is not exactly
// periodic: the mass rests on the stop at a penetration of order h|u̇| that differs from one
// impact to the next, so δ stalls near the discretization error instead of reaching 1e-7; the
// test takes period 100 and checks that δ is no larger than the error against the closed form.
TEST(MoreauJean, PlasticImpactOscillatorConvergesToTheClosedFormOrbit) {
  const wbm::testing::PlasticImpactOscillator o;
  const double period = 1.0 / o.f;
  ASSERT_GT(o.t_impact, o.t1 + 0.25 * period);
  ASSERT_LT(o.t_impact, o.t1 + period);
  EXPECT_GE(o.omega * (o.t_impact - period), -std::acos(o.k * o.gap / o.amplitude));  // lands while the load pushes
  for (int i = 1; i < 1000; ++i) {
    EXPECT_LT(o.flight(o.t1 + (o.t_impact - o.t1) * i / 1000.0), o.gap);
  }
  const int p = 1024;
  Eigen::VectorXd exact(p);
  for (int i = 0; i < p; ++i) exact(i) = o.displacement(static_cast<double>(i) / p);
  const std::vector<solvers::ContactPoint> stop{{0, std::make_shared<contact::RigidStop>(o.gap)}};
  std::vector<double> h, errors;
  for (int steps : {1 << 12, 1 << 14, 1 << 16}) {
    solvers::MoreauJeanOptions options;
    options.steps_per_period = steps;
    options.samples_per_period = p;
    options.max_periods = 100;
    const auto r = solvers::integrate_moreau_jean_to_periodic(o.system(), {0, o.amplitude, o.f}, stop, options);
    ASSERT_EQ(r.report.periods, 100);
    h.push_back(1.0 / steps);
    errors.push_back(solvers::rms_relative_error(r.displacement.row(0).transpose(), exact));
    EXPECT_LT(r.report.periodicity.back(), 1.5 * errors.back()) << steps;
    EXPECT_LT(r.displacement.maxCoeff() - o.gap, 0.01 * o.gap) << steps;  // at the stop, within a step's penetration
  }
  // Measured: 2.2e-3, 4.9e-4, 1.8e-4 (order 0.9).
  EXPECT_NEAR(wbm::testing::observed_order(h, errors), 1.0, 0.3);
  EXPECT_LT(errors.back(), 3e-4);
}
