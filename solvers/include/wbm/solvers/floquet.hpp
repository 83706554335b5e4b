#pragma once
/// Stability of periodic solutions: the monodromy matrix and its Floquet multipliers.
/// Units: SI; times in s, frequencies in Hz.
///
/// About a periodic solution u*(t) of M ü + C u̇ + K u = f(t) − Σ_c e_c f_c(u_c), a perturbation
/// y = (δu, δu̇) (length 2n, displacements then velocities) obeys the linear periodic system
///   ẏ = A₀ y + Σ_c k_c(t) b_c e_cᵀ y,   A₀ = [[0, I], [−M⁻¹K, −M⁻¹C]],
///   k_c(t) = f_c'(u*_c(t)),  b_c = (0, −M⁻¹ e_c),  e_cᵀ y = δu_c,
/// and the monodromy matrix Φ = Y(T), Y(0) = I, T = 1/f, maps a perturbation over one period.
/// Its eigenvalues are the Floquet multipliers; the solution is asymptotically stable if all
/// lie inside the unit circle.
///
/// Why the monodromy matrix and not Hill's method: it needs only u*_c(t), so it treats every
/// trial basis alike (Haar's piecewise-constant u*_c included), and it has no truncation
/// artefacts (Hill's method on M harmonics returns 2nM exponents, most of them spurious, and a
/// dense 2nM eigenproblem). The nonlinearity lives on n_c DOFs, which this exploits:
/// integration on P steps of h = T/P, the linear part exactly, the contact part by the
/// trapezoidal rule (variation of constants):
///   (I − (h/2) K_{p+1}) Y_{p+1} = e^{A₀h} (I + (h/2) K_p) Y_p,   K_p = Σ_c k_c(t_p) b_c e_cᵀ,
/// second-order in h where k_c is smooth; K_p has rank n_c, so both brackets cost O(n n_c)
/// (Woodbury), and a run of L steps over which the stiffnesses stay the same (k_c = 0, or a
/// linear penalty in contact) is the power T_k^L of that one step matrix (e^{A₀h} without
/// contact), by binary powers: O(log L) products of 2n × 2n instead of L. A step in which a
/// contact displacement crosses its gap (where the penalty laws' stiffness jumps) is split at the crossing of the samples' linear interpolant, each piece with
/// its own e^{A₀h_s} and one-sided stiffnesses: the switch then sits at the crossing to O(h²)
/// instead of at a sample (first order, with an error growing with the stop's stiffness; issue
/// #19: a stop 100× stiffer than its spring had |μ| up to 1.6 instead of 0.94 at P = 512).
/// e^{A₀h}: Eigen's matrix exponential (unsupported/MatrixFunctions, scaling and squaring Padé),
/// of the balanced state (δu, δu̇/σ), σ = √‖M⁻¹K‖₁, whose matrix has both off-diagonal blocks of
/// the order of the highest natural frequency: ‖A₀h‖₁ is its square, which took ~11 squarings
/// and cost 3 digits in e^{A₀h} for a 25-element rod at h = T/8192 (floquet.cpp). The
/// multipliers are those of the similar matrix D Φ D⁻¹, D = diag(I, I/σ); `monodromy` is Φ.
///
/// Stiff contacts: e_cᵀ b_d = 0 (the contact force changes velocities only) makes the trapezoidal
/// rule explicit in the contact force, a kick–flight–kick scheme, stable only while h ω_c < 2,
/// ω_c the contacts' own frequency against their mass (√(k_c e_cᵀ M⁻¹ e_c) for one contact; for
/// several, Gershgorin's bound on K_c E M⁻¹ Eᵀ). Beyond it the multipliers grow without bound
/// (LL11's blade at P = 512: h ω_c = 29, |μ| = 1e13). The samples are therefore refined by linear
/// interpolation (the interpolant the crossings use) by the smallest power of two that brings
/// h ω_c to 0.5 (FloquetResult::steps is the P used), and a contact that would need more than
/// 32 768 steps per period is refused (std::invalid_argument naming its stiffness). Accuracy
/// then comes from the error estimate, as for any P. FloquetAnalysis avoids both for linear
/// penalty stops: their flights between crossings are exact (FloquetOptions::exact_flights).
///
/// Jenkins elements (contact::JenkinsLaw, friction.hpp). The element's force depends on its
/// slider, so the state carries one more unknown per element, the perturbation φ_j of its force
/// [N]: z = (δu, δu̇, φ), 2n + n_J, the elements in contact order, and the force perturbation in
/// the kicks is φ_j instead of k_c e_cᵀ δu. Along the orbit the element's periodic loop on the
/// samples (contact::jenkins_loop, under its normal contact's force where it has one) says where
/// it sticks; φ then follows the linearized return map:
///   stick: φ̇ = k_t e_cᵀ δu̇ (φ = k_t (δw − δs), the slider perturbation δs held);
///   slip:  φ = μ σ n'(u_n) δu_n (σ the slip direction, n' the normal law's stiffness; 0 under a
///          constant normal load): the slip force's perturbation, the earlier φ forgotten.
/// In this force form every switch is continuous in the force, so no saltation matrix is needed:
/// a perturbed orbit switches at a shifted instant, which changes the force by a second-order
/// amount. A slip onset inside a step (where the elastic trial f_p + k_t θ Δw meets the
/// interpolated slip force) splits the step there, as a penalty law's crossing does; a slip ends
/// where the displacement reverses, at a sample of its linear interpolant. Multipliers: each
/// element that slips somewhere contributes a multiplier 0 (the slip forgets φ). An element that
/// never slips (full stick) would carry the slider's neutral direction, a multiplier 1 exactly
/// (every slider position gives a periodic orbit; the solvers' convention puts it at the origin):
/// it is stepped as a spring k_t, its φ row zero (a multiplier 0). Tested against the closed forms
/// of full stick and of permanent slip under a normal load (mode coupling, [HFAG02] in
/// docs/references.md),
/// and against a finite-difference monodromy of an independent time stepping in stick–slip
/// (tests/solvers/test_floquet_jenkins.cpp).
///
/// FloquetAnalysis (below) sets up once per branch what does not depend on the point, and for a
/// classical damping matrix steps in modal coordinates, with every multiplier from the formed Φ up
/// to 64 states and the dominant ones by Arnoldi above.

#include <cmath>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include <wbm/solvers/mechanical_system.hpp>

namespace wbm::solvers {
namespace detail {
struct Balanced;  // floquet_stepping.hpp (private)
}  // namespace detail

struct FloquetResult {
  /// Φ, 2n × 2n in (δu, δu̇); with Jenkins elements (2n + n_J) × (2n + n_J), their force
  /// perturbations φ [N] last, in contact order (above).
  Eigen::MatrixXd monodromy;
  Eigen::VectorXcd multipliers;       // eigenvalues of Φ, by decreasing modulus
  double max_modulus = 0.0;           // spectral radius of Φ
  /// Estimated error of each multiplier (same order): |(V⁻¹ (Φ_P − Φ_{P/2}) V)_ii| / 3, the
  /// Richardson estimate of Φ's error (second order) mapped by eigenvector perturbation; it grows
  /// near a collision of two multipliers, where they are most sensitive. inf when it cannot be
  /// formed (P odd or < 16, eigenvectors singular to rounding). Costs a second integration on
  /// the P/2 even samples.
  Eigen::VectorXd multiplier_errors;
  int steps = 0;                      // P, the integration steps
  /// True when `multipliers` holds only those of largest modulus, down to one below 0.9 (and
  /// `monodromy` is empty): FloquetAnalysis above FloquetOptions::dense_states. The others lie
  /// inside that modulus, so they cannot change the verdict unless their errors exceed 0.05;
  /// settled() judges the ones computed.
  bool dominant_only = false;
  /// A verdict the error estimate cannot overturn: every ||μ_i| − 1| > 2 error_i.
  [[nodiscard]] bool settled() const {
    for (Eigen::Index i = 0; i < multipliers.size(); ++i) {
      if (!(std::abs(std::abs(multipliers(i)) - 1.0) > 2.0 * multiplier_errors(i))) return false;
    }
    return true;
  }
  [[nodiscard]] bool stable(double tolerance = 1e-6) const { return max_modulus < 1.0 + tolerance; }
};

/// Monodromy matrix and Floquet multipliers about a periodic solution given by its contact
/// displacements: contact_displacement is n_c × P, row c = u*_c(τ_p) [m] at τ_p = p/P of one
/// period (P ≥ 8 steps; the row order of `contacts`). Without contacts pass a 0 × P matrix.
/// With a moving counter-surface (ContactPoint::obstacle) pass the relative displacements
/// u*_c(τ_p) − s_c(τ_p), which the laws see (trace_response does); s is prescribed, so it adds
/// no term to the variational equation. Throws std::invalid_argument for P < 8, a row count
/// other than n_c, non-finite samples, f ≤ 0, a rigid stop (contact::RigidStop: an impacting
/// orbit needs saltation matrices, which impact_shooting.hpp computes on the exact orbit it
/// shoots), exact Coulomb friction (contact::CoulombFriction; a Jenkins element is taken, above),
/// or a contact
/// too stiff to resolve in 32 768 steps (above). P is raised for a stiff contact (above).
[[nodiscard]] FloquetResult floquet_multipliers(const MechanicalSystem& system,
                                                const std::vector<ContactPoint>& contacts,
                                                const Eigen::MatrixXd& contact_displacement, double frequency_hz);

/// Which coordinates FloquetAnalysis steps the monodromy matrix in.
enum class FloquetPath {
  Automatic,  ///< Modal when C is classical and M positive definite, Balanced otherwise
  Balanced,   ///< floquet_multipliers: the physical state, e^{A₀h} by a dense Padé exponential per step length
  Modal,      ///< the undamped modes; std::invalid_argument at construction if C is not classical
};

struct FloquetOptions {
  FloquetPath path = FloquetPath::Automatic;
  /// Fill FloquetResult::monodromy on the modal path (4 products of n × n by n × 2n per point);
  /// a continuation that reads the multipliers only leaves it empty.
  bool monodromy = true;
  /// Up to this many states (2n) the modal path forms Φ and all its multipliers (O(n³) per
  /// point). Above, it computes only the multipliers of largest modulus, by Arnoldi on the
  /// products Φ v (O(P n n_c) each, Φ never formed), enough that the last lies below 0.9 in
  /// modulus (FloquetResult::dominant_only); it forms Φ where Arnoldi does not converge.
  Eigen::Index dense_states = 64;
  /// With every contact a contact::LinearPenalty (stiffness k_c in contact, 0 out), on the modal
  /// path: Φ as the product of the exact flights e^{A_S Δt} of the contact configurations S
  /// between the crossings, A_S = A₀ + Σ_{c ∈ S} k_c b_c e_cᵀ (a penalty force is continuous at
  /// its crossing: no saltation matrix), each A_S diagonalized once per branch (V e^{Λ Δt} V⁻¹,
  /// kept for the next points) and a contact-free interval by the modes' closed form. A crossing
  /// lies in each step whose samples straddle the gap (the stepping's rule), located on the cubic
  /// through the four nearest samples (fourth order in T/P where the orbit is smooth; the
  /// stepping's linear interpolant is second order), and the stiffness sets no step limit: the
  /// samples are not refined, FloquetResult::steps is the P given, the error estimate is
  /// Richardson's second-order one between the P and the P/2 even samples (conservative here),
  /// and resolved_steps returns P. Falls back to the stepping when an A_S has no
  /// well-conditioned eigenvector basis (κ₁(V) > 1e8: a rigid-body mode the contacts do not hold,
  /// critical damping). false: always the stepping (the slow reference path).
  bool exact_flights = true;
};

/// The stability of the points of one branch (one structure, one set of contacts): what does not
/// depend on the point is set up once, and each call returns floquet_multipliers' result for one
/// point (the same scheme, steps, error estimate and exceptions). Const calls are thread-safe.
///
/// When the damping matrix is classical (Rayleigh, modal ratios, any C with C M⁻¹ K = K M⁻¹ C and
/// Φᵀ C Φ diagonal; solvers/src/forced_response/modal_damping_structure.hpp) the stepping runs in
/// the undamped modes' coordinates x = (q, q̇/ω), u = Φ q, Φᵀ M Φ = I: the linear part's flight
/// e^{A₀h} is then one 2 × 2 block per mode in closed form,
///   e^{A_i t} = e^{−d_i t/2} (cos ν_i t I + (sin ν_i t / ν_i)(A_i + (d_i/2) I)),
///   A_i = [[0, 1], [−ω_i², −d_i]],  ν_i² = ω_i² − d_i²/4  (cosh/sinh when ν_i² < 0),
/// applied in O(n) per column, instead of a dense Padé exponential of 2n × 2n for every step
/// length (each contact crossing splits a step) and a dense LU of M per point. A contact-free run
/// of L steps is e^{A₀Lh} itself. Set-up: one dense generalized eigenproblem of (K, M), O(n³),
/// once. The multipliers are those of the similar matrix T⁻¹ Φ T, T = diag(Φ, Φ Ω); `monodromy`
/// is Φ in (δu, δu̇) when options.monodromy. Otherwise (Balanced) each call gives
/// floquet_multipliers' result, with its dense LU of M done once.
/// Throws std::invalid_argument as floquet_multipliers does (exact friction and rigid stops at
/// construction), and for FloquetPath::Modal with a non-classical C.
class FloquetAnalysis {
 public:
  FloquetAnalysis(const MechanicalSystem& system, std::vector<ContactPoint> contacts, FloquetOptions options = {});
  /// contact_displacement: n_c × P, as floquet_multipliers; frequency_hz > 0 [Hz].
  [[nodiscard]] FloquetResult operator()(const Eigen::MatrixXd& contact_displacement, double frequency_hz) const;
  /// True when the modal path is used.
  [[nodiscard]] bool modal() const noexcept;
  /// The steps per period a call will use on these samples: P times the smallest power of two
  /// that resolves the stiffest contact (h ω_c ≤ 0.5, above). A caller that can evaluate its orbit
  /// exactly (a trial basis) passes that many samples instead of letting the call refine the
  /// given ones by linear interpolation. Throws std::invalid_argument as a call would (a contact
  /// too stiff to resolve in 32 768 steps).
  [[nodiscard]] Eigen::Index resolved_steps(const Eigen::MatrixXd& contact_displacement, double frequency_hz) const;
  struct Modes;

 private:
  MechanicalSystem system_;
  std::vector<ContactPoint> contacts_;
  FloquetOptions options_;
  std::shared_ptr<const Modes> modes_;  // null: the balanced path
  std::shared_ptr<const detail::Balanced> balanced_;  // the balanced path's set-up (one LU of M)
  Eigen::MatrixXd flexibility_;         // E M⁻¹ Eᵀ, n_c × n_c [1/kg]
};

/// How a multiplier crossed the unit circle between two solutions of a branch.
enum class Bifurcation { None, Fold, PeriodDoubling, NeimarkSacker };
[[nodiscard]] std::string_view to_string(Bifurcation b) noexcept;

/// Compares two consecutive points' multipliers: if the number outside the unit circle
/// (|μ| > 1 + tolerance) changed, the crossing multiplier (of those outside at the less stable
/// point, the one nearest the circle: another may have left earlier) classifies it: near +1
/// Fold (real, the branch turns), near −1 PeriodDoubling, a complex pair NeimarkSacker
/// (|arg μ| in (0.05, π − 0.05)).
[[nodiscard]] Bifurcation classify_crossing(const FloquetResult& before, const FloquetResult& after,
                                            double tolerance = 1e-6);

}  // namespace wbm::solvers
