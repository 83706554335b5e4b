// shoot_periodic_orbit and finite_difference_monodromy (impact_shooting.hpp): periodic orbits of
// the event-driven flow by shooting through the project's Newton core, and the slow reference
// monodromy by central differences of the flow.
#include <wbm/solvers/impact_shooting.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>

namespace wbm::solvers {

namespace {
// The scaled period map z ↦ D (x(t₀ + T) − x), x = D⁻¹ z, with its Jacobian D Φ D⁻¹ − I; the last
// flow is kept, so that the residual and the Jacobian at one iterate cost one flow.
class PeriodMap {
 public:
  PeriodMap(const ImpactFlow& flow, double t0, Eigen::VectorXd scale)
      : flow_(flow), t0_(t0), scale_(std::move(scale)) {}
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& z) const {
    const ImpactFlowResult* r = run(z);
    if (r == nullptr) return Eigen::VectorXd::Constant(z.size(), std::numeric_limits<double>::quiet_NaN());
    return r->state.cwiseProduct(scale_) - z;
  }
  [[nodiscard]] Eigen::MatrixXd jacobian(const Eigen::VectorXd& z) const {
    const ImpactFlowResult* r = run(z);
    const Eigen::Index m = z.size();
    if (r == nullptr) return Eigen::MatrixXd::Constant(m, m, std::numeric_limits<double>::quiet_NaN());
    return scale_.asDiagonal() * r->monodromy * scale_.cwiseInverse().asDiagonal() - Eigen::MatrixXd::Identity(m, m);
  }

  // The flow from D⁻¹ z (kept from the last residual or Jacobian at z), or null if it failed.
  const ImpactFlowResult* run(const Eigen::VectorXd& z) const {
    if (last_z_.size() == z.size() && last_z_ == z) return last_ ? &*last_ : nullptr;
    last_z_ = z;
    last_.reset();
    try {
      last_ = flow_.flow(z.cwiseQuotient(scale_), t0_, flow_.period_s());
    } catch (const std::domain_error&) {
      return nullptr;  // a graze, chatter or penetration on this iterate: the line search backs away
    }
    return &*last_;
  }

 private:
  const ImpactFlow& flow_;
  double t0_;
  Eigen::VectorXd scale_;
  mutable Eigen::VectorXd last_z_;
  mutable std::optional<ImpactFlowResult> last_;
};

// s_u = max |u|, and the displacement and velocity scales of x (velocities by ω).
std::pair<double, double> amplitudes(const Eigen::VectorXd& x, double omega) {
  const Eigen::Index n = x.size() / 2;
  return {x.head(n).lpNorm<Eigen::Infinity>(), x.tail(n).lpNorm<Eigen::Infinity>() / omega};
}
}  // namespace

ImpactOrbit shoot_periodic_orbit(const ImpactFlow& flow, const Eigen::VectorXd& x_guess, double t0,
                                 const NewtonOptions& options) {
  const Eigen::Index n = flow.dofs();
  if (x_guess.size() != 2 * n || !x_guess.allFinite()) {
    throw std::invalid_argument("shoot_periodic_orbit: x_guess must hold 2n = " + std::to_string(2 * n) +
                                " finite values");
  }
  const double omega = 2.0 * std::numbers::pi / flow.period_s();
  const auto [su, sv] = amplitudes(x_guess, omega);
  const double s = std::max(su, sv);
  if (!(s > 0.0)) throw std::invalid_argument("shoot_periodic_orbit: x_guess is zero; give the orbit's state at t0");
  Eigen::VectorXd scale(2 * n);
  scale.head(n).setConstant(1.0 / s);
  scale.tail(n).setConstant(1.0 / (omega * s));
  const PeriodMap map(flow, t0, scale);
  ImpactOrbit orbit;
  orbit.start_s = t0;
  const NewtonResult solved = newton(map, x_guess.cwiseProduct(scale), options);
  orbit.report = solved.report;
  orbit.state = solved.x.cwiseQuotient(scale);
  if (!orbit.report.converged()) return orbit;
  const ImpactFlowResult* last = map.run(solved.x);  // Newton's last residual was evaluated there
  if (last == nullptr) throw std::logic_error("shoot_periodic_orbit: the converged iterate's flow failed");
  orbit.period = *last;
  const Eigen::EigenSolver<Eigen::MatrixXd> eig(orbit.period.monodromy, false);
  orbit.multipliers = eig.eigenvalues();
  std::sort(orbit.multipliers.data(), orbit.multipliers.data() + orbit.multipliers.size(),
            [](const auto& a, const auto& b) { return std::abs(a) > std::abs(b); });
  orbit.max_modulus = orbit.multipliers.size() > 0 ? std::abs(orbit.multipliers(0)) : 0.0;
  return orbit;
}

Eigen::MatrixXd finite_difference_monodromy(const ImpactFlow& flow, const Eigen::VectorXd& x0, double t0, double step) {
  const Eigen::Index n = flow.dofs();
  if (x0.size() != 2 * n) throw std::invalid_argument("finite_difference_monodromy: x0 must hold 2n values");
  if (!(step > 0.0 && step < 1.0)) throw std::invalid_argument("finite_difference_monodromy: step must lie in (0, 1)");
  const double omega = 2.0 * std::numbers::pi / flow.period_s();
  const auto [su, sv] = amplitudes(x0, omega);
  Eigen::MatrixXd phi(2 * n, 2 * n);
  for (Eigen::Index j = 0; j < 2 * n; ++j) {
    const double base = j < n ? std::max(su, sv) : omega * std::max(su, sv);
    const double delta = step * std::max(std::abs(x0(j)), base);
    Eigen::VectorXd xp = x0, xm = x0;
    xp(j) += delta;
    xm(j) -= delta;
    phi.col(j) = (flow.flow(xp, t0, flow.period_s()).state - flow.flow(xm, t0, flow.period_s()).state) / (2.0 * delta);
  }
  return phi;
}

}  // namespace wbm::solvers
