// Rigid stops continued piece by piece (SignoriniResponseFamily, response_curve.hpp), against
// truths from outside the code: central differences of each piece's residual, the gaps recomputed
// from the full coefficients (not through the Delassus operator), the min/max identity of a
// piece and its events, fixed-frequency solves the branch must pass through, and the same branch
// after a rounding-level change of the input.
#include <wbm/solvers/response_curve.hpp>

#include <cmath>
#include <memory>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include <wbm/contact/friction.hpp>
#include <wbm/contact/signorini.hpp>
#include <wbm/solvers/post_processing.hpp>
#include <wbm/spectral/layout.hpp>

#include "shipped_scenes.hpp"
#include "testing.hpp"
#include "weighted_residual_fixtures.hpp"

using namespace wbm;
using solvers::ActiveSet;
using solvers::TimeBasis;

namespace {

// Case 1 of [JL14 Table 1] with its exponential penalty replaced by a rigid stop at the same gap.
struct RigidRod {
  explicit RigidRod(const char* name = "jl14_case1") : scene(models::load_scene(name)) {}
  scene::Scene scene;
  solvers::MechanicalSystem system = scene.system();
  solvers::HarmonicForcing forcing = scene.harmonic_forcing();
  double gap = scene.contact_points().front().law->gap();
  int tip = scene.contact_points().front().dof;
  std::vector<solvers::ContactPoint> stop{{tip, std::make_shared<contact::RigidStop>(gap)}};
};

// The converged impulses shifted so that no row ties: half the instants get more force, the rest
// a small negative or positive one.
Eigen::VectorXd off_the_kinks(const solvers::WeightedResidualSolution& s) {
  Eigen::VectorXd lambda = spectral::stacked(s.contact_force_samples);
  for (Eigen::Index i = 0; i < lambda.size(); ++i) lambda(i) += (i % 2 == 0 ? 0.1 : -0.05) * s.max_contact_force;
  return lambda;
}

}  // namespace

// On a fixed piece the residual is affine in λ and smooth in f and in the load: its Jacobian and
// parameter derivatives against central differences, on a piece that is not the min's (every
// third entry flipped), for both continuation parameters.
TEST(RigidContinuation, PieceLinearizationMatchesFiniteDifferences) {
  const RigidRod c;
  const int m = 32;
  for (const char* name : {"fourier", "bspline"}) {
    const solvers::WeightedResidual wr(c.system, c.forcing, c.stop, TimeBasis::from_name(name, m),
                                       TimeBasis::from_name(name, m));
    const auto s = wr.solve();
    ASSERT_TRUE(s.converged()) << s.report.message;
    const Eigen::VectorXd lambda = off_the_kinks(s);
    ActiveSet piece = wr.signorini_active_set(lambda);
    for (size_t i = 0; i < piece.size(); i += 3) piece[i] ^= 1U;
    for (auto parameter : {solvers::ContinuationParameter::Frequency, solvers::ContinuationParameter::Amplitude}) {
      const solvers::ForcedResponseFamily family(wr, parameter);
      const solvers::SignoriniResponseFamily pieces(family);
      const double p0 = parameter == solvers::ContinuationParameter::Frequency ? wr.frequency_hz()
                                                                                 : 0.8 * wr.forcing().amplitude;
      const auto lin = pieces.linearize(lambda, p0, piece);
      struct OnPiece {
        const solvers::SignoriniResponseFamily* p;
        double p0;
        const ActiveSet* piece;
        Eigen::VectorXd residual(const Eigen::VectorXd& l) const { return p->residual(l, p0, *piece); }
        Eigen::MatrixXd jacobian(const Eigen::VectorXd& l) const { return p->linearize(l, p0, *piece).jacobian.dense(); }
      };
      wbm::testing::expect_jacobian_matches_fd(OnPiece{&pieces, p0, &piece}, lambda, 1e-7, 1e-6, s.max_contact_force);
      const double h = 1e-5 * p0;
      const Eigen::VectorXd fd =
          (pieces.residual(lambda, p0 + h, piece) - pieces.residual(lambda, p0 - h, piece)) / (2.0 * h);
      EXPECT_GT(fd.norm(), 0.0);
      EXPECT_LE((lin.parameter_derivative - fd).norm(), 1e-6 * fd.norm()) << name;
    }
  }
}

// A piece and its events split the min and the max of the two Signorini rows: on the min's own
// piece the residual is the nonsmooth residual, and residual + event = (c λ + g)/s_r row by row,
// with the gaps g = g0 − u(τ_{k+1}) evaluated from the full coefficients (expand_forces and the
// trial functions), not through the Delassus operator the code uses.
TEST(RigidContinuation, PieceAndEventsAreTheMinAndTheMaxOfTheSignoriniRows) {
  const RigidRod c;
  const int m = 32;
  const auto trial = TimeBasis::from_name("haar", m);
  const solvers::WeightedResidual wr(c.system, c.forcing, c.stop, trial, TimeBasis::fourier(m));
  const auto s = wr.solve();
  ASSERT_TRUE(s.converged()) << s.report.message;
  const Eigen::VectorXd lambda = off_the_kinks(s);
  const ActiveSet piece = wr.signorini_active_set(lambda);
  const Eigen::VectorXd phi = wr.signorini_residual(lambda), on_piece = wr.signorini_residual(lambda, 1.0, &piece);
  const Eigen::VectorXd events = wr.signorini_events(lambda, 1.0, piece);
  const Eigen::VectorXd times = wr.collocation_times();
  Eigen::VectorXd next(m);
  for (int k = 0; k < m; ++k) next(k) = times((k + 1) % m);
  const Eigen::VectorXd u =
      solvers::evaluate_trial(trial, spectral::as_coefficients(wr.expand_forces(lambda), wr.dofs()), c.tip, next, 1.0);
  const double sr = wr.residual_scale(), compliance = wr.force_compliance();
  int touching = 0;
  for (int k = 0; k < m; ++k) {
    const double force = compliance * lambda(k) / sr, gap = (c.gap - u(k)) / sr;
    EXPECT_NEAR(on_piece(k), phi(k), 1e-12 * std::abs(phi(k)) + 1e-15) << k;
    EXPECT_NEAR(on_piece(k), std::min(force, gap), 1e-8 * (std::abs(force) + std::abs(gap))) << k;
    EXPECT_NEAR(events(k), std::max(force, gap), 1e-8 * (std::abs(force) + std::abs(gap))) << k;
    touching += piece[static_cast<size_t>(k)];
  }
  EXPECT_GT(touching, 0);
  EXPECT_LT(touching, m);
}

// The branch continued piece by piece passes through the solutions that solve() finds on its own
// at fixed frequencies; every impulse that starts or ends is an event (no corner is jumped and no
// step rejected at one), and a rounding-level change of the stiffness (1 + 1e-12) gives the same
// branch: its events and amplitudes.
TEST(RigidContinuation, BranchCrossesEveryChangeOfTheActiveInstantsAsAnEvent) {
  RigidRod c("jl14_case2");
  c.forcing.frequency_hz = 1000.0;
  const auto trial = TimeBasis::fourier(32);
  solvers::ResponseCurveOptions o;
  o.parameter_min = 1000.0;
  o.parameter_max = 1700.0;
  o.stability = false;
  o.max_parameter_step = 5.0;
  const solvers::WeightedResidual base(c.system, c.forcing, c.stop, trial, trial);
  const auto curve = solvers::trace_response(base, o);
  ASSERT_EQ(curve.stop, solvers::StopReason::RangeReached) << curve.message;
  EXPECT_GE(curve.events, 2);
  EXPECT_GE(curve.switches, curve.events);
  EXPECT_EQ(curve.kinks, 0);
  for (double f : {1200.0, 1400.0, 1600.0}) {
    const auto s = base.at_frequency(f).solve();
    ASSERT_TRUE(s.converged());
    const Eigen::VectorXd u = solvers::evaluate_trial(trial, s.coefficients, c.tip, Eigen::VectorXd::LinSpaced(1024, 0.0, 1023.0 / 1024), f);
    const double amplitude = 0.5 * (u.maxCoeff() - u.minCoeff());
    // The branch between its first two points around f, linearly.
    EXPECT_NEAR(wbm::testing::branch_amplitude_at(curve, f), amplitude, 2e-3 * amplitude) << f << " Hz";
  }
  c.system.stiffness *= 1.0 + 1e-12;
  const solvers::WeightedResidual nudged(c.system, c.forcing, c.stop, trial, trial);
  const auto again = solvers::trace_response(nudged, o);
  ASSERT_EQ(again.stop, solvers::StopReason::RangeReached) << again.message;
  EXPECT_EQ(again.events, curve.events);
  EXPECT_EQ(again.switches, curve.switches);
  ASSERT_EQ(again.points.size(), curve.points.size());
  for (size_t i = 0; i < curve.points.size(); ++i) {
    EXPECT_NEAR(again.points[i].amplitude, curve.points[i].amplitude, 1e-8 * curve.points[i].amplitude) << i;
  }
}

// What the pieces are not defined for is refused by name.
TEST(RigidContinuation, RefusesFrictionAndPiecesOfTheWrongLength) {
  const RigidRod c;
  const int m = 16;
  const auto basis = TimeBasis::fourier(m);
  const solvers::WeightedResidual stop(c.system, c.forcing, c.stop, basis, basis);
  const Eigen::VectorXd lambda = Eigen::VectorXd::Zero(m);
  const ActiveSet short_piece(m - 1, 0);
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)stop.signorini_residual(lambda, 1.0, &short_piece); }, {"piece", "length", "n_c*M"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)stop.signorini_events(lambda, 1.0, short_piece); }, {"piece", "length"});
  std::vector<solvers::ContactPoint> rubbing = c.stop;
  rubbing.push_back({c.tip - 1, std::make_shared<contact::CoulombFriction>(contact::CoulombParameters{0.3, 1.0})});
  const solvers::WeightedResidual with_friction(c.system, c.forcing, rubbing, basis, basis);
  const ActiveSet piece(2 * m, 0);
  wbm::testing::expect_throw_with<std::logic_error>(
      [&] { (void)with_friction.signorini_residual(Eigen::VectorXd::Zero(2 * m), 1.0, &piece); },
      {"friction", "without a piece"});
  wbm::testing::expect_throw_with<std::logic_error>(
      [&] { (void)with_friction.signorini_active_set(Eigen::VectorXd::Zero(2 * m)); }, {"signorini_active_set", "without friction"});
  const solvers::ForcedResponseFamily family(with_friction, solvers::ContinuationParameter::Frequency);
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { (void)solvers::SignoriniResponseFamily{family}; },
                                                         {"rigid stops", "without friction", "ForcedResponseFamily"});
}
