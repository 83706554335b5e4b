#pragma once
/// Real Fourier basis on normalized time τ ∈ [0, 1) (period normalized to 1 [JL14 Sec. 1]).
/// Units: τ is dimensionless; derivatives are with respect to τ (multiply the d-th derivative
/// by f^d, f the frequency in Hz, for derivatives in physical time).

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace wbm::spectral {

/// Real Fourier basis of dimension M = 2^J, M ≥ 2 [JL14 Sec. 3.1], ordered
///   q_0 = 1,  q_{2m−1} = cos 2πmτ,  q_{2m} = sin 2πmτ  (m = 1 … M/2 − 1),  q_{M−1} = cos πMτ,
/// so that it has the same dimension as the periodized wavelet bases at the same level J.
/// The functions are not normalized: ∫₀¹ q_j q_k dτ = diag(1, ½, …, ½).
/// The last function, cos πMτ (harmonic M/2), has its derivative −πM sin πMτ outside the span:
/// its Galerkin first-derivative row and column are zero.
/// Throws std::invalid_argument if M is not a power of two or M < 2.
class FourierBasis {
 public:
  explicit FourierBasis(int dimension);

  [[nodiscard]] int dimension() const noexcept { return dimension_; }
  /// Harmonic number m of function k (0 for the constant, M/2 for the last function).
  [[nodiscard]] int harmonic(int k) const;

  /// d-th τ-derivative of q_k at τ, d ≥ 0. Throws std::out_of_range for k outside [0, M).
  [[nodiscard]] double value(int k, double tau, int derivative = 0) const;
  /// Matrix of values (rows = times, columns = basis functions): V(p, k) = q_k^{(d)}(τ_p).
  [[nodiscard]] Eigen::MatrixXd values(const Eigen::VectorXd& tau, int derivative = 0) const;

  /// Exact Galerkin time operator (M × M, sparse):  A_d(j, k) = ∫₀¹ q_j(τ) q_k^{(d)}(τ) dτ,
  /// d = 0, 1, 2: row j = weighting function, column k = trial function. These are the time
  /// factors of the Kronecker products in [JL14 Eq. (14)] for Fourier:Fourier.
  [[nodiscard]] Eigen::SparseMatrix<double> galerkin_operator(int derivative) const;

 private:
  int dimension_;
};

/// True if n is a power of two (1, 2, 4, ...).
[[nodiscard]] constexpr bool is_power_of_two(long n) noexcept { return n > 0 && (n & (n - 1)) == 0; }

}  // namespace wbm::spectral
