#pragma once
// Private to wbm_solvers: whether the undamped modes K Φ = M Φ Λ, Φᵀ M Φ = I diagonalize the
// damping matrix C, so that the weighted-residual operator G splits into one block per mode
// (KroneckerFactorization's modal path): Rayleigh C = c_M M + c_K K, or any classical C
// (modal damping ratios, a Caughey series, one DOF), each mode then damped by (Φᵀ C Φ)_ii.

#include <optional>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <wbm/solvers/mechanical_system.hpp>

namespace wbm::solvers::detail {

/// C = c_M M + c_K K by least squares in the Frobenius inner product; true (c_M, c_K set) if it
/// fits to 1e-12 relative (the rod: c_K = β), or C = 0. False when M ∝ K (ambiguous: one DOF).
bool rayleigh_fit(const MechanicalSystem& s, double& c_m, double& c_k);

/// Caughey & O'Kelly [1965, J. Appl. Mech. 32(3) 583–588]: with M positive definite, C is
/// diagonalized by the undamped modes (classical damping) iff C M⁻¹ K = K M⁻¹ C. Checked on three
/// fixed probe vectors with one sparse LDLᵀ of M, O(nnz), before an O(n³) eigenproblem is paid
/// for: false when M cannot be factorized, a product is not finite, or a probe differs by more
/// than 1e-8 of its size (a non-classical C differs by O(1)).
bool classical_damping_probe(const MechanicalSystem& s);

/// Φᵀ C Φ's diagonal (length n) for the modes `phi` (n × n, Φᵀ M Φ = I) when its off-diagonal
/// part is below 1e-10 of it in the Frobenius norm; nothing otherwise (e.g. a repeated frequency
/// whose modes C couples). O(n nnz(C) + n³).
std::optional<Eigen::VectorXd> modal_damping_of(const MechanicalSystem& s, const Eigen::MatrixXd& phi);

}  // namespace wbm::solvers::detail
