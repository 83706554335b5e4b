#include <wbm/solvers/post_processing.hpp>

#include <cmath>
#include <stdexcept>
#include <string>

namespace wbm::solvers {

std::string velocity_unavailable(const TimeBasis& trial) {
  if (trial.max_derivative() >= 1) return {};
  const auto* w = trial.wavelet_basis();
  if (w != nullptr && w->family().kind == wavelets::FamilyKind::Haar) return {};  // delta pairs
  return trial.name() + " has no pointwise first derivative and is not piecewise constant; no velocity "
                        "representation (use DB6 or smoother trial functions)";
}

Eigen::VectorXd evaluate_trial(const TimeBasis& trial, const Eigen::MatrixXd& coefficients, int dof,
                               const Eigen::VectorXd& tau, double frequency_hz, int derivative) {
  const int m = trial.dimension();
  if (coefficients.cols() != m) {
    throw std::invalid_argument("evaluate_trial: coefficients have " + std::to_string(coefficients.cols()) +
                                " columns, the trial basis " + trial.name() + " has M = " + std::to_string(m));
  }
  if (dof < 0 || dof >= coefficients.rows()) {
    throw std::invalid_argument("evaluate_trial: dof = " + std::to_string(dof) + " outside [0, " +
                                std::to_string(coefficients.rows()) + ")");
  }
  if (derivative < 0 || derivative > 1) {
    throw std::invalid_argument("evaluate_trial: derivative = " + std::to_string(derivative) +
                                " must be 0 (displacement) or 1 (velocity)");
  }
  const Eigen::VectorXd a = coefficients.row(dof).transpose();
  if (derivative <= trial.max_derivative()) {
    return std::pow(frequency_hz, derivative) * (trial.values(tau, derivative) * a);
  }
  if (const std::string why = velocity_unavailable(trial); !why.empty()) {
    throw std::invalid_argument("evaluate_trial: " + why);
  }
  const auto* w = trial.wavelet_basis();
  // Delta-pair velocity of [JL14 Sec. 5.2] in the box form of the header.
  Eigen::VectorXd cell(m);
  for (int k = 0; k < m; ++k) cell(k) = a(k) * w->value(k, (k + 0.5) / m);
  Eigen::VectorXd v(tau.size());
  for (Eigen::Index p = 0; p < tau.size(); ++p) {
    const double t = tau(p) - std::floor(tau(p));
    const int k = static_cast<int>(std::floor(t * m + 0.5)) % m;  // jump k/M nearest to τ
    v(p) = frequency_hz * m * (cell(k) - cell((k + m - 1) % m));
  }
  return v;
}

PeriodicFields evaluate_fields(const TimeBasis& trial, const Eigen::MatrixXd& coefficients, const Eigen::VectorXd& tau,
                               double frequency_hz) {
  PeriodicFields f{tau, Eigen::MatrixXd(coefficients.rows(), tau.size()),
                   Eigen::MatrixXd(coefficients.rows(), tau.size())};
  for (int i = 0; i < coefficients.rows(); ++i) {
    f.displacement.row(i) = evaluate_trial(trial, coefficients, i, tau, frequency_hz, 0).transpose();
    f.velocity.row(i) = evaluate_trial(trial, coefficients, i, tau, frequency_hz, 1).transpose();
  }
  return f;
}

Eigen::VectorXd contact_force(const std::vector<ContactPoint>& contacts, const Eigen::MatrixXd& displacement) {
  Eigen::VectorXd f = Eigen::VectorXd::Zero(displacement.cols());
  if (contacts.empty()) return f;
  require_fixed_obstacles(contacts, "contact_force (a function of u alone)",
                          "evaluate the law on u_c(τ) − s_c(τ) (obstacle_samples)");
  if (contacts.front().law->hysteretic()) {
    throw std::invalid_argument("contact_force: the contact at DOF " + std::to_string(contacts.front().dof) + " is a " +
                                contacts.front().law->describe() + ", whose force depends on the history over the "
                                "period: read WeightedResidualSolution::contact_force_samples instead");
  }
  if (contacts.front().law->rigid()) {
    throw std::invalid_argument("contact_force: the contact at DOF " + std::to_string(contacts.front().dof) +
                                " is a rigid stop, whose force is not a function of the displacement: read "
                                "WeightedResidualSolution::contact_force_samples instead");
  }
  for (Eigen::Index p = 0; p < f.size(); ++p) f(p) = contacts.front().law->force(contacts.front().displacement(displacement.col(p)));
  return f;
}

Eigen::VectorXd system_energy(const MechanicalSystem& system, const std::vector<ContactPoint>& contacts,
                              const Eigen::MatrixXd& displacement, const Eigen::MatrixXd& velocity) {
  if (displacement.rows() != system.dofs() || velocity.rows() != system.dofs() ||
      displacement.cols() != velocity.cols()) {
    throw std::invalid_argument("system_energy: displacement " + std::to_string(displacement.rows()) + " x " +
                                std::to_string(displacement.cols()) + " and velocity " +
                                std::to_string(velocity.rows()) + " x " + std::to_string(velocity.cols()) +
                                " must both be n x P with n = " + std::to_string(system.dofs()));
  }
  require_fixed_obstacles(contacts, "system_energy",
                          "a moving counter-surface works on the structure: E is not an invariant of its motion");
  for (const auto& c : contacts) {
    if (c.law->hysteretic()) {
      throw std::invalid_argument("system_energy: the contact at DOF " + std::to_string(c.dof) + " is a " +
                                  c.law->describe() + ", which stores k_t-spring energy that depends on the history "
                                  "and dissipates by slip: no energy function of u exists");
    }
  }
  const Eigen::MatrixXd mv = system.mass * velocity;
  const Eigen::MatrixXd ku = system.stiffness * displacement;
  Eigen::VectorXd e(displacement.cols());
  for (Eigen::Index p = 0; p < e.size(); ++p) {
    e(p) = 0.5 * velocity.col(p).dot(mv.col(p)) + 0.5 * displacement.col(p).dot(ku.col(p));
    for (const auto& c : contacts) e(p) += c.law->potential(c.displacement(displacement.col(p)));
  }
  return e;
}

double rms(const Eigen::VectorXd& v) {
  return v.size() == 0 ? 0.0 : std::sqrt(v.squaredNorm() / static_cast<double>(v.size()));
}

double rms_relative_error(const Eigen::VectorXd& u, const Eigen::VectorXd& u_ref) {
  if (u.size() != u_ref.size()) {
    throw std::invalid_argument("rms_relative_error: " + std::to_string(u.size()) + " samples against " +
                                std::to_string(u_ref.size()) + " reference samples; sample both at the same times");
  }
  const double r = rms(u_ref);
  if (!(r > 0.0)) throw std::invalid_argument("rms_relative_error: the reference is identically zero");
  return rms(u - u_ref) / r;
}

}  // namespace wbm::solvers
