#pragma once
/// What a parametrized system hands to the continuation (continuation.hpp): its residual, its
/// Jacobian (dense or sparse) and its derivative in the parameter.

#include <concepts>

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace wbm::solvers {

/// Residual R (n), Jacobian ∂R/∂x (n × n) and parameter derivative ∂R/∂λ (n) at (x, λ).
struct Linearization {
  Eigen::VectorXd residual;
  Eigen::MatrixXd jacobian;
  Eigen::VectorXd parameter_derivative;
};

/// The same with a sparse Jacobian: the bordered systems are then solved by sparse LU
/// (Eigen::SparseLU, COLAMD ordering), for large systems with few couplings, e.g. harmonic
/// balance of an FE model whose nonlinearity sits on a few DOFs.
struct SparseLinearization {
  Eigen::VectorXd residual;
  Eigen::SparseMatrix<double> jacobian;
  Eigen::VectorXd parameter_derivative;
};

/// A square system along one parameter: residual(x, λ) and linearize(x, λ), the latter
/// returning a Linearization (dense) or a SparseLinearization. A system may also provide
/// linear_solver(), a linear-solver policy (newton.hpp) for its Jacobians and for their forms
/// bordered by the continuation (one more row and column); pseudo_arclength then uses it.
template <class S>
concept ParametrizedSystem = requires(const S& s, const Eigen::VectorXd& x, double p) {
  { s.residual(x, p) } -> std::convertible_to<Eigen::VectorXd>;
  requires std::same_as<decltype(s.linearize(x, p)), Linearization> ||
               std::same_as<decltype(s.linearize(x, p)), SparseLinearization>;
};

}  // namespace wbm::solvers
