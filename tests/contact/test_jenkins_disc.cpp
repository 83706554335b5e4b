// The Jenkins element with two tangents (contact/jenkins_disc.hpp). Truths not produced by this
// code:
//   - the closed-form steady state on a circular orbit of radius a > F_s/k_t: |f| = F_s, the slider
//     on the circle r_s = √(a² − (F_s/k_t)²), the force ahead of w by π/2 − atan(F_s/(k_t r_s)),
//     the energy 2π r_s F_s per cycle; approached at first order in 1/Q (backward Euler turns the
//     slip direction one step late);
//   - along a line the element is jenkins_loop (an independent 1D return map): forces, energy and
//     ∂f/∂w along the line;
//   - full stick f = k_t w below the threshold; a steady slide δ per period: |f| = F_s along δ,
//     energy F_s |δ|;
//   - central differences of the force in every sample of w and of the slip force;
//   - near the threshold, the plain return map written in the test, iterated to its fixed point.
#include <wbm/contact/friction.hpp>
#include <wbm/contact/jenkins_disc.hpp>

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "testing.hpp"

using wbm::contact::jenkins_disc_loop;
using wbm::contact::JenkinsDiscLoop;
using wbm::testing::kPi;

namespace {

constexpr double kKt = 1e4, kFs = 10.0;  // N/m, N: F_s/k_t = 1 mm

Eigen::MatrixXd circle(int q, double a) {
  Eigen::MatrixXd w(2, q);
  for (int i = 0; i < q; ++i) {
    const double t = 2.0 * kPi * i / q;
    w(0, i) = a * std::cos(t);
    w(1, i) = a * std::sin(t);
  }
  return w;
}

Eigen::VectorXd constant_load(Eigen::Index q) { return Eigen::VectorXd::Constant(q, kFs); }

// Central differences of the loop's forces in every entry of w (2Q × 2Q, tangent-major).
Eigen::MatrixXd displacement_differences(const Eigen::MatrixXd& w, const Eigen::VectorXd& fs, double h) {
  const Eigen::Index q = w.cols();
  Eigen::MatrixXd d(2 * q, 2 * q);
  for (int j = 0; j < 2; ++j) {
    for (Eigen::Index r = 0; r < q; ++r) {
      Eigen::MatrixXd wp = w, wm = w;
      wp(j, r) += h;
      wm(j, r) -= h;
      const Eigen::MatrixXd df = (jenkins_disc_loop(kKt, wp, fs).force - jenkins_disc_loop(kKt, wm, fs).force) / (2 * h);
      for (int i = 0; i < 2; ++i) d.block(i * q, j * q + r, q, 1) = df.row(i).transpose();
    }
  }
  return d;
}

}  // namespace

TEST(JenkinsDisc, ACircularOrbitApproachesTheClosedFormSteadySlipAtFirstOrder) {
  const double a = 2.0 * kFs / kKt;
  const double rs = std::sqrt(a * a - kFs * kFs / (kKt * kKt));
  const double energy = 2.0 * kPi * rs * kFs, lag = kPi / 2.0 - std::atan(kFs / (kKt * rs));
  double previous_energy = 0.0, previous_lag = 0.0;
  for (int q : {128, 512, 2048}) {
    const JenkinsDiscLoop l = jenkins_disc_loop(kKt, circle(q, a), constant_load(q));
    EXPECT_EQ(l.slipping_samples, q);
    for (int i = 0; i < q; ++i) EXPECT_NEAR(l.force.col(i).norm(), kFs, 1e-12 * kFs);
    const double angle = std::atan2(l.force(1, 0), l.force(0, 0));  // w_0 lies along +x
    const double e_energy = std::abs(l.dissipated_energy - energy) / energy, e_lag = std::abs(angle - lag);
    std::printf("Q = %d: energy %.3e, lag %.3e rad from the closed form\n", q, e_energy, e_lag);
    EXPECT_LT(e_energy, 4.0 / q);
    EXPECT_LT(e_lag, 8.0 / q);
    if (previous_energy > 0.0) {  // first order: ×4 the samples, ÷4 the error
      EXPECT_NEAR(previous_energy / e_energy, 4.0, 0.3);
      EXPECT_NEAR(previous_lag / e_lag, 4.0, 0.3);
    }
    previous_energy = e_energy;
    previous_lag = e_lag;
  }
}

TEST(JenkinsDisc, AlongALineItIsTheJenkinsElementOfOneTangent) {
  const int q = 96;
  const double phi = 0.3, a = 2.0 * kFs / kKt;
  const Eigen::Vector2d e(std::cos(phi), std::sin(phi));
  Eigen::VectorXd s(q);
  for (int i = 0; i < q; ++i) s(i) = a * std::cos(2.0 * kPi * i / q) + 0.3 * a * std::sin(4.0 * kPi * i / q);
  const Eigen::MatrixXd w = e * s.transpose();
  const JenkinsDiscLoop l = jenkins_disc_loop(kKt, w, constant_load(q));
  const wbm::contact::JenkinsLoop line = wbm::contact::jenkins_loop(kKt, s, constant_load(q));
  ASSERT_GT(line.slipping_samples, 0);
  EXPECT_EQ(l.slipping_samples, line.slipping_samples);
  EXPECT_NEAR(l.dissipated_energy, line.dissipated_energy, 1e-12 * line.dissipated_energy);
  // ∂f/∂w along e: eᵀ (∂f/∂w) e per pair of samples, against the 1D element's k_t in stick and
  // −k_t at the last slip (its documented sparse form).
  for (int i = 0; i < q; ++i) {
    EXPECT_NEAR(e.dot(l.force.col(i)), line.force(i), 1e-12 * kFs);
    EXPECT_NEAR(e(1) * l.force(0, i) - e(0) * l.force(1, i), 0.0, 1e-12 * kFs);  // no force across the line
    for (int r = 0; r < q; ++r) {
      double along = 0.0;
      for (int m = 0; m < 2; ++m) {
        for (int n = 0; n < 2; ++n) along += e(m) * l.jacobian(m * q + i, n * q + r) * e(n);
      }
      const double expected = (r == i ? line.stiffness(i) : 0.0) - (r == line.anchor(i) ? kKt : 0.0);
      EXPECT_NEAR(along, expected, 1e-8 * kKt) << "sample " << i << ", column " << r;
    }
  }
}

TEST(JenkinsDisc, BelowTheThresholdItSticksWithTheSpringAlone) {
  const int q = 32;
  const Eigen::MatrixXd w = circle(q, 0.8 * kFs / kKt);
  const JenkinsDiscLoop l = jenkins_disc_loop(kKt, w, constant_load(q));
  EXPECT_EQ(l.slipping_samples, 0);
  EXPECT_LT((l.force - kKt * w).cwiseAbs().maxCoeff(), 1e-12 * kFs);
  EXPECT_LT((l.jacobian - kKt * Eigen::MatrixXd::Identity(2 * q, 2 * q)).cwiseAbs().maxCoeff(), 1e-12 * kKt);
  EXPECT_EQ(l.dissipated_energy, 0.0);
}

TEST(JenkinsDisc, ASteadySlideSaturatesTheForceAlongIt) {
  const int q = 32;
  for (const double size : {5.0, 1e-3}) {  // a slide of 5 widths per period, and one of a thousandth
    const Eigen::Vector2d slide = size * kFs / kKt * Eigen::Vector2d(0.6, 0.8);
    Eigen::MatrixXd w(2, q);
    for (int i = 0; i < q; ++i) w.col(i) = slide * i / q;  // w + δ τ: the next period continues the ramp
    const JenkinsDiscLoop l = jenkins_disc_loop(kKt, w, constant_load(q), 64, slide);
    EXPECT_EQ(l.slipping_samples, q);
    EXPECT_NEAR(l.dissipated_energy, kFs * slide.norm(), 1e-9 * kFs * slide.norm());
    for (int i = 0; i < q; ++i) EXPECT_LT((l.force.col(i) - kFs * slide.normalized()).norm(), 1e-9 * kFs);
  }
}

TEST(JenkinsDisc, ItsDerivativesAreCentralDifferencesOfTheLoop) {
  // A stick–slip orbit (an ellipse with a second harmonic and an offset) under a varying slip force.
  const int q = 40;
  const double a = 2.0 * kFs / kKt;
  Eigen::MatrixXd w(2, q);
  Eigen::VectorXd fs(q);
  for (int i = 0; i < q; ++i) {
    const double t = 2.0 * kPi * i / q;
    w(0, i) = a * std::cos(t) + 0.5 * a * std::cos(2.0 * t);
    w(1, i) = 0.6 * a * std::sin(t) + 0.2 * a;
    fs(i) = kFs * (1.0 + 0.3 * std::cos(t + 0.4));
  }
  const JenkinsDiscLoop l = jenkins_disc_loop(kKt, w, fs);
  ASSERT_GT(l.slipping_samples, 0);
  ASSERT_LT(l.slipping_samples, q);
  const Eigen::MatrixXd dw = displacement_differences(w, fs, 1e-7 * a);
  EXPECT_LT((dw - l.jacobian).cwiseAbs().maxCoeff(), 1e-8 * kKt);
  Eigen::MatrixXd df(2 * q, q);
  const double h = 1e-7 * kFs;
  for (int r = 0; r < q; ++r) {
    Eigen::VectorXd up = fs, down = fs;
    up(r) += h;
    down(r) -= h;
    const Eigen::MatrixXd d = (jenkins_disc_loop(kKt, w, up).force - jenkins_disc_loop(kKt, w, down).force) / (2 * h);
    for (int i = 0; i < 2; ++i) df.block(i * q, r, q, 1) = d.row(i).transpose();
  }
  EXPECT_LT((df - l.load_jacobian).cwiseAbs().maxCoeff(), 1e-7);
}

TEST(JenkinsDisc, ItReachesItsFixedPointNearTheThresholdWhereThePeriodMapBarelyContracts) {
  // On a circle of radius a → F_s/k_t the plain period map contracts by exp(−2π r_s k_t/F_s) ≈ 1.
  // The slow reference: the return map written out here, iterated period after period from the
  // unstretched spring until the force at the period's end stops moving (thousands of periods).
  const int q = 128;
  const double a = 1.0001 * kFs / kKt;
  const Eigen::MatrixXd w = circle(q, a);
  const JenkinsDiscLoop l = jenkins_disc_loop(kKt, w, constant_load(q), 16);
  EXPECT_LE(l.periods, 16);
  EXPECT_EQ(l.slipping_samples, q);
  Eigen::MatrixXd f = Eigen::MatrixXd::Zero(2, q);
  Eigen::Vector2d state = Eigen::Vector2d::Zero(), w_prev = Eigen::Vector2d::Zero();
  int periods = 0;
  for (double change = 1.0; change > 1e-13 * kFs && periods < 100000; ++periods) {
    const Eigen::Vector2d start = state;
    for (int i = 0; i < q; ++i) {
      const Eigen::Vector2d trial = state + kKt * (w.col(i) - w_prev);
      state = trial.norm() > kFs ? Eigen::Vector2d(kFs * trial.normalized()) : trial;
      w_prev = w.col(i);
      f.col(i) = state;
    }
    change = (state - start).norm();
  }
  std::printf("near the threshold: %d period evaluations against %d plain periods\n", l.periods, periods);
  EXPECT_GT(periods, 10 * l.periods);  // the plain map is slow here
  EXPECT_LT((l.force - f).cwiseAbs().maxCoeff(), 1e-10 * kFs);
}

TEST(JenkinsDisc, BadArgumentsAreNamed) {
  const Eigen::MatrixXd w = circle(8, 1e-3);
  const auto message = [](auto&& call) {
    try {
      call();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(message([&] { (void)jenkins_disc_loop(0.0, w, constant_load(8)); }).find("tangential_stiffness"),
            std::string::npos);
  EXPECT_NE(message([&] { (void)jenkins_disc_loop(kKt, w.topRows(1), constant_load(8)); }).find("2 rows"),
            std::string::npos);
  EXPECT_NE(message([&] { (void)jenkins_disc_loop(kKt, w, constant_load(7)); }).find("slip_force"),
            std::string::npos);
  EXPECT_NE(message([&] { (void)jenkins_disc_loop(kKt, w, -constant_load(8)); }).find("slip_force[0]"),
            std::string::npos);
  const wbm::contact::JenkinsDiscLaw law({kKt, 0.3, 10.0});
  Eigen::VectorXd f(8), k(8);
  Eigen::VectorXi anchor(8);
  EXPECT_THROW(law.evaluate_period(w.row(0).transpose(), f, k, anchor), std::logic_error);
  EXPECT_THROW((void)law.force(0.0), std::logic_error);
  EXPECT_NE(message([&] { (void)law.loop(w, Eigen::VectorXd::Constant(3, 1.0)); }).find("normal has 3"),
            std::string::npos);
}
