// Scaling functions on the real line against truths that do not come from this code.
#include <algorithm>
#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include <wbm/wavelets/scaling_function.hpp>

#include "testing.hpp"

namespace ww = wbm::wavelets;

namespace {
std::vector<ww::Family> all_compact_families() {
  std::vector<ww::Family> f = {ww::Family::haar()};
  for (int L = 4; L <= 20; L += 2) f.push_back(ww::Family::daubechies(L));
  return f;
}
}  // namespace

// Orthonormality of integer translates ⟺ Σ_l p_l p_{l+2m} = 2 δ_m, and Σ_l p_l = 2 [D92, Ch. 6],
// for GSL's tables converted to the paper's normalization [JL14 Eq. (32)].
TEST(RefinementCoefficients, OrthonormalityAndNormalizationOfGslTables) {
  for (const auto& family : all_compact_families()) {
    const auto p = ww::refinement_coefficients(family);
    const int L = static_cast<int>(p.size());
    ASSERT_EQ(L, family.filter_length);
    double sum = 0.0;
    for (double v : p) sum += v;
    EXPECT_NEAR(sum, 2.0, 1e-14) << family.name();
    for (int m = 0; 2 * m < L; ++m) {
      double s = 0.0;
      for (int l = 0; l + 2 * m < L; ++l) s += p[static_cast<size_t>(l)] * p[static_cast<size_t>(l + 2 * m)];
      EXPECT_NEAR(s, m == 0 ? 2.0 : 0.0, 1e-14) << family.name() << " m = " << m;
    }
  }
}

// N = L/2 vanishing moments of the Daubechies wavelet ψ(t) = Σ_l (−1)^l p_{L−1−l} φ(2t − l)
// ⟺ Σ_l (−1)^l l^m p_l = 0 for m = 0 … N − 1 [D92, Sec. 6.4]. Relative to Σ_l l^m |p_l|.
TEST(RefinementCoefficients, DaubechiesWaveletHasHalfLVanishingMoments) {
  for (int L = 4; L <= 20; L += 2) {
    const auto p = ww::refinement_coefficients(ww::Family::daubechies(L));
    for (int m = 0; m < L / 2; ++m) {
      double s = 0.0, scale = 0.0;
      for (int l = 0; l < L; ++l) {
        const double term = std::pow(static_cast<double>(l), m) * p[static_cast<size_t>(l)];
        s += (l % 2 == 0 ? 1.0 : -1.0) * term;
        scale += std::abs(term);
      }
      EXPECT_LE(std::abs(s), 1e-13 * scale) << "DB" << L << " moment " << m;
    }
  }
}

// Closed form at the integers for DB4 [D92, Sec. 6.5]: φ(1) = (1+√3)/2, φ(2) = (1−√3)/2.
TEST(ScalingFunction, Db4IntegerValuesMatchClosedForm) {
  const ww::ScalingFunction phi(ww::Family::daubechies(4));
  EXPECT_NEAR(phi.value(1.0), (1.0 + std::numbers::sqrt3) / 2.0, 1e-14);
  EXPECT_NEAR(phi.value(2.0), (1.0 - std::numbers::sqrt3) / 2.0, 1e-14);
  EXPECT_EQ(phi.value(0.0), 0.0);
  EXPECT_EQ(phi.value(3.0), 0.0);
}

// Polynomial reproduction [SN96]: Σ_k k^m φ^{(d)}(t − k) = d!·δ_{md} for m ≤ d < N at every t (the
// normalization fixes it at t = 0 only; the dyadic refinement must carry it everywhere).
TEST(ScalingFunction, PartitionOfUnityAndDerivativeReproductionAtDyadicPoints) {
  for (const auto& family : {ww::Family::daubechies(4), ww::Family::daubechies(6), ww::Family::daubechies(12),
                             ww::Family::daubechies(20), ww::Family::orthogonal_cubic_bspline()}) {
    const ww::ScalingFunction phi(family);
    for (int d = 0; d <= phi.max_derivative(); ++d) {
      for (double t : {0.0, 0.3125, 0.5, 0.7421875}) {
        double s0 = 0.0, sd = 0.0, scale = 0.0;
        for (int k = -200; k <= 200; ++k) {
          const double v = phi.value(t - k, d);
          s0 += v;
          sd += std::pow(static_cast<double>(k), d) * v;
          scale += std::pow(std::abs(static_cast<double>(k)), d) * std::abs(v);
        }
        // Each of the r = 12 refinement levels multiplies rounding by up to 2^d·max|p_l|, so the
        // derivative tables carry relative errors near 1e-10 (DB20, d = 3); a wrong integer-value
        // normalization or refinement would give O(1) errors. B-spline: c_k truncation ≈ 1e-13.
        const double tol = 1e-9 * std::max(scale, 1.0);
        const double factorial = d == 2 ? 2.0 : (d == 3 ? 6.0 : 1.0);
        EXPECT_NEAR(s0, d == 0 ? 1.0 : 0.0, tol) << family.name() << " d = " << d << " t = " << t;
        EXPECT_NEAR(sd, factorial, tol) << family.name() << " d = " << d << " t = " << t;
      }
    }
  }
}

// Orthonormality of integer translates by an independent path: the rectangle rule on the dyadic
// samples, Σ_n φ(n/2^r) φ(n/2^r − k) / 2^r → δ_k as r grows (quadrature error of a Hölder-α
// integrand, largest for DB4, α = 0.55).
TEST(ScalingFunction, DyadicSamplesAreOrthonormalInTheLimit) {
  for (int L = 4; L <= 20; L += 2) {
    const ww::ScalingFunction phi(ww::Family::daubechies(L));
    const int r = 12;
    const Eigen::VectorXd v = phi.dyadic_values(r);
    const long per = 1L << r;
    for (int k = 0; k < L - 1; ++k) {
      double s = 0.0;
      for (long n = k * per; n < v.size(); ++n) s += v(n) * v(n - k * per);
      s /= static_cast<double>(per);
      EXPECT_NEAR(s, k == 0 ? 1.0 : 0.0, L == 4 ? 1e-4 : 1e-6) << "DB" << L << " k = " << k;
    }
  }
}

// ∫φ = 1 for the orthogonal cubic B-spline: Σ_k c_k = 1/√p₃(1) = 1 [JL14 Eqs. (28)–(31)];
// the truncation at |k| ≤ 50 is measured: the neglected tail is small but not zero.
TEST(ScalingFunction, BSplineCoefficientsSumToOneWithinMeasuredTail) {
  const auto& b = ww::orthogonal_cubic_bspline_coefficients();
  ASSERT_EQ(b.truncation, 50);
  double sum = 0.0;
  for (double c : b.c) sum += c;
  EXPECT_NEAR(sum, 1.0, b.tail + 101 * b.quadrature_error);
  EXPECT_GT(b.tail, 0.0);
  EXPECT_LT(b.tail, 1e-12);  // c_k ~ e^{−0.622|k|}: cos ξ = −1.2 is the nearest root of p₃
}

// Bad input names the parameter, the value, the range and a way out.
TEST(ScalingFunction, RefusesMissingDerivativesAndBadFamilies) {
  wbm::testing::expect_throw_with<std::invalid_argument>([] { (void)ww::Family::daubechies(7); },
                                                         {"L = 7", "even", "4 <= L <= 20"});
  wbm::testing::expect_throw_with<std::invalid_argument>([] { (void)ww::Family::daubechies(22); }, {"L = 22"});
  wbm::testing::expect_throw_with<std::invalid_argument>([] { (void)ww::Family::daubechies(2); }, {"haar"});
  const ww::ScalingFunction haar(ww::Family::haar());
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { (void)haar.value(0.5, 1); },
                                                         {"Haar", "order 1", "Distributional"});
  const ww::ScalingFunction db4(ww::Family::daubechies(4));
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { (void)db4.value(0.5, 2); },
                                                         {"DB4", "order 2", "connection coefficients"});
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { (void)db4.value(0.5, 1); }, {"DB4", "order 1"});
  wbm::testing::expect_throw_with<std::invalid_argument>([] { (void)ww::ScalingFunction(ww::Family::haar(), 21); },
                                                         {"resolution = 21", "[0, 20]"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [] { (void)ww::refinement_coefficients(ww::Family::orthogonal_cubic_bspline()); }, {"infinite"});
}
