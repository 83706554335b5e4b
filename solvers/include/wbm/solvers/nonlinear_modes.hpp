#pragma once
/// Nonlinear normal modes of a structure with exact (Signorini) frictionless contact against rigid
/// stops, by the frequency-domain Rayleigh quotient and an augmented Lagrangian [LL11 Secs. 3–4].
/// Units: SI (m, kg, N/m, Hz where the name says _hz).
///
/// Unknowns: real Fourier coefficients of one period, u(τ) = Σ_k Y(:, k) q_k(τ), τ = t/T, with
/// q = {1, cos 2πτ, sin 2πτ, …, cos 2πNτ, sin 2πNτ} (F = 2N + 1 functions, Y is n × F), i.e. the
/// complex Û_n, n = −N … N, of [LL11 Eq. (23)] in real storage. With weights w_0 = 1, w_k = ½ and
/// harmonic ν_k of function k,
///   k̂(Y) = Σ_k w_k Y_kᵀ K Y_k,   m̂(Y) = Σ_k w_k ν_k² Y_kᵀ M Y_k      [LL11 Eq. (11)]
///   ω² = r(Y) = k̂/m̂                                                  [LL11 Eq. (24a)]
///   g_ck = u_c(τ_k) − g_c ≤ 0 at τ_k = k/m, every stop c              [LL11 Eq. (24b)]
///   (u_c = e_cᵀu: one DOF, or a direction over several, RigidStop::along)
///   h(Y) = ½ m̂(Y) − γ = 0                                              [LL11 Eq. (12)]
/// The paper's Eq. (24c) drops the ν² of Eq. (12); we keep it: then h constrains the same
/// functional that divides the Rayleigh quotient (so ω² m̂ = 2 × the time-averaged kinetic energy
/// and h fixes it at ω² γ), and for the linear mode the two agree. The energy axis is normalized by
///   γ_c = ½ m̂ of the linear first mode scaled so that the first stop to touch just reaches its
///   gap (max_c |e_cᵀφ₁|/g_c = 1; with one stop, its DOF's amplitude is its gap),
/// so the reported energy E = γ/γ_c is exactly 1 at contact onset [LL11 Figs. 3, 7]. The time
/// origin is fixed by Y(c₀, sin 2πτ) = 0 at the phase DOF c₀ (default: the `dof` of that first
/// stop), since the problem is invariant under time shifts.
///
/// Nonlinear modes are critical points of r on {h = 0, g ≤ 0} [LL11 Eq. (13)], not minima: on
/// more than one harmonic, r decreases towards ω₁²/ν² along ν-th harmonics of the first mode. So
/// each primal step solves the stationarity ∇L_κ = 0 of the augmented Lagrangian [LL11 Eqs.
/// (18)–(20)] by Newton's method with a line search on ‖∇L_κ‖ (not a descent on L_κ), dense LU of
/// the analytic Hessian, and the multipliers and penalties follow Powell's rules
/// (contact::AugmentedLagrangian, [LL11 Alg. 3]).
///  - ModeAlgorithm::Simultaneous [LL11 Alg. 1]: L_κ = r/ω₀² + φ(g, h), ω from r inside.
///  - ModeAlgorithm::Sequential [LL11 Alg. 2]: L_κ = (k̂ − ω² m̂)/(ω₀² 2γ) + φ(g, h) with ω fixed
///    during each primal solve and updated to √r after it; converged when Powell's measures and
///    the relative change of ω² are below ε.
/// Everything is solved in units of g_ref, the gap of the first stop to touch (g/g_ref, Y/g_ref), and ω₀ (the linear
/// first frequency), so tolerances are dimensionless.
///
/// The frequency of the periodic orbit is ω² = r − μ ω₀² E (μ the normalization multiplier), not
/// the Rayleigh quotient r the paper reports: the stationarity conditions are the harmonic balance
/// of the free motion at that ω (see continue_backbone); both are reported.
///
/// Backbones: backbone() steps in energy with LL11 Alg. 1 or 2 (a secant predictor between
/// levels; fine up to E ≈ 1.3 on the LL11 rod, where the branch starts turning back in energy);
/// continue_backbone() continues the KKT conditions by pseudo-arclength through those turning
/// points and the corners where contact samples change state, located as events (BackboneSystem
/// is a PiecewiseSmoothSystem; to E = 10 on the LL11 rod with N = 8 … 24, m = 256;
/// reproduce/ll11_robustness tabulates N × m). docs/design.md.

#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include <Eigen/SparseCore>

#include <wbm/contact/augmented_lagrangian.hpp>
#include <wbm/contact/penalty.hpp>
#include <wbm/solvers/continuation.hpp>
#include <wbm/solvers/impact_modes.hpp>
#include <wbm/solvers/mechanical_system.hpp>
#include <wbm/solvers/newton.hpp>
#include <wbm/solvers/status.hpp>

namespace wbm::solvers {

namespace detail {
class TripletPattern;  // solvers/src/core/triplet_pattern.hpp
}  // namespace detail

/// A rigid stop: u_c ≤ gap [m], gap > 0, with u_c = u_dof, or u_c = Σ_(j, w) ∈ along w u_j along a
/// direction (e.g. n·u at a 3D node with n the unit outward normal of a casing, g = g0 − n·u;
/// −e_dof for a stop on the −x side). `dof` names the stop and, with `along`, must be one of its
/// DOFs (it is the default phase DOF, so give the component that moves most).
struct RigidStop {
  int dof;
  double gap;
  std::vector<std::pair<int, double>> along = {};  // (DOF, weight) of a direction, or empty
  /// The nonzeros of the direction e_c as (DOF, weight).
  [[nodiscard]] std::vector<std::pair<int, double>> terms() const {
    return along.empty() ? std::vector<std::pair<int, double>>{{dof, 1.0}} : along;
  }
};

enum class ModeAlgorithm { Simultaneous, Sequential };

struct NonlinearModeOptions {
  int harmonics = 16;                 // N
  int samples = 512;                  // m time samples of the constraints, m > 2N
  ModeAlgorithm algorithm = ModeAlgorithm::Simultaneous;
  contact::PowellParameters powell{};
  int max_powell_iterations = 200;
  /// ‖∇L_κ‖∞ of a primal solve (dimensionless); a level is converged only if its last primal
  /// solve reached it (and Powell's measures are below powell.tolerance), or, where ∇L_κ cannot
  /// be evaluated that accurately, within 10 times its measured rounding floor: when the measures
  /// are met and the primal Newton no longer reduces ‖∇L_κ‖∞, the floor is
  /// max over x ⊙ (1 ± ε) of ‖∇L_κ(x ⊙ (1 ± ε)) − ∇L_κ(x)‖∞ (signs alternating), and
  /// ModeLevel::tolerance reports the tolerance used. (With penalties raised to 1e7 the floor of
  /// the LL11 rod at N = 12, m = 256 reaches 1e-9, E ≈ 1.97: a fixed 1e-10 converged there or not
  /// by rounding.) A stall above 10 times the floor fails the level at once.
  double stationarity_tolerance = 1e-10;
  int max_newton_iterations = 60;     // per primal solve (newton() with Levenberg–Marquardt fallback)
  int phase_dof = -1;                 // DOF whose sin 2πτ coefficient is 0; −1: the first-touching stop's
  /// Throws std::invalid_argument naming the field, its value and the range.
  void validate(int dofs) const;
};

/// One mode at one energy level.
struct ModeLevel {
  double energy = 0.0;                // E = γ/γ_c (1 at contact onset)
  double frequency_hz = 0.0;          // ω/2π of the periodic orbit: √(r − μ ω₀² E)/2π (see below)
  double rayleigh_frequency_hz = 0.0; // √r/2π, the eigenvalue ω² = r(Û) of [LL11 Eq. (24a)]
  Eigen::MatrixXd coefficients;       // Y, n × (2N + 1) [m]
  /// Converged only from a verified residual: Powell's measures and ‖∇L_κ‖∞ below their
  /// tolerances (solve), or the KKT residual ‖R‖₂ below the tolerance (continuation levels).
  SolveStatus status = SolveStatus::MaxIterations;
  double residual_norm = 0.0;         // ‖∇L_κ‖∞ (solve) or KKT ‖R‖₂ (continuation), dimensionless
  double tolerance = 0.0;             // the tolerance residual_norm was tested against
  std::string message;
  int powell_iterations = 0, newton_iterations = 0;
  double inequality_measure = 0.0;    // G_i [LL11 Eq. (25a)], in units of the gap
  double equality_measure = 0.0;      // G_e = |h|/γ_c [LL11 Eq. (25b)]
  double max_penetration = 0.0;       // max over stops and samples of (u_c − g_c)/g_ref
  double complementarity = 0.0;       // max_k |λ_k g_k| / max_k λ_k, in units of the gap (0 without contact)
  double normalization_error = 0.0;   // |½ m̂/γ_c − E|
  Eigen::VectorXd multipliers;        // λ at the m samples of each stop (stop-major), dimensionless
  double equality_multiplier = 0.0;   // μ
  /// Contact force samples f_s [N] (stop-major, m per stop) whose rectangle rule
  /// (1/m) Σ_s f_s q_k(τ_s) is the contact term of the harmonic balance; with exact contact they
  /// sit on the few samples where u_c touches its gap.
  Eigen::VectorXd contact_force;
  double wall_time_s = 0.0;
  [[nodiscard]] bool converged() const { return status == SolveStatus::Converged; }
};

struct Backbone {
  std::vector<ModeLevel> levels;      // converged levels in branch order (E increasing between folds)
  std::vector<double> failed_energies;  // levels that did not converge (the step was then shrunk)
  std::vector<double> folds;          // energies where the branch turns back in E (continuation)
  /// Per fold: the level at the fold's state (Fold::x: a located corner, or on a smooth piece the
  /// Hermite interpolant of the step, whose status and residual then say how far it is from a
  /// solution), e.g. to mark the fold at its own frequency where the backbone is multivalued in E.
  std::vector<ModeLevel> fold_levels;
  /// The levels at the energies asked for by `include`, in that order (first passage of the
  /// branch; a level that could not be reached is absent or has converged = false).
  std::vector<ModeLevel> included;
  StopReason stop = StopReason::InitialPointFailed;  // why the branch ended (Alg. 1/2: range reached, step
                                                     // below minimum, time budget, or the first level failed)
  int kinks = 0;                      // continuation: corners of the nonsmooth branch, i.e. the events
                                      // located and crossed (one or more samples switching at once)
  int switches = 0;                   // continuation: samples switched at those events
  int rejected_steps = 0;             // continuation steps retried with half the step
  /// Continuation: Branch::stalled_residual (the corrector's last ‖R‖ when it stalled at its
  /// rounding floor), NaN otherwise.
  double stalled_residual = std::numeric_limits<double>::quiet_NaN();
  /// Converged: the branch reached the end of its energy range (energy_max; with a start, either
  /// end) and holds a level there; PathEnded: it stopped before (`stop` and `message` say why).
  SolveStatus status = SolveStatus::PathEnded;
  /// With BackboneContinuationOptions::start_penalty_stiffness: penalty orbits corrected, and the
  /// penalty stiffness [N/m] whose orbit started the Signorini Newton that converged (0 if none).
  int homotopy_stages = 0;
  double homotopy_stiffness = 0.0;
  std::string message;
  double wall_time_s = 0.0;
  /// The range was reached: status == Converged.
  [[nodiscard]] bool complete() const { return status == SolveStatus::Converged; }
  /// The level of `included` at `energy` (the same energy to 1e-12 relative), converged or not;
  /// nullptr when the branch did not reach it.
  [[nodiscard]] const ModeLevel* included_at(double energy) const;
  /// The one definition of a converged backbone, read by `wbm run`, the Python module and the
  /// reproductions: complete(), and every energy of `requested` (the `include` list it was run
  /// with, or a scene's analysis.levels) has a converged level in `included` (included_at).
  /// Before, the CLI also checked the requested levels and Python did not.
  [[nodiscard]] bool converged(const std::vector<double>& requested = {}) const;
  /// One line: "range reached: 389 levels, 6 folds, 199 corners, 0 rejected steps, 3.8 s".
  [[nodiscard]] std::string brief() const {
    return std::string(to_string(stop)) + ": " + std::to_string(levels.size()) + " levels, " +
           std::to_string(folds.size()) + " folds, " + std::to_string(kinks) + " corners, " +
           std::to_string(rejected_steps) + " rejected steps, " + format_number(wall_time_s) + " s";
  }
};

/// Where a level's energy sits (NonlinearModes::modal_components): mode and harmonic 1-based as
/// printed (mode 1 = the first linear mode), shares of m̂ in [0, 1].
struct ModalComponents {
  double first_mode_share = 0.0;      // S(mode 1, harmonic 1)
  int mode = 0, harmonic = 0;         // the largest other (mode, harmonic) component
  double share = 0.0;                 // its share
};

/// A periodic orbit u(τ) = Σ_k Y(:, k) q_k(τ) at frequency f, to start a backbone from.
struct PeriodicOrbit {
  Eigen::MatrixXd coefficients;       // Y, n × F' [m], the layout of ModeLevel::coefficients
  double frequency_hz = 0.0;          // f [Hz]
};

/// Pseudo-arclength continuation in energy of the backbone [Keller 1977; continuation.hpp].
struct BackboneContinuationOptions {
  double energy_min = 0.5, energy_max = 10.0;  // E range; energy_min < 1 starts below contact
  /// Empty: start on the linear mode at energy_min. Given: start from this orbit (e.g. a forced
  /// response's resonance, harmonic balance's trial coefficients), corrected by Newton at its own
  /// energy E₀ = NonlinearModes::energy(Y) (which must lie inside the range), and continue in the
  /// sense of `direction` until the range or a stop reason ends the branch: the way to trace a
  /// branch that the one from the linear mode does not reach (past an internal-resonance tongue).
  std::optional<PeriodicOrbit> start = std::nullopt;
  int direction = +1;                 // with a start: +1 towards higher E, −1 towards lower E
  /// 0: exact (Signorini) contact; > 0: a linear penalty spring k [N/m] at every stop instead,
  /// f = k (u_c − g_c)₊ (the penalty-limit check [issue #7]).
  double penalty_stiffness = 0.0;
  /// Exact contact from a start only: 0 (default) corrects the start directly by semismooth
  /// Newton from zero multipliers. > 0: a homotopy in the penalty stiffness instead, for starts
  /// far from the exact branch (e.g. a penalty forced response's resonance): the start is first
  /// corrected at its own E₀ on penalty stops of this stiffness k₀ [N/m] (Newton with a line
  /// search); k is then raised by ×10 per stage (the factor is square-rooted after a stage that
  /// fails, down to ×1.2), each stage's penalty orbit corrected from the previous one at the same
  /// E₀ (without line search). These intermediate orbits are corrected to ‖R‖₂ ≤ √tolerance only.
  /// After every stage semismooth Newton on the Signorini conditions starts from that orbit with
  /// the multipliers set to its penalty forces, λ_s = k (u_c(τ_s) − g_c)₊; the first one that
  /// reaches `tolerance` is the branch's first point. Gives up (InitialPointFailed, with the
  /// stiffness reached) once k exceeds 10¹² k₀. Backbone::homotopy_stages and homotopy_stiffness
  /// report what it took. At fixed E the penalty orbit moves with k and may cross another mode's
  /// internal-resonance tongue: check where the first point landed (modal_energy_shares).
  double start_penalty_stiffness = 0.0;
  double initial_step = 1e-2, min_step = 1e-7, max_step = 5e-2;  // scaled arclength (continuation.hpp)
  double max_energy_step = 0.05;      // |ΔE| per step, for a dense curve
  int max_points = 5000;
  std::vector<double> include;        // energies landed on exactly (Backbone::included), e.g. 0.7, 1.8
  double tolerance = 1e-10;           // ‖R‖₂ of the KKT residual below (dimensionless), every level
  int max_newton_iterations = 30;     // semismooth Newton at fixed E (first point, level_at)
  /// Called after each accepted point (index, point: E, step h), e.g. for progress; may be empty.
  std::function<void(size_t index, const BranchPoint& point)> on_point = nullptr;
  /// Throws std::invalid_argument naming the field, its value and the range.
  void validate() const;
};

struct BackboneOptions {
  double energy_min = 0.2, energy_max = 5.0;
  double initial_step = 0.05, min_step = 1e-4, max_step = 0.1;  // in E
  std::vector<double> include;        // energies that must be levels (e.g. 0.7 and 1.8 for Fig. 5),
                                      // also returned in Backbone::included
  /// Called after each converged level, e.g. for progress; may be empty.
  std::function<void(const ModeLevel& level)> on_level = nullptr;
  /// > 0: no level is attempted once this wall time [s] is spent (the one in progress finishes);
  /// the backbone then ends incomplete with StopReason::TimeBudget and the energy reached.
  /// 0: no budget. Throws std::invalid_argument (backbone) if negative or NaN.
  double max_wall_time_s = 0.0;
  /// 0 < energy_min < energy_max, 0 < min_step <= initial_step <= max_step, max_wall_time_s >= 0.
  /// Throws std::invalid_argument naming the field, its value, the range and a value to use.
  void validate() const;
};

/// Options of NonlinearModes::stability.
struct ModeStabilityOptions {
  /// The autonomous shooting and the verdict's tolerance; 15 Newton iterations: on the LL11 rod the
  /// orbits that converge take 5 to 13, and a seed that has not converged by then stagnates between
  /// impact patterns (30 iterations took three times as long for the same verdicts, stop 93).
  ConservativeOrbitOptions orbit = {.newton = {.tolerance = 1e-10, .max_iterations = 15}};
  int samples = 1024;                   // P instants per period: the seed's search, H̄, the distance, m̂ (≥ 64)
  /// The exact orbit must lie within this rms distance of the level's (relative, over the samples
  /// of every stop's displacement e_cᵀu, aligned at the seed): farther, it is another orbit, and
  /// the level's stability is unavailable.
  double max_distance = 0.1;
  /// Throws std::invalid_argument naming the field, its value and the range.
  void validate() const;
};

/// The stability of one backbone level through the exact conservative orbit near it.
struct ModeStability {
  bool available = false;             // false: no verdict; `message` says why
  std::string message;
  bool stable = false;                // every nontrivial multiplier within 1 + tolerance of the unit circle
  double max_modulus = std::numeric_limits<double>::quiet_NaN();  // max |μ| of the nontrivial multipliers
  Eigen::VectorXcd multipliers;       // the nontrivial multipliers (2n − 2), by decreasing modulus
  double frequency_hz = std::numeric_limits<double>::quiet_NaN();  // 1/T of the exact orbit [Hz]
  double energy = std::numeric_limits<double>::quiet_NaN();  // its E = m̂/m̂_c (ConservativeOrbit::mean_square_rate)
  double distance = std::numeric_limits<double>::quiet_NaN();  // rms distance to the level (above)
  int impacts = 0;                    // impacts per period of the exact orbit
  double symplectic_defect = std::numeric_limits<double>::quiet_NaN();
  ConservativeOrbit orbit;            // the exact orbit and its monodromy
};

/// The modal problem of a structure (M, K; damping is ignored) against rigid stops.
/// Throws std::invalid_argument for invalid options, stops on invalid DOFs (or directions with
/// repeated, out-of-range or non-finite entries, zero norm, or not containing `dof`), gap ≤ 0, or
/// a first linear mode that moves no stop
/// (the energy normalization is by the gap; the normalized backbone does not depend on it).
class NonlinearModes {
 public:
  NonlinearModes(const MechanicalSystem& system, std::vector<RigidStop> stops, NonlinearModeOptions options = {});

  [[nodiscard]] double linear_frequency_hz() const { return omega0_ / (2.0 * 3.14159265358979323846); }
  /// Every linear natural frequency f_j [Hz] of (K, M), ascending (n entries): with
  /// modal_energy_shares they name an internal resonance, f_j ≈ h f along a branch.
  [[nodiscard]] const Eigen::VectorXd& linear_frequencies_hz() const { return frequencies_; }
  /// φ₁ scaled so that the first stop to touch has amplitude |e_cᵀφ₁| equal to its gap (E = 1).
  [[nodiscard]] const Eigen::VectorXd& onset_mode() const { return onset_; }
  /// Index (into the stops given) of the stop that touches first in the linear mode.
  [[nodiscard]] int onset_stop() const { return onset_stop_; }
  [[nodiscard]] int harmonics() const { return n_harm_; }
  [[nodiscard]] int dofs() const { return n_; }
  /// The structure (M, K; damping is ignored) and the stops, as given.
  [[nodiscard]] const MechanicalSystem& system() const { return system_; }
  [[nodiscard]] const std::vector<RigidStop>& stops() const { return stops_; }
  /// The DOF whose turning point is the time origin: NonlinearModeOptions::phase_dof, or the
  /// `dof` of the first stop to touch.
  [[nodiscard]] int phase_dof() const {
    return options_.phase_dof >= 0 ? options_.phase_dof : stops_[static_cast<size_t>(onset_stop_)].dof;
  }

  /// The mode at normalized energy E from `start` (a previous level's coefficients, scaled by
  /// √(E/E_start)), or from the linear mode. Never throws for non-convergence. With
  /// max_wall_time_s > 0 no Powell iteration starts once that wall time [s] is spent: the level
  /// then ends unconverged (MaxIterations) with "wall-time budget spent" in its message.
  [[nodiscard]] ModeLevel solve(double energy, const ModeLevel* start = nullptr, double max_wall_time_s = 0.0) const;
  /// Levels from energy_min to energy_max: secant predictor between levels, step grown after
  /// quick convergence and halved after a failure (the failed energy is recorded).
  [[nodiscard]] Backbone backbone(const BackboneOptions& options) const;

  /// The backbone by pseudo-arclength continuation in E of the optimality (KKT) conditions of
  /// [LL11 Eq. (24)], written as the harmonic balance of the free motion with contact forces:
  ///   w_k (K − ν_k² ω² M) Y_k + (1/m) Σ_s q_k(τ_s) f_s e_c = 0   (every (k, dof) but the phase row)
  ///   min(f_s/f_ref, −g_s) = 0                                 (Signorini at every sample s)
  ///   m̂(Y)/m̂_c − E = 0                                        (normalization, Eq. 12)
  /// with unknowns Y (phase coefficient fixed), ω² and f (exact contact), solved by semismooth
  /// Newton inside the continuation (BackboneSystem::KktSolver); or with f_s = k (u_c(τ_s) − g_c)₊ and no f
  /// unknowns (penalty). These are the stationarity conditions of L = r + λᵀg + μ h with
  /// ω² = r − μ ω₀² E (BackboneSystem below), so both methods find the same modes; unlike
  /// energy stepping with solve(), the continuation passes turning points in E.
  [[nodiscard]] Backbone continue_backbone(const BackboneContinuationOptions& options) const;

  /// The KKT (or penalty) system of continue_backbone as a ParametrizedSystem in E. State x =
  /// [Y stacked k·n + dof without the phase coefficient (units of g_ref); ω²/ω₀²; f/f_ref
  /// (stop-major, m per stop, exact contact only)], f_ref = m ω₀² m_ref g_ref with m_ref = 2 m̂_c
  /// [kg] (the modal mass of the onset mode scaled to a unit stop amplitude). Residual rows: harmonic balance / (ω₀² m_ref g_ref) without the phase row; the
  /// normalization; min(f_s/f_ref, −g_s) per sample. Exposed for tests (finite differences).
  class BackboneSystem {
   public:
    BackboneSystem(const NonlinearModes& modes, double penalty_stiffness);
    [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x, double energy) const;
    [[nodiscard]] SparseLinearization linearize(const Eigen::VectorXd& x, double energy) const;
    /// The piecewise-smooth structure (PiecewiseSmoothSystem, linearization.hpp), one entry per
    /// sample (stop-major, m per stop). Exact contact: sample s is active when the min of
    /// min(f_s/f_ref, −g_s) picks −g_s (f_s/f_ref > −g_s); on piece a its row is −g_s (active) or
    /// f_s/f_ref (inactive), and its event function f_s/f_ref (active) or −g_s (inactive).
    /// Penalty: active when g_s > 0 (the spring is compressed), f_s = κ g_s on piece a where
    /// active and 0 elsewhere; event g_s (active) or −g_s (inactive). g_s in units of g_ref.
    /// Throw std::invalid_argument for an active set whose length is not the stops × m.
    [[nodiscard]] ActiveSet active_set(const Eigen::VectorXd& x, double energy) const;
    [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x, double energy, const ActiveSet& active) const;
    [[nodiscard]] SparseLinearization linearize(const Eigen::VectorXd& x, double energy, const ActiveSet& active) const;
    [[nodiscard]] Eigen::VectorXd events(const Eigen::VectorXd& x, double energy, const ActiveSet& active) const;
    /// The state of the linear mode at E ≤ 1 (an exact solution, no contact force).
    [[nodiscard]] Eigen::VectorXd linear_state(double energy) const;
    /// The state of a periodic orbit u(τ) = Σ_k Y(:, k) q_k(τ) at frequency f [Hz], e.g. a forced
    /// response's resonance to start a continuation from: Y is n × F' [m] in the layout of
    /// ModeLevel::coefficients (harmonic balance's trial coefficients with harmonics 0 … H have
    /// it too); columns beyond F = 2N + 1 are dropped, missing ones are zero. Y is shifted in time,
    /// harmonic k by k θ₀, so that the phase coefficient (sin 2πτ at the phase DOF) vanishes and
    /// its cos 2πτ is ≥ 0; ω²/ω₀² = (2πf/ω₀)²; exact contact: the multipliers start at 0. The
    /// energy of the state is NonlinearModes::energy of the shifted Y (a time shift keeps it).
    /// Throws std::invalid_argument for a Y without n rows or a non-finite Y, f ≤ 0.
    [[nodiscard]] Eigen::VectorXd state(const Eigen::MatrixXd& coefficients, double frequency_hz) const;
    /// The level at state x (frequencies, contact forces, diagnostics); its status is
    /// Converged only if the KKT residual ‖R(x, E)‖₂ ≤ tolerance (NonFinite for NaN/inf,
    /// MaxIterations otherwise), with the residual and tolerance reported.
    [[nodiscard]] ModeLevel level(const Eigen::VectorXd& x, double energy, double tolerance) const;
    [[nodiscard]] Eigen::Index size() const { return size_; }
    class KktSolver;
    /// The linear-solver policy for this system's Jacobians, plain (size() rows) and bordered by
    /// a continuation (size() + 1): KktSolver below. continue_backbone, level_at and
    /// pseudo_arclength use it.
    [[nodiscard]] KktSolver linear_solver() const;

   private:
    // A state unpacked: full stacked Y (phase coefficient 0, units of g_ref), the constraint
    // values g and the contact multipliers λ (stop-major, m per stop).
    struct Unpacked {
      Eigen::VectorXd y, g, lambda;
      Eigen::VectorXd penalty_stiffness;  // f′(g) of the penalty law (penalty only)
    };
    // With an active set, the penalty force follows it instead of the sign of g.
    [[nodiscard]] Unpacked unpack(const Eigen::VectorXd& x, const ActiveSet* active = nullptr) const;
    // The nonsmooth system (active == nullptr) or the smooth residual of piece *active.
    [[nodiscard]] SparseLinearization evaluate(const Eigen::VectorXd& x, double energy, bool jacobian,
                                               const ActiveSet* active = nullptr) const;
    void check(const ActiveSet& active) const;
    // evaluate()'s J at M̂Y (my, n × F) and s = ω²/ω₀² (nonlinear_modes_kkt_jacobian.cpp). Exact
    // contact: built column by column in compressed storage, gap_rows[i] != 0 where sample i's
    // row is −g_s; penalty: the blocks and the contact curvature (f′ per sample) by pattern_.
    [[nodiscard]] Eigen::SparseMatrix<double> exact_jacobian(const Eigen::MatrixXd& my, double s,
                                                             const ActiveSet& gap_rows) const;
    [[nodiscard]] Eigen::SparseMatrix<double> penalty_jacobian(const Eigen::MatrixXd& my, double s,
                                                               const Eigen::VectorXd& curvature) const;
    // What exact_jacobian reads that depends on the model only (Θᵀ, the stops' directions by DOF),
    // built once by the constructor; null for a penalty.
    struct ExactLayout;
    [[nodiscard]] std::shared_ptr<const ExactLayout> make_exact_layout() const;
    const NonlinearModes* nm_;
    double penalty_ = 0.0;  // k/(m ω₀² m_ref), dimensionless, 0 for exact contact
    std::optional<contact::LinearPenalty> penalty_law_;  // κ (g)₊ on the normalized gap (penalty only)
    Eigen::Index ny_ = 0, size_ = 0;
    std::shared_ptr<const ExactLayout> exact_layout_;  // make_exact_layout(); copies share it
    // The penalty Jacobian's sparsity patterns, reused while the active set keeps them (copies share it).
    std::shared_ptr<const detail::TripletPattern> pattern_;
  };
  /// The level at exactly `energy` from a converged state x near it: semismooth Newton at fixed E
  /// (newton() without line search, BackboneSystem::KktSolver) to ‖R‖₂ ≤ options.tolerance in at most
  /// options.max_newton_iterations; otherwise the level carries Newton's status and message.
  [[nodiscard]] ModeLevel level_at(const BackboneSystem& system, Eigen::VectorXd x, double energy,
                                   const BackboneContinuationOptions& options) const;

  /// How a level's energy m̂(Y) [LL11 Eq. (11)] splits over the linear modes and the harmonics:
  /// with Y = Φ η (Φ the mass-normalized linear modes, Φᵀ M Φ = I, ascending frequencies),
  ///   S(j, h) = Σ_(k of harmonic h: cos, sin) w_k h² η_jk² / m̂(Y),   Σ_(j, h) S = 1,
  /// an n × (N + 1) matrix (row j = mode j + 1, column h = harmonic h; column 0 is zero, the mean
  /// carries no kinetic energy). S(0, 1) = 1 on the linear first mode; a branch on which another
  /// (mode j, harmonic h) takes a large share with f_j ≈ h f is in h:1 internal resonance with
  /// mode j (a tongue of the backbone). Throws std::invalid_argument for a level whose
  /// coefficients are not n × F or carry no energy.
  [[nodiscard]] Eigen::MatrixXd modal_energy_shares(const ModeLevel& level) const;

  /// The share of the first linear mode at the fundamental, S(0, 1), and the largest other entry
  /// of modal_energy_shares with its mode and harmonic. Throws as modal_energy_shares.
  [[nodiscard]] ModalComponents modal_components(const ModeLevel& level) const;

  /// Normalized energy E = m̂(Y)/m̂_c of a periodic orbit's coefficients Y (n × F [m], the layout of
  /// ModeLevel::coefficients; columns beyond F are ignored) [LL11 Eq. (12)]: 1 for the onset mode.
  /// Throws std::invalid_argument for a Y without n rows.
  [[nodiscard]] double energy(const Eigen::MatrixXd& coefficients) const;

  /// The stability of a level (issue #38, item 4) through the exact orbit near it: with elastic
  /// impacts (e = 1, the only law under which a free orbit can be periodic, impact_modes.hpp),
  ///  1. the level's u and u̇ at τ_p = p/P, and the seed at the sample where the onset stop's
  ///     displacement is farthest from its gap (a turning point, in free flight; with
  ///     NonlinearModeOptions::phase_dof given, where that DOF is lowest); the phase DOF's
  ///     velocity is set to 0 there;
  ///  2. shoot_conservative_orbit at the level's mean Hamiltonian H̄ = (1/P) Σ_p H(x_p) (H is
  ///     conserved on the exact orbit, not on a truncated one), from the period 1/f of the level;
  ///  3. the distance: the rms of e_cᵀu of the exact orbit minus the level's at the same P
  ///     instants from the seed (each over its own period), relative to the level's rms;
  ///  4. the verdict from the nontrivial multipliers (ConservativeOrbit).
  /// The energy axis of a backbone is m̂ (LL11 Eq. 11), not H, so the exact orbit's E is
  /// reported beside the level's: they agree to the truncation. Unavailable (no throw): a level
  /// not converged, a shooting that does not converge (a graze, chatter), an orbit farther than
  /// max_distance. Throws std::invalid_argument for coefficients not n × (2N + 1), invalid
  /// options. `previous`: an exact orbit of a neighbouring level (ModeStability::orbit), tried as
  /// the seed (its state and period, at this level's H̄) when the level's own seed does not
  /// converge: along a backbone the exact family is then followed where a truncated seed is too
  /// far from it (the distance check still applies).
  [[nodiscard]] ModeStability stability(const ModeLevel& level, const ModeStabilityOptions& options = {},
                                        const ConservativeOrbit* previous = nullptr) const;
  /// The stability of every level of a backbone, in branch order (one entry per
  /// Backbone::levels): each level seeded from itself, else from the last exact orbit found along
  /// the branch (`previous` above). `on_level(i, count)` is called after level i (0-based) of
  /// `count`, e.g. for progress; may be empty. Throws as stability(level).
  [[nodiscard]] std::vector<ModeStability> stability(
      const Backbone& backbone, const ModeStabilityOptions& options = {},
      const std::function<void(size_t index, size_t count)>& on_level = nullptr) const;

  /// u (n × P) and du/dt (n × P, [m/s]) at τ_p = p/P of a level.
  [[nodiscard]] Eigen::MatrixXd displacement(const ModeLevel& level, int samples) const;
  [[nodiscard]] Eigen::MatrixXd velocity(const ModeLevel& level, int samples) const;

 private:
  struct Evaluation;
  [[nodiscard]] Evaluation evaluate(const Eigen::VectorXd& y, double energy, double omega2_fixed,
                                    const contact::AugmentedLagrangian& al, bool hessian) const;
  // P × F values of spectral::FourierBasis::with_harmonics(N) (or its d-th τ-derivative) at τ_p = p/P.
  [[nodiscard]] Eigen::MatrixXd basis_values(int samples, int derivative) const;
  // The stacked Y with the fixed phase coefficient (0) inserted back at phase_index_.
  [[nodiscard]] Eigen::VectorXd with_phase(const Eigen::VectorXd& x) const;
  // The exact-contact state at E₀ reached from a start orbit by the penalty homotopy of
  // BackboneContinuationOptions::start_penalty_stiffness; empty (and b.message set) if it fails.
  [[nodiscard]] std::optional<Eigen::VectorXd> homotopy_start(const BackboneSystem& exact, double energy,
                                                              const BackboneContinuationOptions& options,
                                                              Backbone& b) const;

  MechanicalSystem system_;
  std::vector<RigidStop> stops_;
  NonlinearModeOptions options_;
  int n_, n_harm_, f_;
  double omega0_ = 0.0, g_ref_ = 1.0, m_c_ = 0.0;
  Eigen::MatrixXd k_, m_;          // dense K, M
  Eigen::VectorXd weight_, nu_;    // w_k, ν_k
  Eigen::MatrixXd theta_;          // m × F values at τ_k = k/m
  Eigen::VectorXd onset_;
  Eigen::MatrixXd modal_projection_;  // ΦᵀM (Φ the mass-normalized linear modes, ascending): η = ΦᵀM y
  Eigen::VectorXd frequencies_;    // f_j [Hz]
  int phase_index_ = 0;            // index in the stacked y of the fixed coefficient
  int onset_stop_ = 0;             // the stop that touches first in the linear mode
  // u_c(τ_s) − g_c/g_ref at the m samples of every stop (stop-major), Y in units of g_ref.
  [[nodiscard]] Eigen::VectorXd gaps(const Eigen::Ref<const Eigen::MatrixXd>& ym) const;
  // Adds Θᵀλ_c along every stop's direction to the rows of an n × F gradient.
  void add_contact_forces(Eigen::MatrixXd& grad, const Eigen::VectorXd& lambda) const;
  // The entries w_i w_j (Θᵀ diag(κ_c) Θ)_kl at (k n + i, l n + j) for every pair of a stop's DOFs
  // (the curvature of a penalty on the samples, κ stop-major; zero blocks skipped).
  [[nodiscard]] std::vector<Eigen::Triplet<double>> contact_curvature(const Eigen::VectorXd& curvature) const;
  Eigen::SparseMatrix<double> ks_, ms_;  // K/(ω₀² m_ref), M/m_ref (continue_backbone)
  double m_ref_ = 1.0;             // 2 m̂_c g_ref² [kg]
};

/// Linear-solver policy (newton.hpp) for the exact-contact KKT Jacobian J of a BackboneSystem and
/// for J bordered by pseudo-arclength continuation (one more row and column, the parameter E).
/// It exploits the structure of the KKT system: with unknowns ordered
///   [Y_0 … Y_(F−1) (harmonic balance, n per Fourier coefficient, phase row and column removed);
///    ω²/ω₀²; f_s (m per stop); E (bordered only)],
/// the harmonic-balance block A = diag(A_k), A_k = w_k (K̂ − ν_k² s M̂) (n × n, one coefficient
/// each: the undamped harmonic balance does not couple harmonics), is block diagonal; a
/// multiplier column couples to A_k only along its stop's direction, β_k N_c, and so does an
/// active Signorini row, γ_k N_cᵀ; an inactive row is the identity (the min picks f_s). So
///  1. inactive multipliers are read off their rows and moved to the right-hand side;
///  2. each A_k is factorized (dense LU, n × n) and its receptances at the stop directions,
///     V_k = A_k⁻¹ N (n × c, c stops) and G_k = Nᵀ V_k (c × c), are formed: F (n³ + 2n²c) flops
///     (for exact contact about half of it: a harmonic's sine block, equal to its cosine block
///     bit for bit unless it holds the phase coefficient, takes that block's LU, V_k and G_k);
///  3. the Schur complement on the r remaining unknowns (a active samples, ω², and E when
///     bordered: r = a + 1 or a + 2), S = D − C A⁻¹ B, is formed from G_k (S_ij = −Σ_k γ_ik β_jk G_k(c_i, c_j) for
///     two active samples: F a² flops) and factorized (dense LU, r³);
///  4. a solve is F block solves, one r × r solve and the back substitution.
/// The cost follows the F blocks of n DOFs and the active contact unknowns a, not the F n + m c
/// unknowns of the sparse LU (SparseLu, KLU) that it replaces (bench_reduction:
/// BM_KktFactorization: 2–4× faster on the blade, 6 to 48 contact nodes).
/// Penalty stops (BackboneSystem with penalty_stiffness > 0: unknowns [Y; ω²/ω₀²; E], no
/// multipliers) couple the harmonics, but only at the stops: between harmonics k ≠ l stop c adds
/// C_c(k, l) N_k(:, c) N_l(:, c)ᵀ, C_c = Θᵀ diag(κ_c) Θ (F × F), so the harmonic-balance block is
/// blockdiag(Ã_k) + P Ĉ Pᵀ (Ã_k: J's diagonal block k, the curvature within harmonic k included;
/// P: the columns N_k(:, c); Ĉ: the C_c with zero diagonal). The Schur complement is then taken
/// on z = Pᵀ Y for the stops in contact (Ĉ_c ≠ 0): r = F t + 1 or + 2 unknowns for t stops in
/// contact, S = [D − C Ã⁻¹ B, −C Ã⁻¹ P Ĉ; Pᵀ Ã⁻¹ B, I + G Ĉ] with G = Pᵀ Ã⁻¹ P block diagonal
/// in the harmonics (G_k); the cost follows the stops in contact, not the F n unknowns. It needs
/// every DOF in at most one stop's direction (checked once; otherwise SparseLu).
/// Every solve is verified: its normwise backward error ‖b − J x‖∞ / (‖J‖∞ ‖x‖∞ + ‖b‖∞) must be
/// ≤ 1e-11 after at most one step of iterative refinement; otherwise (and whenever the structure
/// is absent: penalty stops sharing a DOF, other sizes, entries outside the blocks; or an A_k or S with a
/// reciprocal condition estimate below 1e-13, e.g. the linear mode, where A_1 is singular) the
/// solve falls back to SparseLu on the same J. Since det J = Π det A_k · det S (inactive rows
/// are the identity), an S whose condition estimate is below machine epsilon while every A_k is
/// well conditioned means J is singular: factorize() then returns false (newton() reports
/// SingularJacobian). counts() reports how often each path ran.
class NonlinearModes::BackboneSystem::KktSolver {
 public:
  explicit KktSolver(const BackboneSystem& system);
  ~KktSolver();
  KktSolver(KktSolver&&) noexcept;
  KktSolver& operator=(KktSolver&&) noexcept;
  /// Factorizes J (size() or size() + 1 rows); false if J is singular or not finite.
  bool factorize(const Eigen::SparseMatrix<double>& jacobian);
  /// x with J x = rhs (J the last factorized matrix; NaN if the last factorize() failed).
  [[nodiscard]] Eigen::VectorXd solve(const Eigen::VectorXd& rhs) const;
  [[nodiscard]] static std::optional<double> rcond() { return std::nullopt; }
  struct Counts {
    int structured = 0;        // factorizations by the Schur complement on the active samples
    int sparse_lu = 0;         // factorizations by SparseLu (no structure, or ill-conditioned blocks)
    int refined = 0;           // structured solves that needed the refinement step
    int fallback_solves = 0;   // structured solves whose backward error stayed too large: SparseLu
    int singular = 0;          // factorizations refused: S singular to working precision, so J is
    int max_active = 0;        // the most Schur unknowns besides ω², E: active samples (penalty: F per stop in contact)
  };
  [[nodiscard]] Counts counts() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace wbm::solvers
