#pragma once
/// Pieces of pseudo_arclength (continuation.hpp), not API: the bordered matrix of the scaled
/// problem, the inner product of the arclength metric, the corrector as a NonlinearSystem for
/// newton(), the tangent, and one predictor–corrector attempt.

#include <cmath>
#include <concepts>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <wbm/solvers/linearization.hpp>
#include <wbm/solvers/newton.hpp>

namespace wbm::solvers::detail {

// The bordered matrix [[∂R/∂x̂, ∂R/∂λ̂]; [t_xᵀ/n, t_λ]] of the scaled problem, dense or sparse
// (every entry of the border stored, so that its pattern depends on ∂R/∂x̂ only and the sparse
// symbolic analysis can be reused).
inline Eigen::MatrixXd bordered(const Linearization& l, const Eigen::VectorXd& t, double xs, double ls) {
  const auto n = l.jacobian.rows();
  Eigen::MatrixXd b(n + 1, n + 1);
  b.topLeftCorner(n, n) = l.jacobian * xs;
  b.topRightCorner(n, 1) = l.parameter_derivative * ls;
  b.bottomLeftCorner(1, n) = t.head(n).transpose() / static_cast<double>(n);
  b(n, n) = t(n);
  return b;
}

// Sparse: written column by column in compressed form (J's columns with the border's row
// appended, then the border's column), the same matrix as setFromTriplets would assemble from
// J's entries and the border's (J has no duplicates; its rows sorted within each column, as
// setFromTriplets and insert() leave them), in O(nnz) without a sort.
inline Eigen::SparseMatrix<double> bordered(const SparseLinearization& l, const Eigen::VectorXd& t, double xs,
                                            double ls) {
  const auto n = l.jacobian.rows();
  Eigen::SparseMatrix<double> b(n + 1, n + 1);
  const auto nnz = l.jacobian.nonZeros() + 2 * n + 1;
  b.resizeNonZeros(nnz);
  int* outer = b.outerIndexPtr();
  int* inner = b.innerIndexPtr();
  double* value = b.valuePtr();
  int k = 0;
  for (Eigen::Index c = 0; c < n; ++c) {
    outer[c] = k;
    for (Eigen::SparseMatrix<double>::InnerIterator it(l.jacobian, c); it; ++it) {
      inner[k] = static_cast<int>(it.row());
      value[k++] = it.value() * xs;
    }
    inner[k] = static_cast<int>(n);
    value[k++] = t(c) / static_cast<double>(n);
  }
  outer[n] = k;
  for (Eigen::Index i = 0; i < n; ++i) {
    inner[k] = static_cast<int>(i);
    value[k++] = l.parameter_derivative(i) * ls;
  }
  inner[k] = static_cast<int>(n);
  value[k++] = t(n);
  outer[n + 1] = k;
  return b;
}

// The same for an identity-plus-low-rank Jacobian: the bordered Woodbury (newton.hpp).
inline LowRankJacobian bordered(const LowRankLinearization& l, const Eigen::VectorXd& t, double xs, double ls) {
  const auto n = l.jacobian.size();
  return bordered_low_rank(l.jacobian, xs, l.parameter_derivative * ls, t.head(n) / static_cast<double>(n), t(n));
}

// The linear-solver policy of a branch: the system's own (linear_solver(), for its Jacobians
// and their bordered forms, e.g. NonlinearModes::BackboneSystem::KktSolver), else SparseLu for
// sparse linearizations, WoodburyLu for low-rank ones and DenseLu for dense ones.
template <class S>
concept ProvidesLinearSolver = requires(const S& s, const Eigen::VectorXd& r) {
  { s.linear_solver().solve(r) } -> std::convertible_to<Eigen::VectorXd>;
};
template <class Lin, class S>
auto branch_linear_solver(const S& system) {
  if constexpr (ProvidesLinearSolver<S>) {
    return system.linear_solver();
  } else if constexpr (std::is_same_v<Lin, SparseLinearization>) {
    return SparseLu{};
  } else if constexpr (std::is_same_v<Lin, LowRankLinearization>) {
    return WoodburyLu{};
  } else {
    return DenseLu{};
  }
}

inline bool finite(const Linearization& l) { return l.jacobian.allFinite() && l.parameter_derivative.allFinite(); }
inline bool finite(const LowRankLinearization& l) {
  return l.jacobian.all_finite() && l.parameter_derivative.allFinite();
}
inline bool finite(const SparseLinearization& l) {
  return Eigen::Map<const Eigen::VectorXd>(l.jacobian.valuePtr(), l.jacobian.nonZeros()).allFinite() &&
         l.parameter_derivative.allFinite();
}

// `to` takes `from`'s contents. Eigen 3.4's SparseMatrix has no move assignment (its operator=
// copies a matrix that is not marked as a temporary), so a sparse linearization is swapped in,
// member by member, rather than copied (a few MB per corrector iteration on a blade).
inline void take(SparseLinearization& to, SparseLinearization&& from) {
  to.residual.swap(from.residual);
  to.jacobian.swap(from.jacobian);
  to.parameter_derivative.swap(from.parameter_derivative);
}
template <class Lin>
void take(Lin& to, Lin&& from) {
  to = std::move(from);
}

inline double inner(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  const auto n = a.size() - 1;
  return a.head(n).dot(b.head(n)) / static_cast<double>(n) + a(n) * b(n);
}

// The corrector of one step as a NonlinearSystem in the scaled ẑ (length n + 1), for newton():
//   [R(x, λ); ⟨t, ẑ − ẑ_k⟩ − h] = 0, Jacobian the bordered matrix.
// residual() evaluates R alone (S::residual, the same arithmetic as the linearization's
// residual); jacobian() and at() linearize, once per ẑ (cached), and the tangent at the converged
// point reuses it. So a Jacobian is formed only where a Newton step or a tangent uses it: where
// the corrector converges (at an iterate, or at once from an exact predictor) none is formed
// unless a tangent is taken, and the event location's trials take none. Where the residuals of
// S::residual and S::linearize agree bit for bit the iterates are those of a corrector that
// linearizes everywhere. A non-finite Jacobian is refused by the linear solver's factorize()
// (newton(): SingularJacobian), and the tangent with one is NaN.
template <class S, class Lin>
struct Corrector {
  const S* system;
  double xs, ls;
  Eigen::VectorXd direction, z_last;
  double step;
  mutable Eigen::VectorXd cached_z;
  mutable Lin cached;
  mutable bool linearized = false;  // cached holds the Jacobian at cached_z, not only R
  [[nodiscard]] const Lin& at(const Eigen::VectorXd& z) const {
    if (!linearized || cached_z.size() != z.size() || cached_z != z) {
      const auto n = z.size() - 1;
      take(cached, system->linearize(z.head(n) * xs, z(n) * ls));
      cached_z = z;
      linearized = true;
    }
    return cached;
  }
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& z) const {
    const auto n = z.size() - 1;
    if (cached_z.size() != z.size() || cached_z != z) {
      cached.residual = system->residual(z.head(n) * xs, z(n) * ls);
      cached_z = z;
      linearized = false;
    }
    Eigen::VectorXd r(n + 1);
    r.head(n) = cached.residual;
    r(n) = inner(direction, z - z_last) - step;
    return r;
  }
  [[nodiscard]] auto jacobian(const Eigen::VectorXd& z) const { return bordered(at(z), direction, xs, ls); }
};

// The unit tangent at a linearization: the bordered matrix with the previous tangent as its last
// row, solved for the right-hand side (0, 1), so that ⟨previous, t⟩ > 0. NaN if the bordered
// matrix is singular. Solver: DenseLu or SparseLu (its symbolic analysis is reused).
template <class Lin, class Solver>
Eigen::VectorXd tangent(Solver& solver, const Lin& l, const Eigen::VectorXd& previous, double xs, double ls) {
  const auto n = previous.size() - 1;
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n + 1);
  rhs(n) = 1.0;
  if (!solver.factorize(bordered(l, previous, xs, ls))) return Eigen::VectorXd::Constant(n + 1, NAN);
  const Eigen::VectorXd t = solver.solve(rhs);
  return t / std::sqrt(inner(t, t));
}

// One predictor–corrector attempt: the scaled point ẑ reached, its tangent, and the corrector's
// outcome: Newton's status; SingularJacobian when the converged point has no tangent (the bordered
// matrix did not factorize); ResidualNotVerified when the nonsmooth residual recomputed at an
// accepted point is above the corrector tolerance (pseudo_arclength).
struct Attempt {
  SolveStatus status = SolveStatus::MaxIterations;
  int iterations = 0;
  double rnorm = 0.0;
  Eigen::VectorXd z, tangent;
  [[nodiscard]] bool converged() const { return status == SolveStatus::Converged; }
  // The corrector was stopped because its iterates cycled (stop_on_cycle): without line search
  // only a cycle stagnates.
  [[nodiscard]] bool cycled() const { return status == SolveStatus::Stagnated; }
};

// Predictor ẑ⁰ = ẑ_last + step·direction, corrector newton() without line search on the
// bordered system, then (unless with_tangent is false) the tangent at the converged point (from
// the cached linearization).
template <class S, class Lin, class Solver>
Attempt attempt_along(const S& system, Solver& solver, double xs, double ls, const NewtonOptions& corrector_options,
                      const Eigen::VectorXd& direction, const Eigen::VectorXd& z_last, double step,
                      bool with_tangent = true) {
  Attempt a;
  const Corrector<S, Lin> corrector{&system, xs, ls, direction, z_last, step, {}, {}};
  NewtonResult r = newton(corrector, Eigen::VectorXd(z_last + step * direction), corrector_options, solver);
  a.status = r.report.status;
  a.iterations = r.report.iterations;
  a.rnorm = r.report.residual_norms.back();
  a.z = std::move(r.x);
  if (a.converged() && with_tangent) {
    a.tangent = tangent(solver, corrector.at(a.z), direction, xs, ls);
    if (!a.tangent.allFinite()) a.status = SolveStatus::SingularJacobian;
  }
  return a;
}

}  // namespace wbm::solvers::detail
