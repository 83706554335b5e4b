// Connection coefficients against published tables, closed forms and polynomial-reproduction
// identities. Convention: Γ^{d1,d2}[k] = ∫ φ^{(d1)}(t) φ^{(d2)}(t − k) dt.
#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include <wbm/wavelets/connection_coefficients.hpp>

#include "testing.hpp"

namespace ww = wbm::wavelets;

// Beylkin 1992, Table for M = 3 (DB6), derivative coefficients r_l = ∫ φ(x − l) φ'(x) dx, i.e.
// r_l = Γ^{0,1}[−l]: r_1 = −272/365, r_2 = 53/365, r_3 = −16/1095, r_4 = −1/2920 [B92].
TEST(ConnectionCoefficients, Db6FirstDerivativeMatchesBeylkin1992) {
  const auto g = ww::connection_coefficients(ww::Family::daubechies(6), 0, 1);
  const double r[] = {-272.0 / 365.0, 53.0 / 365.0, -16.0 / 1095.0, -1.0 / 2920.0};
  for (int l = 1; l <= 4; ++l) EXPECT_NEAR(g.at(-l), r[l - 1], 1e-14) << "l = " << l;
  EXPECT_NEAR(g.at(0), 0.0, 1e-14);
  EXPECT_EQ(g.at(5), 0.0);
}

// Latto, Resnikoff & Tenenbaum 1991, D6 second-derivative connection coefficients
// Γ^{0,2}[0..4] = −295/56, 356/105, −92/105, 4/35, 3/560 [LRT91].
TEST(ConnectionCoefficients, Db6SecondDerivativeMatchesLatto1991) {
  const auto g = ww::connection_coefficients(ww::Family::daubechies(6), 0, 2);
  const double published[] = {-295.0 / 56.0, 356.0 / 105.0, -92.0 / 105.0, 4.0 / 35.0, 3.0 / 560.0};
  for (int k = 0; k <= 4; ++k) {
    EXPECT_NEAR(g.at(k), published[k], 1e-13) << "k = " << k;
    EXPECT_NEAR(g.at(-k), published[k], 1e-13) << "k = " << -k;
  }
}

// DB4: the derivative coefficients are the fourth-order central difference (2/3, −1/12) [B92].
TEST(ConnectionCoefficients, Db4FirstDerivativeIsFourthOrderCentralDifference) {
  const auto g = ww::connection_coefficients(ww::Family::daubechies(4), 0, 1);
  EXPECT_NEAR(g.at(1), 2.0 / 3.0, 1e-14);
  EXPECT_NEAR(g.at(2), -1.0 / 12.0, 1e-14);
}

// Identities from the parity of the autocorrelation Φ (Γ^{0,d}[k] = (−1)^d Φ^{(d)}(k), Φ even),
// integration by parts, and polynomial reproduction of Φ to degree 2N − 1:
//   Γ^{0,1} antisymmetric, Γ^{0,2} symmetric, Γ^{1,1} = −Γ^{0,2}, Σ_k Γ^{0,d}[k] = 0 (d ≥ 1),
//   Σ_k k Γ^{0,1}[k] = 1, Σ_k k² Γ^{0,2}[k] = 2, Σ_k k^m Γ^{0,2}[k] = 0 for 3 ≤ m ≤ 2N − 1.
// For Haar/Daubechies the moment rows are part of the solve; the parities are not. For the
// B-spline nothing here is imposed: all of it tests the product formula and the c_k.
TEST(ConnectionCoefficients, IdentitiesFromPolynomialReproduction) {
  for (const auto& family : {ww::Family::daubechies(6), ww::Family::daubechies(8), ww::Family::daubechies(12),
                             ww::Family::daubechies(20), ww::Family::orthogonal_cubic_bspline()}) {
    const auto g1 = ww::connection_coefficients(family, 0, 1);
    const auto g2 = ww::connection_coefficients(family, 0, 2);
    const auto g11 = ww::connection_coefficients(family, 1, 1);
    const double tol = 1e-12;
    double s1 = 0, m1 = 0, s2 = 0, m2 = 0;
    for (int k = g2.first_shift - 1; k <= g2.last_shift + 1; ++k) {
      EXPECT_NEAR(g1.at(k), -g1.at(-k), tol) << family.name() << " k = " << k;
      EXPECT_NEAR(g2.at(k), g2.at(-k), tol) << family.name() << " k = " << k;
      EXPECT_NEAR(g11.at(k), -g2.at(k), tol) << family.name() << " k = " << k;
      s1 += g1.at(k);
      m1 += k * g1.at(k);
      s2 += g2.at(k);
      m2 += double(k) * k * g2.at(k);
    }
    EXPECT_NEAR(s1, 0.0, tol) << family.name();
    EXPECT_NEAR(m1, 1.0, tol) << family.name();
    EXPECT_NEAR(s2, 0.0, tol) << family.name();
    EXPECT_NEAR(m2, 2.0, 1e-11) << family.name();
    // Higher moments up to 2N − 1 (m ≤ 7 for the B-spline, capped at 9: beyond, k^m amplifies the
    // rounding of Γ, ~1e-16·max|Γ|, past the size of the identity being tested).
    const int top = std::min(2 * family.vanishing_moments() - 1, 9);
    for (int m = 3; m <= top; ++m) {
      double s = 0, scale = 0;
      for (int k = g2.first_shift; k <= g2.last_shift; ++k) {
        s += std::pow(double(k), m) * g2.at(k);
        scale += std::pow(std::abs(double(k)), m);
      }
      EXPECT_LE(std::abs(s), 1e-12 * scale * g2.values.cwiseAbs().maxCoeff()) << family.name() << " moment " << m;
    }
  }
}

TEST(ConnectionCoefficients, GramIsIdentity) {
  for (int L = 2; L <= 20; L += 2) {
    const auto family = L == 2 ? ww::Family::haar() : ww::Family::daubechies(L);
    const auto g = ww::connection_coefficients(family, 0, 0);
    for (int k = g.first_shift; k <= g.last_shift; ++k) EXPECT_NEAR(g.at(k), k == 0 ? 1.0 : 0.0, 1e-13) << family.name();
  }
  const auto& b = ww::orthogonal_cubic_bspline_coefficients();
  const auto g = ww::connection_coefficients(ww::Family::orthogonal_cubic_bspline(), 0, 0);
  for (int k = g.first_shift; k <= g.last_shift; ++k) {
    EXPECT_NEAR(g.at(k), k == 0 ? 1.0 : 0.0, 10.0 * (b.tail + b.quadrature_error)) << "B-spline k = " << k;
  }
}

// Sobolev exponents: Haar 1/2 and DB4 1 in closed form [V92]; DB6 ≈ 1.415 [V92; CD96].
// max order d < 2s: DB4 Γ^{0,2} does not exist (also refused by Nielsen's toolbox, "d=2, D=4").
TEST(ConnectionCoefficients, SobolevExponentsAndAdmissibleOrders) {
  EXPECT_NEAR(ww::sobolev_exponent(ww::Family::haar()), 0.5, 1e-12);
  EXPECT_NEAR(ww::sobolev_exponent(ww::Family::daubechies(4)), 1.0, 1e-10);
  EXPECT_NEAR(ww::sobolev_exponent(ww::Family::daubechies(6)), 1.415, 1e-3);
  EXPECT_EQ(ww::max_connection_order(ww::Family::haar()), 0);
  EXPECT_EQ(ww::max_connection_order(ww::Family::daubechies(4)), 1);
  EXPECT_EQ(ww::max_connection_order(ww::Family::daubechies(6)), 2);
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [] { (void)ww::connection_coefficients(ww::Family::daubechies(4), 0, 2); },
      {"DB4", "d2 = 2", "d1 + d2 <= 1", "DB6"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [] { (void)ww::connection_coefficients(ww::Family::haar(), 0, 1); }, {"Haar", "d1 + d2 <= 0"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [] { (void)ww::connection_coefficients(ww::Family::daubechies(6), -1, 1); }, {">= 0"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [] { (void)ww::periodized_connection_matrix(ww::connection_coefficients(ww::Family::haar(), 0, 0), -1); },
      {"level J = -1"});
}
