#pragma once
/// Second-order mechanical system M ü + C u̇ + K u = f_ext(t) − Σ_c e_c f_c(u_c) [JL14 Eq. (7)].
/// Units: SI (kg, N·s/m, N/m, N, m, s, Hz where the name says _hz).

#include <memory>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <wbm/contact/penalty.hpp>
#include <wbm/fem/rod.hpp>

namespace wbm::solvers {

/// Mass, damping and stiffness matrices, n × n, sparse, symmetric.
struct MechanicalSystem {
  Eigen::SparseMatrix<double> mass;       // M [kg]
  Eigen::SparseMatrix<double> damping;    // C [N·s/m]
  Eigen::SparseMatrix<double> stiffness;  // K [N/m]
  [[nodiscard]] int dofs() const { return static_cast<int>(mass.rows()); }
  /// Throws std::invalid_argument if the matrices are not square of one size, not finite, or
  /// not symmetric to 1e-12 of their largest entry (the message names the matrix and entry).
  void validate() const;
};

/// The FE rod with β-damping C = βK [JL14 Eq. (7)]. Throws std::invalid_argument unless
/// β ≥ 0 and finite.
[[nodiscard]] MechanicalSystem beta_damped(const fem::Rod& rod, double beta);

/// Harmonic point force F cos(2π f t) on one DOF.
struct HarmonicForcing {
  int dof;              // forced DOF, 0 ≤ dof < n
  double amplitude;     // F [N], finite
  double frequency_hz;  // f [Hz] > 0; the period T = 1/f is the period of the response
  /// Throws std::invalid_argument naming the field, its value and the allowed range.
  void validate(int dofs) const;
};

/// A contact law acting on one DOF against a fixed obstacle, or between two DOFs (law shared,
/// immutable). The law is evaluated on the contact displacement u_c = u[dof] − u[other] (u[dof]
/// alone when other < 0), towards closing the gap, and its force f_c pushes the two apart:
/// −f_c on `dof`, +f_c on `other` (the equation of motion has −e_c f_c with e_c = e_dof − e_other).
struct ContactPoint {
  int dof;
  std::shared_ptr<const contact::ContactLaw> law;
  int other = -1;  // the second DOF of a relative contact (two bodies), or −1 (a fixed obstacle)
  /// u_c for a vector indexed by DOF (length n).
  [[nodiscard]] double displacement(const Eigen::Ref<const Eigen::VectorXd>& u) const {
    return other < 0 ? u(dof) : u(dof) - u(other);
  }
  /// e_c (length n): 1 at dof, −1 at other.
  [[nodiscard]] Eigen::VectorXd direction(int n) const {
    Eigen::VectorXd e = Eigen::VectorXd::Zero(n);
    e(dof) = 1.0;
    if (other >= 0) e(other) = -1.0;
    return e;
  }
  /// Throws std::invalid_argument for a DOF (or other DOF) out of range, other == dof, a null law
  /// or a repeated (dof, other) pair.
  static void validate(const std::vector<ContactPoint>& contacts, int dofs);
};

/// Direct complex frequency response without contact: (K − ω² M + iω C) U = F e_dof,
/// ω = 2π f; u(t) = Re(U e^{iωt}). Sparse LU; returns U (length n, complex amplitudes [m]).
[[nodiscard]] Eigen::VectorXcd frequency_response(const MechanicalSystem& system,
                                                  const HarmonicForcing& forcing);

}  // namespace wbm::solvers
