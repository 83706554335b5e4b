#pragma once
/// Periodic steady state by time stepping from rest: the reference solution of [JL14 Sec. 4].

#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

#include <wbm/solvers/mechanical_system.hpp>
#include <wbm/solvers/status.hpp>

namespace wbm::solvers {

struct TimeIntegrationOptions {
  int samples_per_period = 1024;       // P output samples per period, τ_p = p/P
  double relative_tolerance = 1e-10;   // GSL local error control (epsrel)
  double absolute_tolerance = 1e-13;   // [m] on u and on du/dτ (both in metres)
  double periodicity_tolerance = 1e-7; // stop when δ_i < this [JL14 Sec. 4]
  int max_periods = 5000;
  /// Called after each period i >= 2 with (i, δ_i), e.g. for a progress bar; may be empty.
  std::function<void(int period, double periodicity)> on_period = nullptr;
  void validate() const;               // throws std::invalid_argument naming the field
};

struct TimeIntegrationReport {
  /// Converged, MaxIterations, NonFinite, or IntegratorFailed (GSL gave up with finite values).
  SolveStatus status = SolveStatus::MaxIterations;
  int periods = 0;                      // periods integrated from rest
  long steps = 0;                       // BDF steps attempted (gsl evolve count)
  std::vector<double> periodicity;      // δ_i for i = 2..periods
  double wall_time_s = 0.0;
  /// Moreau–Jean only: the steps whose contact problem did not settle, and the largest such
  /// departure; the message says so when there are any. Without friction: the LCP's projected
  /// Gauss–Seidel (at most 1000 sweeps) ended with impulses still changing by more than 1e-14 of
  /// the largest (the departure is that relative change). With friction: Siconos' fc2d returned
  /// a failure or an error (fc2d_compute_error relative to ‖q‖) above 1e-10 (the departure is that
  /// error).
  long unsettled_lcp_steps = 0;
  double largest_lcp_change = 0.0;
  std::string message;
  [[nodiscard]] bool converged() const { return status == SolveStatus::Converged; }
};

/// One period of the steady state. displacement and velocity are n × P (row = DOF,
/// column = sample at τ_p = p/P, p = 0..P−1); velocity in physical time [m/s].
struct PeriodicResponse {
  Eigen::VectorXd tau;
  Eigen::MatrixXd displacement;  // [m]
  Eigen::MatrixXd velocity;      // [m/s]
  /// Moreau–Jean: n_c × P, the impulses of the steps in [τ_p, τ_{p+1}) over the interval's
  /// duration: the mean contact force there [N], row = contact. Central differences: the contact
  /// forces at τ_p [N]. BDF: empty.
  Eigen::MatrixXd contact_force;
  /// Moreau–Jean only (else NaN): the mean powers over the last period [W], summed per step with
  /// v_{k+θ}: input h f_{k+θ}·v, damping h vᵀ C v, and the contacts' absorption Σ_c P_c v_c (the
  /// impulse times the velocity along e_c: the stops' and the friction's). For θ = ½ the scheme's energy identity makes
  /// input − damping − stop the change of energy over the period (≈ 0 once periodic).
  double input_power = std::numeric_limits<double>::quiet_NaN();
  double damping_power = std::numeric_limits<double>::quiet_NaN();
  double stop_power = std::numeric_limits<double>::quiet_NaN();
  double frequency_hz = 0.0;
  TimeIntegrationReport report;
};

/// Integrates M ü + C u̇ + K u = F cos(2π f t) e_f − Σ_c e_c f_c(u_c) from rest (u = u̇ = 0 at
/// t = 0) with GSL's variable-order multistep BDF (gsl_odeiv2_step_msbdf, orders 1–5, the
/// analogue of the NDF solver of [JL14 Sec. 4]) and its analytic Jacobian, in normalized
/// time τ = f t with state y = (u, du/dτ) so that both halves are in metres:
///   du/dτ = w,  M dw/dτ = T² (F cos 2πτ e_f − Σ e_c f_c(u_c) − K u) − T C w,  T = 1/f.
/// Periods are integrated one after another; with u_i the tip (forced-DOF) displacement of
/// period i sampled at the P output times, the run stops at the first i with
///   δ_i = rms(u_i − u_{i−1}) / rms(u_i) < periodicity_tolerance
/// ("rms of the relative error between the tip displacements for the i and i − 1 periods",
/// [JL14 Sec. 4]) and returns period i. Throws std::invalid_argument for invalid inputs (and
/// for rigid stops, which have no force law: integrate_moreau_jean_to_periodic; and for a load
/// at a harmonic h with 2h ≥ P, which the output samples would alias; and for a moving
/// counter-surface, ContactPoint::obstacle: integrate_central_difference_to_periodic takes it);
/// a run that hits max_periods or a GSL failure is reported in `report`, never thrown.
[[nodiscard]] PeriodicResponse integrate_to_periodic(const MechanicalSystem& system,
                                                     const HarmonicForcing& forcing,
                                                     const std::vector<ContactPoint>& contacts,
                                                     const TimeIntegrationOptions& options = {});

/// Options of the Moreau–Jean time stepping (integrate_moreau_jean_to_periodic).
struct MoreauJeanOptions {
  int steps_per_period = 65536;         // N fixed steps per period, h = T/N; a multiple of P
  int samples_per_period = 1024;        // P output samples per period, τ_p = p/P
  double theta = 0.5;                   // θ ∈ [½, 1] (½: trapezoidal away from impacts)
  double restitution = 0.0;             // Newton's coefficient e ∈ [0, 1] at the stops
  double periodicity_tolerance = 1e-7;  // stop when δ_i < this (as TimeIntegrationOptions)
  int max_periods = 5000;               // >= 2
  void validate() const;                // throws std::invalid_argument naming the field
};

/// Periodic steady state with rigid stops and exact Coulomb friction by the Moreau–Jean
/// time-stepping scheme [Jean 1999, CMAME 177 235–257; Acary & Brogliato 2008, Numerical Methods
/// for Nonsmooth Dynamical Systems, Springer, Sec. 10.1], from rest, in physical time with fixed
/// step h = T/N:
///   M (v_{k+1} − v_k) + h (C v_{k+θ} + K q_{k+θ}) = h f_{k+θ} − Σ_c e_c P_c,
///   q_{k+1} = q_k + h v_{k+θ},   x_{k+θ} = θ x_{k+1} + (1 − θ) x_k,
/// with, for every stop c whose predicted gap g0 − q_c − (h/2) U_c ≤ 0 (U_c = e_cᵀ v_k, the
/// velocity towards the stop), Newton's impact law at the velocity level,
///   0 ≤ P_c ⊥ −(U_c,k+1 + e U_c,k) ≥ 0   (P_c ≥ 0 [N·s], the impulse of the step),
/// and P_c = 0 otherwise. The contacts (`contacts`, any order):
///   - rigid stops (contact::RigidStop);
///   - exact Coulomb friction (contact::CoulombFriction) along its direction e_t, either under its
///     constant normal load N (ContactPoint::normal = −1): |P_t| ≤ μ N h; or with
///     ContactPoint::normal naming a rigid stop of the list, a 2D contact whose normal load is
///     that stop's reaction: |P_t| ≤ μ P_n, active only while the stop is (its normal_load must
///     be 0: press the normal DOF with a static load, a HarmonicLoad of harmonic 0). In slip
///     P_t = ±μ P_n opposes U_t,k+1 = e_tᵀ v_{k+1}; in stick U_t,k+1 = 0.
/// Without friction the step's problem is the LCP with the Delassus matrix
/// W = Eᵀ (M + hθC + h²θ²K)⁻¹ E on the active stops, solved exactly for one stop and by projected
/// Gauss–Seidel (to 1e-14 relative) for several. With friction it is the 2D frictional contact
/// problem u = W r + q of the active stops (normal and tangent rows; a stop without friction
/// gets μ = 0) and of the constant-load Coulomb contacts (a decoupled normal row that makes
/// r_n = h N), solved by Siconos Numerics' fc2d_driver with Lemke's method (finite pivoting, no
/// iteration tolerance) and checked by fc2d_compute_error. First order in h through impacts and
/// stick–slip switches, second order elsewhere for θ = ½. Periods, samples and the periodicity
/// test δ_i are those of integrate_to_periodic. Penalty laws go to integrate_to_periodic,
/// Jenkins elements to integrate_central_difference_to_periodic. Throws std::invalid_argument
/// for invalid inputs (a load at 2h ≥ P included; a `normal` that is out of range, names a
/// contact that is not a rigid stop, beside a normal_load ≠ 0, or names a stop another friction
/// contact already names; a moving counter-surface, ContactPoint::obstacle, which the weighted
/// residual takes); a run that hits max_periods is reported.
[[nodiscard]] PeriodicResponse integrate_moreau_jean_to_periodic(const MechanicalSystem& system,
                                                                 const HarmonicForcing& forcing,
                                                                 const std::vector<ContactPoint>& contacts,
                                                                 const MoreauJeanOptions& options = {});

/// Options of the explicit central-difference time stepping (integrate_central_difference_to_periodic).
struct CentralDifferenceOptions {
  int steps_per_period = 65536;         // N fixed steps per period, h = T/N; a multiple of P
  int samples_per_period = 1024;        // P output samples per period, τ_p = p/P
  double periodicity_tolerance = 1e-9;  // stop when δ_i < this (as TimeIntegrationOptions)
  int max_periods = 5000;               // >= 2
  void validate() const;                // throws std::invalid_argument naming the field
};

/// Periodic steady state with penalty laws and Jenkins elements (friction, with a constant or a
/// varying normal load, ContactPoint::normal) by explicit central differences in the
/// velocity-Verlet form with the damping treated by the trapezoidal rule, from rest, in physical
/// time with fixed step h = T/N (Newmark's β = 0, γ = ½, written in velocity-Verlet form):
///   v_{k+½} = v_k + (h/2) M⁻¹ (F_k − K q_k − C v_k − Σ_c e_c f_c,k),   q_{k+1} = q_k + h v_{k+½},
///   (M + (h/2) C) v_{k+1} = M v_{k+½} + (h/2) (F_{k+1} − K q_{k+1} − Σ_c e_c f_c,k+1),
/// with f_c,k+1 = f_c(u_c,k+1) for a memoryless law and, for a Jenkins element, one step of its
/// return map from f_c,k (contact::JenkinsLaw::return_map) under the normal contact's force at
/// q_{k+1}: the slider state is carried from step to step, with no basis and no period loop (a
/// Jenkins element with two tangents, ContactPoint::second_tangent, steps both forces together by
/// contact::JenkinsDiscLaw::return_map, the projection on its disc). A
/// moving counter-surface (ContactPoint::obstacle) enters as the laws' relative displacement
/// u_c,k − s_c(t_k/T) (a periodic motion; its drift is refused by ContactPoint::validate for
/// these laws). The
/// scheme is second order on smooth forces; a stick–slip switch or a contact onset is a kink of
/// the force, met within one step. Explicit: stable for h ω_max < 2, ω_max² the largest
/// eigenvalue of (K + Σ_c k_c e_c e_cᵀ, M) with k_c the law's stiffness in contact (k_t for a
/// Jenkins element, the onset stiffness of an exponential law); N below 2 π ω_max T is refused
/// with the smallest N that passes. Dense (n is small for the systems this reference is for).
/// Output samples, δ_i and max_periods as integrate_to_periodic; contact_force is n_c × P, the
/// contact forces at τ_p [N]. Throws std::invalid_argument for invalid inputs, a rigid law (use
/// integrate_moreau_jean_to_periodic) or exact Coulomb friction; a run that hits max_periods or
/// turns non-finite is reported.
[[nodiscard]] PeriodicResponse integrate_central_difference_to_periodic(const MechanicalSystem& system,
                                                                        const HarmonicForcing& forcing,
                                                                        const std::vector<ContactPoint>& contacts,
                                                                        const CentralDifferenceOptions& options = {});

/// Samples of a trajectory: displacement and velocity n × S at the times t (S).
struct Trajectory {
  Eigen::VectorXd time_s;        // [s]
  Eigen::MatrixXd displacement;  // [m]
  Eigen::MatrixXd velocity;      // [m/s]
  TimeIntegrationReport report;  // status Converged once the whole span is integrated
};

/// Free motion M ü + C u̇ + K u = −Σ_c e_c f_c(u_c) from u(0) = u0, u̇(0) = v0 [m, m/s], over
/// `periods` spans of length period_s [s], sampled samples_per_period times per span (S =
/// periods · P + 1 samples, t = 0 included), by the same GSL msbdf scheme and normalized state
/// as integrate_to_periodic (time unit period_s). For checking periodic orbits, e.g. nonlinear
/// modes (the periodicity tolerance and max_periods of the options are not used). Throws
/// std::invalid_argument for invalid inputs; a GSL failure is reported, never thrown.
[[nodiscard]] Trajectory integrate_free(const MechanicalSystem& system, const std::vector<ContactPoint>& contacts,
                                        const Eigen::VectorXd& u0, const Eigen::VectorXd& v0, double period_s,
                                        int periods, const TimeIntegrationOptions& options = {});

}  // namespace wbm::solvers
