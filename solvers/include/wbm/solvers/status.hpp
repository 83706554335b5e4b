#pragma once
/// Outcome of an iterative solve. Not converging is a reported outcome, never an exception.

#include <string_view>

namespace wbm::solvers {

enum class SolveStatus { Converged, MaxIterations, Stagnated, SingularJacobian, NonFinite };

/// "converged", "max-iterations", "stagnated", "singular-jacobian", "non-finite".
[[nodiscard]] constexpr std::string_view to_string(SolveStatus s) noexcept {
  switch (s) {
    case SolveStatus::Converged: return "converged";
    case SolveStatus::MaxIterations: return "max-iterations";
    case SolveStatus::Stagnated: return "stagnated";
    case SolveStatus::SingularJacobian: return "singular-jacobian";
    case SolveStatus::NonFinite: return "non-finite";
  }
  return "unknown";
}

}  // namespace wbm::solvers
