// WeightedResidual, solution strategies for penalty contact: direct Newton on the condensed
// system, the contact homotopy in σ, load stepping, and the verified full residual
// (weighted_residual_impl.hpp).
#include "weighted_residual_impl.hpp"

#include <wbm/solvers/detail/rounding_floor.hpp>
#include <wbm/solvers/natural_parameter.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

namespace wbm::solvers {

namespace detail {

// weighted_residual_impl.hpp says what these two are for.
PseudoArclengthOptions homotopy_continuation(double lambda_min, double lambda_max, double state_scale,
                                             const WeightedResidualOptions& w) {
  PseudoArclengthOptions o;
  o.parameter_min = lambda_min;
  o.parameter_max = lambda_max;
  o.parameter_scale = 1.0;
  o.state_scale = state_scale;
  o.initial_step = 0.05;
  o.max_step = 0.5;
  o.min_step = 1e-9;
  o.kink_step = 1e-6;
  o.corner_restart = true;
  o.max_points = w.homotopy_max_points;
  o.corrector_tolerance = w.newton.tolerance;
  o.initial_newton = w.newton;
  return o;
}

void record_homotopy(const Branch& branch, double lambda_cap, HomotopyReport& report) {
  report.points = static_cast<int>(branch.points.size());
  report.folds = static_cast<int>(branch.folds.size());
  report.corrector_iterations = branch.corrector_iterations;
  report.stop = branch.stop;
  report.message = branch.message;
  double lambda_max = -std::numeric_limits<double>::infinity();
  for (const auto& bp : branch.points) lambda_max = std::max(lambda_max, bp.parameter);
  report.sigma_reached = branch.points.empty() ? 0.0 : std::pow(10.0, std::min(lambda_max, lambda_cap));
}

}  // namespace detail

// The condensed system at load factor s (forcing s·F) as a NonlinearSystem.
struct WeightedResidual::Condensed {
  const WeightedResidual* wr;
  double load;
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x) const {
    return wr->impl_->contact_residual(x, load);
  }
  [[nodiscard]] LowRankJacobian jacobian(const Eigen::VectorXd& x) const { return wr->contact_jacobian_low_rank(x); }
};

NewtonResult WeightedResidual::solve_with_load_stepping(Eigen::VectorXd x, int& steps) const {
  // detail::load_stepping on the condensed residual, predictor x + Δs·x_lin (the linear part of
  // the response); the last step ends on s = 1.
  const auto& p = *impl_;
  auto predict = [&](const Branch& branch, double s) {
    const BranchPoint& b = branch.points.back();
    return Eigen::VectorXd(b.x + (s - b.parameter) * p.x_lin);
  };
  return detail::load_stepping([this](double s) { return Condensed{this, s}; }, predict, std::move(x), p.x_lin,
                               p.options.newton, 0.5, steps);
}

Eigen::VectorXd WeightedResidual::ContactHomotopy::residual(const Eigen::VectorXd& x, double lambda) const {
  const auto& p = *problem->impl_;
  p.require_factorized();
  return (x - p.x_lin + std::pow(10.0, lambda) * p.compliance_times(p.contact_forces(x, nullptr))) / p.scale;
}

LowRankLinearization WeightedResidual::ContactHomotopy::linearize(const Eigen::VectorXd& x, double lambda) const {
  const auto& p = *problem->impl_;
  p.require_factorized();
  const double sigma = std::pow(10.0, lambda);
  std::vector<Impl::ContactTangent> tangents;
  const Eigen::VectorXd hn = p.compliance_times(p.contact_forces(x, &tangents));
  LowRankLinearization l;
  l.residual = (x - p.x_lin + sigma * hn) / p.scale;
  Impl::scale_tangents(tangents, sigma);  // the tangents of σ n_c(x): J = (I + H (σ N))/s_r in any form
  l.jacobian = p.contact_jacobian_from(tangents);
  l.parameter_derivative = (std::log(10.0) * sigma / p.scale) * hn;  // dσ/dλ = σ ln 10
  return l;
}

NewtonResult WeightedResidual::solve_with_contact_homotopy(HomotopyReport& report) const {
  const auto& p = *impl_;
  // λ₀: σ₀ ‖H N(x_lin)‖∞ = 0.1, so that x_lin is within Newton's reach of the σ₀ solution.
  std::vector<Impl::ContactTangent> tangents;
  (void)p.contact_forces(p.x_lin, &tangents);
  const double coupling = p.hn_product(tangents).lpNorm<Eigen::Infinity>();
  const double lambda0 = std::clamp(coupling > 0.0 ? std::log10(0.1 / coupling) : -1.0, -12.0, -1.0);
  report.lambda_start = lambda0;
  // From λ₀ to σ = 1 (a path turning back below λ₀ has ended), the state in metres as the residual.
  // The continuation lands on σ = 1 (λ = 0) itself, on the piece of the step that passes it.
  PseudoArclengthOptions o = detail::homotopy_continuation(lambda0 - 1.0, 0.0, p.scale, p.options);
  o.land_on = {0.0};
  const Branch branch = pseudo_arclength(contact_homotopy(), p.x_lin, lambda0, o);
  detail::record_homotopy(branch, 0.0, report);
  NewtonResult out;
  if (branch.stop != StopReason::RangeReached || branch.points.back().parameter < 0.0) {
    out.x = branch.points.empty() ? p.x_lin : branch.points.back().x;
    out.report.status = SolveStatus::PathEnded;
    out.report.iterations = static_cast<int>(branch.corrector_iterations);
    out.report.message = "contact homotopy ended at σ = " + format_number(report.sigma_reached) + " (from σ₀ = " +
                         format_number(std::pow(10.0, lambda0)) + ", " + std::to_string(report.points) +
                         " points, " + std::to_string(report.folds) + " folds in σ): " +
                         std::string(to_string(branch.stop)) + ": " + report.message;
    return out;
  }
  // The last step crossed σ = 1: Newton at σ = 1 from the landing there (verified on the
  // homotopy residual already, so this restates it in the report of the condensed problem), or,
  // if the landing did not converge, from the last point, just beyond σ = 1.
  Eigen::VectorXd guess = branch.landings.empty() ? branch.points.back().x : branch.landings.front().x;
  out = newton(Condensed{this, 1.0}, std::move(guess), p.options.newton);
  out.report.iterations += static_cast<int>(branch.corrector_iterations);
  report.status = out.report.status;
  if (report.reached()) report.sigma_reached = 1.0;
  out.report.message = "contact homotopy from σ₀ = " + format_number(std::pow(10.0, lambda0)) + " (" +
                       std::to_string(report.points) + " points, " + std::to_string(report.folds) +
                       " folds in σ), then Newton at σ = 1: " + out.report.message;
  return out;
}

double WeightedResidual::rounding_floor(const Eigen::VectorXd& a, const Eigen::VectorXd& x) const {
  const auto& p = *impl_;
  const double bnorm = p.b.norm() > 0.0 ? p.b.norm() : 1.0;
  double floor = 0.0;
  if (x.size() > 0) {  // the contact unknowns: a stiff contact law
    floor = detail::rounding_floor([&](const Eigen::VectorXd& v) { return residual(expand(v)); }, x) / bnorm;
  }
  // Every coefficient: an ill-conditioned G (its rounding is ≈ ε ‖|G| |a|‖, up to ε κ(G) ‖b‖).
  return std::max(floor, detail::rounding_floor([&](const Eigen::VectorXd& v) { return residual(v); }, a) / bnorm);
}

std::string_view to_string(SolutionPath path) noexcept {
  switch (path) {
    case SolutionPath::DirectNewton: return "direct Newton";
    case SolutionPath::ContactHomotopy: return "contact homotopy";
    case SolutionPath::LoadStepping: return "load stepping";
    case SolutionPath::Linear: return "linear";
    case SolutionPath::FullStepActiveSet: return "full-step active set";
  }
  return "unknown";
}

WeightedResidualSolution WeightedResidual::solve(const Eigen::VectorXd* x0) const {
  const auto start = std::chrono::steady_clock::now();
  const auto& p = *impl_;
  WeightedResidualSolution s;
  s.frequency_hz = p.forcing.frequency_hz;
  s.contact_unknowns = p.nc * p.m;
  s.linear_solver = linear_solver();
  s.operator_rule = p.ops.rule;
  s.condition_number = condition_number();
  if (!p.factorized) {
    s.report.status = SolveStatus::SingularJacobian;
    s.report.message = "linear operator G is singular: " + p.singular_reason();
    s.coefficients = Eigen::MatrixXd::Zero(p.n, p.m);
    s.relative_residual = std::numeric_limits<double>::infinity();
    return s;
  }
  if (p.rigid) return solve_rigid(x0, std::move(s), start);
  Eigen::VectorXd x;
  if (p.nc > 0) {
    Eigen::VectorXd start_x = x0 != nullptr ? *x0 : p.x_lin;
    if (start_x.size() != p.nc * p.m) {
      throw std::invalid_argument("WeightedResidual::solve: initial guess has length " +
                                  std::to_string(start_x.size()) + ", expected n_c*M = " + std::to_string(p.nc * p.m));
    }
    NewtonResult result = newton(Condensed{this, 1.0}, start_x, p.options.newton);
    s.path = SolutionPath::DirectNewton;
    std::string history = "direct Newton: " + result.report.message;
    int iterations = result.report.iterations;
    if (!result.report.converged() && x0 == nullptr && p.options.contact_homotopy) {
      NewtonResult h = solve_with_contact_homotopy(s.homotopy);
      iterations += h.report.iterations;
      history += "; " + h.report.message;
      if (h.report.converged()) {
        s.path = SolutionPath::ContactHomotopy;
        h.report.iterations = iterations;
        h.report.message = history;
      }
      result = std::move(h);
    }
    if (!result.report.converged() && x0 == nullptr) {
      int steps = 0;
      const SolveStatus before = result.report.status;
      NewtonResult stepped = solve_with_load_stepping(Eigen::VectorXd::Zero(start_x.size()), steps);
      iterations += stepped.report.iterations;
      stepped.report.iterations = iterations;
      stepped.report.message = history + "; load stepping (" + std::to_string(steps) + " steps): " +
                               stepped.report.message;
      if (stepped.report.converged()) {
        s.path = SolutionPath::LoadStepping;
      } else if (before == SolveStatus::PathEnded) {
        stepped.report.status = SolveStatus::PathEnded;  // the homotopy's diagnosis stands
      }
      result = std::move(stepped);
    }
    x = std::move(result.x);
    s.report = std::move(result.report);
  } else {
    // Converged provisionally: the full residual below verifies it (ResidualNotVerified if not).
    s.report.status = SolveStatus::Converged;
    s.path = SolutionPath::Linear;
    s.report.message = "linear problem (no contact): one solve";
  }
  const Eigen::VectorXd a = p.nc > 0 ? expand(x) : p.linear_coefficients();
  s.coefficients = spectral::as_coefficients(a, p.n);
  const double bnorm = p.b.norm();
  const Eigen::VectorXd full = residual(a);
  s.relative_residual = full.norm() / (bnorm > 0.0 ? bnorm : 1.0);
  s.backward_error = backward_error(a, full);
  if (p.nc == 0) {  // the one solve's backward error, and the tolerance it is held to
    s.report.residual_norms = {s.backward_error};
    s.report.tolerance = p.options.residual_tolerance;
  }
  if (p.nc > 0) {
    const Eigen::MatrixXd u = p.contact_samples(x);
    s.max_penetration = -std::numeric_limits<double>::infinity();
    std::optional<Eigen::MatrixXd> loops;  // a friction law's force at the samples (its periodic loop)
    for (int c = 0; c < p.nc; ++c) {
      if (p.contacts[c].law->hysteretic()) {  // |f| ≤ μN; no gap to penetrate
        if (!loops) loops = p.contact_force_samples(x, nullptr);
        s.max_contact_force = std::max(s.max_contact_force, loops->row(c).cwiseAbs().maxCoeff());
        continue;
      }
      for (int k = 0; k < p.q; ++k) {
        s.max_penetration = std::max(s.max_penetration, u(c, k) - p.contacts[c].law->gap());
        s.max_contact_force = std::max(s.max_contact_force, p.contacts[c].law->force(u(c, k)));
      }
    }
  }
  s.residual_tolerance = p.options.residual_tolerance;
  if (p.keep.size() > 0) s.dropped_harmonics_residual = p.nc > 0 ? dropped_harmonics_residual(x) : 0.0;
  if (s.report.converged() && (!std::isfinite(s.relative_residual) || !s.coefficients.allFinite())) {
    s.report.status = SolveStatus::NonFinite;
    s.report.message = "non-finite full residual after convergence of the condensed system";
  } else if (s.report.converged() && !(s.backward_error <= p.options.residual_tolerance)) {
    s.report.status = SolveStatus::ResidualNotVerified;
    s.report.message = "the condensed system converged (" + s.report.message + "), but the full residual " +
                       format_number(s.relative_residual) + " ‖b‖ has a backward error " +
                       format_number(s.backward_error) + " above residual_tolerance = " +
                       format_number(p.options.residual_tolerance) +
                       " (condition estimate of G " + format_number(s.condition_number) + ")";
    s.rounding_floor = rounding_floor(a, x);
    s.report.message += "; rounding floor of the residual at this solution " + format_number(s.rounding_floor);
  }
  s.wall_time_s = detail::elapsed(start);
  return s;
}

WeightedResidualSolution solve_weighted_residual(const MechanicalSystem& system, const HarmonicForcing& forcing,
                                                 const std::vector<ContactPoint>& contacts, const TimeBasis& trial,
                                                 const TimeBasis& weighting, const WeightedResidualOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const WeightedResidual wr(system, forcing, contacts, trial, weighting, options);
  WeightedResidualSolution s = wr.solve();
  s.wall_time_s = detail::elapsed(start);
  return s;
}
}  // namespace wbm::solvers
