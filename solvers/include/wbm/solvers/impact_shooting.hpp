#pragma once
/// Exact periodic orbits with impacts, and their stability through saltation matrices.
/// Units: SI; times in s, frequencies in Hz, states (u [m], u̇ [m/s]).
///
/// The system is linear between events: M ü + C u̇ + K u = f_ext(t) − Σ_{c ∈ A} e_c λ_c, with rigid
/// stops e_cᵀ u ≤ g_c (contact::RigidStop: the gap function h_c = g_c − e_cᵀ u ≥ 0) and A the stops
/// in a contact phase (persistent contact, e_cᵀ u = g_c, e_cᵀ u̇ = 0, λ_c ≥ 0). Event-driven:
///   - flight with an active set A: u = Z q + u_A with Z an orthonormal basis of the null space of
///     E_Aᵀ and E_Aᵀ u_A = g_A; Zᵀ M Z q̈ + Zᵀ C Z q̇ + Zᵀ K Z q = Zᵀ (f_ext − K u_A), solved in
///     closed form: its periodic particular solution (one complex solve per load harmonic) plus
///     the homogeneous part V e^{Λ t} V⁻¹ y₀ from the eigendecomposition of the first-order
///     matrix (formed once per active set). The contact forces
///     λ_A = W⁻¹ E_Aᵀ M⁻¹ (f_ext − C u̇ − K u), W = E_Aᵀ M⁻¹ E_A;
///   - an impact (h_c reaches 0 from above, c ∉ A): Newton's law e_cᵀ u̇⁺ = −e e_cᵀ u̇⁻ by the impulse
///     that also keeps the stops of A closed, u̇⁺ = u̇⁻ − M⁻¹ E′ W′⁻¹ D E′ᵀ u̇⁻ (E′ = [E_A, e_c], D =
///     diag(1, …, 1, 1 + e)). For e = 0 the stop then stays closed when its force λ_c > 0 (a contact
///     phase), else it leaves at once;
///   - a release (λ_c reaches 0 from above, c ∈ A): c leaves A, the state is continuous.
/// Events are located on the closed-form flight: brackets of min(T/P, π/(2 max|Im Λ|)) (at most a
/// quarter of the active set's shortest natural period; after each event they start at
/// π/(2 max|Λ|) and double up to it, for the transients of overdamped modes), GSL's Brent solver
/// inside a bracket (to 1e-14 T), and a gap that dips below zero and back inside one bracket is
/// found where its rate −e_cᵀu̇ changes sign. After an event its stop's gap leaves zero slowly
/// (like τ² after a plastic impact that does not close, τ³ after a release), below the rounding of
/// e_cᵀu at first: until the gap exceeds 1e-11 (|g_c| + |e_cᵀu|) at a bracket's end, a return
/// counts when it is below minus that at a bracket's end, and the stop must have opened beyond it
/// inside that bracket, else the impacts accumulate (chatter, a Zeno sequence), which is refused
/// (std::domain_error).
///
/// The monodromy matrix Φ = ∂x(t₀ + T)/∂x(t₀) is the product of the flights' transition matrices
/// and of a saltation matrix at each event [Aizerman & Gantmacher 1958; Müller 1995, Chaos,
/// Solitons & Fractals 5(9) 1671–1681; Leine & Nijmeijer 2004, Dynamics and Bifurcations of
/// Non-Smooth Mechanical Systems, Springer, Sec. 7.1]:
///   S = R + (f⁺ − R f⁻) ∇hᵀ / (∇hᵀ f⁻),
/// R the impact map's Jacobian (blockdiag(I, I − M⁻¹ E′ W′⁻¹ D E′ᵀ)), f∓ the vector fields before
/// and after, ∇h = (−e_c, 0). At a release f⁺ = f⁻ (λ_c = 0), so S = I. For one impact per period
/// and no contact phase, det S = e² and det Φ = e^{2k} exp(−tr(M⁻¹ C) T) for k impacts (Liouville).
/// A plastic impact (e = 0) into a contact phase maps every perturbation onto the constraint, so
/// Φ then has two zero multipliers per stop that closes.
/// Cost: with no stop closed (Z = I) a flight is diag(e^{Λτ}) in the eigen-coordinates Y = V⁻¹ Φ and
/// S is the identity plus rank n_A + 2, so Φ is carried as Y over runs of free flights and impacts:
/// O(n²) per flight and O((n_A + 2) n²) per event instead of O(n³) (Φ = Re(V Y) where a contact
/// phase begins and at the end; `ImpactFlowOptions::dense_monodromy` keeps the dense products).
/// The event search reads the indicators and rates through their rows times V (O(n_c n) per
/// instant) and one complex exponential per conjugate pair of Λ.

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include <wbm/solvers/floquet.hpp>
#include <wbm/solvers/mechanical_system.hpp>
#include <wbm/solvers/newton.hpp>
#include <wbm/solvers/time_basis.hpp>

namespace wbm::solvers {

struct ImpactFlowOptions {
  double restitution = 0.0;       // Newton's coefficient e ∈ [0, 1]
  int steps_per_period = 512;     // P: brackets per period for the event search, at least (≥ 8)
  int max_events = 1000;          // per flow; more (an accumulation of impacts, chatter) is refused
  // true: Φ by dense 2n × 2n products of every flight's transition and event's saltation matrix,
  // the slow reference; false (default): in the free phase's eigen-coordinates (see ImpactFlow).
  bool dense_monodromy = false;
  void validate() const;          // throws std::invalid_argument naming the field, value and range
};

enum class ImpactEventKind { Impact, Release };

struct ImpactEvent {
  double time_s = 0.0;                     // [s]
  int contact = -1;                        // index in the contact list
  ImpactEventKind kind = ImpactEventKind::Impact;
  double normal_velocity = 0.0;            // e_cᵀ u̇⁻ [m/s] before the event (> 0 at an impact)
  bool closes = false;                     // an impact after which the stop stays closed (e = 0)
};

/// One flow of the event-driven system from (t₀, x₀).
struct ImpactFlowResult {
  Eigen::VectorXd state;               // x(t₀ + duration) = (u, u̇), 2n
  Eigen::MatrixXd monodromy;           // ∂x(t₀ + duration)/∂x(t₀) with the saltation matrices, 2n × 2n
  std::vector<ImpactEvent> events;     // in time order
  std::vector<char> active;            // per stop at the end: 1 if in a contact phase
  Eigen::MatrixXd contact_displacement;  // n_c × S: e_cᵀ u at t₀ + s duration/S (S = samples asked)
  Eigen::MatrixXd state_samples;         // 2n × S: x = (u, u̇) at the same instants (u̇ after an event there)
};

/// The event-driven flow of one structure, load and set of rigid stops (set-up once: the
/// eigendecompositions per active set are formed on first use and kept; not thread-safe).
/// Throws std::invalid_argument for invalid matrices or forcing, an empty or non-rigid contact list
/// (penalty laws: FloquetAnalysis; friction is not covered), a moving counter-surface
/// (ContactPoint::obstacle: the stops here are fixed), and at a flow whose linear part is
/// singular at a load harmonic (an undamped resonance, or a static load on a free structure).
class ImpactFlow {
 public:
  ImpactFlow(const MechanicalSystem& system, const HarmonicForcing& forcing, std::vector<ContactPoint> contacts,
             ImpactFlowOptions options = {});
  ~ImpactFlow();
  ImpactFlow(ImpactFlow&&) noexcept;
  ImpactFlow& operator=(ImpactFlow&&) noexcept;

  /// Flows x₀ = (u₀, u̇₀) (2n) from t₀ [s] over `duration` [s] (> 0), starting with the stops of
  /// `active` (n_c entries, or empty: none) in a contact phase (x₀ must then satisfy their
  /// constraints). samples > 0 fills contact_displacement and state_samples. Throws
  /// std::invalid_argument for a wrong size, non-finite values or duration ≤ 0, and
  /// std::domain_error when x₀ penetrates a stop
  /// not in `active` (h_c < −1e-12 (1 + |g_c|)), at a grazing impact (e_cᵀ u̇⁻ ≤ 0), at an impact
  /// whose impulse would pull on a closed stop, at chatter (above), and beyond max_events.
  [[nodiscard]] ImpactFlowResult flow(const Eigen::VectorXd& x0, double t0, double duration,
                                      const std::vector<char>& active = {}, int samples = 0) const;
  [[nodiscard]] int dofs() const noexcept;
  [[nodiscard]] double period_s() const noexcept;  // T = 1/f of the forcing

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// A periodic orbit found by shooting, with its saltation monodromy and Floquet multipliers.
struct ImpactOrbit {
  Eigen::VectorXd state;         // x(t₀) on the orbit, 2n
  double start_s = 0.0;          // t₀ [s], a time of free flight
  ImpactFlowResult period;       // the flow over one period from `state`
  Eigen::VectorXcd multipliers;  // eigenvalues of period.monodromy, by decreasing modulus
  double max_modulus = 0.0;
  NewtonReport report;           // the shooting's Newton solve (converged: verified residual)
};

/// Shooting on the period map in scaled unknowns z = D x: R(z) = D (x(t₀ + T) − x), D =
/// diag(1/s, 1/(ω s)) with s the largest of |u| and |u̇|/ω in x_guess and ω = 2π f, solved by the
/// project's Newton core (dense LU) with the Jacobian D Φ D⁻¹ − I, Φ the saltation monodromy.
/// The orbit starts at t₀ in free flight with every stop open (choose t₀ where the guessed orbit
/// is away from the stops). The tolerance is options.tolerance on ‖R‖ (relative to s). A flow that
/// fails (std::domain_error: a graze, chatter, a penetration) gives a non-finite residual: the line
/// search backs away from it, and at the guess itself the report says NonFinite. Throws
/// std::invalid_argument for a guess of the wrong size, non-finite or zero, and as ImpactFlow does
/// for an active set whose linear part is singular at a load harmonic.
[[nodiscard]] ImpactOrbit shoot_periodic_orbit(const ImpactFlow& flow, const Eigen::VectorXd& x_guess, double t0,
                                               const NewtonOptions& options = {});

/// The slow reference: Φ by central differences of the flow over one period from (t₀, x₀),
/// column j with the step δ_j = step · max(|x₀_j|, s) for a displacement and step · max(|x₀_j|, ω s)
/// for a velocity (s the largest of |u| and |u̇|/ω in x₀). Same throws as ImpactFlow::flow.
[[nodiscard]] Eigen::MatrixXd finite_difference_monodromy(const ImpactFlow& flow, const Eigen::VectorXd& x0,
                                                          double t0, double step = 1e-6);

struct ImpactStabilityOptions {
  NewtonOptions newton = {};      // the shooting (tolerance on the scaled residual, iterations)
  /// The exact orbit must lie within this rms distance of the given one (relative, over the
  /// samples of every contact displacement): farther, it is another orbit, and the point's
  /// stability is unavailable. 0.1 admits the truncation of a coarse basis (Haar at M = 32 on the
  /// JL14 rod: a few %) and refuses a jump to another branch.
  double max_distance = 0.1;
  void validate() const;          // throws std::invalid_argument naming the field, value and range
};

/// The stability of one periodic solution with rigid stops, given by its trial coefficients.
struct ImpactStability {
  bool available = false;         // false: no verdict; `message` says why (floquet then empty)
  std::string message;
  /// monodromy (the saltation monodromy Φ, 2n × 2n), multipliers by decreasing modulus,
  /// max_modulus, multiplier_errors (below); steps 0 (the flow is exact between events).
  FloquetResult floquet;
  ImpactOrbit orbit;              // the exact orbit found by shooting
  /// rms over the samples of the contact displacements of the exact orbit minus the given one,
  /// relative to the given one's rms (rms_relative_error); NaN when no orbit was found.
  double distance = std::numeric_limits<double>::quiet_NaN();
  int impacts = 0;                // impacts per period on the exact orbit
};

/// Stability of a periodic solution of M ü + C u̇ + K u = f_ext(t) with rigid stops, given by the
/// trial coefficients of an approximate method (a weighted-residual solution, n × M, row = DOF),
/// through the exact orbit near it (issue #38 item 4):
///  1. the samples τ_p = p/P of u and u̇ (evaluate_fields; a basis without a pointwise velocity
///     (DB4) by central differences of u over the samples), and t₀ = τ_p/f at the sample where
///     the smallest gap min_c (g_c − e_cᵀu) is largest: a time of free flight;
///  2. shoot_periodic_orbit from (u, u̇)(τ_p) with plastic impacts (e = 0): the weighted residual's
///     Signorini conditions on displacements keep a stop closed once reached, the contact phase of
///     a plastic impact at a massive contact node (its error against Moreau–Jean's e = 0 is the
///     truncation's, test_rigid_contact);
///  3. the verdict from the orbit's saltation monodromy Φ, with the error estimate of each
///     multiplier κ_i δ ‖Φ̂‖_F on the similar Φ̂ = D Φ D⁻¹, D = diag(I, I/ω) (the shooting's
///     scaling), κ_i = ‖v_i‖ ‖w_i‖ its condition (v_i the eigenvector, w_i the row of V⁻¹) and δ
///     the larger of the shooting's final scaled residual and 1e-9 (the saltation
///     monodromy's agreement with central differences on the JL14 rod, 2.9e-9 with the
///     differences' own error, test_impact_shooting); inf when V is singular to rounding.
/// Unavailable (no throw): no sample with every stop open, a flow that fails at the seed (a graze,
/// chatter: std::domain_error's message), a shooting that does not converge or meets an active set
/// whose flight ImpactFlow cannot form (its std::invalid_argument: a linear part singular at a load
/// harmonic, a defective first-order matrix), an exact orbit farther than options.max_distance
/// from the given one. Throws std::invalid_argument for coefficients of the wrong shape or
/// non-finite, samples < 8, invalid options, and as ImpactFlow's constructor does (invalid
/// matrices or forcing, a contact that is not a rigid stop).
[[nodiscard]] ImpactStability impact_stability(const MechanicalSystem& system, const HarmonicForcing& forcing,
                                               const std::vector<ContactPoint>& contacts, const TimeBasis& trial,
                                               const Eigen::MatrixXd& coefficients, int samples,
                                               const ImpactStabilityOptions& options = {});

}  // namespace wbm::solvers
