#pragma once
/// Clamped-free axial rod of two-node linear finite elements [JL14 Sec. 2; LL11 Sec. 5.1].
/// Units: SI throughout (Pa, kg/m³, m², m, N, s, Hz where the name says _hz).

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace wbm::fem {

/// Rod data. No defaults: physics is always stated, so nothing silently inherits a case.
struct RodParameters {
  double young_modulus;  // E [Pa] > 0
  double density;        // ρ [kg/m³] > 0
  double area;           // S [m²] > 0
  double length;         // L [m] > 0
  int elements;          // number of equal elements, >= 1
  /// Throws std::invalid_argument naming the field, its value and the allowed range.
  void validate() const;
};

/// Assembled clamped-free rod. Nodes 0 … E (E = elements) at x_j = j·L/E; node 0 is clamped
/// (Dirichlet, removed), so DOF i ↔ node i + 1 and the free tip is DOF n − 1 with n = E.
/// Element matrices (le = L/E), assembled and stored sparse (n × n, tridiagonal):
///   consistent mass   M_e = ρ S le / 6 · [[2, 1], [1, 2]]   [kg]
///   stiffness         K_e = E S / le · [[1, −1], [−1, 1]]   [N/m]
/// Damping is the solvers' concern (β-damping C = βK of [JL14 Eq. (7)]).
/// Immutable after construction; throws std::invalid_argument on invalid parameters.
class Rod {
 public:
  explicit Rod(const RodParameters& parameters);

  [[nodiscard]] const RodParameters& parameters() const noexcept { return parameters_; }
  [[nodiscard]] int dofs() const noexcept { return parameters_.elements; }
  [[nodiscard]] int tip_dof() const noexcept { return parameters_.elements - 1; }
  /// DOF of node j (1 ≤ j ≤ E); throws std::out_of_range for the clamped node 0 or j > E.
  [[nodiscard]] int dof_of_node(int node) const;
  /// Axial positions [m] of the free nodes, ordered as the DOFs (length n).
  [[nodiscard]] Eigen::VectorXd node_positions() const;

  [[nodiscard]] const Eigen::SparseMatrix<double>& mass() const noexcept { return mass_; }
  [[nodiscard]] const Eigen::SparseMatrix<double>& stiffness() const noexcept { return stiffness_; }

  /// First `count` natural frequencies [Hz], ascending, of K φ = ω² M φ (Eigen's
  /// GeneralizedSelfAdjointEigenSolver on the dense matrices; n is small for rods).
  /// Throws std::invalid_argument unless 1 ≤ count ≤ n.
  [[nodiscard]] Eigen::VectorXd natural_frequencies_hz(int count) const;

 private:
  RodParameters parameters_;
  Eigen::SparseMatrix<double> mass_;
  Eigen::SparseMatrix<double> stiffness_;
};

}  // namespace wbm::fem
