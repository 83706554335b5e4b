#pragma once
/// Damped Newton–Raphson for R(x) = 0 with a backtracking (Armijo) line search.

#include <cmath>
#include <concepts>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>

#include <wbm/solvers/status.hpp>

namespace wbm::solvers {

/// A square nonlinear system: residual(x) (length n) and its Jacobian dR/dx (n × n, dense).
template <class S>
concept NonlinearSystem = requires(const S& s, const Eigen::VectorXd& x) {
  { s.residual(x) } -> std::convertible_to<Eigen::VectorXd>;
  { s.jacobian(x) } -> std::convertible_to<Eigen::MatrixXd>;
};

struct NewtonOptions {
  double tolerance = 1e-10;   // converged when ‖R(x)‖₂ ≤ tolerance (R as scaled by the system)
  int max_iterations = 50;    // Newton steps, >= 0
  bool line_search = true;    // Armijo backtracking on ‖R‖₂ (halving, at most max_backtracks)
  int max_backtracks = 30;
  double min_rcond = 1e-15;   // Jacobians with a smaller reciprocal condition estimate are singular
};

struct NewtonReport {
  SolveStatus status = SolveStatus::MaxIterations;
  int iterations = 0;
  std::vector<double> residual_norms;  // ‖R(x_k)‖₂ for k = 0..iterations
  double jacobian_rcond = 0.0;         // LU reciprocal condition estimate of the last Jacobian
  std::string message;                 // why it stopped, with the last residual
  [[nodiscard]] bool converged() const { return status == SolveStatus::Converged; }
};

struct NewtonResult {
  Eigen::VectorXd x;  // last iterate; meaningful as a solution only if report.converged()
  NewtonReport report;
};

/// Newton–Raphson from x0: J(x_k) Δ = −R(x_k), x_{k+1} = x_k + t Δ with t = 1, ½, ¼, … the
/// first step length that reduces ‖R‖₂ by the factor (1 − 10⁻⁴ t) (Armijo), or t = 1 without
/// line search.
/// Stops with Converged, MaxIterations, Stagnated (no acceptable step),
/// SingularJacobian (rcond < min_rcond) or NonFinite (NaN/inf in R or J); the returned x is then
/// the last finite iterate. Never throws for non-convergence.
template <NonlinearSystem S>
NewtonResult newton(const S& system, Eigen::VectorXd x, const NewtonOptions& options = {}) {
  NewtonReport report;
  auto finish = [&](SolveStatus status, const std::string& why) {
    report.status = status;
    std::ostringstream os;
    os << why << " after " << report.iterations << " iterations, last ||R|| = "
       << (report.residual_norms.empty() ? NAN : report.residual_norms.back());
    report.message = os.str();
    return NewtonResult{std::move(x), std::move(report)};
  };
  Eigen::VectorXd r = system.residual(x);
  double norm = r.norm();
  report.residual_norms.push_back(norm);

  if (!std::isfinite(norm)) return finish(SolveStatus::NonFinite, "non-finite residual at the initial guess");
  for (;;) {
    if (norm <= options.tolerance) return finish(SolveStatus::Converged, "converged");
    if (report.iterations >= options.max_iterations) {
      return finish(SolveStatus::MaxIterations, "iteration limit reached");
    }
    const Eigen::MatrixXd jac = system.jacobian(x);
    if (!jac.allFinite()) return finish(SolveStatus::NonFinite, "non-finite Jacobian");
    const Eigen::PartialPivLU<Eigen::MatrixXd> lu(jac);
    report.jacobian_rcond = lu.rcond();
    if (!(report.jacobian_rcond >= options.min_rcond)) {
      return finish(SolveStatus::SingularJacobian, "singular Jacobian (rcond " +
                                                       std::to_string(report.jacobian_rcond) + ")");
    }
    const Eigen::VectorXd step = -lu.solve(r);
    double t = 1.0;
    bool accepted = false;
    Eigen::VectorXd x_new, r_new;
    double norm_new = 0.0;
    for (int b = 0; b <= options.max_backtracks; ++b, t *= 0.5) {
      x_new = x + t * step;
      r_new = system.residual(x_new);
      norm_new = r_new.norm();
      if (!options.line_search) {
        accepted = std::isfinite(norm_new);
        break;
      }
      if (std::isfinite(norm_new) && norm_new <= (1.0 - 1e-4 * t) * norm) {
        accepted = true;
        break;
      }
    }
    if (!accepted) {
      return finish(std::isfinite(norm_new) ? SolveStatus::Stagnated : SolveStatus::NonFinite,
                    std::isfinite(norm_new) ? "line search found no decrease"
                                            : "non-finite residual along the Newton step");
    }
    x = std::move(x_new);
    r = std::move(r_new);
    norm = norm_new;
    ++report.iterations;
    report.residual_norms.push_back(norm);
  }
}

}  // namespace wbm::solvers
