#pragma once
/// Outcome of an iterative solve. Not converging is a reported outcome, never an exception.
/// One vocabulary for every solver of the project (Newton, the continuation corrector, the
/// nonlinear-mode levels, the forced response).

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

/// A number for a message: 4 significant digits, scientific notation when small or large
/// ("3.2e-11", "1298", "0.0125"), "nan"/"inf" spelled out. Never "0.000000" for 3e-11.
[[nodiscard]] inline std::string format_number(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.4g", v);
  return buffer;
}

}  // namespace wbm::solvers
