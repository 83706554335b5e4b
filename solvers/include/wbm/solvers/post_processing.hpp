#pragma once
/// Post-processing of periodic weighted-residual solutions [JL14 Secs. 5.1–5.5]: displacement and
/// velocity at any time, contact forces, system energy, energy norm and rms errors. Units: SI.

#include <vector>

#include <string>

#include <Eigen/Core>

#include <wbm/solvers/mechanical_system.hpp>
#include <wbm/solvers/time_basis.hpp>

namespace wbm::solvers {

/// Empty if evaluate_trial can give the velocity of `trial` (a pointwise first derivative, or
/// Haar's delta pairs); else why not and what to use instead (DB4 has neither).
[[nodiscard]] std::string velocity_unavailable(const TimeBasis& trial);

/// Displacement (d = 0, [m]) or velocity in physical time (d = 1, [m/s]) of DOF `dof` at the
/// normalized times tau, from an n × M trial coefficient matrix:
///   u_i(τ) = Σ_k A(i, k) q_k(τ) [JL14 Eq. (11)],   u̇_i(τ) = f Σ_k A(i, k) q̇_k(τ) [JL14 Eq. (34)].
/// Haar trial functions have no pointwise derivative; their velocity uses the delta-pair
/// representation of [JL14 Sec. 5.2], q̇_k = c (δ(τ − k/M) − δ(τ − (k+1)/M)) with c the value of
/// q_k on its cell, in the discrete form where each δ(τ − k/M) is a box of width 1/M and
/// height M centred on the jump. Hence, with u_k the value of u on cell [k/M, (k+1)/M),
///   u̇(τ) = f M (u_k − u_{k−1})   for τ ∈ [(k − ½)/M, (k + ½)/M)   (indices mod M),
/// the difference quotient of neighbouring cells, second-order accurate at τ = k/M.
/// Throws std::invalid_argument for d outside {0, 1}, a DOF outside [0, n), a column count other
/// than M, or a velocity of a non-Haar basis with no pointwise derivative (DB4).
[[nodiscard]] Eigen::VectorXd evaluate_trial(const TimeBasis& trial, const Eigen::MatrixXd& coefficients, int dof,
                                             const Eigen::VectorXd& tau, double frequency_hz, int derivative = 0);

/// Displacement and velocity of every DOF on the samples tau (n × P each; row = DOF).
struct PeriodicFields {
  Eigen::VectorXd tau;           // [-]
  Eigen::MatrixXd displacement;  // [m]
  Eigen::MatrixXd velocity;      // [m/s]
};
[[nodiscard]] PeriodicFields evaluate_fields(const TimeBasis& trial, const Eigen::MatrixXd& coefficients,
                                             const Eigen::VectorXd& tau, double frequency_hz);

/// Contact force f_c(u_c(τ_p)) of the first contact [N] at each sample (Eq. 5); zero without
/// contact. displacement is n × P. Throws std::invalid_argument for a rigid stop (its force
/// is the solution's contact_force_samples, not a function of u) and for a moving
/// counter-surface (ContactPoint::obstacle: the force depends on τ as well).
[[nodiscard]] Eigen::VectorXd contact_force(const std::vector<ContactPoint>& contacts,
                                            const Eigen::MatrixXd& displacement);

/// System energy at each sample [J] [JL14 Eq. (35)]:
///   E(τ_p) = ½ u̇ᵀ M u̇ + ½ uᵀ K u + Σ_c V_c(u_c),   V_c = ∫ f_c du (ContactLaw::potential).
/// displacement and velocity are n × P. Throws std::invalid_argument on mismatched shapes, and
/// for a moving counter-surface (ContactPoint::obstacle), which works on the structure.
[[nodiscard]] Eigen::VectorXd system_energy(const MechanicalSystem& system, const std::vector<ContactPoint>& contacts,
                                            const Eigen::MatrixXd& displacement, const Eigen::MatrixXd& velocity);

/// Root mean square √((1/P) Σ_p v_p²) over equispaced samples of one period.
[[nodiscard]] double rms(const Eigen::VectorXd& v);

/// rms relative error rms(u − u_ref) / rms(u_ref) [JL14 Sec. 5.5, Fig. 11]: both sampled at the
/// same P equispaced times of one period. Throws std::invalid_argument on different lengths or
/// a zero reference.
[[nodiscard]] double rms_relative_error(const Eigen::VectorXd& u, const Eigen::VectorXd& u_ref);

}  // namespace wbm::solvers
