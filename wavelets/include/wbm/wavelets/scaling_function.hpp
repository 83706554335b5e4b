#pragma once
/// Scaling functions φ of the orthogonal wavelet families of [JL14 Secs. 3.3–3.5] on the real
/// line: Haar, Daubechies (L = 4, 6, …, 20 filter coefficients) and the orthogonal cubic B-spline
/// (Battle–Lemarié). t is dimensionless; φ is the L²-orthonormal scaling function
/// (∫ φ(t) φ(t − k) dt = δ_k, ∫ φ dt = 1). Periodization and the paper's ∫₀¹ = 1 scaling live in
/// periodized_basis.hpp.

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace wbm::wavelets {

enum class FamilyKind { Haar, Daubechies, OrthogonalCubicBSpline };

/// A wavelet family. filter_length is L, the number of refinement coefficients: 2 for Haar,
/// an even number in [4, 20] for Daubechies (L = 6 is the paper's DB6), 0 for the orthogonal
/// cubic B-spline, whose refinement mask is infinite. Build through the named constructors,
/// which validate.
struct Family {
  FamilyKind kind = FamilyKind::Haar;
  int filter_length = 2;

  [[nodiscard]] static Family haar() { return {FamilyKind::Haar, 2}; }
  /// Throws std::invalid_argument unless filter_length is even and 4 ≤ L ≤ 20 (GSL's tables);
  /// the message names L and suggests haar() for L = 2.
  [[nodiscard]] static Family daubechies(int filter_length);
  [[nodiscard]] static Family orthogonal_cubic_bspline() { return {FamilyKind::OrthogonalCubicBSpline, 0}; }
  /// "Haar", "DB6", "B-spline".
  [[nodiscard]] std::string name() const;
  /// Number of vanishing wavelet moments N (polynomials of degree < N are reproduced by the
  /// translates of φ): L/2 for Haar and Daubechies, 4 for the cubic B-spline.
  [[nodiscard]] int vanishing_moments() const;

  friend bool operator==(const Family&, const Family&) = default;
};

/// Refinement (two-scale) coefficients p_l, l = 0 … L−1, of φ(t) = Σ_l p_l φ(2t − l)
/// [JL14 Eq. (32)], normalized Σ_l p_l = 2 (and Σ_l p_l p_{l+2m} = 2 δ_m). Haar: p = {1, 1}
/// [JL14 Sec. 3.5]. Daubechies: GSL's `gsl_wavelet_daubechies` tables (extremal phase, h_l with
/// Σ h_l = √2), converted by p_l = √2 h_l. Throws std::invalid_argument for the B-spline family
/// (infinite mask: use orthogonal_cubic_bspline_coefficients()).
[[nodiscard]] std::vector<double> refinement_coefficients(const Family& family);

/// Largest d for which φ^{(d)} exists pointwise (is continuous): the integer part of the Hölder
/// exponent. Haar 0 (discontinuous, value only); Daubechies from the Hölder exponents
/// 0.550, 1.088, 1.618, 1.969, 2.189, 2.460, 2.761, 3.073, 3.363 for L = 4 … 20 [D92, Ch. 7]:
/// 0 for DB4, 1 for DB6–DB10, 2 for DB12–DB16, 3 for DB18–DB20; B-spline 2 (φ ∈ C²).
[[nodiscard]] int max_pointwise_derivative(const Family& family);

/// Cubic B-spline B₃ of [JL14 Eq. (29)], support [0, 4], and its derivatives d = 0 … 3
/// (B₃''' is piecewise constant; at the knots the right limit is returned).
/// Throws std::invalid_argument for d outside [0, 3].
[[nodiscard]] double cubic_bspline(double t, int derivative = 0);

/// Coefficients c_k, |k| ≤ K, of the orthogonal cubic B-spline φ(t) = Σ_k c_k B₃(t − k)
/// [JL14 Eq. (28)], with c_k = c_{−k} = (1/π) ∫₀^π cos(kξ) / √p₃(cos ξ) dξ [JL14 Eqs. (30)–(31)]
/// computed by GSL adaptive quadrature (QAG for k = 0, QAWO cosine-weighted for k > 0).
/// The truncation is measured, not assumed:
///   tail = Σ_{K < |k| ≤ 2K} |c_k| (same quadrature), and the worst defect of orthonormality
///   and of ∫φ = 1 caused by keeping |k| ≤ K are reported by connection_coefficients.hpp.
struct BSplineCoefficients {
  int truncation = 0;              // K; c has 2K + 1 entries, c[k + K] = c_k
  std::vector<double> c;
  double tail = 0.0;               // Σ_{K<|k|≤2K} |c_k|, the neglected part of the sum
  double quadrature_error = 0.0;   // largest GSL abserr estimate over the c_k kept
};
/// Throws std::invalid_argument if truncation < 1 or > 200.
[[nodiscard]] BSplineCoefficients compute_orthogonal_cubic_bspline_coefficients(int truncation);
/// The paper's truncation K = 50 [JL14 Sec. 3.3], computed once per process (thread-safe).
[[nodiscard]] const BSplineCoefficients& orthogonal_cubic_bspline_coefficients();

/// φ^{(d)} of one family on the real line, d ≤ max_pointwise_derivative(family), tabulated once.
/// Haar and the B-spline are evaluated exactly from Eqs. (33) and (28)–(29). Daubechies values are
/// exact at the dyadic points n/2^r of the table level r = `resolution` (eigenvector of the
/// two-scale matrix at the integers, then refinement [CHS96]); at other t, value() interpolates
/// linearly between the two neighbouring dyadic values (error O(2^{−r·α}), α the Hölder exponent
/// of φ^{(d)}). Immutable; share it through std::shared_ptr<const ScalingFunction>.
class ScalingFunction {
 public:
  /// Throws std::invalid_argument if resolution is outside [0, 20].
  explicit ScalingFunction(const Family& family, int resolution = 12);

  [[nodiscard]] const Family& family() const noexcept { return family_; }
  [[nodiscard]] int resolution() const noexcept { return resolution_; }
  /// Support [begin, end] of φ: Haar [0, 1], Daubechies [0, L − 1], B-spline [−K, K + 4].
  [[nodiscard]] double support_begin() const noexcept { return begin_; }
  [[nodiscard]] double support_end() const noexcept { return end_; }
  [[nodiscard]] int max_derivative() const noexcept { return max_derivative_; }

  /// φ^{(d)}(t). Throws std::invalid_argument if d < 0 or d > max_derivative(); the message names
  /// the family, the order, and the distributional alternative (connection coefficients).
  [[nodiscard]] double value(double t, int derivative = 0) const;

  /// φ^{(d)} at the dyadic points t_n = begin + n / 2^j, n = 0 … (end − begin)·2^j (exact for
  /// Haar and the B-spline; for Daubechies by [CHS96]: integer values from the eigenvector of
  /// P(i, m) = p_{2i−m} for the eigenvalue 2^{−d}, normalized by Σ_m (−m)^d φ^{(d)}(m) = d!, then
  /// φ^{(d)}(t) = 2^d Σ_l p_l φ^{(d)}(2t − l) level by level). Haar takes φ(1) = 0 (Eq. (33)).
  /// Throws std::invalid_argument for j outside [0, 20] or an unavailable derivative.
  [[nodiscard]] Eigen::VectorXd dyadic_values(int level, int derivative = 0) const;

 private:
  Family family_;
  int resolution_;
  double begin_ = 0.0, end_ = 1.0;
  int max_derivative_ = 0;
  std::vector<double> p_;                 // Daubechies refinement coefficients
  std::vector<Eigen::VectorXd> tables_;   // Daubechies: dyadic values at `resolution`, per d
};

}  // namespace wbm::wavelets
