#pragma once
/// Periodized scaling-function basis of dimension M = 2^J on normalized time τ ∈ [0, 1)
/// [JL14 Sec. 3.2.1], the wavelet counterpart of wbm::spectral::FourierBasis. τ is dimensionless;
/// derivatives are with respect to τ (multiply the d-th by f^d, f in Hz, for physical time).

#include <memory>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <wbm/wavelets/connection_coefficients.hpp>
#include <wbm/wavelets/scaling_function.hpp>

namespace wbm::wavelets {

/// Scaling of the periodized functions. Orthonormal: φ_{J,k}(τ) = Σ_ℓ 2^{J/2} φ(2^J(τ−ℓ) − k),
/// ∫₀¹ φ_{J,i} φ_{J,k} = δ_ik [JL14 Eqs. (19), (25)]. UnitIntegral: the paper's figures and text,
/// ∫₀¹ φ_{J,k} = 1 [JL14 Sec. 3.3], i.e. the orthonormal functions times 2^{J/2}.
enum class Normalization { Orthonormal, UnitIntegral };

struct PeriodizedBasisOptions {
  Normalization normalization = Normalization::Orthonormal;
  /// Daubechies values are exact on the grid τ = n / 2^R, R = grid_level (table level R − J of
  /// the scaling function) and linearly interpolated between; −1 means R = max(J, 12).
  int grid_level = -1;
  /// The grid level used at basis level J: grid_level, or max(J, 12) for −1.
  [[nodiscard]] int grid_level_at(int level) const;
  /// Throws std::invalid_argument naming the field, its value and the range for level J:
  /// grid_level = −1 or in [J, J + 20]; normalization one of the two enumerators.
  void validate(int level) const;
};

/// Basis {φ_{J,k}, k = 0 … M − 1} of V_J on the circle, ordered by shift k; function k is the
/// periodized φ(2^J τ − k), so it starts at τ = k/M (Haar, Daubechies). At J = 0 every family
/// reduces to the constant 1 (partition of unity). Immutable and cheap to copy (the tabulated
/// scaling function is shared).
/// Throws std::invalid_argument if level < 0 or level > 20, or as options.validate(level).
class PeriodizedBasis {
 public:
  PeriodizedBasis(const Family& family, int level, PeriodizedBasisOptions options = {});

  [[nodiscard]] const Family& family() const noexcept { return function_->family(); }
  [[nodiscard]] int level() const noexcept { return level_; }
  [[nodiscard]] int dimension() const noexcept { return dimension_; }
  [[nodiscard]] Normalization normalization() const noexcept { return normalization_; }
  /// Factor applied to the orthonormal functions: 1 or 2^{J/2}.
  [[nodiscard]] double scale() const noexcept { return scale_; }
  /// Largest pointwise derivative order (max_pointwise_derivative(family)).
  [[nodiscard]] int max_derivative() const noexcept { return function_->max_derivative(); }
  [[nodiscard]] const ScalingFunction& scaling_function() const noexcept { return *function_; }

  /// d-th τ-derivative of φ_{J,k} at τ (any real τ; periodic). Throws std::out_of_range for k
  /// outside [0, M), std::invalid_argument for d > max_derivative() (naming the alternative).
  [[nodiscard]] double value(int k, double tau, int derivative = 0) const;
  /// Values (rows = times, columns = basis functions): V(p, k) = φ_{J,k}^{(d)}(τ_p); built by
  /// support, O(Q · support width) evaluations of φ (a dense Q × M result). Any finite τ (taken
  /// modulo 1); throws std::invalid_argument for a non-finite τ_p (naming p), and as value().
  [[nodiscard]] Eigen::MatrixXd values(const Eigen::VectorXd& tau, int derivative = 0) const;
  /// The same values as a sparse row-major matrix (Q × M, the zeros outside the supports not
  /// stored): O(Q · support width) time and memory (DB6, M = 2^14 on Q = 2M samples: at most 11
  /// entries per row, about 4 MB, where the dense matrix needs 4.3 GB). Throws as values().
  [[nodiscard]] Eigen::SparseMatrix<double, Eigen::RowMajor> sparse_values(const Eigen::VectorXd& tau,
                                                                           int derivative = 0) const;
  /// Values on the uniform grid τ_q = q/Q, q = 0 … Q − 1 (Q × M). Throws if samples < 1.
  [[nodiscard]] Eigen::MatrixXd sampled(int samples, int derivative = 0) const;

  /// Exact operator C(i, k) = ∫₀¹ φ_{J,i}^{(d1)} φ_{J,k}^{(d2)} dτ (M × M, sparse) from the
  /// connection coefficients, in this basis' normalization (× scale()²). Throws as
  /// connection_coefficients().
  [[nodiscard]] Eigen::SparseMatrix<double> connection_matrix(int d1, int d2) const;
  /// Galerkin time operator A_d(j, k) = ∫₀¹ φ_j φ_k^{(d)} dτ = connection_matrix(0, d): row j =
  /// weighting function, column k = trial function, as FourierBasis::galerkin_operator.
  [[nodiscard]] Eigen::SparseMatrix<double> galerkin_operator(int derivative) const {
    return connection_matrix(0, derivative);
  }
  /// The paper's discrete inner products on Q points [JL14 Sec. 5]:
  ///   D(i, k) = (1/Q) Σ_q φ_{J,i}^{(d1)}(τ_q) φ_{J,k}^{(d2)}(τ_q),  τ_q = q/Q  (M × M, dense).
  /// Needs pointwise derivatives (d1, d2 ≤ max_derivative()).
  [[nodiscard]] Eigen::MatrixXd discrete_inner_products(int d1, int d2, int samples) const;

 private:
  std::shared_ptr<const ScalingFunction> function_;
  int level_, dimension_;
  Normalization normalization_;
  double scale_;
};

}  // namespace wbm::wavelets
