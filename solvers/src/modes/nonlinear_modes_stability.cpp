// NonlinearModes::stability (nonlinear_modes.hpp): the stability of a backbone level through the
// exact conservative orbit with elastic impacts near it (impact_modes.hpp, issue #38 item 4).
#include <wbm/solvers/nonlinear_modes.hpp>

#include <cmath>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <wbm/contact/signorini.hpp>

namespace wbm::solvers {

void ModeStabilityOptions::validate() const {
  orbit.validate();
  if (samples < 64) {
    throw std::invalid_argument("ModeStabilityOptions.samples = " + std::to_string(samples) +
                                ": must be at least 64 (instants per period for the seed and the distance)");
  }
  if (!(max_distance > 0.0) || !std::isfinite(max_distance)) {
    throw std::invalid_argument("ModeStabilityOptions.max_distance = " + format_number(max_distance) +
                                ": must be finite and > 0 (e.g. 0.1)");
  }
}

ModeStability NonlinearModes::stability(const ModeLevel& level, const ModeStabilityOptions& options,
                                       const ConservativeOrbit* previous) const {
  options.validate();
  if (level.coefficients.rows() != n_ || level.coefficients.cols() != f_) {
    throw std::invalid_argument("NonlinearModes::stability: coefficients " + std::to_string(level.coefficients.rows()) +
                                " × " + std::to_string(level.coefficients.cols()) + ", expected " +
                                std::to_string(n_) + " × " + std::to_string(f_));
  }
  ModeStability out;
  if (!level.converged()) {
    out.message = "the level did not converge (" + std::string(to_string(level.status)) + ")";
    return out;
  }
  const int p = options.samples;
  const Eigen::MatrixXd u = displacement(level, p), v = velocity(level, p);
  std::vector<ContactPoint> contacts;
  Eigen::MatrixXd directions = Eigen::MatrixXd::Zero(n_, static_cast<Eigen::Index>(stops_.size()));
  for (size_t c = 0; c < stops_.size(); ++c) {
    contacts.push_back({stops_[c].dof, std::make_shared<contact::RigidStop>(stops_[c].gap), -1, stops_[c].along});
    for (const auto& [j, w] : stops_[c].terms()) directions(j, static_cast<Eigen::Index>(c)) = w;
  }
  const Eigen::MatrixXd stop_u = directions.transpose() * u;  // n_c × P
  // The seed: a turning point of the phase DOF (its velocity is then set to 0), in free flight for
  // the default phase DOF, the onset stop's: where that stop is farthest from its gap.
  const int phase_dof = phase_index_ - 2 * n_;
  Eigen::Index seed = 0;
  if (options_.phase_dof >= 0) {
    u.row(phase_dof).minCoeff(&seed);
  } else {
    stop_u.row(onset_stop_).minCoeff(&seed);
  }
  double mean_h = 0.0;
  Eigen::VectorXd x(2 * n_);
  for (int j = 0; j < p; ++j) {
    x << u.col(j), v.col(j);
    mean_h += hamiltonian(system_, x) / p;
  }
  x << u.col(seed), v.col(seed);
  out.orbit = shoot_conservative_orbit(system_, contacts, x, 1.0 / level.frequency_hz, phase_dof, OrbitLevel::Energy,
                                       mean_h, options.orbit, p);
  if (!out.orbit.converged() && previous != nullptr && previous->converged() &&
      previous->state.size() == 2 * n_) {
    ConservativeOrbit from_previous = shoot_conservative_orbit(system_, contacts, previous->state, previous->period_s,
                                                               phase_dof, OrbitLevel::Energy, mean_h, options.orbit, p);
    if (from_previous.converged()) {
      out.orbit = std::move(from_previous);
    } else {
      out.orbit.report.message += "; from the previous orbit: " + from_previous.report.message;
    }
  }
  const ConservativeOrbit& o = out.orbit;
  if (!o.converged()) {
    out.message = "no exact orbit near the level: " + o.report.message;
    return out;
  }
  double diff = 0.0, ref = 0.0;
  for (int j = 0; j < p; ++j) {
    const Eigen::VectorXd level_j = stop_u.col((seed + j) % p);
    diff += (o.period.contact_displacement.col(j) - level_j).squaredNorm();
    ref += level_j.squaredNorm();
  }
  out.distance = std::sqrt(diff / ref);
  out.frequency_hz = o.frequency_hz;
  out.energy = o.mean_square_rate / (m_c_ * g_ref_ * g_ref_);
  out.impacts = static_cast<int>(o.period.events.size());
  out.multipliers = o.nontrivial_multipliers;
  out.max_modulus = o.max_modulus;
  out.symplectic_defect = o.symplectic_defect;
  if (!(out.distance <= options.max_distance)) {
    out.message = "the exact orbit found lies " + format_number(out.distance) + " from the level (max_distance " +
                  format_number(options.max_distance) + "): another orbit";
    return out;
  }
  out.available = true;
  out.stable = o.stable;
  return out;
}

std::vector<ModeStability> NonlinearModes::stability(const Backbone& backbone, const ModeStabilityOptions& options,
                                                     const std::function<void(size_t, size_t)>& on_level) const {
  std::vector<ModeStability> out;
  out.reserve(backbone.levels.size());
  const ConservativeOrbit* previous = nullptr;
  for (size_t i = 0; i < backbone.levels.size(); ++i) {
    out.push_back(stability(backbone.levels[i], options, previous));
    if (out.back().orbit.converged()) previous = &out.back().orbit;  // reserve(): the address is kept
    if (on_level) on_level(i, backbone.levels.size());
  }
  return out;
}

}  // namespace wbm::solvers
