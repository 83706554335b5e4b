#pragma once
// Private to wbm_solvers: the collocation data of exact contact in the weighted residual (rigid
// stops and exact Coulomb friction; weighted_residual.hpp), shared by the forms of one problem at
// every frequency (WeightedResidual::Impl::collocation): the impulse instants τ_k, the trial
// values V at τ_{k+1} and the weighting values W at τ_k over M, the friction rows' increments, the
// stops' gaps per row, and which contact is which. Set up once in weighted_residual_operators.cpp.

#include <vector>

#include <Eigen/Core>

namespace wbm::solvers::detail {

struct Collocation {
  Eigen::VectorXd tau;
  Eigen::MatrixXd trial_values, weights;
  Eigen::MatrixXd increments;  // V(τ_{k+1}) − V(τ_k) (M × M), friction rows
  Eigen::VectorXd gaps;        // g0 of contact c at row k·n_c + c
  std::vector<char> coulomb;   // per contact: exact Coulomb friction (1) or a rigid stop (0)
  Eigen::VectorXd slip_forces; // μ N of contact c (0 for a stop, and under a rigid normal stop)
  // Per contact: the rigid stop whose multiplier is a friction contact's normal load
  // (ContactPoint::normal, a 2D contact), or −1; and that contact's μ.
  std::vector<int> normal_of;
  Eigen::VectorXd friction_coefficients;
  bool any_coulomb = false;
  bool any_normal = false;  // some friction contact takes its normal load from a stop
  // Moving counter-surfaces (ContactPoint::obstacle; empty when every obstacle is fixed): a
  // stop's s(τ_{k+1}) is in `gaps`; a friction row's slip is relative, Δ_k − (s(τ_{k+1}) − s(τ_k)),
  // slip_offsets(k·n_c + c) the counter-surface's own (0 on a stop's row); pin_offsets(c) = s_c(τ_1),
  // where a contact in full stick is pinned (u_c(τ_1) − s_c(τ_1) = 0).
  Eigen::VectorXd slip_offsets, pin_offsets;
};

}  // namespace wbm::solvers::detail
