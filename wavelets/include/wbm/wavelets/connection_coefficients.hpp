#pragma once
/// Connection coefficients of the scaling functions of scaling_function.hpp on the real line,
/// and their periodized M×M operator matrices at level J [LRT91; B92; RL93; JL14 Sec. 3.4].
/// Dimensionless; derivatives are with respect to t (real line) or τ ∈ [0, 1) (periodized).

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <wbm/wavelets/scaling_function.hpp>

namespace wbm::wavelets {

/// Γ^{d1,d2}[k] = ∫ φ^{(d1)}(t) φ^{(d2)}(t − k) dt for first_shift ≤ k ≤ last_shift (zero
/// outside), with d = d1 + d2. Exact identities (from φ(t) and Σ_k k^m φ(t − k) = t^m + …):
///   Γ^{d1,d2}[k] = (−1)^{d1} Γ^{0,d}[k],  Γ^{0,d}[−k] = (−1)^d Γ^{0,d}[k],
///   Σ_k k^m Γ^{0,d}[k] = 0 for m < d and d! for m = d (d ≤ 2N − 1, N vanishing moments).
/// Haar and Daubechies: Γ^{0,d} is the solution of the two-scale eigen-system
///   Γ^{0,d}[k] = 2^d Σ_j a_j Γ^{0,d}[2k − j],  a_j = ½ Σ_l p_l p_{l+j}  (Σ_j a_j = 2),
/// with the moment rows above as normalization [LRT91; B92], solved in least squares by a
/// rank-revealing QR; `residual` is the largest equation residual of that solution.
/// B-spline: Γ^{d1,d2}[k] = Σ_s A[s] β^{e1,e2}[k + s] with A[s] = Σ_i c_i c_{i+s} and β the
/// exact (4-point Gauss–Legendre, GSL) cubic B-spline connection coefficients, derivatives
/// balanced by parts so that e1, e2 ≤ 3; exact up to the truncation of c_k.
struct ConnectionCoefficients {
  int d1 = 0, d2 = 0;
  int first_shift = 0, last_shift = 0;
  Eigen::VectorXd values;   // values(k − first_shift) = Γ^{d1,d2}[k]
  double residual = 0.0;

  /// Γ^{d1,d2}[k], zero outside [first_shift, last_shift].
  [[nodiscard]] double at(int k) const {
    return (k < first_shift || k > last_shift) ? 0.0 : values(k - first_shift);
  }
};

/// L² Sobolev exponent s of φ (φ ∈ H^σ for σ < s): s = −log₄ ρ′, ρ′ the spectral radius of the
/// transfer matrix T(i, m) = a_{2i−m}, |i|, |m| ≤ L − 1, once the eigenvalues 2^{−m},
/// m = 0 … 2N − 1, of polynomial reproduction are removed [V92; CD96]. Haar ½ and DB4 1 in
/// closed form; DB6 log₄(64/9) ≈ 1.415. B-spline 3.5 (B₃ ∈ H^{3.5−ε}).
[[nodiscard]] double sobolev_exponent(const Family& family);

/// Largest total order d = d1 + d2 for which Γ^{d1,d2} exists (in the distributional sense
/// φ ∈ H^s, φ^{(d)} ∈ H^{s−d}, a pairing that needs d < 2s): Haar 0, DB4 1, DB6 2, DB8 3,
/// DB10–DB12 4, DB14–DB16 5, DB18–DB20 6, B-spline 6. For Haar and Daubechies this is exactly
/// the condition 2^{−d} > ρ′ under which the eigen-system above has a unique normalized solution.
[[nodiscard]] int max_connection_order(const Family& family);

/// Γ^{d1,d2} of `family`. Throws std::invalid_argument if d1 < 0, d2 < 0, or
/// d1 + d2 > max_connection_order(family); the message names the family, the order and the
/// largest admissible order, and suggests a smoother family (e.g. DB6 for d = 2).
[[nodiscard]] ConnectionCoefficients connection_coefficients(const Family& family, int d1, int d2);

/// Periodized connection-coefficient operator at level J as an M×M sparse matrix, M = 2^J:
///   C(i, k) = ∫₀¹ φ_{J,i}^{(d1)}(τ) φ_{J,k}^{(d2)}(τ) dτ = 2^{J(d1+d2)} Σ_ℓ Γ^{d1,d2}[k − i + ℓM],
/// 0 ≤ i, k < M (row i carries the d1-differentiated function), for the L²-orthonormal periodized
/// φ_{J,k}(τ) = Σ_ℓ 2^{J/2} φ(2^J(τ − ℓ) − k) [JL14 Eqs. (19), (25)], wrapped as in [RL93];
/// valid for every J ≥ 0, including levels where the support is longer than the period.
/// The paper's ∫₀¹ φ_{J,k} = 1 scaling multiplies C by 2^J (see PeriodizedBasis).
/// Throws std::invalid_argument if level < 0 or level > 20.
[[nodiscard]] Eigen::SparseMatrix<double> periodized_connection_matrix(
    const ConnectionCoefficients& coefficients, int level);

}  // namespace wbm::wavelets
