#include <wbm/spectral/fourier_basis.hpp>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

namespace wbm::spectral {

FourierBasis::FourierBasis(int dimension) : dimension_(dimension) {
  if (!is_fourier_dimension(dimension)) {
    throw std::invalid_argument("FourierBasis(M = " + std::to_string(dimension) +
                                "): M must be a power of two >= 2 (M = 2^J, the paper's basis) or odd >= 3 "
                                "(M = 2H + 1, H harmonics)");
  }
}

FourierBasis FourierBasis::with_harmonics(int harmonics) {
  if (harmonics < 1 || harmonics > (1 << 28)) {
    throw std::invalid_argument("FourierBasis::with_harmonics(H = " + std::to_string(harmonics) +
                                "): H must lie in [1, 2^28]");
  }
  return FourierBasis(2 * harmonics + 1);
}

bool FourierBasis::is_sine(int k) const {
  (void)harmonic(k);  // range check
  return k > 0 && k % 2 == 0 && !(has_top_function() && k == dimension_ - 1);
}

int FourierBasis::harmonic(int k) const {
  if (k < 0 || k >= dimension_) {
    throw std::out_of_range("FourierBasis::harmonic(k = " + std::to_string(k) +
                            "): k must lie in [0, " + std::to_string(dimension_) + ")");
  }
  if (has_top_function() && k == dimension_ - 1) return dimension_ / 2;
  return (k + 1) / 2;
}

double FourierBasis::value(int k, double tau, int derivative) const {
  if (derivative < 0) {
    throw std::invalid_argument("FourierBasis::value: derivative order " +
                                std::to_string(derivative) + " must be >= 0");
  }
  const int m = harmonic(k);
  if (m == 0) return derivative == 0 ? 1.0 : 0.0;
  const bool sine = is_sine(k);
  const double w = 2.0 * std::numbers::pi * m;
  // d^d/dτ^d of cos(wτ) = w^d cos(wτ + dπ/2); of sin(wτ) = w^d sin(wτ + dπ/2).
  const double phase = w * tau + derivative * std::numbers::pi / 2.0;
  return std::pow(w, derivative) * (sine ? std::sin(phase) : std::cos(phase));
}

Eigen::MatrixXd FourierBasis::values(const Eigen::VectorXd& tau, int derivative) const {
  Eigen::MatrixXd v(tau.size(), dimension_);
  for (Eigen::Index p = 0; p < tau.size(); ++p) {
    if (!std::isfinite(tau(p))) {
      throw std::invalid_argument("FourierBasis::values: tau[" + std::to_string(p) + "] is not finite; give finite "
                                  "normalized times (the functions are 1-periodic)");
    }
  }
  if (derivative < 0) (void)value(0, 0.0, derivative);  // throws, naming the order
  // One phase per harmonic for its cosine and sine (the same expressions as value(), so the same
  // bits; the compiler fuses the two calls into one sincos): half the libm calls of M value()s.
  const double d_phase = derivative * std::numbers::pi / 2.0;
  const bool top = has_top_function();
  const int paired = top ? dimension_ / 2 - 1 : dimension_ / 2;
  v.col(0).setConstant(derivative == 0 ? 1.0 : 0.0);
  for (int h = 1; h <= paired + (top ? 1 : 0); ++h) {
    const double w = 2.0 * std::numbers::pi * h;
    const double scale = std::pow(w, derivative);
    const bool sine = h <= paired;  // the top function cos(πMτ) has no sine partner
    const int cos_column = h <= paired ? 2 * h - 1 : dimension_ - 1;
    for (Eigen::Index p = 0; p < tau.size(); ++p) {
      const double phase = w * tau(p) + d_phase;
      v(p, cos_column) = scale * std::cos(phase);
      if (sine) v(p, 2 * h) = scale * std::sin(phase);
    }
  }
  return v;
}

Eigen::MatrixXd FourierBasis::grid_values(int points, bool midpoints) const {
  if (points < 1 || points > (1 << 28)) {
    throw std::invalid_argument("FourierBasis::grid_values(points = " + std::to_string(points) +
                                "): the number of grid points must lie in [1, 2^28]");
  }
  const long long period = 2LL * points;  // the table's length: angles πi/P
  Eigen::VectorXd cos_table(period), sin_table(period);
  for (long long i = 0; i < period; ++i) {
    if ((4 * i) % period == 0) {  // a multiple of π/2: exact
      const long long quadrant = (4 * i) / period;
      cos_table(i) = quadrant == 0 ? 1.0 : quadrant == 2 ? -1.0 : 0.0;
      sin_table(i) = quadrant == 1 ? 1.0 : quadrant == 3 ? -1.0 : 0.0;
    } else {
      const double angle = std::numbers::pi * static_cast<double>(i) / points;
      cos_table(i) = std::cos(angle);
      sin_table(i) = std::sin(angle);
    }
  }
  const bool top = has_top_function();
  const int paired = top ? dimension_ / 2 - 1 : dimension_ / 2;
  const long long s = midpoints ? 1 : 0;
  Eigen::MatrixXd v(points, dimension_);
  v.col(0).setOnes();
  for (int h = 1; h <= paired + (top ? 1 : 0); ++h) {
    const int cos_column = h <= paired ? 2 * h - 1 : dimension_ - 1;
    for (int p = 0; p < points; ++p) {
      const auto i = static_cast<Eigen::Index>((static_cast<long long>(h) * (2LL * p + s)) % period);
      v(p, cos_column) = cos_table(i);
      if (h <= paired) v(p, 2 * h) = sin_table(i);
    }
  }
  return v;
}

Eigen::SparseMatrix<double> FourierBasis::derivative_matrix() const {
  std::vector<Eigen::Triplet<double>> t;
  const int paired = has_top_function() ? dimension_ / 2 - 1 : dimension_ / 2;  // harmonics with a sine partner
  for (int h = 1; h <= paired; ++h) {
    const double w = 2.0 * std::numbers::pi * h;
    t.emplace_back(2 * h - 1, 2 * h, -w);  // (cos ωτ)' = −ω sin ωτ
    t.emplace_back(2 * h, 2 * h - 1, w);   // (sin ωτ)' = ω cos ωτ
  }
  Eigen::SparseMatrix<double> d(dimension_, dimension_);
  d.setFromTriplets(t.begin(), t.end());
  return d;
}

Eigen::SparseMatrix<double> FourierBasis::galerkin_operator(int derivative) const {
  if (derivative < 0 || derivative > 2) {
    throw std::invalid_argument("FourierBasis::galerkin_operator: derivative order " +
                                std::to_string(derivative) + " must be 0, 1 or 2");
  }
  const int big_m = dimension_;
  std::vector<Eigen::Triplet<double>> t;
  const double pi = std::numbers::pi;
  if (derivative == 0) t.emplace_back(0, 0, 1.0);
  const int paired = has_top_function() ? big_m / 2 - 1 : big_m / 2;  // harmonics with a sine partner
  for (int m = 1; m <= paired; ++m) {
    const int c = 2 * m - 1, s = 2 * m;
    const double w = 2.0 * pi * m;
    switch (derivative) {
      case 0:  // ∫cos² = ∫sin² = ½
        t.emplace_back(c, c, 0.5);
        t.emplace_back(s, s, 0.5);
        break;
      case 1:  // ∫cos·(w cos) = w/2, ∫sin·(−w sin) = −w/2
        t.emplace_back(c, s, 0.5 * w);
        t.emplace_back(s, c, -0.5 * w);
        break;
      default:  // ∫cos·(−w² cos) = −w²/2
        t.emplace_back(c, c, -0.5 * w * w);
        t.emplace_back(s, s, -0.5 * w * w);
    }
  }
  if (has_top_function()) {
    const int last = big_m - 1;
    const double w_last = pi * big_m;
    if (derivative == 0) t.emplace_back(last, last, 0.5);
    if (derivative == 2) t.emplace_back(last, last, -0.5 * w_last * w_last);
  }
  Eigen::SparseMatrix<double> a(big_m, big_m);
  a.setFromTriplets(t.begin(), t.end());
  return a;
}

}  // namespace wbm::spectral
