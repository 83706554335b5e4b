#pragma once
// The undamped modes of a structure, K Φ = M Φ Λ with Φᵀ M Φ = I: the modal basis of the
// weighted-residual solvers' modal path (LinearSolverPath::Modal).
#include <optional>
#include <string>

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace wbm::solvers {

/// Eigenpairs of the symmetric-definite pencil (K, M).
///  - lambda: the n eigenvalues λ_i = ω_i² [rad²/s²], ascending;
///  - phi: n × n, column i the mode of λ_i, mass-normalized: Φᵀ M Φ = I;
///  - method: "dense" (Eigen's GeneralizedSelfAdjointEigenSolver: Cholesky of M, Householder
///    tridiagonalization and QR, O(n³)) or "tridiagonal" (below).
struct UndampedModes {
  Eigen::VectorXd lambda;
  Eigen::MatrixXd phi;
  std::string method;
};

/// The modes of a pencil whose K and M are both tridiagonal (a rod or a chain in its natural DOF
/// order), in O(n²) instead of O(n³):
///  - each λ_i by bisection on Sylvester's inertia: the number of negative pivots of the LDLᵀ of
///    the tridiagonal K − σM is the number of eigenvalues below σ [Parlett, The Symmetric
///    Eigenvalue Problem, 1998, Sec. 3.3 and 7.2 (Sturm sequences)], to the last bits of σ;
///  - each φ_i by inverse iteration, (K − λ_i M) y = M x with LAPACK's tridiagonal LU (dgttrf,
///    partial pivoting), three steps, M-orthogonalized against the modes of its cluster
///    (|λ_i − λ_j| ≤ 1e-3 |λ_i|), as LAPACK's dstein does for a standard tridiagonal matrix.
/// K and M are n × n symmetric, tridiagonal, M positive definite. nullopt if they are not
/// tridiagonal, not of one size, or if M is not positive definite (a nonpositive pivot of its
/// LDLᵀ). Throws nothing else.
[[nodiscard]] std::optional<UndampedModes> tridiagonal_undamped_modes(const Eigen::SparseMatrix<double>& stiffness,
                                                                      const Eigen::SparseMatrix<double>& mass);

/// The modes by the tridiagonal method when K and M are tridiagonal and n ≥ 400 (where it is
/// measured faster: 1 280 DOFs in docs/design.md), by the dense method otherwise; so the models
/// of the papers' figures (n ≤ 100) keep the dense method's bits. Throws std::invalid_argument
/// if the dense eigenproblem fails (M not positive definite).
[[nodiscard]] UndampedModes undamped_modes(const Eigen::SparseMatrix<double>& stiffness,
                                           const Eigen::SparseMatrix<double>& mass);

}  // namespace wbm::solvers
