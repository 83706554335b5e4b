#pragma once
/// Ordering of stacked unknowns, defined once for the whole project.
///
/// A time-discretized field of n DOFs on M basis functions is stored either as the n × M
/// coefficient matrix A (row = DOF i, column = basis function k) or as the stacked vector
/// a = vec(A) of length n·M, column-major, so that
///   a(k·n + i) = A(i, k)   (basis function k of DOF i).
/// With this order Θ(τ) = θ(τ)ᵀ ⊗ I_n [JL14 Eq. (13)] and every linear operator of the
/// weighted-residual method is a sum of Kronecker products (time operator) ⊗ (M, C or K):
///   (T ⊗ X) vec(A) = vec(X A Tᵀ).
/// All code indexes stacked vectors through this header.

#include <Eigen/Core>

namespace wbm::spectral {

/// Position of basis function `k` of DOF `dof` in a stacked vector of `n_dof` DOFs.
[[nodiscard]] constexpr Eigen::Index stacked_index(Eigen::Index k, Eigen::Index dof,
                                                   Eigen::Index n_dof) noexcept {
  return k * n_dof + dof;
}

/// View of a stacked vector (length n_dof·M) as its n_dof × M coefficient matrix.
[[nodiscard]] inline Eigen::Map<const Eigen::MatrixXd> as_coefficients(
    const Eigen::VectorXd& stacked, Eigen::Index n_dof) {
  return {stacked.data(), n_dof, stacked.size() / n_dof};
}

/// Stacked vector vec(A) of an n_dof × M coefficient matrix.
[[nodiscard]] inline Eigen::VectorXd stacked(const Eigen::MatrixXd& coefficients) {
  return Eigen::Map<const Eigen::VectorXd>(coefficients.data(), coefficients.size());
}

}  // namespace wbm::spectral
