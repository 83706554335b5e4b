#pragma once
/// Real circulant matrices, diagonalized by the discrete Fourier transform (FFTW). The time
/// operators of a periodized wavelet basis with itself are circulant (function k + 1 is function
/// k shifted by 1/M), and so is every combination f² A_M + f c A_C + λ A_K of them: a circulant
/// system of size M is solved in O(M log M) instead of by an O(M³) or banded LU.

#include <complex>

#include <Eigen/Core>

namespace wbm::spectral {

/// Real DFT of every column of x (M rows): X(m, j) = Σ_k x(k, j) e^{−2πikm/M}, m = 0 … ⌊M/2⌋
/// (FFTW r2c, unnormalized; the other bins are the conjugates). Throws std::invalid_argument if
/// x has no rows.
[[nodiscard]] Eigen::MatrixXcd real_dft_columns(const Eigen::MatrixXd& x);
/// Inverse of real_dft_columns for M = `dimension` rows: x(k, j) = (1/M) Σ_{m=0}^{M−1} X(m, j)
/// e^{2πikm/M} with X Hermitian (FFTW c2r; the imaginary parts of bins 0 and M/2 are ignored).
/// Throws std::invalid_argument unless X has ⌊M/2⌋ + 1 rows.
[[nodiscard]] Eigen::MatrixXd inverse_real_dft_columns(const Eigen::MatrixXcd& bins, int dimension);

/// The M × M circulant C(i, k) = c((i − k) mod M) of its first column c (length M), stored by its
/// eigenvalues ĉ_m = Σ_j c_j e^{−2πijm/M}, m = 0 … ⌊M/2⌋ (the others are their conjugates):
///   C v = c ⊛ v (circular convolution),   DFT(C v)_m = ĉ_m DFT(v)_m,
///   Cᵀ has eigenvalues conj(ĉ_m),   C⁻¹ has 1/ĉ_m.
/// Products cost one r2c and one c2r transform of length M (FFTW, plans shared per length).
/// Immutable; one object may be used by several threads.
/// Throws std::invalid_argument for an empty or non-finite first column.
class Circulant {
 public:
  explicit Circulant(const Eigen::VectorXd& first_column);
  /// The circulant of size M = `dimension` with eigenvalues ĉ_m, m = 0 … ⌊M/2⌋ (the others their
  /// conjugates); its first column is their inverse real DFT. The imaginary parts of ĉ_0 and (M
  /// even) ĉ_{M/2} are taken as 0, as a real circulant has them. A combination of circulants
  /// Σ_i w_i C_i formed on their eigenvalues, Σ_i w_i ĉ_{i,m}, keeps each bin to the rounding of
  /// its own terms, where forming the first column first and transforming it mixes every bin's
  /// rounding into each (a stiffness operator's bins span (πM)²: its top bins' rounding would
  /// swamp the near-resonant one). Throws std::invalid_argument unless `eigenvalues` has ⌊M/2⌋ +
  /// 1 finite entries and M ≥ 1.
  [[nodiscard]] static Circulant from_eigenvalues(const Eigen::VectorXcd& eigenvalues, int dimension);

  [[nodiscard]] int dimension() const noexcept { return static_cast<int>(column_.size()); }
  /// The first column c (length M).
  [[nodiscard]] const Eigen::VectorXd& first_column() const noexcept { return column_; }
  /// ĉ_m, m = 0 … ⌊M/2⌋.
  [[nodiscard]] const Eigen::VectorXcd& eigenvalues() const noexcept { return eigenvalues_; }
  /// min_m |ĉ_m| / max_m |ĉ_m| (0 for a singular matrix): the reciprocal of the 2-norm condition
  /// number, since C is normal.
  [[nodiscard]] double reciprocal_condition() const;
  /// C⁻¹, itself circulant. Throws std::domain_error if some ĉ_m = 0 (C singular).
  [[nodiscard]] Circulant inverse() const;
  /// C v, or Cᵀ v, for each column of v (M rows). Throws std::invalid_argument unless v has M rows.
  [[nodiscard]] Eigen::MatrixXd apply(const Eigen::MatrixXd& v, bool transposed = false) const;
  /// The dense M × M matrix.
  [[nodiscard]] Eigen::MatrixXd dense() const;

  /// True if the square matrix A is circulant to rel_tol · max|A| (entrywise): A(i, k) = A(0 …)
  /// along every wrapped diagonal. O(M²).
  [[nodiscard]] static bool is_circulant(const Eigen::MatrixXd& a, double rel_tol = 1e-13);

 private:
  Circulant(Eigen::VectorXd column, Eigen::VectorXcd eigenvalues);
  Eigen::VectorXd column_;
  Eigen::VectorXcd eigenvalues_;
};

}  // namespace wbm::spectral
