#pragma once
/// Second-order mechanical system M ü + C u̇ + K u = f_ext(t) − Σ_c e_c f_c(u_c) [JL14 Eq. (7)].
/// Units: SI (kg, N·s/m, N/m, N, m, s, Hz where the name says _hz).

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <wbm/contact/friction.hpp>
#include <wbm/contact/jenkins_disc.hpp>
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

/// Modal damping of one ratio ζ for every mode [Géradin & Rixen 2015, Mechanical Vibrations,
/// 3rd ed., Sec. 2.9; the damping NLvib's examples use]:
///   C_ζ = (M Φ) diag(2 ζ ω_i) (M Φ)ᵀ,   K Φ = M Φ Ω², Φᵀ M Φ = I,
/// so that Φᵀ C_ζ Φ = diag(2 ζ ω_i): mode i of the undamped system decays at the ratio ζ of its
/// circular frequency ω_i [rad/s]. Rigid-body modes (ω_i = 0, and eigenvalues below 1e-12 of the
/// largest, rounding) are not damped. n × n [N·s/m], symmetric, dense in general (stored sparse).
/// O(n³): one dense generalized eigenproblem of (K, M). `ratio` ζ ≥ 0 [-], finite; ζ = 0 gives
/// the zero matrix. The result is classical, so the weighted-residual solvers keep their modal
/// path (LinearSolverPath). Throws std::invalid_argument if ζ is negative or not finite, if the
/// matrices are invalid (validate()), or if M is not positive definite (a massless DOF: condense
/// it first, solvers/condensation.hpp).
[[nodiscard]] Eigen::SparseMatrix<double> modal_damping(const MechanicalSystem& system, double ratio);

/// One load F cos(2π h f t + φ) on a DOF: amplitude F [N], phase φ [rad], harmonic order h ≥ 0
/// of the forcing frequency f (h = 0: a constant load F cos φ, e.g. a static preload).
struct HarmonicLoad {
  int dof;
  double amplitude;
  double phase_rad = 0.0;
  int harmonic = 1;
};

/// External force of period T = 1/f:
///   f_ext(t) = F cos(2π f t) e_dof + Σ_j F_j cos(2π h_j f t + φ_j) e_{dof_j}   (j over `more`),
/// the first term the point force of [JL14 Eq. (7)], the sum further loads (several forced DOFs,
/// phases, harmonics, a force vector). Amplitude continuation (response_curve.hpp) scales every
/// load by λ/F.
struct HarmonicForcing {
  int dof;              // forced DOF, 0 ≤ dof < n
  double amplitude;     // F [N], finite (may be 0 when `more` carries the loads)
  double frequency_hz;  // f [Hz] > 0; the period T = 1/f is the period of the response
  std::vector<HarmonicLoad> more = {};
  /// Every load, the first one {dof, amplitude, 0, 1}, then `more`.
  [[nodiscard]] std::vector<HarmonicLoad> loads() const;
  /// f_ext at normalized time τ = f t (length n) [N].
  [[nodiscard]] Eigen::VectorXd at(double tau, int n) const;
  /// Throws std::invalid_argument naming the field, its value and the allowed range (also for
  /// each entry of `more`: DOF, finite amplitude and phase, harmonic ≥ 0).
  void validate(int dofs) const;
  /// Refuses a load that `functions` periodic functions (or samples) per period cannot carry:
  /// every load with F_j ≠ 0 needs 2 h_j < functions (the sampling theorem), i.e.
  /// h_j ≤ highest_resolved_harmonic(functions); above it its samples or projections alias it to
  /// a lower harmonic (issue #40: harmonic 250 on M = 65 functions came out at harmonic 6).
  /// Throws std::invalid_argument naming the load, its harmonic, `what` (e.g. "the weighted
  /// residual's M = 65 trial functions") and `fix` (e.g. "raise the basis dimension").
  void require_resolved(int functions, const std::string& what, const std::string& fix) const;
};

/// The highest harmonic h with 2h < `functions`: ⌊(functions − 1)/2⌋ (H for M = 2H + 1 Fourier
/// functions; M/2 − 1 for M = 2^J, whose top Fourier function cos πMτ has no sine partner).
[[nodiscard]] constexpr int highest_resolved_harmonic(int functions) noexcept { return (functions - 1) / 2; }

/// The prescribed motion of a contact's counter-surface along the contact direction e_c (a moving
/// obstacle: a casing that is out of round, a rotating disc, a shaker's table), over one period
/// of the response, τ = f t:
///   s(τ) = d τ + Σ_{h=1}^{H} (a_h cos 2πhτ + b_h sin 2πhτ)   [m],
/// a_h = cosine[h − 1], b_h = sine[h − 1] (either list may be shorter: missing terms are 0), d the
/// drift per period (a counter-surface sliding by: a friction contact's tangent only; a Jenkins
/// element carries its slider across the period, ContactLaw::evaluate_period). The law of
/// the contact is evaluated on the relative displacement u_c − s(τ): for a normal law the gap at τ
/// is g0 + s(τ) − u_c (s > 0 moves the obstacle away), for a friction law the slip is that of
/// u_c − s. Since s is given in τ, it does not change with the frequency; it is not scaled by
/// the forcing (load stepping and amplitude continuation scale the loads only). Units: those of
/// u_c (m for a unit direction over translations).
struct ObstacleMotion {
  std::vector<double> cosine = {};  // a_h [m], h = 1, 2, …
  std::vector<double> sine = {};    // b_h [m], h = 1, 2, …
  double drift = 0.0;               // d [m per period]
  /// False for the fixed obstacle (every term zero).
  [[nodiscard]] bool moving() const;
  /// The highest h with a_h or b_h ≠ 0 (0 if none).
  [[nodiscard]] int highest_harmonic() const;
  /// s(τ) [m] and ds/dτ [m per period], for any real τ (the drift is not wrapped).
  [[nodiscard]] double at(double tau) const;
  [[nodiscard]] double rate(double tau) const;
  /// max over τ of |s(τ) − d τ| bounded by Σ_h √(a_h² + b_h²) [m] (a length scale for reports).
  [[nodiscard]] double amplitude_bound() const;
};

/// A contact law acting along a direction over the DOFs (law shared, immutable). The law is
/// evaluated on the contact displacement u_c = e_cᵀ u, towards closing the gap g0 − u_c, and its
/// force f_c ≥ 0 enters the equation of motion as −e_c f_c. The direction e_c is
///   - e_dof: one DOF against a fixed obstacle (the default);
///   - e_dof − e_other: between two DOFs (two bodies; −f_c on dof, +f_c on other);
///   - Σ_(j, w) ∈ along w e_j when `along` is given: any direction, e.g. n·u at a 3D node with
///     n a unit normal (g = g0 − n·u), or −e_dof for a stop on the −x side. `dof` then names
///     the contact and must be one of along's DOFs; `other` must be −1.
/// Units: u_c in the units of the DOFs (m for a unit n over translations).
struct ContactPoint {
  int dof;
  std::shared_ptr<const contact::ContactLaw> law;
  int other = -1;  // the second DOF of a relative contact (two bodies), or −1 (a fixed obstacle)
  std::vector<std::pair<int, double>> along = {};  // (DOF, weight) of a general direction, or empty
  /// A friction contact whose normal load varies: the index, in the same contact list, of the
  /// normal contact whose force [N] is the normal load.
  ///   - A Jenkins element (contact::ContactLaw::takes_normal_load): a penalty law n_c(u_n), linear
  ///     or exponential, with its gap (a negative gap is a preload); the slip force is then
  ///     μ (N + n_c) at every sample (N its own preload), and the tangential force depends on both
  ///     displacements.
  ///   - Exact Coulomb friction (contact::CoulombFriction, with N = 0): a rigid stop, whose
  ///     multiplier is the normal load (a 2D contact; one friction contact per stop). The weighted
  ///     residual and Moreau–Jean solve the two together.
  /// −1: a constant normal load.
  int normal = -1;
  /// A Jenkins element with two tangents (contact::JenkinsDiscLaw, an isotropic slip disc [MY98]):
  /// the index, in the same contact list, of the contact along its other tangent. The two
  /// contacts share the law object and name each other; their directions must be orthogonal and
  /// of equal length (e_1ᵀ e_2 = 0, |e_1| = |e_2|), so that the disc is isotropic; they share their
  /// `normal`. The force along each tangent depends on the displacements along both
  /// (jenkins_disc_contact_loop). −1: a contact with one direction.
  int second_tangent = -1;
  /// The counter-surface's prescribed motion along e_c (ObstacleMotion above); the default is a
  /// fixed obstacle. A drift is for friction laws only (ContactPoint::validate).
  ObstacleMotion obstacle = {};
  /// The nonzeros of e_c as (DOF, weight), in the order given.
  [[nodiscard]] std::vector<std::pair<int, double>> terms() const {
    if (!along.empty()) return along;
    if (other >= 0) return {{dof, 1.0}, {other, -1.0}};
    return {{dof, 1.0}};
  }
  /// u_c = e_cᵀ u for a vector indexed by DOF (length n).
  [[nodiscard]] double displacement(const Eigen::Ref<const Eigen::VectorXd>& u) const {
    double v = 0.0;
    for (const auto& [j, w] : terms()) v += w * u(j);
    return v;
  }
  /// e_c (length n).
  [[nodiscard]] Eigen::VectorXd direction(int n) const {
    Eigen::VectorXd e = Eigen::VectorXd::Zero(n);
    for (const auto& [j, w] : terms()) e(j) += w;
    return e;
  }
  /// Throws std::invalid_argument for a DOF (or other DOF) out of range, other == dof, a null law,
  /// a direction (along) with a DOF out of range or repeated, a non-finite weight, all weights
  /// zero, dof not among its DOFs or other ≥ 0 beside it, the same direction twice, or a `normal`
  /// that is out of range, names the contact itself, is given to a law that is neither exact
  /// Coulomb friction nor takes_normal_load(), names for a Jenkins element a law that is rigid or
  /// hysteretic, names for exact Coulomb friction a law that is not a rigid stop or a stop that
  /// another friction contact names, or beside a Coulomb normal_load ≠ 0; for an obstacle motion
  /// with a term that is not finite, or a drift ≠ 0 on a law that is not a friction law (a normal
  /// gap that grows without bound has no periodic response); for a second_tangent out of range or
  /// naming the contact itself, one that does not name it back, two contacts that do not share one
  /// contact::JenkinsDiscLaw, directions that are not orthogonal or of unequal length, or
  /// different `normal`s; for a JenkinsDiscLaw without a second_tangent.
  static void validate(const std::vector<ContactPoint>& contacts, int dofs);
};

/// True if some contact's counter-surface moves (ObstacleMotion::moving).
[[nodiscard]] bool any_moving_obstacle(const std::vector<ContactPoint>& contacts);

/// The counter-surfaces' displacements s_c(τ_p) at the given instants (n_c × P, row c = contact
/// c, column p = tau(p)) [m]; with derivative = 1, ds_c/dτ [m per period]. Zero rows for fixed
/// obstacles.
[[nodiscard]] Eigen::MatrixXd obstacle_samples(const std::vector<ContactPoint>& contacts,
                                               const Eigen::Ref<const Eigen::VectorXd>& tau, int derivative = 0);

/// Refuses moving counter-surfaces where `what` (e.g. "the Moreau-Jean reference") does not model
/// them: throws std::invalid_argument naming the first moving contact, `what` and `fix`.
void require_fixed_obstacles(const std::vector<ContactPoint>& contacts, const std::string& what,
                             const std::string& fix);

/// The force of contact `c` over the Q uniform samples of one period, u (n_c × Q, row = contact,
/// the contact displacements u_c(τ_q)): ContactLaw::evaluate_period, or for a friction contact
/// with a `normal`, ContactLaw::evaluate_period_loaded under the normal contact's force at the
/// same samples; u is relative to the counter-surfaces, so a drifting one's samples move by −d
/// over the next period (ContactLaw::evaluate_period's period_shift). force, stiffness
/// (∂f_q/∂u_c,q), anchor and load_sensitivity have Q entries (load_sensitivity(q) = ∂f_q/∂n_r as
/// documented there, 0 without a normal). Throws as the laws do (std::logic_error for a rigid law).
/// For a Jenkins element (contact::JenkinsLaw), a stick/slip `pattern` (Q entries, 1 = slip)
/// evaluates that pattern's piece instead of the return map's (jenkins_contact_loop);
/// std::logic_error when one is given for another law. For a Jenkins element with two tangents
/// (ContactPoint::second_tangent) force is contact c's component of jenkins_disc_contact_loop,
/// stiffness 0, anchor −1 and load_sensitivity 0 (the forces only: the element's
/// derivatives are dense and couple the two tangents, so a caller that linearizes reads them from
/// jenkins_disc_contact_loop).
void evaluate_contact_period(const std::vector<ContactPoint>& contacts, int c, const Eigen::MatrixXd& u,
                             Eigen::Ref<Eigen::VectorXd> force, Eigen::Ref<Eigen::VectorXd> stiffness,
                             Eigen::Ref<Eigen::VectorXi> anchor, Eigen::Ref<Eigen::VectorXd> load_sensitivity,
                             const std::vector<std::uint8_t>* pattern = nullptr);

/// The whole loop (contact::JenkinsLoop: forces, slip sensitivities, margins) of the Jenkins
/// element of contact `c` over the Q samples u (n_c × Q, relative to the counter-surfaces, whose
/// drift carries into the next period as in evaluate_contact_period): JenkinsLaw::loop, under the
/// force of the contact's normal law at the same samples where it has one, on the piece of a
/// stick/slip `pattern` if given. `normal`, if given, receives that normal force [N] (Q entries,
/// 0 without a normal contact). Throws std::logic_error if contact c is not a Jenkins element,
/// and as JenkinsLaw::loop does.
[[nodiscard]] contact::JenkinsLoop jenkins_contact_loop(const std::vector<ContactPoint>& contacts, int c,
                                                        const Eigen::MatrixXd& u,
                                                        const std::vector<std::uint8_t>* pattern = nullptr,
                                                        Eigen::VectorXd* normal = nullptr);

/// The loop (contact::JenkinsDiscLoop) of the Jenkins element with two tangents that contact `c`
/// carries with its second_tangent t: JenkinsDiscLaw::loop on the rows (c, t) of u (n_c × Q,
/// relative to the counter-surfaces, whose drifts carry into the next period as in
/// evaluate_contact_period), under the force of their normal law at the same samples where they
/// have one. Tangent 0 of the result is contact c's, tangent 1 is t's. `normal`, if given,
/// receives that normal force [N] (Q entries, 0 without a normal contact); derivatives as in
/// contact::jenkins_disc_loop. Throws std::logic_error if contact c has no second tangent, and as
/// JenkinsDiscLaw::loop does.
[[nodiscard]] contact::JenkinsDiscLoop jenkins_disc_contact_loop(const std::vector<ContactPoint>& contacts, int c,
                                                                 const Eigen::MatrixXd& u,
                                                                 Eigen::VectorXd* normal = nullptr,
                                                                 bool derivatives = true);

/// The friction coefficient μ [-] every Jenkins element (contact::JenkinsLaw) of `contacts`
/// shares: the continuation parameter of ContinuationParameter::FrictionCoefficient
/// (response_curve.hpp). Throws std::invalid_argument when there is no Jenkins element, when two
/// of them differ (both named: give every element the start's μ), or for exact Coulomb friction
/// (contact::CoulombFriction: its μ sits in the rigid path's collocation; use a stiff Jenkins
/// element).
[[nodiscard]] double common_friction_coefficient(const std::vector<ContactPoint>& contacts);

/// `contacts` with every Jenkins element's μ set to `mu` (its k_t and preload N kept, a new law
/// object each; the other contacts shared as they are). Throws std::invalid_argument for a μ that
/// is not finite and >= 0, and as common_friction_coefficient does for the contacts.
[[nodiscard]] std::vector<ContactPoint> with_friction_coefficient(const std::vector<ContactPoint>& contacts, double mu);

/// Checks a contact direction over the DOFs, given as (DOF, weight) pairs: every DOF in
/// [0, dofs), none twice, finite weights, not all zero, and `dof` (the DOF that names the
/// contact) among them. Throws std::invalid_argument starting with `where`, naming the entry.
void validate_direction(const std::vector<std::pair<int, double>>& along, int dof, int dofs, const std::string& where);

/// Direct complex frequency response without contact: (K − ω² M + iω C) U = Σ_j F_j e^{iφ_j} e_{dof_j},
/// ω = 2π f; u(t) = Re(U e^{iωt}). Sparse LU; returns U (length n, complex amplitudes [m]).
/// Throws std::invalid_argument if a load has harmonic ≠ 1 (the response is then not at one
/// frequency: solve the weighted residual without contact instead).
[[nodiscard]] Eigen::VectorXcd frequency_response(const MechanicalSystem& system,
                                                  const HarmonicForcing& forcing);

}  // namespace wbm::solvers
