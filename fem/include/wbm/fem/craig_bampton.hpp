#pragma once
/// Craig–Bampton reduction [Craig & Bampton 1968, AIAA J. 6(7) 1313–1319; LL11 Sec. 5.2]:
/// the interface (boundary) DOFs b are kept, the interior DOFs i are represented by the static
/// constraint modes Ψ = −K_ii⁻¹ K_ib and the first m fixed-interface normal modes Φ of
/// K_ii φ = ω² M_ii φ (mass-normalized, Φᵀ M_ii Φ = I, Φᵀ K_ii Φ = Ω² = diag ω_k²):
///   u_b = q_b,   u_i = Ψ q_b + Φ η,   q = (q_b, η)  (|b| + m reduced coordinates),
///   K_r = Tᵀ K T = [[K_bb + K_bi Ψ, 0], [0, Ω²]],
///   M_r = Tᵀ M T = [[M_bb + M_bi Ψ + Ψᵀ M_ib + Ψᵀ M_ii Ψ, (M_bi + Ψᵀ M_ii) Φ], [sym., I]].
/// Statics are exact for interface loads (K_r reproduces the full model's interface stiffness);
/// frequencies converge from above as m grows. Sparse throughout: one sparse Cholesky (LLᵀ,
/// CHOLMOD supernodal) of K_ii serves both Ψ and Spectra's shift-invert Lanczos for Φ (SymGEigsShiftSolver
/// at shift 0) — never a dense eigensolver on the full model. Units: those of K and M.

#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace wbm::fem {

struct CraigBamptonModel {
  Eigen::MatrixXd stiffness;       // K_r, (|b| + m) × (|b| + m), symmetric
  Eigen::MatrixXd mass;            // M_r, (|b| + m) × (|b| + m), symmetric positive definite
  std::vector<int> boundary;       // b: the kept DOFs (rows of the full model), in the order given
  std::vector<int> interior;       // i: the others, ascending
  Eigen::MatrixXd constraint_modes;  // Ψ, |i| × |b|
  Eigen::MatrixXd normal_modes;      // Φ, |i| × m, mass-normalized
  Eigen::VectorXd normal_frequencies_hz;  // ω_k / 2π of the fixed-interface modes, ascending
  /// Wall time [s] of the stages: Cholesky of K_ii, the |b| solves for Ψ, the Lanczos for Φ,
  /// the assembly of K_r and M_r.
  double factorization_s = 0.0, constraint_modes_s = 0.0, eigensolve_s = 0.0, assembly_s = 0.0;
  /// Applications of the shift-invert operator K_ii⁻¹ M_ii by the Lanczos (one triangular solve
  /// pair with the Cholesky factor each, Spectra's num_operations), and the passes of its
  /// implicitly restarted loop (num_iterations; 1: converged without a restart).
  long eigensolve_operations = 0, eigensolve_passes = 0;
  /// Full displacements (n × k, rows of the full model) from reduced coordinates (|b| + m) × k.
  [[nodiscard]] Eigen::MatrixXd expand(const Eigen::MatrixXd& reduced) const;
};

/// Reduces (K, M) (n × n, symmetric; K_ii positive definite, i.e. the interface and the model's
/// boundary conditions remove every rigid-body motion of the interior) onto `boundary` + `modes`
/// fixed-interface modes (an empty boundary gives the whole model's first `modes` normal modes,
/// sparse, e.g. as the reference for the reduction's frequencies). Throws std::invalid_argument for a size mismatch, a boundary DOF out of
/// range or repeated, modes < 0 or ≥ |i|, and std::runtime_error if K_ii is not positive definite
/// (its Cholesky fails: name it) or the eigensolver does not converge (with Spectra's status).
[[nodiscard]] CraigBamptonModel craig_bampton(const Eigen::SparseMatrix<double>& stiffness,
                                              const Eigen::SparseMatrix<double>& mass,
                                              const std::vector<int>& boundary, int modes);

}  // namespace wbm::fem
