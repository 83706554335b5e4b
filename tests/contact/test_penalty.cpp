#include <wbm/contact/penalty.hpp>

#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

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

// A law behind a spring of flexibility c: y + c f(y) = s. For a linear law k it is the series
// spring k/(1 + ck) (force, stiffness and potential in closed form); for the exponential law the
// node position solves its equation, the stiffness is the derivative of the force and the
// potential's derivative is the force (central differences).
namespace {
// A law whose force overflows: f(u) = k (e^{α(u − g)} − 1) with no linear extension (α = 1e4 /m:
// inf from u − g > 0.071 m).
struct Unbounded final : ContactLaw {
  double force(double u) const override { return u <= 1e-3 ? 0.0 : 1e6 * std::expm1(1e4 * (u - 1e-3)); }
  double stiffness(double u) const override { return u <= 1e-3 ? 0.0 : 1e10 * std::exp(1e4 * (u - 1e-3)); }
  double potential(double u) const override { return u <= 1e-3 ? 0.0 : 1e2 * std::expm1(1e4 * (u - 1e-3)) - 1e6 * (u - 1e-3); }
  double gap() const override { return 1e-3; }
  std::string describe() const override { return "unbounded exponential"; }
};
}  // namespace

// Where the inner force overflows at s itself, the node position is still the root of
// y + c f(y) = s (Brent's bracket is first shrunk to where the force is finite).
TEST(SeriesCompliance, SolvesTheNodePositionWhereTheInnerForceOverflowsAtS) {
  const auto law = std::make_shared<Unbounded>();
  const double c = 1e-8;
  const SeriesCompliance series(law, c);
  for (double s : {0.2, 1.0, 1e3}) {
    ASSERT_FALSE(std::isfinite(law->force(s))) << s;
    const double y = series.node_position(s);
    EXPECT_GT(y, 1e-3);
    EXPECT_LT(y, 0.071);
    // |y − y*| ≤ 1e-15 (|s| + |g0|) (the documented bracket), so the residual is within the
    // slope 1 + c f'(y) times that, plus the rounding of s.
    const double bound = 2.0 * (1.0 + c * law->stiffness(y)) * 1e-15 * (s + 1e-3) + 4.0 * std::numeric_limits<double>::epsilon() * s;
    EXPECT_LE(std::abs(y + c * law->force(y) - s), bound) << s;
  }
}

TEST(SeriesCompliance, IsTheLawInSeriesWithTheSpring) {
  const double c = 1e-8;  // a 1e8 N/m spring
  const auto linear = std::make_shared<LinearPenalty>(LinearPenaltyParameters{3e8, 1e-3});
  const SeriesCompliance through(linear, c);
  const double k = 3e8 / (1.0 + c * 3e8);
  for (double s : {-1e-3, 0.0, 1e-3, 1.5e-3, 4e-3}) {
    const double d = std::max(s - 1e-3, 0.0);
    EXPECT_NEAR(through.force(s), k * d, 1e-12 * k * 3e-3) << s;
    EXPECT_NEAR(through.stiffness(s), d > 0 ? k : 0.0, 1e-9 * k) << s;
    EXPECT_NEAR(through.potential(s), 0.5 * k * d * d, 1e-12 * k * 1e-5 + 1e-18) << s;
  }
  const auto exponential = std::make_shared<ExponentialPenalty>(kCase1);
  const SeriesCompliance series(exponential, c);
  for (double s : {0.5e-3, 1e-3, 1.02e-3, 1.1e-3, 1.5e-3, 3e-3}) {
    const double y = series.node_position(s);
    EXPECT_NEAR(y + c * exponential->force(y), s, 1e-14) << s;
    EXPECT_LE(y, s);
    EXPECT_NEAR(series.force(s), exponential->force(y), 1e-12 * (1.0 + series.force(s))) << s;
    const double h = 1e-9;
    if (std::abs(s - 1e-3) > 2 * h) {
      EXPECT_NEAR(series.stiffness(s), central([&](double v) { return series.force(v); }, s, h),
                  1e-5 * (1.0 + series.stiffness(s))) << s;
      EXPECT_NEAR(series.force(s), central([&](double v) { return series.potential(v); }, s, h),
                  1e-5 * (1.0 + series.force(s))) << s;
    }
  }
  // Far in: the node barely moves past the gap and the force approaches the spring's (s − y)/c.
  EXPECT_NEAR(series.force(0.1), (0.1 - series.node_position(0.1)) / c, 1e-9 * series.force(0.1));
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { (void)SeriesCompliance(linear, 0.0); },
                                                         {"SeriesCompliance.flexibility (c) = 0", "> 0 [m/N]"});
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { (void)SeriesCompliance(nullptr, c); },
                                                         {"SeriesCompliance: the inner law is null"});
}
