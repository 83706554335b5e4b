// Static condensation of massless DOFs (solvers/condensation.hpp) against closed forms: series
// springs, the condensed model's natural frequencies, and the static equilibrium of every
// massless DOF in a solved forced response with a stop behind a spring.
#include <wbm/solvers/condensation.hpp>

#include <cmath>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <vector>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <wbm/contact/penalty.hpp>
#include <wbm/contact/signorini.hpp>
#include <wbm/solvers/post_processing.hpp>
#include <wbm/solvers/weighted_residual.hpp>

#include "testing.hpp"

using namespace wbm;

namespace {

Eigen::SparseMatrix<double> sparse(const Eigen::MatrixXd& a) { return a.sparseView(); }

// DOFs: x1 (m), n (massless), x2 (m), c (massless contact node on x2).
// Springs: k0 from x1 and x2 to ground, k1 x1–n, k2 n–x2, kc x2–c; dashpot d on x1.
constexpr double kMass = 2.0, kK0 = 1e4, kK1 = 3e4, kK2 = 6e4, kKc = 5e4, kD = 3.0;

solvers::MechanicalSystem chain() {
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(4, 4), k = Eigen::MatrixXd::Zero(4, 4), c = Eigen::MatrixXd::Zero(4, 4);
  m(0, 0) = kMass;
  m(2, 2) = kMass;
  auto spring = [&](int i, int j, double s) {
    k(i, i) += s;
    if (j >= 0) {
      k(j, j) += s;
      k(i, j) -= s;
      k(j, i) -= s;
    }
  };
  spring(0, -1, kK0);
  spring(2, -1, kK0);
  spring(0, 1, kK1);
  spring(1, 2, kK2);
  spring(2, 3, kKc);
  c(0, 0) = kD;
  return {sparse(m), sparse(c), sparse(k)};
}

}  // namespace

// Without contact: the junction n is the series spring k_s = k1 k2/(k1 + k2) between x1 and x2,
// n = (k1 x1 + k2 x2)/(k1 + k2), and c follows x2. The condensed model's natural frequencies
// are those of two equal masses on k0 coupled by k_s: √(k0/m) and √((k0 + 2k_s)/m).
TEST(MasslessCondensation, SeriesSpringsAndNaturalFrequencies) {
  const auto r = solvers::condense_massless(chain(), {}, {0});
  EXPECT_EQ(r.retained, (std::vector<int>{0, 2}));
  EXPECT_EQ(r.massless, (std::vector<int>{1, 3}));
  const double ks = kK1 * kK2 / (kK1 + kK2);
  const Eigen::MatrixXd k(r.system.stiffness);
  EXPECT_NEAR(k(0, 0), kK0 + ks, 1e-10 * ks);
  EXPECT_NEAR(k(0, 1), -ks, 1e-10 * ks);
  EXPECT_NEAR(k(1, 1), kK0 + ks, 1e-10 * ks);
  EXPECT_NEAR(r.transfer(0, 0), kK1 / (kK1 + kK2), 1e-14);
  EXPECT_NEAR(r.transfer(0, 1), kK2 / (kK1 + kK2), 1e-14);
  EXPECT_NEAR(r.transfer(1, 0), 0.0, 1e-14);
  EXPECT_NEAR(r.transfer(1, 1), 1.0, 1e-14);
  EXPECT_NEAR(Eigen::MatrixXd(r.system.damping)(0, 0), kD, 0.0);
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(k, Eigen::MatrixXd(r.system.mass));
  EXPECT_NEAR(std::sqrt(eig.eigenvalues()(0)), std::sqrt(kK0 / kMass), 1e-10);
  EXPECT_NEAR(std::sqrt(eig.eigenvalues()(1)), std::sqrt((kK0 + 2 * ks) / kMass), 1e-10);
  Eigen::MatrixXd um(2, 1);
  um << 1e-3, -2e-3;
  const Eigen::MatrixXd u = r.expand_displacement(um);
  EXPECT_NEAR(u(1, 0), (kK1 * 1e-3 - kK2 * 2e-3) / (kK1 + kK2), 1e-18);
  EXPECT_NEAR(u(3, 0), -2e-3, 1e-18);
}

// A stop behind a spring: exponential law on c (direction −1), forced response by harmonic
// balance on the condensed model, then every massless row of the full equations,
// (K u)_s + e_s f_c = 0, holds at every sample of the recovered motion; a rigid stop behind kc
// is the penalty kc itself.
TEST(MasslessCondensation, RecoveredMasslessDofsAreInStaticEquilibrium) {
  const auto law = std::make_shared<contact::ExponentialPenalty>(contact::ExponentialPenaltyParameters{1e3, 2e3, 2e-4});
  const std::vector<solvers::ContactPoint> contacts = {{3, law, -1, {{3, -1.0}}}};
  const auto full = chain();
  const auto r = solvers::condense_massless(full, contacts, {0});
  ASSERT_EQ(r.contacts.size(), 1u);
  EXPECT_EQ(r.contacts[0].terms(), (std::vector<std::pair<int, double>>{{1, -1.0}}));
  const auto tb = solvers::TimeBasis::fourier_harmonics(16);
  const auto solution = solvers::solve_weighted_residual(r.system, {0, 40.0, 12.0}, r.contacts, tb, tb);
  ASSERT_TRUE(solution.report.converged()) << solution.report.message;
  const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(200, 0.0, 199.0 / 200.0);
  const auto fields = solvers::evaluate_fields(tb, solution.coefficients, tau, 12.0);
  ASSERT_GT(solvers::contact_force(r.contacts, fields.displacement).maxCoeff(), 10.0);  // the stop is met
  const Eigen::MatrixXd u = r.expand_displacement(fields.displacement);
  const Eigen::MatrixXd k(full.stiffness);
  for (Eigen::Index p = 0; p < tau.size(); ++p) {
    const double fc = law->force(-u(3, p));
    EXPECT_NEAR((k.row(1) * u.col(p))(0), 0.0, 1e-9 * kK1 * u.col(p).cwiseAbs().maxCoeff()) << p;
    EXPECT_NEAR((k.row(3) * u.col(p))(0) - fc, 0.0, 1e-9 * (fc + kKc * u.col(p).cwiseAbs().maxCoeff())) << p;
  }
  // Velocities: the massless rows' time derivative (K v)_s + e_s f_c' u̇_c = 0, by the chain rule.
  const Eigen::MatrixXd v = r.expand_velocity(fields.displacement, fields.velocity);
  for (Eigen::Index p = 0; p < tau.size(); ++p) {
    const double dfc = law->stiffness(-u(3, p)) * -v(3, p);
    EXPECT_NEAR((k.row(3) * v.col(p))(0) - dfc, 0.0, 1e-8 * (std::abs(dfc) + kKc * v.col(p).cwiseAbs().maxCoeff())) << p;
  }
  const std::vector<solvers::ContactPoint> rigid = {{3, std::make_shared<contact::RigidStop>(2e-4), -1, {{3, 1.0}}}};
  const auto rr = solvers::condense_massless(full, rigid, {0});
  EXPECT_NEAR(rr.contacts[0].law->stiffness(1.0), kKc, 1e-9 * kKc);
  EXPECT_FALSE(rr.contacts[0].law->rigid());
}

TEST(MasslessCondensation, RefusesWhatIsNotStatic) {
  const auto law = std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{1e5, 1e-3});
  const auto full = chain();
  using wbm::testing::expect_throw_with;
  expect_throw_with<std::invalid_argument>([&] { (void)solvers::condense_massless(full, {}, {1}); },
                                           {"the force acts on the massless DOF DOF 1; force a DOF with mass"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)solvers::condense_massless(full, {{0, law, 1}}, {0}, {"x1", "n", "x2", "c"}); },
      {"involves the massless DOF n and other DOFs"});
  // x (mass), a and b massless: springs x–a, a–b, b–ground; stops on a and b share the a–b spring.
  Eigen::MatrixXd m3 = Eigen::MatrixXd::Zero(3, 3), k3(3, 3);
  m3(0, 0) = 1.0;
  k3 << 1e4, -1e4, 0.0, -1e4, 3e4, -2e4, 0.0, -2e4, 5e4;
  const solvers::MechanicalSystem coupled{sparse(m3), Eigen::SparseMatrix<double>(3, 3), sparse(k3)};
  expect_throw_with<std::invalid_argument>(
      [&] { (void)solvers::condense_massless(coupled, {{1, law}, {2, law}}, {0}, {"x", "a", "b"}); },
      {"the massless contact DOFs b and a are coupled through springs"});
  EXPECT_NO_THROW((void)solvers::condense_massless(coupled, {{1, law}}, {0}));  // one of them alone is fine
  auto damped = full;
  damped.damping = sparse(Eigen::MatrixXd(full.stiffness) * 1e-4);
  expect_throw_with<std::invalid_argument>([&] { (void)solvers::condense_massless(damped, {}, {0}); },
                                           {"C has an entry at", "on a massless DOF"});
  auto all = full;
  all.mass = Eigen::SparseMatrix<double>(4, 4);
  expect_throw_with<std::invalid_argument>([&] { (void)solvers::condense_massless(all, {}, {}); }, {"no DOF has mass"});
}
