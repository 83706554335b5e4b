#pragma once
/// Outcome of an iterative solve. Not converging is a reported outcome, never an exception.
/// One vocabulary for every solver of the project (Newton, the continuation corrector, the
/// nonlinear-mode levels, the forced response) and, for branches (continuation, homotopies,
/// backbones), one StopReason.

#include <cmath>
#include <cstdio>
#include <string>
#include <string_view>

namespace wbm::solvers {

/// Converged: the residual was verified below the tolerance in force.
/// MaxIterations: the iteration limit came first. Stagnated: no step reduced the residual,
/// or the iterates cycle (NewtonOptions::stop_on_cycle).
/// SingularJacobian: the linear solver could not factorize (or its reciprocal condition
/// estimate was below the limit). NonFinite: NaN or inf in a residual, a Jacobian or a step.
/// ResidualNotVerified: the reduced problem converged, but the residual of the full problem,
/// recomputed from the solution, is above its stated tolerance. PathEnded: a homotopy or
/// continuation meant to reach the problem from an easier one stopped before it (its report
/// says where and why, e.g. the contact homotopy of weighted_residual.hpp). IntegratorFailed:
/// a time integrator (GSL's msbdf) gave up with finite values, e.g. its step fell below the
/// smallest it allows (its message names GSL's error).
enum class SolveStatus {
  Converged,
  MaxIterations,
  Stagnated,
  SingularJacobian,
  NonFinite,
  ResidualNotVerified,
  PathEnded,
  IntegratorFailed
};

/// "converged", "max-iterations", "stagnated", "singular-jacobian", "non-finite",
/// "residual-not-verified", "path-ended", "integrator-failed".
[[nodiscard]] constexpr std::string_view to_string(SolveStatus s) noexcept {
  switch (s) {
    case SolveStatus::Converged: return "converged";
    case SolveStatus::MaxIterations: return "max-iterations";
    case SolveStatus::Stagnated: return "stagnated";
    case SolveStatus::SingularJacobian: return "singular-jacobian";
    case SolveStatus::NonFinite: return "non-finite";
    case SolveStatus::ResidualNotVerified: return "residual-not-verified";
    case SolveStatus::PathEnded: return "path-ended";
    case SolveStatus::IntegratorFailed: return "integrator-failed";
  }
  return "unknown";
}

/// Why a branch ended. Retraced: the branch came back along a piece it had already traced
/// (detected by the caller that knows the problem, e.g. a backbone falling back below contact
/// onset after a corner) and was cut where it turned back; or, for a piecewise-smooth system,
/// pseudo_arclength reached one of its switching points again, on the same piece and in the same
/// direction (a closed loop of pieces it would go round until max_points). UndampedResonance: a forced response
/// with the M = 2^J Fourier basis followed the undamped resonance of its top function cos πMτ
/// (response_curve.hpp) and was cut where that function took over.
enum class StopReason {
  RangeReached,
  StepBelowMinimum,
  MaxPoints,
  InitialPointFailed,
  StateBound,
  Retraced,
  UndampedResonance,
  DegenerateEvent,
  TimeBudget,  // a wall-time budget spent (NaturalParameterOptions::max_wall_time_s, e.g. LL11 Alg. 1)
  GoalReached  // the caller's goal held at the last point (NaturalParameterOptions::goal)
};

[[nodiscard]] constexpr std::string_view to_string(StopReason r) noexcept {
  switch (r) {
    case StopReason::RangeReached: return "range reached";
    case StopReason::StepBelowMinimum: return "step below minimum";
    case StopReason::MaxPoints: return "point limit reached";
    case StopReason::InitialPointFailed: return "initial point did not converge";
    case StopReason::StateBound: return "state bound exceeded";
    case StopReason::Retraced: return "branch retraced itself";
    case StopReason::UndampedResonance: return "undamped resonance of the top Fourier function";
    case StopReason::DegenerateEvent: return "degenerate switching point";
    case StopReason::TimeBudget: return "wall-time budget spent";
    case StopReason::GoalReached: return "goal reached";
  }
  return "?";
}

/// The outcome of a branch (a continuation, a response curve, a backbone) from why it stopped:
/// Converged when it reached what it was asked for (the end of its range, or the caller's goal),
/// PathEnded otherwise (the stop and the message say why). The one definition of a converged
/// branch, read by Branch, ResponseCurve, Backbone, `wbm run`, the Python module and the
/// reproductions.
[[nodiscard]] constexpr SolveStatus branch_status(StopReason stop) noexcept {
  return stop == StopReason::RangeReached || stop == StopReason::GoalReached ? SolveStatus::Converged
                                                                             : SolveStatus::PathEnded;
}

/// One number through a printf conversion for one double, `spec` such as "%.4g", "%.3f" or
/// "%.1e" (it must convert exactly one double; the result is cut at 63 characters). The one
/// number formatter of the project: format_number, the scene's messages and tables and the
/// reproductions' tables go through it. (std::format needs GCC 13's libstdc++; Debian 12 has
/// GCC 12, and fmt's libfmt-dev is not on the CI image, so this is printf.)
[[nodiscard]] inline std::string format(const char* spec, double v) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, spec, v);
  return buffer;
}

/// A number for a message: 4 significant digits, scientific notation when small or large
/// ("3.2e-11", "1298", "0.0125"), "nan"/"inf" spelled out. Never "0.000000" for 3e-11.
[[nodiscard]] inline std::string format_number(double v) { return format("%.4g", v); }

}  // namespace wbm::solvers
