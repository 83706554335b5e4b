#pragma once
/// Pseudo-arclength continuation of R(x, λ) = 0 through folds [Keller 1977; for harmonic balance
/// with contact, von Groll & Ewins 2001, ref. [38] of JL14 Sec. 5.6].
///
/// Unknowns are scaled, x̂ = x / state_scale and λ̂ = λ / parameter_scale, and the arclength is
/// measured in the metric ⟨a, b⟩ = (1/n) â_xᵀ b̂_x + â_λ b̂_λ (n = length of x), so a step means the
/// same whatever n and whether λ is 150 Hz or 1500 Hz. Each step (JL14 Sec. 5.6, [38]):
///   predictor  ẑ⁰ = ẑ_k + h t_k (tangent t_k, ⟨t_k, t_k⟩ = 1);
///   corrector  Newton on [R(x, λ); ⟨t_k, ẑ − ẑ_k⟩ − h] = 0 with the bordered Jacobian
///              [[∂R/∂x̂, ∂R/∂λ̂]; [t_kᵀ W]] — one extra row and column; this is newton()
///              without line search, with the system's own linear-solver policy when it has
///              one (S::linear_solver(), e.g. NonlinearModes::BackboneSystem::KktSolver), else
///              dense LU (Linearization) or sparse LU (SparseLinearization, one SparseLu per
///              branch, its symbolic analysis reused while the pattern holds);
///   tangent    t_{k+1} from the same bordered matrix with right-hand side (0, 1), normalized, so
///              ⟨t_k, t_{k+1}⟩ > 0 and the branch never turns back on itself;
///   step       h ← h · clamp(target/iterations, ½, 2) after a success, h ← h/2 and retry after a
///              corrector failure or a tangent turning by more than max_turn_degrees; a turn that
///              persists down to h = kink_step is a corner of a nonsmooth branch, jumped by one
///              step of the last accepted length along the old tangent when that continues in
///              the old direction, else kept; with corner_restart, a corrector that fails down
///              to h = kink_step restarts along the tangent of the piece beyond the corner
///              (complementarity branches may turn back by more than 90° there);
///   corners    with corner_bisection, the corrector stops once its residual norms cycle
///              (NewtonOptions::stop_on_cycle:
///              a semismooth Newton whose hyperplane misses the branch beyond a corner alternates
///              between active sets), and the distance to that hyperplane caps the next steps at
///              half of what remains (bisection toward the corner, one attempt per halving), and
///              at kink_step once less than kink_step remains. On the blade's first-mode branch
///              (reproduce/ll11_blade, 10 corners) this took the rejected steps from 134 to 66
///              and the time from 127 s to 70 s, with the same levels. Off by
///              default: it changes the path, and so the last digits, of every other solver's
///              continuation; continue_backbone (exact contact) turns it on.
/// Piecewise-smooth systems (PiecewiseSmoothSystem, linearization.hpp: complementarity or penalty
/// contact at samples) are continued by events instead (detail/continuation_events.hpp): the
/// corrector works on one piece (a fixed active set, a smooth residual), a step that ends with
/// an event function below 0 has crossed a switching surface, the crossing is located by regula
/// falsi on the step length and kept as a point (BranchPoint::event), every entry crossing there
/// is flipped, and the branch goes on along the new piece's tangent, oriented so that the flipped
/// entries' new event functions grow (it may turn back by more than 90°). Step halving is left
/// for a corrector that fails on a smooth piece; the corner options (kink_step, corner_restart,
/// corner_bisection) are not used, and every accepted point is verified on the nonsmooth residual.
/// Branch::events and switches count the events and the entries flipped; a switching point where
/// no piece continues the branch ends it with StopReason::DegenerateEvent and the reason, and a
/// switching point reached again on the same piece, in the same direction (within 1e-6 in the
/// scaled metric), with StopReason::Retraced: the pieces close a loop (DB6 nonlinear modes with
/// midpoint samples at M = 128 went round one between E = 1.0007 and 1.066 until max_points).
/// A fold (turning point) is a sign change of the λ-component of the tangent between two points;
/// its parameter is the extremum of the cubic Hermite interpolant of λ(s) on that step, and its
/// state (Fold::x) the interpolant of x(s) there; at a switching point where the new piece turns
/// back in λ, the switching point's λ and x.
/// The branch stops on a StopReason; every point it holds converged (‖R‖ ≤ corrector_tolerance);
/// with RangeReached the last point lies beyond the range by less than one step.
/// Non-convergence is never thrown.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <concepts>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>
#include <Eigen/SparseCore>
#include <Eigen/SparseLU>

#include <wbm/solvers/detail/continuation_corner.hpp>
#include <wbm/solvers/detail/continuation_corrector.hpp>
#include <wbm/solvers/detail/continuation_events.hpp>
#include <wbm/solvers/detail/continuation_fold.hpp>
#include <wbm/solvers/detail/rounding_floor.hpp>
#include <wbm/solvers/linearization.hpp>
#include <wbm/solvers/newton.hpp>

namespace wbm::solvers {

// StopReason, why a branch ended, is in status.hpp with SolveStatus: one vocabulary.

struct BranchPoint {
  double parameter = 0.0;       // λ
  Eigen::VectorXd x;            // converged state
  Eigen::VectorXd tangent;      // scaled tangent (x̂ part then λ̂), ⟨t, t⟩ = 1
  double arclength = 0.0;       // scaled arclength from the first point
  double step = 0.0;            // h that reached this point
  bool event = false;           // a switching point (piecewise-smooth systems): tangent is the new piece's
  int corrector_iterations = 0;
  double residual_norm = 0.0;   // ‖R‖₂ at the point
  [[nodiscard]] double parameter_tangent() const { return tangent(tangent.size() - 1); }
};

struct PseudoArclengthOptions {
  double parameter_min = 0.0, parameter_max = 0.0;  // the branch stops when λ leaves [min, max]
  double parameter_scale = 1.0;  // λ̂ = λ / parameter_scale (> 0), e.g. the start frequency
  double state_scale = 1.0;      // x̂ = x / state_scale (> 0), e.g. the gap
  int direction = +1;            // sign of dλ at the start
  double initial_step = 1e-2;    // h, in the scaled metric
  double min_step = 1e-7;
  double max_step = 5e-2;
  double max_parameter_step = 0.0;  // > 0: also |Δλ| <= this per step (λ units), for a dense curve
  double max_state = 0.0;           // > 0: stop (StateBound) once ‖x̂‖∞ = ‖x‖∞/state_scale exceeds it
  int max_points = 10000;
  int max_corrector_iterations = 8;
  double corrector_tolerance = 1e-9;  // on ‖R‖₂, R as the system scales it
  int target_iterations = 3;          // corrector iterations the step adaptation aims at
  double max_turn_degrees = 30.0;     // a larger angle between consecutive tangents halves h ...
  double kink_step = 1e-4;            // ... unless h <= kink_step: then the point is kept (a kink)
  bool corner_restart = false;        // a corrector failing at h <= kink_step restarts along the
                                      // new piece's tangent (turning corners, see below)
  bool corner_bisection = false;      // a corrector that cycles is stopped and the next steps
                                      // bisect toward its hyperplane (corners, see below)
  NewtonOptions initial_newton{};     // for the first point, at fixed λ
  /// Parameter values to land on exactly (Branch::landings): at the first step whose ends
  /// bracket a value, Newton at that fixed λ (on the step's piece for a PiecewiseSmoothSystem)
  /// from the linear interpolation of the ends, to corrector_tolerance, verified on the
  /// (nonsmooth) residual. Include parameter_min/max to land on the range's ends.
  std::vector<double> land_on = {};
  /// Called after each accepted point with its index (0 = the first) and the point, e.g. for a
  /// progress display (λ, step h); may be empty. It must not throw.
  std::function<void(size_t index, const BranchPoint& point)> on_point = nullptr;
  /// Throws std::invalid_argument naming the field, its value and the range.
  void validate() const;
};


struct Fold {
  double parameter = 0.0;  // λ at the turning point (Hermite interpolation)
  size_t after = 0;        // the fold lies between points[after] and points[after + 1]
  /// The state there (length n, units of BranchPoint::x): the cubic Hermite interpolant of x(s)
  /// on that step at the fold's arclength, or a switching point's x where the new piece turns back.
  Eigen::VectorXd x;
};

struct Branch {
  std::vector<BranchPoint> points;
  /// One point per value of PseudoArclengthOptions::land_on that the branch passed and Newton
  /// reached (first passage, in the order passed; `step` is 0, the tangent that of the step).
  std::vector<BranchPoint> landings;
  std::vector<Fold> folds;
  StopReason stop = StopReason::InitialPointFailed;
  std::string message;      // why it stopped, with the last λ and step
  int rejected_steps = 0;   // corrector failures and over-sharp turns, each retried with h/2
  int kinks = 0;            // corners met at h <= kink_step (nonsmooth branch), jumped or kept
  int events = 0;           // piecewise-smooth systems: switching points located and crossed
  int switches = 0;         // entries flipped at them (simultaneous crossings count each entry)
  long corrector_iterations = 0;
  double wall_time_s = 0.0;
  /// StepBelowMinimum after a corrector that failed at a residual its system cannot resolve: the
  /// corrector's last ‖R‖ when it lies within kFloorFactor of the rounding floor of R measured at
  /// the last accepted point x (the largest ‖R(x ⊙ (1 ± ε p), λ) − R(x, λ)‖ over the two
  /// alternating sign patterns p, ε = 2⁻⁵²: how far R moves when x moves by its own rounding).
  /// The tolerance then lies at or under that floor (a residual evaluated through ill-conditioned
  /// solves, a penalty too stiff for the arithmetic), and the way out is a larger tolerance, not a
  /// shorter step. NaN otherwise, e.g. at a corner of a nonsmooth residual, where the corrector
  /// fails far above the floor.
  double stalled_residual = std::numeric_limits<double>::quiet_NaN();
  double rounding_floor = std::numeric_limits<double>::quiet_NaN();  // the floor measured then
  static constexpr double kFloorFactor = 10.0;
  /// branch_status(stop): Converged when the range (or the goal) was reached.
  [[nodiscard]] SolveStatus status() const { return branch_status(stop); }
  [[nodiscard]] bool converged() const { return status() == SolveStatus::Converged; }
  /// One line: "range reached: 212 points, 2 folds, 14 events, 3 rejected steps, 0.41 s".
  [[nodiscard]] std::string brief() const {
    return std::string(to_string(stop)) + ": " + std::to_string(points.size()) + " points, " +
           std::to_string(folds.size()) + " folds, " + std::to_string(events) + " events, " +
           std::to_string(rejected_steps) + " rejected steps, " + format_number(wall_time_s) + " s";
  }
};

inline void PseudoArclengthOptions::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("PseudoArclengthOptions." + what); };
  if (!(parameter_min < parameter_max)) fail("parameter_min must be < parameter_max");
  if (!(parameter_scale > 0.0) || !(state_scale > 0.0)) fail("parameter_scale and state_scale must be > 0");
  if (direction != 1 && direction != -1) fail("direction = " + std::to_string(direction) + ": must be +1 or -1");
  if (!(min_step > 0.0 && min_step <= initial_step && initial_step <= max_step)) {
    fail("steps: need 0 < min_step <= initial_step <= max_step");
  }
  if (max_points < 1 || max_corrector_iterations < 1 || target_iterations < 1) {
    fail("max_points, max_corrector_iterations and target_iterations must be >= 1");
  }
  if (!(corrector_tolerance > 0.0)) fail("corrector_tolerance must be > 0");
  if (!(max_turn_degrees > 0.0 && max_turn_degrees < 180.0)) fail("max_turn_degrees must lie in (0, 180)");
  if (!(kink_step >= min_step)) fail("kink_step must be >= min_step");
}


namespace detail {
/// The step rule of both modes of the continuation layer (pseudo_arclength here, natural_parameter
/// in natural_parameter.hpp): after a success with `iterations` corrector iterations,
/// h · clamp(target/iterations, ½, 2), so that the corrector works about `target` iterations.
[[nodiscard]] inline double adapted_step(double h, int iterations, int target) {
  return h * std::clamp(static_cast<double>(target) / std::max(1, iterations), 0.5, 2.0);
}
}  // namespace detail

/// Traces the branch through (x0, λ0): x0 is corrected at fixed λ0 first (initial_newton), then
/// continued until a StopReason. Throws std::invalid_argument for invalid options or λ0 outside
/// [parameter_min, parameter_max].
template <ParametrizedSystem S>
Branch pseudo_arclength(const S& system, Eigen::VectorXd x0, double lambda0, const PseudoArclengthOptions& o) {
  o.validate();
  if (!(lambda0 >= o.parameter_min && lambda0 <= o.parameter_max)) {
    throw std::invalid_argument("pseudo_arclength: λ0 = " + format_number(lambda0) + " outside [" +
                                format_number(o.parameter_min) + ", " + format_number(o.parameter_max) + "]");
  }
  const auto start = std::chrono::steady_clock::now();
  const double xs = o.state_scale, ls = o.parameter_scale;
  const auto n = x0.size();
  Branch branch;
  auto finish = [&](StopReason why, const std::string& text) {
    branch.stop = why;
    branch.message = text;
    branch.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return branch;
  };
  // A failed corrector at a step below min_step whose ‖R‖ lies within kFloorFactor of the rounding
  // floor of R at the last accepted point (Branch::stalled_residual): the message's tail saying
  // so, or nothing.
  auto floor_stop = [&](const detail::Attempt& a, const BranchPoint& last) -> std::optional<std::string> {
    if (a.converged() || !std::isfinite(a.rnorm)) return std::nullopt;
    const double floor = detail::rounding_floor(
        [&](const Eigen::VectorXd& x) { return Eigen::VectorXd(system.residual(x, last.parameter)); }, last.x);
    if (!(a.rnorm <= Branch::kFloorFactor * floor)) return std::nullopt;
    branch.stalled_residual = a.rnorm;
    branch.rounding_floor = floor;
    return " (h below min_step = " + format_number(o.min_step) + "): the corrector stalls at ‖R‖ = " +
           format_number(a.rnorm) + ", within " + format_number(Branch::kFloorFactor) +
           " × the rounding floor of R at the last point (" + format_number(floor) +
           ", R's change when x moves by its own rounding), above corrector_tolerance = " +
           format_number(o.corrector_tolerance) + ": that tolerance is below what R resolves; raise it";
  };
  auto scaled = [&](const Eigen::VectorXd& x, double lambda) {
    Eigen::VectorXd z(n + 1);
    z.head(n) = x / xs;
    z(n) = lambda / ls;
    return z;
  };

  // Fixed-λ system for the first point.
  struct Fixed {
    const S* s;
    double lambda;
    [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x) const { return s->residual(x, lambda); }
    [[nodiscard]] auto jacobian(const Eigen::VectorXd& x) const { return s->linearize(x, lambda).jacobian; }
  };

  using Lin = decltype(system.linearize(x0, lambda0));
  // One linear solver for the whole branch (the system's own, or SparseLu, which keeps its symbolic
  // analysis across steps, or DenseLu).
  auto solver = detail::branch_linear_solver<Lin>(system);
  constexpr bool kPiecewise = PiecewiseSmoothSystem<S>;
  NewtonResult first = newton(Fixed{&system, lambda0}, std::move(x0), o.initial_newton, solver);
  if (!first.report.converged()) return finish(StopReason::InitialPointFailed, first.report.message);

  // Tangent at the first point, oriented by `direction`.
  Eigen::VectorXd seed = Eigen::VectorXd::Zero(n + 1);
  seed(n) = o.direction;
  BranchPoint p0;
  p0.parameter = lambda0;
  p0.x = first.x;
  p0.residual_norm = first.report.residual_norms.back();
  p0.corrector_iterations = first.report.iterations;
  p0.tangent = detail::tangent(solver, system.linearize(p0.x, lambda0), seed, xs, ls);
  branch.points.push_back(p0);
  if (o.on_point) o.on_point(0, branch.points.back());

  std::vector<bool> landed(o.land_on.size(), false);
  const NewtonOptions landing_options{.tolerance = 0.5 * o.corrector_tolerance,
                                      .max_iterations = std::max(8, o.max_corrector_iterations),
                                      .line_search = false};
  const double cos_turn = std::cos(o.max_turn_degrees * 3.14159265358979323846 / 180.0);
  double h = o.initial_step;
  double h_accepted = h;  // the step of the last accepted point, for jumps over kinks
  // Distance (scaled arclength, from the last point) to the hyperplane of a corrector that
  // cycled: a corner lies before it. Steps are capped at half of it (bisection toward the
  // corner, one attempt per halving); within kink_step of it the cap is kink_step, so that the
  // corner is met (and restarted from) at once. Infinite when none.
  constexpr double kNoCorner = std::numeric_limits<double>::infinity();
  double corner_ahead = kNoCorner;
  // The corrector is newton() on the bordered system, without line search.
  const NewtonOptions corrector_options{.tolerance = o.corrector_tolerance,
                                        .max_iterations = o.max_corrector_iterations,
                                        .line_search = false,
                                        .stop_on_cycle = o.corner_bisection};
  auto attempt_along = [&](const Eigen::VectorXd& direction, const Eigen::VectorXd& z_last, double step) {
    return detail::attempt_along<S, Lin>(system, solver, xs, ls, corrector_options, direction, z_last, step);
  };
  // Piecewise-smooth systems: the piece of the current point, and the events crossed in a row
  // without moving (each flips at least one entry, so more than the entries means a cycle).
  ActiveSet piece;
  if constexpr (kPiecewise) piece = system.active_set(p0.x, lambda0);
  size_t standing_events = 0;
  // Piecewise-smooth systems: each switching point's index and the piece it continued on. A
  // switching point reached again, on the same piece, in the same direction, closes a loop of
  // pieces that the branch would go round until max_points: it ends the branch (Retraced).
  std::vector<std::pair<size_t, ActiveSet>> switching_points;
  // On a piece the corrector aims at half the tolerance, and an event function counts as crossed
  // below −tolerance/4 (the nonsmooth residual of every point accepted is verified against the
  // tolerance). Event functions within the tolerance of 0 are at their surface (zero band): the
  // multipliers and gaps of a converged point are not known any better.
  const double event_tolerance = 0.25 * o.corrector_tolerance, zero_band = o.corrector_tolerance;
  NewtonOptions piece_options = corrector_options;
  piece_options.tolerance = 0.5 * o.corrector_tolerance;
  piece_options.stop_on_cycle = false;
  while (static_cast<int>(branch.points.size()) < o.max_points) {
    const BranchPoint& last = branch.points.back();
    const Eigen::VectorXd z_last = scaled(last.x, last.parameter);
    detail::Attempt a;
    bool sharp = false;
    double h_taken = h;                // the step from the last point to a's
    Eigen::VectorXd incoming;          // at a switching point: the old piece's tangent there
    ActiveSet step_piece;              // the piece the step was taken on
    if constexpr (kPiecewise) {
      step_piece = piece;
      detail::PieceStep ps = detail::piece_step<S, Lin>(system, solver, xs, ls, piece_options, piece, last.tangent,
                                                        z_last, h, event_tolerance, zero_band);
      branch.corrector_iterations += ps.iterations;
      if (!ps.failure.empty()) {
        return finish(StopReason::DegenerateEvent, ps.failure + "; at λ = " + format_number(ps.a.z(n) * ls) +
                                                       " after " + std::to_string(branch.events) + " events");
      }
      if (ps.event) {
        ++branch.events;
        branch.switches += ps.switched;
        piece = std::move(ps.next);
        if (ps.step == 0.0) {  // the event lies at the last point: continue from it on the new piece
          branch.points.back().tangent = std::move(ps.a.tangent);
          if (++standing_events > piece.size()) {
            return finish(StopReason::DegenerateEvent,
                          "the pieces cycle at λ = " + format_number(last.parameter) + ": " +
                              std::to_string(standing_events) + " events without moving (a degenerate switching point)");
          }
          continue;
        }
        h_taken = ps.step;
        incoming = std::move(ps.incoming);
      } else {
        sharp = ps.a.converged() && detail::inner(ps.a.tangent, last.tangent) < cos_turn;
      }
      a = std::move(ps.a);
      // Every accepted point is verified on the nonsmooth residual.
      if (a.converged()) {
        a.rnorm = system.residual(a.z.head(n) * xs, a.z(n) * ls).norm();
        if (!(a.rnorm <= o.corrector_tolerance)) a.status = SolveStatus::ResidualNotVerified;
      }
      if (!a.converged() || sharp) {
        ++branch.rejected_steps;
        h *= 0.5;
        if (h < o.min_step) {
          if (const auto why = floor_stop(a, last)) {
            return finish(StopReason::StepBelowMinimum,
                          "step below minimum on a smooth piece at λ = " + format_number(last.parameter) + *why);
          }
          return finish(StopReason::StepBelowMinimum,
                        "step below minimum on a smooth piece at λ = " + format_number(last.parameter) + " (h = " +
                            format_number(h) +
                            (a.converged() ? ", tangent turning too fast"
                                         : ", corrector failed, ‖R‖ = " + format_number(a.rnorm)) +
                            "): a singular point of the piece (a bifurcation or an unbounded branch), not a switch");
        }
        continue;
      }
      standing_events = 0;
    } else {
      if (o.corner_bisection && corner_ahead < kNoCorner) {
        h = std::min(h, corner_ahead <= o.kink_step ? o.kink_step : 0.5 * corner_ahead);
      }
      a = attempt_along(last.tangent, z_last, h);
      branch.corrector_iterations += a.iterations;
      // A sharp turn halves h, down to kink_step: below it the turn is a corner of a nonsmooth
      // branch (a contact sample changing state). The corner is then jumped: one step of the last
      // accepted length along the old tangent; if that lands on a branch that continues in the old
      // direction it is taken (a secondary branch that starts at the corner is not followed),
      // otherwise the corner point itself is kept.
      sharp = a.converged() && detail::inner(a.tangent, last.tangent) < cos_turn;
      if (sharp && h <= o.kink_step) {
        ++branch.kinks;
        detail::Attempt jump = attempt_along(last.tangent, z_last, h_accepted);
        branch.corrector_iterations += jump.iterations;
        if (jump.converged() && detail::inner(jump.tangent, last.tangent) >= cos_turn) {
          a = std::move(jump);
          h = h_accepted;
          sharp = false;
        }
      }
      if (!a.converged() && h <= o.kink_step && o.corner_restart) {
        detail::Attempt c;
        if (detail::restart_at_corner(system, solver, xs, ls, last.tangent, z_last, o.kink_step, o.max_step, attempt_along,
                                      branch.corrector_iterations, c)) {
          ++branch.kinks;
          a = std::move(c);
          corner_ahead = kNoCorner;
          sharp = false;
        }
      }
      if (!a.converged() || (sharp && h > o.kink_step)) {
        ++branch.rejected_steps;
        if (a.cycled()) corner_ahead = std::min(corner_ahead, h);
        h *= 0.5;
        if (h < o.min_step) {
          if (const auto why = floor_stop(a, last)) {
            return finish(StopReason::StepBelowMinimum,
                          "step below minimum at λ = " + format_number(last.parameter) + *why);
          }
          return finish(StopReason::StepBelowMinimum,
                        "step below minimum at λ = " + format_number(last.parameter) + " (h = " + format_number(h) +
                            (a.converged() ? ", tangent turning too fast)"
                                         : ", corrector failed, ‖R‖ = " + format_number(a.rnorm) + ", tolerance " +
                                               format_number(o.corrector_tolerance) + ")"));
        }
        continue;
      }
    }
    const int iterations = a.iterations;
    const double rnorm = a.rnorm;
    const Eigen::VectorXd& z = a.z;
    const Eigen::VectorXd& t_new = a.tangent;
    BranchPoint p;
    p.parameter = z(n) * ls;
    p.x = z.head(n) * xs;
    p.tangent = t_new;
    const Eigen::VectorXd dz = z - z_last;
    const double ds = std::sqrt(detail::inner(dz, dz));
    p.arclength = last.arclength + ds;
    p.step = h_taken;
    p.corrector_iterations = iterations;
    p.residual_norm = rnorm;
    p.event = incoming.size() > 0;
    // Fold: the λ-component of the tangent changes sign; Hermite cubic λ̂(s) on [0, ds] on the
    // smooth piece (to the old piece's tangent at a switching point), and at a switching point
    // whose new piece turns back in λ, the point itself.
    // The fold's state is the Hermite interpolant of x̂(s) at the same s (an estimate on the step,
    // not a corrected point: O(ds⁴) on a smooth piece).
    const double d0 = last.parameter_tangent(), d1 = p.event ? incoming(n) : p.parameter_tangent();
    if (d0 * d1 < 0.0) {
      const double s_fold = detail::fold_arclength(z_last(n), z(n), d0, d1, ds);
      const Eigen::VectorXd t1 = p.event ? Eigen::VectorXd(incoming.head(n)) : Eigen::VectorXd(t_new.head(n));
      Eigen::VectorXd x_fold = detail::hermite<Eigen::VectorXd>(z_last.head(n), z.head(n), last.tangent.head(n), t1, ds, s_fold);
      branch.folds.push_back({detail::hermite(z_last(n), z(n), d0, d1, ds, s_fold) * ls, branch.points.size() - 1,
                              std::move(x_fold) * xs});
    }
    if (p.event && d1 * p.parameter_tangent() < 0.0) branch.folds.push_back({p.parameter, branch.points.size() - 1, p.x});
    // Landings on the listed values this step passed (Newton at fixed λ from the interpolation).
    for (size_t k = 0; k < o.land_on.size(); ++k) {
      const double target = o.land_on[k];
      if (landed[k] || (last.parameter - target) * (p.parameter - target) > 0.0) continue;
      landed[k] = true;
      const double w = p.parameter == last.parameter ? 0.0 : (target - last.parameter) / (p.parameter - last.parameter);
      Eigen::VectorXd guess = last.x + w * (p.x - last.x);
      NewtonResult r = [&] {
        if constexpr (kPiecewise) {
          return newton(detail::FixedOnPiece<S>{&system, target, &step_piece}, std::move(guess), landing_options, solver);
        } else {
          return newton(Fixed{&system, target}, std::move(guess), landing_options, solver);
        }
      }();
      const double rn = system.residual(r.x, target).norm();
      if (!(rn <= o.corrector_tolerance)) continue;  // not reached: absent from landings
      BranchPoint l;
      l.parameter = target;
      l.x = std::move(r.x);
      l.tangent = p.event ? incoming : t_new;
      l.arclength = last.arclength + std::clamp(w, 0.0, 1.0) * ds;
      l.corrector_iterations = r.report.iterations;
      l.residual_norm = rn;
      branch.landings.push_back(std::move(l));
    }
    branch.points.push_back(std::move(p));
    if (o.on_point) o.on_point(branch.points.size() - 1, branch.points.back());
    if constexpr (kPiecewise) {
      if (branch.points.back().event) {
        const BranchPoint& q = branch.points.back();
        for (const auto& [k, k_piece] : switching_points) {
          const BranchPoint& r = branch.points[k];
          if (k_piece != piece) continue;
          Eigen::VectorXd d(n + 1);
          d << (q.x - r.x) / xs, (q.parameter - r.parameter) / ls;
          // Within 1e-6 in the scaled metric (steps are 1e-7 … 5e-2 of it; a located switching
          // point is known to the zero band): the same point.
          if (std::sqrt(detail::inner(d, d)) <= 1e-6 && detail::inner(q.tangent, r.tangent) > 0.0) {
            double low = q.parameter, high = q.parameter;
            for (size_t j = k; j < branch.points.size(); ++j) {
              low = std::min(low, branch.points[j].parameter);
              high = std::max(high, branch.points[j].parameter);
            }
            return finish(StopReason::Retraced,
                          "the branch came back to its switching point at λ = " + format_number(r.parameter) +
                              " (point " + std::to_string(k) + ") on the same piece and in the same direction: it "
                              "goes round a closed loop of pieces between λ = " + format_number(low) + " and " +
                              format_number(high));
          }
        }
        switching_points.emplace_back(branch.points.size() - 1, piece);
      }
    }
    const double lambda = branch.points.back().parameter;
    if (o.max_state > 0.0 && branch.points.back().x.lpNorm<Eigen::Infinity>() / xs > o.max_state) {
      return finish(StopReason::StateBound, "‖x‖∞/state_scale > " + format_number(o.max_state) + " at λ = " +
                                                format_number(lambda));
    }
    if (lambda < o.parameter_min || lambda > o.parameter_max) {
      return finish(StopReason::RangeReached, "λ = " + format_number(lambda) + " left [" +
                                                  format_number(o.parameter_min) + ", " +
                                                  format_number(o.parameter_max) + "]");
    }
    // Keep h after a switching point: the step to it says nothing of the piece beyond.
    if (branch.points.back().event) continue;
    h_accepted = h;
    corner_ahead = corner_ahead - h > 0.0 ? corner_ahead - h : kNoCorner;
    double h_max = o.max_step;
    const double t_lambda = std::abs(branch.points.back().parameter_tangent());
    if (o.max_parameter_step > 0.0 && t_lambda > 0.0) {
      h_max = std::min(h_max, o.max_parameter_step / (ls * t_lambda));  // |Δλ| ≈ h |t_λ| ls
    }
    h = std::clamp(detail::adapted_step(h, iterations, o.target_iterations), o.min_step, std::max(o.min_step, h_max));
  }
  return finish(StopReason::MaxPoints, "point limit " + std::to_string(o.max_points) + " reached at λ = " +
                                           format_number(branch.points.back().parameter));
}

}  // namespace wbm::solvers
