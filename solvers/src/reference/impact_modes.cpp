// shoot_conservative_orbit (impact_modes.hpp): exact conservative periodic orbits with elastic
// impacts by autonomous shooting through the project's Newton core, and their nontrivial Floquet
// multipliers on the energy surface.
#include <wbm/solvers/impact_modes.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>

namespace wbm::solvers {

void ConservativeOrbitOptions::validate() const {
  if (steps_per_period < 8) {
    throw std::invalid_argument("ConservativeOrbitOptions.steps_per_period = " + std::to_string(steps_per_period) +
                                ": must be at least 8 (the event search's brackets per period)");
  }
  if (max_events < 1) {
    throw std::invalid_argument("ConservativeOrbitOptions.max_events = " + std::to_string(max_events) +
                                ": must be at least 1");
  }
  if (!(stability_tolerance >= 0.0) || !std::isfinite(stability_tolerance)) {
    throw std::invalid_argument("ConservativeOrbitOptions.stability_tolerance = " +
                                format_number(stability_tolerance) + ": must be finite and >= 0 (e.g. 1e-6)");
  }
  newton.validate();
}

double hamiltonian(const MechanicalSystem& system, const Eigen::VectorXd& x) {
  const Eigen::Index n = system.mass.rows();
  if (x.size() != 2 * n) {
    throw std::invalid_argument("hamiltonian: x must hold 2n = " + std::to_string(2 * n) + " values (u, u̇)");
  }
  const Eigen::VectorXd u = x.head(n), v = x.tail(n);
  return 0.5 * v.dot(system.mass * v) + 0.5 * u.dot(system.stiffness * u);
}

namespace {

// ∇H(x) = (K u, M u̇) for x = (u, u̇), with the dense M and K.
Eigen::VectorXd energy_gradient(const Eigen::MatrixXd& m, const Eigen::MatrixXd& k, const Eigen::VectorXd& x) {
  const Eigen::Index n = m.rows();
  Eigen::VectorXd g(2 * n);
  g.head(n) = k * x.head(n);
  g.tail(n) = m * x.tail(n);
  return g;
}

// The scaled shooting map z ↦ (D (x(T) − x₀) without row `dropped`; level equation), with
// z = (D x₀ without the phase velocity; T/T_guess), and its Jacobian. The last flow is kept, so
// that the residual and the Jacobian at one iterate cost one flow.
class AutonomousMap {
 public:
  // m, k: the dense M and K, kept by the caller for the map's lifetime.
  AutonomousMap(const ImpactFlow& flow, const MechanicalSystem& system, const Eigen::MatrixXd& m,
                const Eigen::MatrixXd& k, Eigen::VectorXd scale, double period_guess, int phase_row, int dropped,
                OrbitLevel level, double value)
      : flow_(flow), system_(system), m_(m), k_(k), m_llt_(m), scale_(std::move(scale)), t_ref_(period_guess),
        phase_row_(phase_row), dropped_(dropped), level_(level), value_(value) {}

  // x₀ (unscaled, 2n) and T [s] of an unknown vector z.
  [[nodiscard]] Eigen::VectorXd state_of(const Eigen::VectorXd& z) const {
    const Eigen::Index nx = scale_.size();
    Eigen::VectorXd xs(nx);
    xs.head(phase_row_) = z.head(phase_row_);
    xs(phase_row_) = 0.0;
    xs.segment(phase_row_ + 1, nx - phase_row_ - 1) = z.segment(phase_row_, nx - phase_row_ - 1);
    return xs.cwiseQuotient(scale_);
  }
  [[nodiscard]] double period_of(const Eigen::VectorXd& z) const { return z(z.size() - 1) * t_ref_; }
  [[nodiscard]] Eigen::VectorXd unknowns(const Eigen::VectorXd& x, double period) const {
    const Eigen::Index nx = scale_.size();
    const Eigen::VectorXd xs = x.cwiseProduct(scale_);
    Eigen::VectorXd z(nx);
    z.head(phase_row_) = xs.head(phase_row_);
    z.segment(phase_row_, nx - phase_row_ - 1) = xs.tail(nx - phase_row_ - 1);
    z(nx - 1) = period / t_ref_;
    return z;
  }

  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& z) const {
    const ImpactFlowResult* r = run(z);
    const Eigen::Index nx = scale_.size();
    if (r == nullptr) return Eigen::VectorXd::Constant(nx, std::numeric_limits<double>::quiet_NaN());
    const Eigen::VectorXd x0 = state_of(z);
    const Eigen::VectorXd full = (r->state - x0).cwiseProduct(scale_);
    Eigen::VectorXd out(nx);
    out.head(dropped_) = full.head(dropped_);
    out.segment(dropped_, nx - dropped_ - 1) = full.tail(nx - dropped_ - 1);
    out(nx - 1) = level_ == OrbitLevel::Energy ? (hamiltonian(system_, x0) - value_) / value_
                                                : (period_of(z) - value_) / value_;
    return out;
  }

  [[nodiscard]] Eigen::MatrixXd jacobian(const Eigen::VectorXd& z) const {
    const ImpactFlowResult* r = run(z);
    const Eigen::Index nx = scale_.size();
    if (r == nullptr) return Eigen::MatrixXd::Constant(nx, nx, std::numeric_limits<double>::quiet_NaN());
    const Eigen::VectorXd x0 = state_of(z);
    // ∂(D (x(T) − x₀))/∂(D x₀) = D Φ D⁻¹ − I; ∂/∂(T/T_ref) = T_ref D f(x(T)).
    Eigen::MatrixXd full(nx, nx + 1);
    full.leftCols(nx) = scale_.asDiagonal() * r->monodromy * scale_.cwiseInverse().asDiagonal();
    full.leftCols(nx).diagonal().array() -= 1.0;
    full.col(nx) = t_ref_ * field(r->state).cwiseProduct(scale_);
    // The level row: ∂H/∂(D x₀) = D⁻¹ ∇H, ∇H = (K u₀, M u̇₀); or ∂(T/T*)/∂(T/T_ref) = T_ref/T*.
    Eigen::RowVectorXd level = Eigen::RowVectorXd::Zero(nx + 1);
    if (level_ == OrbitLevel::Energy) {
      level.head(nx) = energy_gradient(m_, k_, x0).cwiseQuotient(scale_).transpose() / value_;
    } else {
      level(nx) = t_ref_ / value_;
    }
    // Keep the rows but `dropped_` and the columns but the phase velocity's.
    Eigen::MatrixXd rows(nx, nx + 1);
    rows.topRows(dropped_) = full.topRows(dropped_);
    rows.middleRows(dropped_, nx - dropped_ - 1) = full.bottomRows(nx - dropped_ - 1);
    rows.row(nx - 1) = level;
    Eigen::MatrixXd j(nx, nx);
    j.leftCols(phase_row_) = rows.leftCols(phase_row_);
    j.rightCols(nx - phase_row_) = rows.rightCols(nx - phase_row_);
    return j;
  }

  // ẋ = (u̇, −M⁻¹ K u) of the free flight (no stop is held: elastic impacts open at once).
  [[nodiscard]] Eigen::VectorXd field(const Eigen::VectorXd& x) const {
    const Eigen::Index n = x.size() / 2;
    Eigen::VectorXd f(2 * n);
    f.head(n) = x.tail(n);
    f.tail(n) = -m_llt_.solve(k_ * x.head(n));
    return f;
  }

  // The flow from z (kept from the last residual or Jacobian at z), or null if it failed.
  const ImpactFlowResult* run(const Eigen::VectorXd& z) const {
    if (last_z_.size() == z.size() && last_z_ == z) return last_ ? &*last_ : nullptr;
    last_z_ = z;
    last_.reset();
    last_error_.clear();
    const double period = period_of(z);
    if (!(period > 0.0) || !std::isfinite(period)) {
      last_error_ = "a period of " + format_number(period) + " s";
      return nullptr;
    }
    try {
      last_ = flow_.flow(state_of(z), 0.0, period);
    } catch (const std::domain_error& e) {
      last_error_ = e.what();  // a graze, chatter or penetration on this iterate: the line search backs away
      return nullptr;
    }
    return &*last_;
  }
  [[nodiscard]] const std::string& last_error() const { return last_error_; }

 private:
  const ImpactFlow& flow_;
  const MechanicalSystem& system_;
  const Eigen::MatrixXd& m_;
  const Eigen::MatrixXd& k_;
  Eigen::LLT<Eigen::MatrixXd> m_llt_;
  Eigen::VectorXd scale_;
  double t_ref_;
  int phase_row_, dropped_;
  OrbitLevel level_;
  double value_;
  mutable Eigen::VectorXd last_z_;
  mutable std::optional<ImpactFlowResult> last_;
  mutable std::string last_error_;
};

Eigen::VectorXcd by_decreasing_modulus(Eigen::VectorXcd mu) {
  std::stable_sort(mu.data(), mu.data() + mu.size(),
                   [](const auto& a, const auto& b) { return std::abs(a) > std::abs(b); });
  return mu;
}

}  // namespace

ConservativeOrbit shoot_conservative_orbit(const MechanicalSystem& system, const std::vector<ContactPoint>& stops,
                                           const Eigen::VectorXd& x_guess, double period_guess_s, int phase_dof,
                                           OrbitLevel level, double value, const ConservativeOrbitOptions& options,
                                           int samples) {
  options.validate();
  system.validate();
  const int n = system.dofs();
  if (x_guess.size() != 2 * n || !x_guess.allFinite()) {
    throw std::invalid_argument("shoot_conservative_orbit: x_guess must hold 2n = " + std::to_string(2 * n) +
                                " finite values (u, u̇)");
  }
  if (!(period_guess_s > 0.0) || !std::isfinite(period_guess_s)) {
    throw std::invalid_argument("shoot_conservative_orbit: period_guess_s = " + format_number(period_guess_s) +
                                ": must be finite and > 0 [s]");
  }
  if (!(value > 0.0) || !std::isfinite(value)) {
    throw std::invalid_argument("shoot_conservative_orbit: value = " + format_number(value) + ": the " +
                                (level == OrbitLevel::Energy ? "Hamiltonian [J]" : "period [s]") +
                                " must be finite and > 0");
  }
  if (phase_dof < 0 || phase_dof >= n) {
    throw std::invalid_argument("shoot_conservative_orbit: phase_dof = " + std::to_string(phase_dof) +
                                ": must lie in [0, " + std::to_string(n) + ")");
  }
  if (samples < 0) {
    throw std::invalid_argument("shoot_conservative_orbit: samples = " + std::to_string(samples) + ": must be >= 0");
  }
  // The undamped structure, elastic impacts, no load (the forcing's frequency only sizes the
  // event search's brackets: T/steps_per_period).
  MechanicalSystem free = system;
  free.damping = Eigen::SparseMatrix<double>(n, n);
  const ImpactFlowOptions flow_options{.restitution = 1.0, .steps_per_period = options.steps_per_period,
                                       .max_events = options.max_events};
  const ImpactFlow flow(free, HarmonicForcing{0, 0.0, 1.0 / period_guess_s}, stops, flow_options);

  const double omega = 2.0 * std::numbers::pi / period_guess_s;
  Eigen::VectorXd guess = x_guess;
  guess(n + phase_dof) = 0.0;
  const double s = std::max(guess.head(n).lpNorm<Eigen::Infinity>(), guess.tail(n).lpNorm<Eigen::Infinity>() / omega);
  if (!(s > 0.0)) throw std::invalid_argument("shoot_conservative_orbit: x_guess is zero; give the orbit's state");
  Eigen::VectorXd scale(2 * n);
  scale.head(n).setConstant(1.0 / s);
  scale.tail(n).setConstant(1.0 / (omega * s));
  // The periodicity row to drop: the largest |∂Ĥ/∂x̂_i| = |∇H_i|/D_i at the guess.
  const Eigen::MatrixXd m = Eigen::MatrixXd(system.mass), k = Eigen::MatrixXd(system.stiffness);
  Eigen::Index dropped = 0;
  energy_gradient(m, k, guess).cwiseQuotient(scale).cwiseAbs().maxCoeff(&dropped);

  const AutonomousMap map(flow, free, m, k, scale, period_guess_s, n + phase_dof, static_cast<int>(dropped), level,
                          value);
  ConservativeOrbit orbit;
  const NewtonResult solved = newton(map, map.unknowns(guess, period_guess_s), options.newton);
  orbit.report = solved.report;
  orbit.state = map.state_of(solved.x);
  orbit.period_s = map.period_of(solved.x);
  orbit.frequency_hz = 1.0 / orbit.period_s;
  orbit.hamiltonian = hamiltonian(free, orbit.state);
  if (!map.last_error().empty() && !orbit.report.converged()) {
    orbit.report.message += (orbit.report.message.empty() ? "" : "; ") + std::string("last flow: ") + map.last_error();
  }
  if (!orbit.report.converged()) return orbit;
  // The whole periodicity residual, the dropped row included, verified on one flow from the
  // converged state (sampled when asked).
  try {
    orbit.period = flow.flow(orbit.state, 0.0, orbit.period_s, {}, samples);
  } catch (const std::domain_error& e) {
    orbit.report.status = SolveStatus::NonFinite;
    orbit.report.message = std::string("the converged orbit's flow failed: ") + e.what();
    return orbit;
  }
  orbit.periodicity_residual = (orbit.period.state - orbit.state).cwiseProduct(scale).norm();
  if (!(orbit.periodicity_residual <= options.newton.tolerance)) {
    orbit.report.status = SolveStatus::MaxIterations;
    orbit.report.message = "the periodicity residual with the dropped row, " +
                           format_number(orbit.periodicity_residual) + ", exceeds the tolerance " +
                           format_number(options.newton.tolerance) + " (raise newton.tolerance)";
    return orbit;
  }
  if (samples > 0) {
    // (1/T) ∫ u̇ᵀ M u̇ dt / ω² by the periodic trapezoidal rule on the samples t_j = j T/S.
    double sum = 0.0;
    for (int j = 0; j < samples; ++j) {
      const Eigen::VectorXd v = orbit.period.state_samples.col(j).tail(n);
      sum += v.dot(system.mass * v);
    }
    const double w = 2.0 * std::numbers::pi / orbit.period_s;
    orbit.mean_square_rate = sum / samples / (w * w);
  }
  // Multipliers: of Φ̂ = D Φ D⁻¹ (the similar matrix in the shooting's scaling), and of the map
  // induced on {∇Ĥᵀ δ = 0} modulo f̂: R = Bᵀ Φ̂ B.
  const Eigen::MatrixXd phi = scale.asDiagonal() * orbit.period.monodromy * scale.cwiseInverse().asDiagonal();
  orbit.multipliers = by_decreasing_modulus(Eigen::EigenSolver<Eigen::MatrixXd>(phi, false).eigenvalues());
  Eigen::MatrixXd span(2 * n, 2);
  span.col(0) = energy_gradient(m, k, orbit.state).cwiseQuotient(scale);
  span.col(1) = map.field(orbit.state).cwiseProduct(scale);
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(span);
  const Eigen::MatrixXd q = qr.householderQ() * Eigen::MatrixXd::Identity(2 * n, 2 * n);
  const Eigen::MatrixXd b = q.rightCols(2 * n - 2);
  if (b.cols() > 0) {
    const Eigen::MatrixXd reduced = b.transpose() * phi * b;
    orbit.nontrivial_multipliers =
        by_decreasing_modulus(Eigen::EigenSolver<Eigen::MatrixXd>(reduced, false).eigenvalues());
    orbit.max_modulus = std::abs(orbit.nontrivial_multipliers(0));
  } else {
    orbit.nontrivial_multipliers.resize(0);
    orbit.max_modulus = 1.0;  // one DOF: only the trivial pair
  }
  if (!std::isfinite(orbit.max_modulus)) {  // no verdict from a monodromy that is not finite
    orbit.report.status = SolveStatus::NonFinite;
    orbit.report.message = "the monodromy's nontrivial multipliers are not finite";
    return orbit;
  }
  orbit.stable = orbit.max_modulus <= 1.0 + options.stability_tolerance;
  // Symplecticity in the scaled coordinates: Ω̂ = D⁻¹ Ω D⁻¹ with Ω = [[0, M], [−M, 0]].
  Eigen::MatrixXd omega_form = Eigen::MatrixXd::Zero(2 * n, 2 * n);
  omega_form.topRightCorner(n, n) = m;
  omega_form.bottomLeftCorner(n, n) = -m;
  const Eigen::VectorXd inv = scale.cwiseInverse();
  omega_form = inv.asDiagonal() * omega_form * inv.asDiagonal();
  orbit.symplectic_defect = (phi.transpose() * omega_form * phi - omega_form).norm() / omega_form.norm();
  return orbit;
}

}  // namespace wbm::solvers
