#pragma once
/// Natural-parameter continuation: the second mode of the one continuation layer (the first,
/// pseudo-arclength, is continuation.hpp). λ is stepped and the state is corrected at fixed λ:
///   predictor  x⁰ = predict(branch, λ_{k+1}) (default: the secant through the last two points,
///              x_k + (λ_{k+1} − λ_k)/(λ_k − λ_{k−1}) (x_k − x_{k−1}); x_0 from the first point);
///   corrector  correct(λ_{k+1}, x⁰), whatever the caller solves at fixed λ: newton() on
///              R(x, λ) = 0 (to_correction below turns its result into a Correction; the load
///              stepping of WeightedResidual::solve), Powell's augmented Lagrangian at a fixed energy (LL11
///              Algs. 1–2, NonlinearModes::backbone), a penalty orbit (the penalty homotopy of
///              NonlinearModes::continue_backbone);
///   step       |Δλ| = h, h ← grow(h, iterations) after a success (default the rule of
///              pseudo_arclength, detail::adapted_step: h · clamp(target/iterations, ½, 2),
///              within [min_step, max_step]); h ← shrink · h and retry from the same point after a
///              failure, until h < min_step;
///   landing    a step that would pass a value of land_on, or the range's end in `direction` (or
///              fall short of it by less than 1e-9 of its length), is shortened to end on it exactly, so the branch holds a point at every listed value
///              it reaches (also copied to Branch::landings) and ends on the range's end.
/// It shares with pseudo_arclength the report (Branch: points, landings, stop, message, rejected
/// steps, corrector iterations, wall time), the stop vocabulary (StopReason) and the step rule.
/// Natural-parameter stepping cannot pass a fold (a turning point in λ): there the corrector
/// fails at every step length and the branch ends with StepBelowMinimum; its message says so and
/// names pseudo-arclength continuation as the way on. BranchPoint::tangent holds the unit secant
/// (x, λ) of the step that reached the point (at the first point: (0, direction)); events, folds
/// and kinks are not detected (Branch::folds stays empty).
/// Units: λ and the steps in the parameter's own units; x as the caller's.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include <wbm/solvers/continuation.hpp>
#include <wbm/solvers/newton.hpp>

namespace wbm::solvers {

struct NaturalParameterOptions {
  double parameter_min = 0.0, parameter_max = 0.0;  // the range; the branch ends on its end in `direction`
  int direction = +1;                               // +1: toward parameter_max, −1: toward parameter_min
  double initial_step = 0.1;  // |Δλ| of the first step, λ units
  double min_step = 1e-6;     // a failure that would take h below it ends the branch
  double max_step = 1.0;
  double shrink = 0.5;        // h ← shrink · h after a failed correction, in (0, 1)
  int target_iterations = 3;  // for the default step rule
  int max_points = 10000;
  std::string parameter_name = "λ";  // in messages, e.g. "E" or "s"
  double max_wall_time_s = 0.0;  // > 0: the branch ends (TimeBudget) once this is spent, checked before
                                 // each correction (the first included) and after a failed one
  /// The step after a success with `iterations` corrector iterations; empty: detail::adapted_step
  /// (h · clamp(target_iterations/iterations, ½, 2)). Clamped to [min_step, max_step] after.
  std::function<double(double h, int iterations)> grow = nullptr;
  /// Values to end a step on exactly (besides the range's end), e.g. the energies to compare at.
  std::vector<double> land_on = {};
  /// Called after each accepted point with its index (0 = the first); must not throw.
  std::function<void(size_t index, const BranchPoint& point)> on_point = nullptr;
  /// Called after each accepted point (after on_point); true ends the branch there with
  /// StopReason::GoalReached (e.g. the exact-contact orbit reached from this penalty orbit).
  std::function<bool(const BranchPoint& point)> goal = nullptr;

  /// Throws std::invalid_argument naming the field, its value, the allowed range and a way out.
  void validate() const;
};

/// What the corrector reports for one fixed λ: the state, its status (Converged only to the
/// caller's verified tolerance), its iterations (for the step rule), its residual norm and, on
/// failure, why.
struct Correction {
  Eigen::VectorXd x;
  SolveStatus status = SolveStatus::MaxIterations;
  int iterations = 0;
  double residual_norm = std::numeric_limits<double>::quiet_NaN();
  std::string message;
  /// The corrector stopped because a wall-time budget ran out (its own or the branch's): the
  /// branch then ends with StopReason::TimeBudget instead of counting a failed step.
  bool interrupted = false;
  [[nodiscard]] bool converged() const { return status == SolveStatus::Converged; }
};

/// A Newton solve at fixed λ as a Correction (its NewtonReport's status).
[[nodiscard]] inline Correction to_correction(NewtonResult&& r) {
  Correction c;
  c.status = r.report.status;
  c.iterations = r.report.iterations;
  if (!r.report.residual_norms.empty()) c.residual_norm = r.report.residual_norms.back();
  c.message = std::move(r.report.message);
  c.x = std::move(r.x);
  return c;
}

inline void NaturalParameterOptions::validate() const {
  auto fail = [](const std::string& field, double value, const std::string& rule) {
    throw std::invalid_argument("NaturalParameterOptions." + field + " = " + format_number(value) + ": " + rule);
  };
  if (!(parameter_min < parameter_max) || !std::isfinite(parameter_min) || !std::isfinite(parameter_max)) {
    fail("parameter_max", parameter_max, "must be finite and > parameter_min = " + format_number(parameter_min));
  }
  if (direction != 1 && direction != -1) fail("direction", direction, "must be +1 or -1");
  if (!(min_step > 0.0)) fail("min_step", min_step, "must be > 0 (e.g. 1e-6 of the range)");
  if (!(initial_step >= min_step && initial_step <= max_step) || !std::isfinite(max_step)) {
    fail("initial_step", initial_step,
         "need min_step = " + format_number(min_step) + " <= initial_step <= max_step = " + format_number(max_step));
  }
  if (!(shrink > 0.0 && shrink < 1.0)) fail("shrink", shrink, "must lie in (0, 1), e.g. 0.5");
  if (target_iterations < 1) fail("target_iterations", target_iterations, "must be >= 1");
  if (max_points < 1) fail("max_points", max_points, "must be >= 1");
  if (!(max_wall_time_s >= 0.0)) fail("max_wall_time_s", max_wall_time_s, "must be >= 0 (0: no budget)");
}

/// The default predictor: the secant through the branch's last two points at λ (the last point
/// alone when there is one).
[[nodiscard]] inline Eigen::VectorXd secant_predictor(const Branch& branch, double lambda) {
  const BranchPoint& last = branch.points.back();
  if (branch.points.size() < 2) return last.x;
  const BranchPoint& before = branch.points[branch.points.size() - 2];
  const double s = (lambda - last.parameter) / (last.parameter - before.parameter);
  return last.x + s * (last.x - before.x);
}

/// Steps λ from lambda0 over [parameter_min, parameter_max] in `direction` (see the top of this
/// file). `correct(double λ, Eigen::VectorXd guess) -> Correction`; `predict(const Branch&,
/// double λ) -> Eigen::VectorXd`. The first point is correct(lambda0, x0) (x0 may be empty if the
/// corrector needs no guess there). Every point the branch holds converged by the corrector's
/// own test. Throws std::invalid_argument for invalid options or lambda0 outside the range;
/// non-convergence is a StopReason, never thrown.
template <class Correct, class Predict>
Branch natural_parameter(Correct&& correct, Predict&& predict, Eigen::VectorXd x0, double lambda0,
                         const NaturalParameterOptions& o) {
  o.validate();
  if (!(lambda0 >= o.parameter_min && lambda0 <= o.parameter_max)) {
    throw std::invalid_argument("natural_parameter: " + o.parameter_name + "0 = " + format_number(lambda0) + " outside [" +
                                format_number(o.parameter_min) + ", " + format_number(o.parameter_max) + "]");
  }
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  Branch branch;
  auto finish = [&](StopReason why, const std::string& text) {
    branch.stop = why;
    branch.message = text;
    branch.wall_time_s = elapsed();
    return branch;
  };
  const double end = o.direction > 0 ? o.parameter_max : o.parameter_min;
  std::vector<bool> landed(o.land_on.size(), false);
  // Accepts a corrected point at λ reached by a step of length h.
  auto accept = [&](Correction&& c, double lambda, double h) {
    BranchPoint p;
    p.parameter = lambda;
    p.step = h;
    p.corrector_iterations = c.iterations;
    p.residual_norm = c.residual_norm;
    branch.corrector_iterations += c.iterations;
    const auto n = c.x.size();
    p.tangent = Eigen::VectorXd::Zero(n + 1);
    p.tangent(n) = o.direction;
    if (!branch.points.empty()) {
      const BranchPoint& last = branch.points.back();
      if (last.x.size() == n) {
        p.tangent.head(n) = c.x - last.x;
        p.tangent(n) = lambda - last.parameter;
        const double norm = p.tangent.norm();
        p.arclength = last.arclength + norm;
        if (norm > 0.0) p.tangent /= norm;
      }
    }
    p.x = std::move(c.x);
    for (size_t k = 0; k < o.land_on.size(); ++k) {
      if (!landed[k] && o.land_on[k] == lambda) {
        landed[k] = true;
        branch.landings.push_back(p);
      }
    }
    branch.points.push_back(std::move(p));
    if (o.on_point) o.on_point(branch.points.size() - 1, branch.points.back());
  };

  auto spent = [&] { return o.max_wall_time_s > 0.0 && elapsed() >= o.max_wall_time_s; };
  auto budget_message = [&](const std::string& where) {
    return "wall-time budget of " + format_number(o.max_wall_time_s) + " s spent (" + format_number(elapsed()) + " s) " +
           where;
  };
  if (spent()) return finish(StopReason::TimeBudget, budget_message("before the first point"));
  Correction first = correct(lambda0, std::move(x0));
  if (!first.converged()) {
    if (first.interrupted || spent()) return finish(StopReason::TimeBudget, budget_message("during the first point"));
    return finish(StopReason::InitialPointFailed,
                  "at " + o.parameter_name + " = " + format_number(lambda0) + ": " + first.message);
  }
  accept(std::move(first), lambda0, 0.0);
  if (o.goal && o.goal(branch.points.back())) {
    return finish(StopReason::GoalReached, "goal reached at " + o.parameter_name + " = " + format_number(lambda0));
  }
  double h = o.initial_step;
  while (static_cast<int>(branch.points.size()) < o.max_points) {
    const BranchPoint& last = branch.points.back();
    if (last.parameter == end) {
      return finish(StopReason::RangeReached, "reached the range end " + o.parameter_name + " = " + format_number(end));
    }
    if (spent()) {
      return finish(StopReason::TimeBudget, budget_message("after " + o.parameter_name + " = " + format_number(last.parameter)));
    }
    // The next λ: one step on, shortened to the nearest listed value or the range's end it passes.
    // A step that falls short of one by less than kSnap of its length ends on it: steps summed in
    // floating point (0.9 + 8 × 0.05 = 1.2999999999999994) would otherwise add a step of 6e-16.
    constexpr double kSnap = 1e-9;
    double next = last.parameter + o.direction * h;
    auto passes = [&](double v) { return (next - v) * o.direction > -kSnap * h; };
    for (size_t k = 0; k < o.land_on.size(); ++k) {
      const double v = o.land_on[k];
      if (!landed[k] && (v - last.parameter) * o.direction > 0.0 && passes(v)) next = v;
    }
    if (passes(end)) next = end;
    Correction c = correct(next, predict(branch, next));
    if (!c.converged()) {
      if (c.interrupted || spent()) {  // cut by the budget: no failure
        return finish(StopReason::TimeBudget, budget_message("during the step from " + o.parameter_name + " = " +
                                                             format_number(last.parameter) + " to " + format_number(next)));
      }
      ++branch.rejected_steps;
      h *= o.shrink;
      if (h < o.min_step) {
        const std::string& name = o.parameter_name;
        return finish(StopReason::StepBelowMinimum,
                      "step below minimum after " + name + " = " + format_number(last.parameter) + " (|Δ" + name +
                          "| = " + format_number(h) + " < min_step = " + format_number(o.min_step) + "; at " + name +
                          " = " + format_number(next) + ": " + c.message +
                          "); natural-parameter stepping cannot pass a fold (a turning point in " + name +
                          "): follow the branch by pseudo-arclength continuation");
      }
      continue;
    }
    const int iterations = c.iterations;
    accept(std::move(c), next, std::abs(next - last.parameter));
    if (o.goal && o.goal(branch.points.back())) {
      return finish(StopReason::GoalReached, "goal reached at " + o.parameter_name + " = " + format_number(next));
    }
    const double grown = o.grow ? o.grow(h, iterations) : detail::adapted_step(h, iterations, o.target_iterations);
    h = std::clamp(grown, o.min_step, o.max_step);
  }
  return finish(StopReason::MaxPoints, "point limit " + std::to_string(o.max_points) + " reached at " + o.parameter_name + " = " +
                                           format_number(branch.points.back().parameter));
}

/// natural_parameter with the secant predictor.
template <class Correct>
Branch natural_parameter(Correct&& correct, Eigen::VectorXd x0, double lambda0, const NaturalParameterOptions& o) {
  return natural_parameter(std::forward<Correct>(correct), secant_predictor, std::move(x0), lambda0, o);
}

}  // namespace wbm::solvers
