#pragma once
/// Real Fourier basis on normalized time τ ∈ [0, 1) (period normalized to 1 [JL14 Sec. 1]).
/// Units: τ is dimensionless; derivatives are with respect to τ (multiply the d-th derivative
/// by f^d, f the frequency in Hz, for derivatives in physical time).

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace wbm::spectral {

/// Real Fourier basis on τ ∈ [0, 1), in one of two forms, told apart by the parity of M:
///  - M = 2^J, M ≥ 2 [JL14 Sec. 3.1], the paper's form, with the dimension of the periodized
///    wavelet bases at the same level J:
///      q_0 = 1,  q_{2m−1} = cos 2πmτ,  q_{2m} = sin 2πmτ  (m = 1 … M/2 − 1),  q_{M−1} = cos πMτ.
///    The last ("top") function cos πMτ has no sine partner: its derivative −πM sin πMτ is
///    outside the span, so its Galerkin first-derivative row and column are zero and a damping
///    term C u̇ does not reach it (an undamped harmonic, issue #19).
///  - M = 2H + 1, H ≥ 1 (with_harmonics(H)): harmonic balance as usually written [LL11 Eq. (21)],
///    q_0 = 1, q_{2m−1} = cos 2πmτ, q_{2m} = sin 2πmτ (m = 1 … H); every harmonic has its pair.
/// The functions are not normalized: ∫₀¹ q_j q_k dτ = diag(1, ½, …, ½).
/// Throws std::invalid_argument if M is neither a power of two ≥ 2 nor an odd number ≥ 3.
class FourierBasis {
 public:
  explicit FourierBasis(int dimension);
  /// The 2H + 1 functions of harmonics 0 … H. Throws std::invalid_argument unless H ≥ 1.
  [[nodiscard]] static FourierBasis with_harmonics(int harmonics);

  [[nodiscard]] int dimension() const noexcept { return dimension_; }
  /// True for M = 2^J (the lone top function cos πMτ), false for M = 2H + 1.
  [[nodiscard]] bool has_top_function() const noexcept { return dimension_ % 2 == 0; }
  /// Highest harmonic: M/2 for M = 2^J, H for M = 2H + 1.
  [[nodiscard]] int highest_harmonic() const noexcept { return dimension_ / 2; }
  /// Harmonic number m of function k (0 for the constant, M/2 for the top function).
  /// Throws std::out_of_range for k outside [0, M).
  [[nodiscard]] int harmonic(int k) const;
  /// True if q_k is a sine (k even, 0 < k, and not the top function).
  [[nodiscard]] bool is_sine(int k) const;

  /// d-th τ-derivative of q_k at τ, d ≥ 0. Throws std::out_of_range for k outside [0, M).
  [[nodiscard]] double value(int k, double tau, int derivative = 0) const;
  /// Matrix of values (rows = times, columns = basis functions): V(p, k) = q_k^{(d)}(τ_p).
  /// Throws std::invalid_argument for a non-finite τ_p (naming p).
  [[nodiscard]] Eigen::MatrixXd values(const Eigen::VectorXd& tau, int derivative = 0) const;
  /// values() on the uniform grid τ_p = (p + s/2)/P, p = 0 … P − 1 (P = `points` rows, M
  /// columns), s = 1 for the cell midpoints (`midpoints`), else 0. Entry (p, k) of harmonic h is
  /// read from a table of cos(πi/P) and sin(πi/P), i = 0 … 2P − 1, at i = h(2p + s) mod 2P: the
  /// argument is reduced exactly, in integers (values() rounds 2πhτ_p, an error growing like
  /// h·eps), the multiples of π/2 are exact (cos πMτ is exactly 0 at the midpoints of P = M), and
  /// it costs 2P libm calls instead of P·M/2. Throws std::invalid_argument unless P ≥ 1.
  [[nodiscard]] Eigen::MatrixXd grid_values(int points, bool midpoints) const;

  /// The derivative in coefficient space, D (M × M, sparse): q_k' = Σ_l D(k, l) q_l, i.e.
  /// D(cos_h, sin_h) = −2πh and D(sin_h, cos_h) = 2πh, so that (Σ_k a_k q_k)' has coefficients
  /// a D. Exact for every function but the top one cos πMτ (M = 2^J), whose derivative
  /// −πM sin πMτ is outside the span: its row is zero.
  [[nodiscard]] Eigen::SparseMatrix<double> derivative_matrix() const;

  /// Exact Galerkin time operator (M × M, sparse):  A_d(j, k) = ∫₀¹ q_j(τ) q_k^{(d)}(τ) dτ,
  /// d = 0, 1, 2: row j = weighting function, column k = trial function. These are the time
  /// factors of the Kronecker products in [JL14 Eq. (14)] for Fourier:Fourier.
  [[nodiscard]] Eigen::SparseMatrix<double> galerkin_operator(int derivative) const;

 private:
  int dimension_;
};

/// True if n is a power of two (1, 2, 4, ...).
[[nodiscard]] constexpr bool is_power_of_two(long n) noexcept { return n > 0 && (n & (n - 1)) == 0; }
/// True if M is a valid FourierBasis dimension: a power of two ≥ 2 or an odd number ≥ 3.
[[nodiscard]] constexpr bool is_fourier_dimension(long m) noexcept {
  return (m >= 2 && is_power_of_two(m)) || (m >= 3 && m % 2 == 1);
}

}  // namespace wbm::spectral
