#pragma once
/// Forced-response curves of the weighted-residual problem by pseudo-arclength continuation
/// [JL14 Sec. 5.6], in the forcing frequency or the forcing amplitude, for any trial:weighting
/// pair and formulation. The continuation runs on the condensed contact unknowns x (n_c·M) of
/// WeightedResidual, so each corrector iteration costs one refactorization of G(f), r products
/// with the compliance and an (r + 2) bordered Woodbury LU, r the contact samples that carry rank
/// (issue #39; an (n_c·M + 1) dense LU once r > 3/4 n_c·M). Units: SI, Hz.

#include <complex>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include <wbm/solvers/continuation.hpp>
#include <wbm/solvers/floquet.hpp>
#include <wbm/solvers/impact_shooting.hpp>
#include <wbm/solvers/weighted_residual.hpp>

namespace wbm::solvers {

enum class ContinuationParameter {
  Frequency,  // λ = f [Hz]; G(f) is refactorized at each new f (WeightedResidual::at_frequency)
  Amplitude,  // λ = F [N]; the condensed residual is linear in F (r = (x − (F/F₀) x_lin + H n)/s_r)
  /// λ = μ [-], the friction coefficient every Jenkins element shares (common_friction_coefficient,
  /// mechanical_system.hpp), at the base problem's frequency and load: G is factorized once for
  /// the branch and kept (WeightedResidual::set_friction_coefficient), ∂r/∂μ is exact on each
  /// stick/slip pattern (contact_residual_friction_derivative). Under a constant normal load only
  /// the slip force μN enters, so a branch in μ is also one in the preload N (N = λ N₀/μ₀, the
  /// friction damper's optimal-load curve). Jenkins elements only: exact Coulomb is refused.
  FrictionCoefficient,
};

/// The condensed residual r(x; λ) of a WeightedResidual as a ParametrizedSystem:
///   residual(x, λ) = contact_residual at λ,
///   linearize(x, λ) = {r, ∂r/∂x, ∂r/∂λ} with ∂r/∂f from contact_residual_frequency_derivative,
///   ∂r/∂F = −x_lin/(F₀ s_r) and ∂r/∂μ from contact_residual_friction_derivative; ∂r/∂x identity
///   plus low rank (contact_jacobian_low_rank, or signorini_jacobian with rigid stops).
/// The WeightedResidual of the last frequency asked for is cached (continuation asks each f
/// several times); for μ, one copy of the base problem (one factorization of G) whose Jenkins
/// elements take each μ asked for. At a frequency ≤ 0, a μ < 0, or a non-finite λ (a predictor
/// overshooting the range) residual and linearization are NaN, so the corrector fails there and
/// the step is halved. Throws std::invalid_argument for an amplitude parameter with F = 0, and
/// for μ as common_friction_coefficient does (no Jenkins element, unequal μ, exact Coulomb).
/// Not thread-safe (the cache is mutable).
class ForcedResponseFamily {
 public:
  ForcedResponseFamily(const WeightedResidual& base, ContinuationParameter parameter);
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x, double lambda) const;
  [[nodiscard]] LowRankLinearization linearize(const Eigen::VectorXd& x, double lambda) const;
  /// The problem at λ (a frequency; the base problem for an amplitude; for μ the family's copy
  /// with its Jenkins elements at μ = λ, valid until the next call with another λ).
  [[nodiscard]] const WeightedResidual& at(double lambda) const;
  /// Forcing scale s = F/F₀ at λ (1 for a frequency or friction coefficient parameter).
  [[nodiscard]] double load(double lambda) const;
  [[nodiscard]] ContinuationParameter parameter() const { return parameter_; }
  [[nodiscard]] const WeightedResidual& base() const { return *base_; }
  /// False at a frequency ≤ 0, a μ < 0, or a non-finite λ (no problem exists there; residuals
  /// are NaN).
  [[nodiscard]] bool defined(double lambda) const;

 private:
  const WeightedResidual* base_;
  ContinuationParameter parameter_;
  double base_amplitude_;
  mutable std::optional<WeightedResidual> cache_;
  mutable double cache_lambda_ = 0.0;
};

/// What the piecewise-smooth views of a ForcedResponseFamily share (SignoriniResponseFamily,
/// JenkinsResponseFamily): the family's nonsmooth residual and linearization, which the
/// continuation verifies every accepted point on. The family must outlive the view.
class PiecewiseResponseFamily {
 public:
  explicit PiecewiseResponseFamily(const ForcedResponseFamily& family) : family_(&family) {}
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x, double lambda) const {
    return family_->residual(x, lambda);
  }
  [[nodiscard]] LowRankLinearization linearize(const Eigen::VectorXd& x, double lambda) const {
    return family_->linearize(x, lambda);
  }

 protected:
  const ForcedResponseFamily* family_;
};

/// Rigid stops without friction: the family's Signorini conditions on the impulses as a
/// PiecewiseSmoothSystem (linearization.hpp). Its pieces are the active instants (1: the sample
/// touches its stop, the row g0 − u(λ) = 0; 0: it is free, c λ = 0), on each of which the
/// residual is affine in λ and smooth in f; its events are the rows a piece does not hold, c λ on
/// the touching samples and g0 − u(λ) on the free ones (WeightedResidual::signorini_events), so
/// pseudo_arclength locates each impulse that starts or ends and crosses it onto the
/// neighbouring piece (continuation.hpp) instead of halving its step at the corner. On the
/// reduced blade of reproduce/ll11_blade_forced (24 stops, H = 12) the corner path stalled at
/// 0.9806 f1 after 9 points, whatever the corrector tolerance (issue #38). The nonsmooth
/// residual and linearization are the family's; active_set is the min's piece at (x, λ).
/// Throws std::invalid_argument (construction) unless the family's problem is rigid without
/// friction.
class SignoriniResponseFamily : public PiecewiseResponseFamily {
 public:
  explicit SignoriniResponseFamily(const ForcedResponseFamily& family);
  using PiecewiseResponseFamily::linearize;
  using PiecewiseResponseFamily::residual;
  [[nodiscard]] ActiveSet active_set(const Eigen::VectorXd& x, double lambda) const;
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x, double lambda, const ActiveSet& piece) const;
  [[nodiscard]] LowRankLinearization linearize(const Eigen::VectorXd& x, double lambda, const ActiveSet& piece) const;
  [[nodiscard]] Eigen::VectorXd events(const Eigen::VectorXd& x, double lambda, const ActiveSet& piece) const;
};

/// Jenkins elements (contact::JenkinsLaw) without rigid stops: the family's residual on the
/// elements' stick/slip pieces as a PiecewiseSmoothSystem (linearization.hpp). A piece names, at
/// every sample of every element, stick (0) or slip (1) (WeightedResidual::jenkins_active_set's
/// layout); on it the sampled return map is one affine function of the samples and of μN (the
/// piece's own extension beyond its boundary, contact::jenkins_loop with a pattern), so the
/// residual is smooth there (affine in x under a constant normal load) and a stick/slip switch is
/// where an event function changes sign: the slider's margin (F_s,q − |f*_q|)/(k_t s_r), positive
/// on the piece (WeightedResidual::jenkins_events). pseudo_arclength then locates each switch and
/// crosses it onto the neighbouring piece (continuation.hpp) instead of halving its step at a kink
/// whose geometry does not change with the step: on a piecewise-affine residual a corner looks
/// the same at every scale. The nonsmooth residual and linearization are the family's;
/// active_set is the return map's piece at (x, λ). A normal law under a varying normal load keeps
/// its own kinks (only the elements' samples are pieces). Throws std::invalid_argument
/// (construction) for rigid stops or a problem without a Jenkins element.
class JenkinsResponseFamily : public PiecewiseResponseFamily {
 public:
  explicit JenkinsResponseFamily(const ForcedResponseFamily& family);
  using PiecewiseResponseFamily::linearize;
  using PiecewiseResponseFamily::residual;
  [[nodiscard]] ActiveSet active_set(const Eigen::VectorXd& x, double lambda) const;
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x, double lambda, const ActiveSet& piece) const;
  [[nodiscard]] LowRankLinearization linearize(const Eigen::VectorXd& x, double lambda, const ActiveSet& piece) const;
  [[nodiscard]] Eigen::VectorXd events(const Eigen::VectorXd& x, double lambda, const ActiveSet& piece) const;
};

/// One point of a forced-response curve.
struct ResponsePoint {
  double parameter = 0.0;              // f [Hz], F [N] or μ [-] (ResponseCurveOptions::parameter)
  double frequency_hz = 0.0;
  double amplitude_n = 0.0;            // F [N]
  Eigen::VectorXd contact_unknowns;    // x (n_c·M, x(k·n_c + c)) [m]; the rest: family.at(λ).expand(x);
                                       // rigid stops: the impulses λ [N] (expand_forces)
  double max_displacement = 0.0;       // max over P samples of u at `observed_dof` [m]
  double min_displacement = 0.0;       // min [m]
  double amplitude = 0.0;              // (max − min)/2 [m], the curve's amplitude measure
  double max_contact_force = 0.0;      // max over contacts and P samples of f_c [N]
  /// With a harmonic selection: WeightedResidual::dropped_harmonics_residual at this point
  /// (one more factorization of G per point); NaN without one.
  double dropped_harmonics_residual = std::numeric_limits<double>::quiet_NaN();
  int corrector_iterations = 0;
  // Stability (ResponseCurveOptions::stability): floquet.hpp; with rigid stops impact_stability
  // (impact_shooting.hpp), the saltation monodromy of the exact orbit near the point's.
  /// False when the point has no verdict (rigid stops: no exact orbit found near it, see
  /// stability_message); the fields below are then meaningless (stable false, multipliers 0).
  bool stability_available = true;
  std::string stability_message;       // why stability is unavailable; empty otherwise
  double max_multiplier = 0.0;         // spectral radius of the monodromy matrix
  double max_multiplier_error = 0.0;   // largest FloquetResult::multiplier_errors entry
  int monodromy_steps = 0;             // P used: `samples`, ×4 up to twice while not settled; 0 with rigid stops
  bool stability_settled = true;       // FloquetResult::settled() at monodromy_steps
  bool stable = true;                  // every |μ| < 1 + 1e-6
  /// Rigid stops: ImpactStability::distance, the exact orbit's rms distance from this point's
  /// (its contact displacements, relative), and its impacts per period; NaN and 0 otherwise.
  double shooting_distance = std::numeric_limits<double>::quiet_NaN();
  int impacts = 0;
  Bifurcation crossing = Bifurcation::None;  // between the previous point and this one
  /// The Floquet multiplier of largest modulus (FloquetResult::multipliers(0)); its argument
  /// tells a crossing's kind (classify_crossing: near 0 fold, near π period doubling).
  std::complex<double> leading_multiplier = 0.0;
  /// The trial coefficients of ResponseCurveOptions::keep_dofs at this point (row i = DOF
  /// keep_dofs[i], column = trial function) [m]; empty when keep_dofs is.
  Eigen::MatrixXd kept_coefficients;
};

struct ResponseCurve {
  std::vector<ResponsePoint> points;
  std::vector<Fold> folds;             // parameters of the turning points
  /// Per fold: the response at its state Fold::x (max/min/amplitude, contact force, kept
  /// coefficients; no stability, corrector_iterations 0), so that a fold is drawn where it lies on a
  /// multivalued curve, not at the amplitude of the nearest point in λ.
  std::vector<ResponsePoint> fold_points;
  /// Per fold: a Floquet multiplier crosses +1 within four points of it on either side (with
  /// stability), i.e. it is a fold of the dynamics and not only of the truncated weighted-residual
  /// system (the crossing of the truncated orbit may lag the fold by a few points: 4 on the stiff
  /// stop at H = 32).
  std::vector<bool> fold_confirmed;
  StopReason stop = StopReason::InitialPointFailed;
  std::string message;
  /// Branch::stalled_residual: the corrector's last ‖R‖ when it stalled at the rounding floor of
  /// the residual (StepBelowMinimum within 10× of that floor), NaN otherwise.
  double stalled_residual = std::numeric_limits<double>::quiet_NaN();
  int rejected_steps = 0;
  int kinks = 0;
  int events = 0;                      // switching points located (rigid stops without friction, Jenkins pieces)
  int switches = 0;                    // impulses or stick/slip samples that switched there
  long corrector_iterations = 0;
  double wall_time_s = 0.0;            // continuation only (post-processing excluded)
  /// Wall time spent on the points' monodromy matrices after the continuation. For penalty laws
  /// and Jenkins elements with two threads or more, each point's multipliers are computed on a
  /// worker while the continuation goes on (the same multipliers as computed afterwards), and
  /// this is only the wait that remained; stability_work_s is the thread time of them all.
  double stability_time_s = 0.0;
  double stability_work_s = 0.0;       // thread time summed over every point's multipliers [s]
  /// Points whose multipliers were computed during the continuation and kept (0 on one thread,
  /// and for rigid stops); the others were computed after it.
  int stability_points_beside = 0;
  int unsettled_points = 0;            // verdicts the error estimate could still overturn at 16 P
  int unavailable_points = 0;          // points without a verdict (ResponsePoint::stability_available)
  /// branch_status(stop): Converged when the range was reached (its last point on the range end).
  [[nodiscard]] SolveStatus status() const { return branch_status(stop); }
  [[nodiscard]] bool converged() const { return status() == SolveStatus::Converged; }
  /// One line: "range reached: 163 points, 2 folds, 0 rejected steps, 0.22 s (stability 0.5 s)",
  /// with ", 14 events" after the folds when the branch was continued by events.
  [[nodiscard]] std::string brief() const {
    return std::string(to_string(stop)) + ": " + std::to_string(points.size()) + " points, " +
           std::to_string(folds.size()) + " folds, " +
           (events > 0 ? std::to_string(events) + " events, " : std::string()) +
           std::to_string(rejected_steps) + " rejected steps, " +
           format_number(wall_time_s) + " s (stability " + format_number(stability_time_s) + " s)";
  }
};

/// How a branch with Jenkins elements crosses their stick/slip switches (ResponseCurveOptions).
enum class StickSlipEvents {
  /// The nonsmooth corrector with the return map's generalized Jacobian, as long as it converges;
  /// where it stalls (step below minimum, not at the rounding floor), the branch goes on from its
  /// last point piece by piece (JenkinsResponseFamily), every switch located and crossed.
  OnStall,
  Always,  // piece by piece from the start
  Never,   // the nonsmooth corrector alone (a stall ends the branch)
};

struct ResponseCurveOptions {
  ContinuationParameter parameter = ContinuationParameter::Frequency;
  /// Jenkins elements: how their stick/slip switches are crossed (StickSlipEvents). OnStall keeps
  /// the cheaper nonsmooth corrector wherever it works, since every sample's switch is an event
  /// (the damper of examples/scenes/friction_damper_load.toml at Q = 256 stalls at the onset of
  /// full stick, μ = 0.998, and completes on events).
  StickSlipEvents stick_slip_events = StickSlipEvents::OnStall;
  double parameter_min = 0.0, parameter_max = 0.0;  // range of λ; the start is the base problem's
  int direction = +1;                               // sign of dλ at the start
  double initial_step = 5e-3, min_step = 1e-7, max_step = 2e-2;  // scaled arclength (see continuation.hpp)
  double max_parameter_step = 0.0;     // > 0: |Δλ| per step at most this (λ units)
  double max_state = 100.0;            // > 0: stop (StateBound) once ‖x‖∞ > max_state · s_r
                                       // (s_r = WeightedResidual::residual_scale); 0: no bound
  int max_points = 5000;
  int max_corrector_iterations = 8;
  double corrector_tolerance = 1e-9;
  int observed_dof = -1;               // DOF of max/min/amplitude; −1 = the forced DOF
  /// P samples per period for max/min, and the monodromy steps; where a verdict is not settled
  /// (some ||μ| − 1| ≤ 2 × its error estimate, floquet.hpp) P is quadrupled, at most twice.
  /// Throws std::invalid_argument (trace_response) if P < 8.
  int samples = 512;
  bool stability = true;               // Floquet multipliers of every point (floquet.hpp)
  /// Rigid stops: the shooting of each point's exact orbit and the distance it may lie from the
  /// point's (impact_stability, impact_shooting.hpp).
  ImpactStabilityOptions impact_stability = {};
  /// Threads for the stability of the points: a oneTBB task arena of this many (each point's
  /// monodromy matrix is independent, so the multipliers are bit-identical for any count);
  /// 0: oneTBB's default concurrency (the cores this process may use). With two or more, the
  /// points of penalty laws and Jenkins elements start on one of them during the continuation.
  /// Throws std::invalid_argument (trace_response) if < 0.
  int threads = 0;
  /// DOFs whose trial coefficients every point keeps (ResponsePoint::kept_coefficients), e.g. to
  /// report their amplitudes or harmonics along the branch; each costs nothing more than the
  /// expansion of the point's solution (one solve with G per point). Throws if out of range.
  std::vector<int> keep_dofs = {};
  /// Called after each accepted point (index, point: λ, step h), e.g. for progress; may be empty.
  std::function<void(size_t index, const BranchPoint& point)> on_point = nullptr;
  /// The checks of the fields alone: threads >= 0, samples >= 8, max_parameter_step and
  /// max_state finite and >= 0, parameter_min < parameter_max, 0 < min_step <= initial_step <=
  /// max_step, max_points >= 1, max_corrector_iterations >= 1, corrector_tolerance > 0,
  /// direction ±1 (trace_response checks the rest against the problem: the start inside the
  /// range, the observed and kept DOFs, stability with rigid stops). Throws std::invalid_argument
  /// naming the field, its value, the range and a value to use.
  void validate() const;
};

/// Traces the response of `base` (its frequency and amplitude are the start) over the range of
/// the parameter. With StopReason::RangeReached the last point lies on the range end: the step
/// that left the range is replaced by Newton at the end's λ (unless a fold lies on that step;
/// a failed landing keeps the overshooting point and says so in the message). Scaling: λ̂ = λ/λ₀, x̂ = x/s_r (the gap, WeightedResidual::residual_scale).
/// The start is solved with base.solve() (load stepping if needed). Throws
/// std::invalid_argument for a start outside [parameter_min, parameter_max] or a base problem
/// without contact (a linear curve needs no continuation: frequency_response()), for a
/// friction coefficient parameter as ForcedResponseFamily does or with parameter_min < 0, and
/// for stability = true with exact Coulomb friction (no saltation matrices for its rigid-plastic
/// stick–slip; Jenkins elements have their stability) or with rigid stops
/// whose counter-surface moves (ContactPoint::obstacle; the exact orbits are shot against fixed
/// stops). A penalty law's monodromy matrix takes the displacements relative to a moving
/// counter-surface. With rigid stops the
/// stability of each point is that of the exact orbit near it (impact_stability: plastic impacts,
/// its saltation monodromy; ResponsePoint::shooting_distance says how near), or unavailable with
/// the reason (ResponsePoint::stability_available, ResponseCurve::unavailable_points); a
/// crossing is classified against the last point with a verdict. Rigid stops (WeightedResidual::
/// rigid()): the unknowns are the impulses λ (contact_unknowns of the points), the residual the
/// Signorini conditions. Without friction the branch is continued piece by piece
/// (SignoriniResponseFamily): every change of the active instants is an event, located and
/// crossed, and counted in ResponseCurve::events and switches. With exact friction (three
/// branches per row) the continuation restarts at the corners of the branch instead
/// (PseudoArclengthOptions::corner_restart), with the generalized Jacobian. In a continuation in
/// μ (ContinuationParameter::FrictionCoefficient) every point is at the base problem's frequency
/// (ResponsePoint::parameter is its μ), and its stability is that of its own Jenkins elements.
/// With Jenkins elements the branch crosses their stick/slip switches as options.stick_slip_events
/// says: by default with the nonsmooth corrector, and on located events (JenkinsResponseFamily)
/// from where that stalls, back where the pieces cycle; ResponseCurve::events counts them and the
/// message says where each part ended.
[[nodiscard]] ResponseCurve trace_response(const WeightedResidual& base, const ResponseCurveOptions& options);

/// One change of stability along a traced curve: the number of Floquet multipliers outside the
/// unit circle differs between `before` and `after` (ResponsePoint::crossing of point `after`).
struct StabilityCrossing {
  size_t before = 0, after = 0;  // indices into ResponseCurve::points; `before` is the last point
                                 // with a verdict before `after` (rigid stops: some have none)
  /// Where the largest |μ| passes 1 on the segment from `before` (0) to `after` (1):
  /// t = (1 − |μ|_before)/(|μ|_after − |μ|_before) clamped to [0, 1]; ½ if both are equal.
  double t = 0.5;
  double parameter = 0.0;        // λ_before + t (λ_after − λ_before) (λ units: Hz, N or the friction coefficient)
  double frequency_hz = 0.0;     // the same interpolation of the forcing frequency [Hz]
  double amplitude = 0.0;        // the same interpolation of ResponsePoint::amplitude [m]
  /// The leading multiplier (ResponsePoint::leading_multiplier) of the unstable one of the two points.
  std::complex<double> multiplier = 0.0;
  Bifurcation kind = Bifurcation::None;  // classify_crossing: fold, period doubling or Neimark–Sacker
  bool stability_lost = false;   // true when `after` is the unstable one (in the curve's order)
};

/// The curve's stability crossings in its order, one per point whose ResponsePoint::crossing is
/// not None, each located by linear interpolation of the spectral radius between the two points
/// (StabilityCrossing::t): first order in the step, so the located λ lies within one step of the
/// point where the exact multiplier passes 1. Empty for a curve traced without stability. No
/// errors (a curve of fewer than two points has none).
[[nodiscard]] std::vector<StabilityCrossing> stability_crossings(const ResponseCurve& curve);

}  // namespace wbm::solvers
