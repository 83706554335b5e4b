#pragma once
/// Static condensation of massless DOFs (a contact node on a spring, a spring-only junction).
/// Units: SI as in mechanical_system.hpp.
///
/// Partition u = (u_m, u_s): m the DOFs with mass, s the massless ones (their rows and columns
/// of M are exactly zero). The massless rows carry no inertia and no damping, so at every instant
///   K_ss u_s + K_sm u_m = −Σ_{c on s} e_c f_c,
/// and with the flexibility F = K_ss⁻¹ and the transfer T = −F K_sm (|s| × |m|):
///   u_s = T u_m − F Σ_c e_c f_c,
///   M_mm ü_m + C_mm u̇_m + K̃ u_m + Σ_c e'_c f_c = f_m,   K̃ = K_mm + K_ms T   (Guyan, exact here).
/// A contact on a massless DOF j (direction σ e_j, σ = ±1) becomes a contact on the DOFs with
/// mass along e'_c = σ Tᵀ e_j, whose displacement s = σ (T u_m)_j is where node j would be
/// without contact; its law is reached through the spring of flexibility F_jj:
///   - a rigid stop becomes contact::LinearPenalty{1/F_jj, g0} (the spring is the contact
///     stiffness: exact, not an approximation);
///   - a penalty law becomes contact::SeriesCompliance{law, F_jj}.
/// Contacts between DOFs with mass are kept as they are. Exact as long as the conditions below
/// hold; otherwise condense_massless throws std::invalid_argument saying which and how to fix it:
///   - C is zero on the massless rows and columns (a dashpot on a massless node makes it a
///     first-order DOF, not a static one);
///   - no force acts on a massless DOF;
///   - a contact on a massless DOF involves that DOF only (a stop, not a contact between DOFs),
///     and contacts on DOFs with mass do not involve massless DOFs;
///   - two massless contact DOFs are not coupled through F (F_jk = 0 to 1e-12 relative), so that
///     each contact force depends on its own s only;
///   - K_ss is positive definite (every massless DOF is held by springs).
/// Cost: one sparse Cholesky of K_ss and |m| solves; for the small spring-node models this is
/// for, not for condensing a large FE model (that is Craig–Bampton's job).
#include <string>
#include <vector>

#include <Eigen/Core>

#include <wbm/solvers/mechanical_system.hpp>

namespace wbm::solvers {

struct MasslessCondensation {
  std::vector<int> retained;  // the DOFs with mass, ascending (full numbering)
  std::vector<int> massless;  // the massless DOFs, ascending (full numbering)
  /// M_mm, C_mm, K̃ (retained numbering). C_mm is the given C's block.
  MechanicalSystem system;
  /// One per given contact, same order, on the retained numbering.
  std::vector<ContactPoint> contacts;
  Eigen::MatrixXd transfer;     // T, |s| × |m|
  Eigen::MatrixXd flexibility;  // F = K_ss⁻¹, |s| × |s|
  /// For each given contact: its row in `massless` if it acts on a massless DOF, else −1.
  std::vector<int> contact_row;
  /// ±1: the sign σ of each contact on a massless DOF (0 for the others).
  std::vector<double> contact_sign;

  /// Full numbering → retained numbering, or −1 for a massless DOF.
  [[nodiscard]] int retained_index(int dof) const;
  /// Displacements of every DOF (n × P, full numbering) from those of the retained DOFs
  /// (|m| × P): u_s = T u_m − F Σ_c e_c f_c(s_c) at each column.
  [[nodiscard]] Eigen::MatrixXd expand_displacement(const Eigen::MatrixXd& retained_displacement) const;
  /// Velocities of every DOF (n × P): u̇_s = T u̇_m − F Σ_c e_c f_c'(s_c) ṡ_c.
  [[nodiscard]] Eigen::MatrixXd expand_velocity(const Eigen::MatrixXd& retained_displacement,
                                                const Eigen::MatrixXd& retained_velocity) const;
};

/// The massless DOFs of M: rows that are exactly zero (ascending).
[[nodiscard]] std::vector<int> massless_dofs(const Eigen::SparseMatrix<double>& mass);

/// Condenses the massless DOFs of `system` out, with its contacts, as described above.
/// `forced_dofs` are the DOFs that carry an external force (none may be massless); `names`
/// (optional, one per DOF) name the DOFs in messages. Throws std::invalid_argument (conditions
/// above, each message naming the DOF) or if there is no massless DOF, or no DOF with mass.
[[nodiscard]] MasslessCondensation condense_massless(const MechanicalSystem& system,
                                                     const std::vector<ContactPoint>& contacts,
                                                     const std::vector<int>& forced_dofs,
                                                     const std::vector<std::string>& names = {});

}  // namespace wbm::solvers
