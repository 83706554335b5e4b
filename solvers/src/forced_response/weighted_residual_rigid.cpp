// WeightedResidual, rigid stops: the collocation instants, the Delassus operator D = V H W, the
// Signorini conditions as a semismooth system (primal-dual active set) and their penalty homotopy
// (weighted_residual_impl.hpp).
#include "weighted_residual_impl.hpp"

#include <cmath>
#include <stdexcept>

#include <wbm/contact/signorini.hpp>

namespace wbm::solvers {


void WeightedResidual::Impl::set_delassus(bool set_force_compliance) {
  const Collocation& col = *collocation;
  const Eigen::Index size = static_cast<Eigen::Index>(nc) * m;
  Eigen::MatrixXd w = Eigen::MatrixXd::Zero(size, size);  // W ⊗ I_{n_c}
  for (int c = 0; c < nc; ++c) w(Eigen::seq(c, Eigen::last, nc), Eigen::seq(c, Eigen::last, nc)) = col.weights;
  delassus = per_contact(col.trial_values, compliance_times(w));
  u_lin = per_contact(col.trial_values, x_lin);
  if (!set_force_compliance) return;
  force_compliance = delassus.diagonal().cwiseAbs().mean();
  if (!(force_compliance > 0.0) || !std::isfinite(force_compliance)) force_compliance = 1.0;
}


Eigen::VectorXd WeightedResidual::Impl::signorini(const Eigen::VectorXd& lambda, double load, std::vector<int>* gap_rows) const {
  require_factorized();
  const Eigen::VectorXd gap = collocation->gaps - (load * u_lin - delassus * lambda);
  Eigen::VectorXd phi(gap.size());
  if (gap_rows != nullptr) gap_rows->clear();
  for (Eigen::Index i = 0; i < gap.size(); ++i) {
    const auto cp = contact::signorini_min(force_compliance * lambda(i), gap(i));
    phi(i) = cp.value;
    if (cp.gap_branch && gap_rows != nullptr) gap_rows->push_back(static_cast<int>(i));
  }
  return phi;
}
bool WeightedResidual::rigid() const { return impl_->rigid; }

Eigen::VectorXd WeightedResidual::collocation_times() const {
  impl_->require_rigid("collocation_times");
  return impl_->collocation->tau;
}

const Eigen::MatrixXd& WeightedResidual::delassus() const {
  impl_->require_rigid("delassus");
  impl_->require_factorized();
  return impl_->delassus;
}

double WeightedResidual::force_compliance() const {
  impl_->require_rigid("force_compliance");
  impl_->require_factorized();
  return impl_->force_compliance;
}

Eigen::VectorXd WeightedResidual::signorini_residual(const Eigen::VectorXd& lambda, double load) const {
  const auto& p = *impl_;
  p.require_rigid("signorini_residual");
  if (lambda.size() != static_cast<Eigen::Index>(p.nc) * p.m) {
    throw std::invalid_argument("WeightedResidual::signorini_residual: lambda has length " + std::to_string(lambda.size()) +
                                ", expected n_c*M = " + std::to_string(p.nc * p.m));
  }
  return p.signorini(lambda, load, nullptr) / p.scale;
}

LowRankJacobian WeightedResidual::signorini_jacobian(const Eigen::VectorXd& lambda) const {
  const auto& p = *impl_;
  p.require_rigid("signorini_jacobian");
  std::vector<int> active;
  (void)p.signorini(lambda, 1.0, &active);
  const Eigen::Index size = lambda.size();
  const auto rank = static_cast<Eigen::Index>(active.size());
  const double c = p.force_compliance;
  LowRankJacobian jac;
  jac.scale = p.scale / c;  // J = (c/s_r)(I + P_A (D/c − I)_A)
  jac.rows = size;
  if (4 * rank > 3 * size) {  // dense form: s J = I with the gap rows replaced by D/c
    jac.capacitance = Eigen::MatrixXd::Identity(size, size);
    for (int i : active) jac.capacitance.row(i) = p.delassus.row(i) / c;
    return jac;
  }
  jac.u = Eigen::MatrixXd::Zero(size, rank);
  for (Eigen::Index i = 0; i < rank; ++i) jac.u(active[static_cast<size_t>(i)], i) = 1.0;
  auto rows = std::make_shared<Eigen::MatrixXd>(p.delassus(active, Eigen::all) / c);  // (D/c)_A, r × n
  for (Eigen::Index i = 0; i < rank; ++i) (*rows)(i, active[static_cast<size_t>(i)]) -= 1.0;
  jac.capacitance = p.delassus(active, active) / c;  // I + (D/c − I)_AA
  jac.times_v = [rows](const Eigen::MatrixXd& y) { return Eigen::MatrixXd(*rows * y); };
  return jac;
}

Eigen::VectorXd WeightedResidual::signorini_frequency_derivative(const Eigen::VectorXd& lambda, double load) const {
  const auto& p = *impl_;
  p.require_rigid("signorini_frequency_derivative");
  std::vector<int> gap_rows;
  (void)p.signorini(lambda, load, &gap_rows);
  const Eigen::MatrixXd a = spectral::as_coefficients(expand_forces(lambda, load), p.n);  // n × M
  // G′ a, then P G⁻¹, then the trial values at τ_{k+1}.
  const Eigen::VectorXd du =
      p.per_contact(p.collocation->trial_values, p.gather(p.solve_stacked(p.frequency_derivative_times(a), false)));
  Eigen::VectorXd out = Eigen::VectorXd::Zero(lambda.size());
  for (int i : gap_rows) out(i) = du(i) / p.scale;  // g = g0 − u and ∂u/∂f = −V P G⁻¹ G′ a
  return out;
}

Eigen::VectorXd WeightedResidual::signorini_load_derivative(const Eigen::VectorXd& lambda, double load) const {
  const auto& p = *impl_;
  p.require_rigid("signorini_load_derivative");
  std::vector<int> gap_rows;
  (void)p.signorini(lambda, load, &gap_rows);
  Eigen::VectorXd out = Eigen::VectorXd::Zero(lambda.size());
  for (int i : gap_rows) out(i) = -p.u_lin(i) / p.scale;
  return out;
}

Eigen::VectorXd WeightedResidual::expand_forces(const Eigen::VectorXd& lambda, double load) const {
  const auto& p = *impl_;
  p.require_rigid("expand_forces");
  p.require_factorized();
  Eigen::VectorXd rhs = load * p.b;
  const Eigen::VectorXd nx = p.collocation_forces(lambda);
  p.scatter(rhs, nx, -1.0);
  return p.solve_stacked(rhs, false);
}

Eigen::VectorXd WeightedResidual::residual(const Eigen::VectorXd& a, const Eigen::VectorXd& lambda) const {
  const auto& p = *impl_;
  p.require_rigid("residual(a, lambda)");
  Eigen::VectorXd r = p.linear_residual(a);
  const Eigen::VectorXd nx = p.collocation_forces(lambda);
  p.scatter(r, nx, 1.0);
  return r;
}

// The Signorini conditions at load s as a NonlinearSystem on λ (rigid stops).
struct WeightedResidual::Signorini {
  const WeightedResidual* wr;
  double load;
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& lambda) const { return wr->signorini_residual(lambda, load); }
  [[nodiscard]] LowRankJacobian jacobian(const Eigen::VectorXd& lambda) const { return wr->signorini_jacobian(lambda); }
};

// The Signorini conditions regularized by a penalty of relative stiffness κ = 10^μ at the same
// instants, as a ParametrizedSystem in μ (rigid stops):
//   r(λ, μ) = (c λ − κ (u(λ) − g0)₊) / s_r,   ∂r/∂λ = (c I + κ P_A D) / s_r,
//   ∂r/∂μ = −ln 10 · κ (u − g0)₊ / s_r,   A = the instants that penetrate.
// Its solutions are those of the linear penalty k = κ/c at the instants; as κ → ∞ they tend to
// the rigid one (penetration c λ/κ).
struct WeightedResidual::SignoriniPenalty {
  const WeightedResidual* wr;
  [[nodiscard]] Eigen::VectorXd penetration(const Eigen::VectorXd& lambda) const {
    const auto& p = *wr->impl_;
    return ((p.u_lin - p.delassus * lambda) - p.collocation->gaps).cwiseMax(0.0);
  }
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& lambda, double mu) const {
    const auto& p = *wr->impl_;
    return (p.force_compliance * lambda - std::pow(10.0, mu) * penetration(lambda)) / p.scale;
  }
  [[nodiscard]] Linearization linearize(const Eigen::VectorXd& lambda, double mu) const {
    const auto& p = *wr->impl_;
    const double kappa = std::pow(10.0, mu);
    const Eigen::VectorXd pen = penetration(lambda);
    Linearization l;
    l.residual = (p.force_compliance * lambda - kappa * pen) / p.scale;
    l.jacobian = Eigen::MatrixXd::Zero(lambda.size(), lambda.size());
    for (Eigen::Index i = 0; i < lambda.size(); ++i) {
      if (pen(i) > 0.0) l.jacobian.row(i) = (kappa / p.scale) * p.delassus.row(i);
      l.jacobian(i, i) += p.force_compliance / p.scale;
    }
    l.parameter_derivative = (-std::log(10.0) * kappa / p.scale) * pen;
    return l;
  }
};

NewtonResult WeightedResidual::solve_rigid_with_penalty_homotopy(HomotopyReport& report) const {
  const auto& p = *impl_;
  // From κ₀ = 10⁻², where λ ≈ κ₀ (u_lin − g0)₊ / c barely moves the structure, to κ = 10⁸
  // (penetration about 10⁻⁸ c λ), then the active-set Newton on the exact conditions.
  constexpr double kMuStart = -2.0, kMuEnd = 8.0;
  report.lambda_start = kMuStart;
  const SignoriniPenalty system{this};
  const Eigen::VectorXd start = std::pow(10.0, kMuStart) * system.penetration(Eigen::VectorXd::Zero(p.u_lin.size())) /
                                p.force_compliance;
  // λ in newtons: the state scaled so that c λ is compared with s_r in metres.
  const PseudoArclengthOptions o = detail::homotopy_continuation(kMuStart - 1.0, kMuEnd, p.scale / p.force_compliance, p.options);
  const Branch branch = pseudo_arclength(system, start, kMuStart, o);
  detail::record_homotopy(branch, kMuEnd, report);
  // Newton on the exact conditions from the stiffest penalty point reached: near the end of the
  // path its active set is the rigid one.
  Eigen::VectorXd guess = branch.points.empty() ? start : branch.points.back().x;
  NewtonResult out = newton(Signorini{this, 1.0}, std::move(guess), p.options.newton);
  out.report.iterations += static_cast<int>(branch.corrector_iterations);
  out.report.message = "penalty homotopy of the Signorini conditions, kappa from 1e" + format_number(kMuStart) +
                       " to " + format_number(report.sigma_reached) + " (" + std::to_string(report.points) + " points, " +
                       std::to_string(report.folds) + " folds; " + std::string(to_string(branch.stop)) + ": " +
                       report.message + "), then the active-set Newton: " +
                       out.report.message;
  if (!out.report.converged() && branch.stop != StopReason::RangeReached) out.report.status = SolveStatus::PathEnded;
  report.status = out.report.status;
  return out;
}

WeightedResidualSolution WeightedResidual::solve_rigid(const Eigen::VectorXd* lambda0, WeightedResidualSolution s,
                                                       std::chrono::steady_clock::time_point start) const {
  const auto& p = *impl_;
  const Eigen::Index size = static_cast<Eigen::Index>(p.nc) * p.m;
  const Eigen::VectorXd l0 = lambda0 != nullptr ? *lambda0 : Eigen::VectorXd::Zero(size);
  if (l0.size() != size) {
    throw std::invalid_argument("WeightedResidual::solve: initial contact forces have length " + std::to_string(l0.size()) +
                                ", expected n_c*M = " + std::to_string(size) + " (rigid stops: the force samples λ)");
  }
  NewtonResult result = newton(Signorini{this, 1.0}, l0, p.options.newton);
  s.path = SolutionPath::DirectNewton;
  std::string history = "primal-dual active set (semismooth Newton on the Signorini conditions): " + result.report.message;
  if (!result.report.converged() && lambda0 == nullptr && p.options.contact_homotopy) {
    NewtonResult h = solve_rigid_with_penalty_homotopy(s.homotopy);
    h.report.iterations += result.report.iterations;
    history += "; " + h.report.message;
    if (h.report.converged()) s.path = SolutionPath::ContactHomotopy;
    result = std::move(h);
  }
  s.report = std::move(result.report);
  s.report.message = history;
  const Eigen::VectorXd& lambda = result.x;
  const Eigen::VectorXd a = expand_forces(lambda);
  s.coefficients = spectral::as_coefficients(a, p.n);
  s.contact_force_samples = spectral::as_coefficients(lambda, p.nc);
  const double bnorm = p.b.norm();
  s.relative_residual = residual(a, lambda).norm() / (bnorm > 0.0 ? bnorm : 1.0);
  s.residual_tolerance = p.options.residual_tolerance;
  // The conditions recomputed from the coefficients, not from D λ.
  const Eigen::VectorXd xa = p.gather(a);
  const Eigen::VectorXd gap = p.collocation->gaps - p.per_contact(p.collocation->trial_values, xa);
  Eigen::VectorXd phi(size);
  for (Eigen::Index i = 0; i < size; ++i) phi(i) = contact::signorini_min(p.force_compliance * lambda(i), gap(i)).value;
  s.collocation_penetration = (-gap).maxCoeff();
  s.complementarity = phi.cwiseAbs().maxCoeff();
  s.max_contact_force = lambda.maxCoeff();
  const Eigen::MatrixXd u = p.contact_samples(xa);
  s.max_penetration = -std::numeric_limits<double>::infinity();
  for (int c = 0; c < p.nc; ++c) s.max_penetration = std::max(s.max_penetration, u.row(c).maxCoeff() - p.contacts[c].law->gap());
  const double phi_norm = detail::residual_norm(phi / p.scale, p.options.newton.norm);
  if (s.report.converged() && (!std::isfinite(s.relative_residual) || !s.coefficients.allFinite())) {
    s.report.status = SolveStatus::NonFinite;
    s.report.message = "non-finite full residual after convergence of the Signorini conditions";
  } else if (s.report.converged() && !(s.relative_residual <= p.options.residual_tolerance &&
                                       phi_norm <= p.options.newton.tolerance)) {
    s.report.status = SolveStatus::ResidualNotVerified;
    s.report.message = "the Signorini conditions converged (" + s.report.message + "), but recomputed from the "
                       "coefficients the full residual is " + format_number(s.relative_residual) + " ‖b‖ (bound " +
                       format_number(p.options.residual_tolerance) + ") and the complementarity residual " +
                       format_number(phi_norm) + " s_r (bound " + format_number(p.options.newton.tolerance) +
                       "; condition estimate of G " + format_number(s.condition_number) + ")";
  }
  s.wall_time_s = detail::elapsed(start);
  return s;
}
}  // namespace wbm::solvers
