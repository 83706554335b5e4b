// impact_stability (impact_shooting.hpp): the stability of an approximate periodic solution with
// rigid stops, through the exact event-driven orbit near it and its saltation monodromy.
#include <wbm/solvers/impact_shooting.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <wbm/solvers/post_processing.hpp>

namespace wbm::solvers {

namespace {
// The multipliers of Φ by decreasing modulus, each with its error estimate κ_i δ ‖Φ̂‖_F
// (impact_shooting.hpp), on the similar Φ̂ = D Φ D⁻¹, D = diag(I, I/ω): the shooting's scaling,
// in which its residual δ is measured.
FloquetResult multipliers_with_errors(const Eigen::MatrixXd& phi, double omega, double delta) {
  FloquetResult r;
  r.monodromy = phi;
  r.steps = 0;
  const Eigen::Index n = phi.rows() / 2;
  Eigen::MatrixXd scaled = phi;
  scaled.bottomRows(n) /= omega;
  scaled.rightCols(n) *= omega;
  const Eigen::EigenSolver<Eigen::MatrixXd> eig(scaled, true);
  const Eigen::VectorXcd mu = eig.eigenvalues();
  const Eigen::MatrixXcd v = eig.eigenvectors();
  const Eigen::PartialPivLU<Eigen::MatrixXcd> lu(v);
  const Eigen::MatrixXcd w = lu.inverse();
  const double scale = delta * scaled.norm();
  Eigen::VectorXd error(mu.size());
  for (Eigen::Index i = 0; i < mu.size(); ++i) {
    const double kappa = v.col(i).norm() * w.row(i).norm();
    error(i) = std::isfinite(kappa) ? kappa * scale : std::numeric_limits<double>::infinity();
  }
  std::vector<Eigen::Index> order(static_cast<size_t>(mu.size()));
  std::iota(order.begin(), order.end(), Eigen::Index{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](Eigen::Index a, Eigen::Index b) { return std::abs(mu(a)) > std::abs(mu(b)); });
  r.multipliers.resize(mu.size());
  r.multiplier_errors.resize(mu.size());
  for (size_t k = 0; k < order.size(); ++k) {
    r.multipliers(static_cast<Eigen::Index>(k)) = mu(order[k]);
    r.multiplier_errors(static_cast<Eigen::Index>(k)) = error(order[k]);
  }
  r.max_modulus = mu.size() > 0 ? std::abs(r.multipliers(0)) : 0.0;
  return r;
}
}  // namespace

void ImpactStabilityOptions::validate() const {
  if (!(max_distance > 0.0) || !std::isfinite(max_distance)) {
    throw std::invalid_argument("ImpactStabilityOptions.max_distance = " + format_number(max_distance) +
                                ": must be finite and > 0 (e.g. 0.1)");
  }
  newton.validate();
}

ImpactStability impact_stability(const MechanicalSystem& system, const HarmonicForcing& forcing,
                                 const std::vector<ContactPoint>& contacts, const TimeBasis& trial,
                                 const Eigen::MatrixXd& coefficients, int samples,
                                 const ImpactStabilityOptions& options) {
  options.validate();
  const auto n = static_cast<Eigen::Index>(system.mass.rows());
  if (coefficients.rows() != n || coefficients.cols() != trial.dimension() || !coefficients.allFinite()) {
    throw std::invalid_argument("impact_stability: coefficients must be finite, n × M = " + std::to_string(n) + " × " +
                                std::to_string(trial.dimension()) + "; got " + std::to_string(coefficients.rows()) +
                                " × " + std::to_string(coefficients.cols()));
  }
  if (samples < 8) {
    throw std::invalid_argument("impact_stability: samples = " + std::to_string(samples) + ": must be >= 8");
  }
  const ImpactFlow flow(system, forcing, contacts);  // refuses a contact that is not a rigid stop
  const double f = forcing.frequency_hz;
  const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(samples, 0.0, 1.0 - 1.0 / samples);
  // The contact displacements on the samples (one evaluation of the basis); u and u̇ at the start only.
  const Eigen::MatrixXd u = coefficients * trial.values(tau, 0).transpose();  // n × P
  const auto nc = static_cast<Eigen::Index>(contacts.size());
  Eigen::MatrixXd uc(nc, samples);
  for (Eigen::Index c = 0; c < nc; ++c) {
    for (int p = 0; p < samples; ++p) uc(c, p) = contacts[static_cast<size_t>(c)].displacement(u.col(p));
  }
  // The start: the sample whose smallest gap is largest.
  int start = 0;
  double widest = -std::numeric_limits<double>::infinity();
  for (int p = 0; p < samples; ++p) {
    double gap = std::numeric_limits<double>::infinity();
    for (Eigen::Index c = 0; c < nc; ++c) gap = std::min(gap, contacts[static_cast<size_t>(c)].law->gap() - uc(c, p));
    if (gap > widest) {
      widest = gap;
      start = p;
    }
  }
  ImpactStability result;
  if (!(widest > 0.0)) {
    result.message = "no sample of the orbit has every stop open (largest smallest gap " + format_number(widest) +
                     " m): the shooting needs a start in free flight";
    return result;
  }
  Eigen::VectorXd guess(2 * n);
  if (velocity_unavailable(trial).empty()) {
    guess << u.col(start), evaluate_fields(trial, coefficients, tau.segment(start, 1), f).velocity;
  } else {  // DB4: a central difference over the samples, u̇(τ_p) ≈ f P (u_{p+1} − u_{p−1})/2
    guess << u.col(start), 0.5 * f * samples * (u.col((start + 1) % samples) - u.col((start + samples - 1) % samples));
  }
  const double t0 = tau(start) / f;
  try {
    result.orbit = shoot_periodic_orbit(flow, guess, t0, options.newton);
  } catch (const std::invalid_argument& e) {  // a phase met on the way whose flight ImpactFlow cannot form
    result.message = std::string("the event-driven flow refused the orbit: ") + e.what();
    return result;
  }
  if (!result.orbit.report.converged()) {
    result.message = "the shooting of the exact orbit did not converge: " + result.orbit.report.message;
    return result;
  }
  ImpactFlowResult sampled;
  try {
    sampled = flow.flow(result.orbit.state, t0, flow.period_s(), {}, samples);
  } catch (const std::domain_error& e) {  // the converged orbit's flow again, now sampled: not expected
    result.message = std::string("the exact orbit's sampled flow failed: ") + e.what();
    return result;
  }
  Eigen::VectorXd given(nc * samples), exact(nc * samples);
  for (Eigen::Index c = 0; c < nc; ++c) {
    for (int s = 0; s < samples; ++s) {
      given(c * samples + s) = uc(c, (start + s) % samples);
      exact(c * samples + s) = sampled.contact_displacement(c, s);
    }
  }
  result.distance = rms_relative_error(exact, given);
  for (const ImpactEvent& e : result.orbit.period.events) result.impacts += e.kind == ImpactEventKind::Impact ? 1 : 0;
  if (!(result.distance <= options.max_distance)) {
    result.message = "the exact orbit found lies " + format_number(result.distance) +
                     " (rms, relative) from the given one, " +
                     "beyond ImpactStabilityOptions.max_distance = " + format_number(options.max_distance) +
                     ": another orbit (raise the basis dimension, or max_distance)";
    return result;
  }
  const double delta = std::max(result.orbit.report.residual_norms.back(), 1e-9);
  result.floquet = multipliers_with_errors(result.orbit.period.monodromy, 2.0 * std::numbers::pi * f, delta);
  result.available = true;
  return result;
}

}  // namespace wbm::solvers
