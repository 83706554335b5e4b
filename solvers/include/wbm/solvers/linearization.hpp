#pragma once
/// What a parametrized system hands to the continuation (continuation.hpp): its residual, its
/// Jacobian (dense or sparse) and its derivative in the parameter.

#include <concepts>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <wbm/solvers/newton.hpp>

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

/// The same with an identity-plus-low-rank Jacobian (newton.hpp), the condensed contact systems:
/// J = (I + U V)/s with rank r the samples in contact. The bordered systems are then solved by
/// the bordered Woodbury (bordered_low_rank, WoodburyLu): an (r + 2) LU per corrector iteration
/// instead of an (n + 1) one, and U costs r products with the compliance instead of n.
struct LowRankLinearization {
  Eigen::VectorXd residual;
  LowRankJacobian jacobian;
  Eigen::VectorXd parameter_derivative;
};

/// A square system along one parameter: residual(x, λ) and linearize(x, λ), the latter
/// returning a Linearization (dense), a SparseLinearization or a LowRankLinearization. A system may also provide
/// linear_solver(), a linear-solver policy (newton.hpp) for its Jacobians and for their forms
/// bordered by the continuation (one more row and column); pseudo_arclength then uses it.
template <class S>
concept ParametrizedSystem = requires(const S& s, const Eigen::VectorXd& x, double p) {
  { s.residual(x, p) } -> std::convertible_to<Eigen::VectorXd>;
  requires std::same_as<decltype(s.linearize(x, p)), Linearization> ||
               std::same_as<decltype(s.linearize(x, p)), SparseLinearization> ||
               std::same_as<decltype(s.linearize(x, p)), LowRankLinearization>;
};

/// The smooth piece of a piecewise-smooth residual: one entry per switching unknown (a contact
/// sample), 1 where the nonsmooth law takes its active branch (Signorini: the sample touches its
/// stop, g_s = 0; penalty: the spring is compressed, f_s = k g_s), 0 where it takes the other
/// (f_s = 0).
using ActiveSet = std::vector<std::uint8_t>;

/// A ParametrizedSystem whose residual is smooth on each piece of a finite partition, such as the
/// complementarity min(λ_s, −g_s) or the kink of a penalty law at g_s = 0 [Leine & Nijmeijer
/// 2004, Ch. 7; Acary & Brogliato 2008, Ch. 12]. Besides residual(x, p) and linearize(x, p) (the
/// nonsmooth system, verified at every accepted point), it gives
///   active_set(x, p)        the piece the nonsmooth residual picks at (x, p);
///   residual(x, p, a),
///   linearize(x, p, a)      the smooth residual of piece a and its linearization;
///   events(x, p, a)         one event function per entry of a (same length and order), ≥ 0
///                           while (x, p) lies in piece a: for Signorini λ_s on an active sample
///                           and −g_s on an inactive one; for a penalty g_s and −g_s.
/// A branch crosses into the neighbouring piece where an event function changes sign; the entry
/// of that event is then flipped. pseudo_arclength locates these events and switches pieces
/// there (continuation.hpp).
template <class S>
concept PiecewiseSmoothSystem =
    ParametrizedSystem<S> && requires(const S& s, const Eigen::VectorXd& x, double p, const ActiveSet& a) {
      { s.active_set(x, p) } -> std::same_as<ActiveSet>;
      { s.residual(x, p, a) } -> std::convertible_to<Eigen::VectorXd>;
      { s.events(x, p, a) } -> std::convertible_to<Eigen::VectorXd>;
      requires std::same_as<decltype(s.linearize(x, p, a)), decltype(s.linearize(x, p))>;
    };

}  // namespace wbm::solvers
