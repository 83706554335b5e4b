#include <wbm/contact/penalty.hpp>

#include <cmath>
#include <limits>
#include <stdexcept>

#include <gtest/gtest.h>

#include "testing.hpp"

using namespace wbm::contact;

namespace {
// Case 1 of [JL14 Table 1]: a_c = 1e8 N, α = 50 1/m, g0 = 1 mm.
const ExponentialPenaltyParameters kCase1{1e8, 50.0, 1e-3};

double central(const auto& f, double u, double h) { return (f(u + h) - f(u - h)) / (2 * h); }
}  // namespace

// Eq. (5) by hand at one point: a_c (e^{α(u−g0)} − 1).
TEST(ExponentialPenalty, MatchesEquation5) {
  const ExponentialPenalty law(kCase1);
  EXPECT_DOUBLE_EQ(law.force(0.5e-3), 0.0);
  EXPECT_DOUBLE_EQ(law.force(1e-3), 0.0);
  EXPECT_NEAR(law.force(1.2e-3), 1e8 * (std::exp(50.0 * 0.2e-3) - 1.0), 1e-6);
}

// Derivatives against central differences: stiffness = dF/du and force = dV/du, on both sides
// of contact and on both branches of the overflow guard.
TEST(ExponentialPenalty, StiffnessAndPotentialAreConsistent) {
  const ExponentialPenalty law({1e8, 500.0, 1e-3, 30.0});
  for (double pen : {-1e-4, 1e-5, 1e-3, 0.05, 0.059, 0.0601, 0.2}) {
    const double u = 1e-3 + pen;
    const double h = 1e-9;
    const double k_fd = central([&](double x) { return law.force(x); }, u, h);
    const double f_fd = central([&](double x) { return law.potential(x); }, u, h);
    EXPECT_NEAR(law.stiffness(u), k_fd, 1e-6 * std::max(1.0, std::abs(k_fd))) << "pen " << pen;
    EXPECT_NEAR(law.force(u), f_fd, 1e-6 * std::max(1.0, std::abs(f_fd))) << "pen " << pen;
  }
}

// Overflow guard: α = 500, penetration 10 m would be e^5000; the law stays finite, continuous
// and C¹ at x_lin, and grows linearly beyond it.
TEST(ExponentialPenalty, HugePenetrationStaysFiniteAndC1) {
  const ExponentialPenalty law({1e12, 500.0, 0.0, 30.0});
  EXPECT_TRUE(std::isfinite(law.force(10.0)));
  EXPECT_TRUE(std::isfinite(law.potential(10.0)));
  const double onset = law.linear_onset();
  EXPECT_NEAR(onset, 30.0 / 500.0, 1e-15);
  const double below = law.force(onset * (1 - 1e-12)), above = law.force(onset * (1 + 1e-12));
  EXPECT_NEAR(below, above, 1e-9 * above);
  EXPECT_DOUBLE_EQ(law.stiffness(onset * 2), law.stiffness(onset * 3));
}

// Negative gap = prestress: at u = 0 the stop already pushes with a_c (e^{−α g0} − 1).
TEST(ExponentialPenalty, NegativeGapPrestresses) {
  const ExponentialPenalty law({1e8, 20.0, -1e-3});
  EXPECT_NEAR(law.force(0.0), 1e8 * std::expm1(20.0 * 1e-3), 1e-6);
}

// NaN input must propagate (so that Newton reports NonFinite) instead of reading as "no contact".
TEST(ContactLaw, NanPropagates) {
  const ExponentialPenalty e(kCase1);
  const LinearPenalty l({1e9, 0.0});
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(std::isnan(e.force(nan)));
  EXPECT_TRUE(std::isnan(e.stiffness(nan)));
  EXPECT_TRUE(std::isnan(l.force(nan)));
  EXPECT_TRUE(std::isnan(l.stiffness(nan)));
}

TEST(LinearPenalty, IsAPiecewiseLinearSpring) {
  const LinearPenalty law({2e9, 1e-3});
  EXPECT_DOUBLE_EQ(law.force(0.5e-3), 0.0);
  EXPECT_DOUBLE_EQ(law.force(1.5e-3), 2e9 * 0.5e-3);
  EXPECT_DOUBLE_EQ(law.stiffness(1.5e-3), 2e9);
  EXPECT_DOUBLE_EQ(law.potential(1.5e-3), 0.5 * 2e9 * 0.25e-6);
}

TEST(ContactLaw, RejectsInvalidParameters) {
  using wbm::testing::expect_throw_with;
  expect_throw_with<std::invalid_argument>([] { ExponentialPenalty l({-1.0, 50.0, 0.0}); },
                                           {"coefficient", "> 0"});
  expect_throw_with<std::invalid_argument>([] { ExponentialPenalty l({1e8, 0.0, 0.0}); },
                                           {"exponent", "> 0"});
  expect_throw_with<std::invalid_argument>([] { ExponentialPenalty l({1e8, 50.0, 0.0, 800.0}); },
                                           {"linear_beyond", "(0, 700]"});
  expect_throw_with<std::invalid_argument>([] { LinearPenalty l({0.0, 0.0}); }, {"stiffness"});
}
