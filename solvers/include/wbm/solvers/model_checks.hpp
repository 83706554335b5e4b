#pragma once
/// Physical admissibility of a structure M ü + C u̇ + K u = f, and what makes a dynamic
/// stiffness singular (issue #40, item 5). Units: SI (kg, N/m, Hz).
///
/// Sylvester's law of inertia: for symmetric K and M positive semidefinite, the numbers of
/// negative pivots of the sparse LDLᵀ factorizations of K + σM and K − σM are the numbers of
/// generalized eigenvalues ω² of K φ = ω² M φ below −σ and below +σ. With σ = 1e-12 ω²_scale
/// (ω²_scale = max_i K_ii / max_i M_ii, an upper estimate of the largest ω²) the first counts
/// the unstable directions (a negative stiffness), the difference the rigid-body modes (ω² = 0
/// to rounding). The tolerance 1e-12 leaves the first mode of a 10⁵-element rod (ω₁²/ω²_max
/// ≈ 2.5e-11) above it.

#include <string>

#include <wbm/solvers/mechanical_system.hpp>

namespace wbm::solvers {

/// The signs of the generalized eigenvalues ω² of K φ = ω² M φ (massless DOFs, rows of zeros of
/// M, count with the sign of K's Schur complement on them).
struct StiffnessInertia {
  int negative = 0;   // ω² < −σ: K is not positive semidefinite (the structure is unstable)
  int rigid_body = 0; // |ω²| ≤ σ: rigid-body modes (K singular)
  double sigma = 0.0; // σ [1/s²], the zero band used
  bool factorized = true;  // false: an LDLᵀ pivot was exactly zero; the counts are then unknown
};

/// Counts as in the file comment; two sparse LDLᵀ (Eigen::SimplicialLDLT) of n × n. Throws
/// std::invalid_argument from MechanicalSystem::validate.
[[nodiscard]] StiffnessInertia stiffness_inertia(const MechanicalSystem& system);

/// Throws std::invalid_argument unless M is symmetric positive definite (Cholesky) and K
/// symmetric positive semidefinite (stiffness_inertia: no negative ω²); rigid-body modes are
/// allowed here (the caller decides: a scene refuses them without a contact). `what` prefixes
/// the message, e.g. "MechanicalSystem"; the message names the matrix, the count and the fix.
void require_physical(const MechanicalSystem& system, const std::string& what);

/// True when (2π h f)² max|M_ii| or 2π h f max|C_ii| overflows a double for h = highest_harmonic
/// (≥ 1): the dynamic stiffness G_h cannot even be formed at that frequency.
[[nodiscard]] bool dynamic_stiffness_overflows(const MechanicalSystem& system, double frequency_hz,
                                               int highest_harmonic);

/// Why the dynamic stiffness G_h = K − (hΩ)² M + i hΩ C of harmonic h = 0 … highest, Ω = 2πf,
/// is singular, in words: rigid-body modes (G_0 = K singular), an undamped natural frequency
/// f_j = h f (the mode j and h named), or an overflow of (hΩ)² for an absurd f; "" when none of
/// these is found (then G is numerically singular for another reason). Dense generalized
/// eigenproblem for n ≤ 2000, else only the rigid-body and overflow tests.
[[nodiscard]] std::string explain_singular_dynamic_stiffness(const MechanicalSystem& system, double frequency_hz,
                                                             int highest_harmonic);

}  // namespace wbm::solvers
