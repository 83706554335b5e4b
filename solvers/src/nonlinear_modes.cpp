#include <wbm/solvers/nonlinear_modes.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/SparseLU>

#include <wbm/spectral/fourier_basis.hpp>
#include <wbm/spectral/layout.hpp>

namespace wbm::solvers {

void NonlinearModeOptions::validate(int dofs) const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("NonlinearModeOptions." + what); };
  if (harmonics < 1 || harmonics > 512) fail("harmonics = " + std::to_string(harmonics) + ": must lie in [1, 512]");
  if (samples <= 2 * harmonics) {
    fail("samples = " + std::to_string(samples) + ": must exceed 2N = " + std::to_string(2 * harmonics) +
         " (LL11: m much larger than N)");
  }
  if (max_powell_iterations < 1 || max_newton_iterations < 1) fail("iteration limits must be >= 1");
  if (!(stationarity_tolerance > 0.0)) fail("stationarity_tolerance must be > 0");
  if (phase_dof < -1 || phase_dof >= dofs) fail("phase_dof = " + std::to_string(phase_dof) + ": must be -1 or a DOF");
  powell.validate();
}

struct NonlinearModes::Evaluation {
  Eigen::VectorXd gradient;   // reduced (phase coefficient removed)
  Eigen::MatrixXd hessian;    // reduced, if asked
  Eigen::VectorXd g;          // constraint values, stop-major: g(c·m + k)
  double h = 0.0;             // ½m̂/γ_c − E
  double r = 0.0;             // Rayleigh quotient [(rad/s)²]
};

NonlinearModes::NonlinearModes(const MechanicalSystem& system, std::vector<RigidStop> stops, NonlinearModeOptions options)
    : system_(system), stops_(std::move(stops)), options_(options) {
  system_.validate();  // square, finite, symmetric: the eigensolver reads one triangle
  system_.mass.makeCompressed();
  n_ = system_.dofs();
  options_.validate(n_);
  if (stops_.empty()) throw std::invalid_argument("NonlinearModes: no rigid stop; a linear mode needs no solver");
  g_ref_ = 0.0;
  for (const auto& s : stops_) {
    if (s.dof < 0 || s.dof >= n_) {
      throw std::invalid_argument("NonlinearModes: stop DOF " + std::to_string(s.dof) + " outside [0, " +
                                  std::to_string(n_) + ")");
    }
    if (!(s.gap > 0.0) || !std::isfinite(s.gap)) {
      throw std::invalid_argument("NonlinearModes: stop gap " + format_number(s.gap) + " m: must be > 0 (energies "
                                  "are normalized by contact onset; the normalized backbone does not depend on g0, "
                                  "so any small positive gap will do)");
    }
    g_ref_ = std::max(g_ref_, s.gap);
  }
  n_harm_ = options_.harmonics;
  f_ = 2 * n_harm_ + 1;
  k_ = Eigen::MatrixXd(system_.stiffness);
  m_ = Eigen::MatrixXd(system_.mass);
  weight_ = Eigen::VectorXd::Constant(f_, 0.5);
  weight_(0) = 1.0;
  nu_.resize(f_);
  for (int k = 0; k < f_; ++k) nu_(k) = (k + 1) / 2;
  theta_ = basis_values(options_.samples, 0);

  // Linear first mode and the onset scaling [LL11 Sec. 5.1: 1297.5 Hz for the rod].
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(k_, m_);
  if (eig.info() != Eigen::Success) throw std::invalid_argument("NonlinearModes: K φ = M φ ω² failed (is M SPD?)");
  omega0_ = std::sqrt(eig.eigenvalues()(0));
  const int c0 = stops_.front().dof;
  Eigen::VectorXd phi = eig.eigenvectors().col(0);
  if (std::abs(phi(c0)) < 1e-12 * phi.cwiseAbs().maxCoeff()) {
    throw std::invalid_argument("NonlinearModes: the first stop's DOF does not move in the first linear mode");
  }
  onset_ = phi * (stops_.front().gap / phi(c0));  // amplitude g0 at the stop: contact onset
  const Eigen::VectorXd on = onset_ / g_ref_;
  m_c_ = 0.5 * on.dot(m_ * on);  // m̂ of the onset mode (cos 2πτ, w = ½, ν = 1), normalized units
  phase_index_ = static_cast<int>(spectral::stacked_index(2, options_.phase_dof >= 0 ? options_.phase_dof : c0, n_));
  m_ref_ = 2.0 * m_c_;
  ks_ = system_.stiffness / (omega0_ * omega0_ * m_ref_);
  ms_ = system_.mass / m_ref_;
  ks_.makeCompressed();
  ms_.makeCompressed();
}

Eigen::VectorXd NonlinearModes::with_phase(const Eigen::VectorXd& x) const {
  Eigen::VectorXd full(x.size() + 1);
  full << x.head(phase_index_), 0.0, x.tail(x.size() - phase_index_);
  return full;
}

Eigen::MatrixXd NonlinearModes::basis_values(int samples, int derivative) const {
  // LL11 Eq. (21): harmonics 0 … N, each cosine with its sine (spectral's 2N + 1 form).
  const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(samples, 0.0, samples - 1.0) / samples;
  return spectral::FourierBasis::with_harmonics(n_harm_).values(tau, derivative);
}

NonlinearModes::Evaluation NonlinearModes::evaluate(const Eigen::VectorXd& y, double energy, double omega2_fixed,
                                                    const contact::AugmentedLagrangian& al, bool hessian) const {
  const bool simultaneous = options_.algorithm == ModeAlgorithm::Simultaneous;
  const Eigen::Map<const Eigen::MatrixXd> ym(y.data(), n_, f_);
  const Eigen::MatrixXd ky = k_ * ym, my = m_ * ym;
  double kh = 0.0, mh = 0.0;
  for (int k = 0; k < f_; ++k) {
    kh += weight_(k) * ym.col(k).dot(ky.col(k));
    mh += weight_(k) * nu_(k) * nu_(k) * ym.col(k).dot(my.col(k));
  }
  Evaluation e;
  e.r = kh / mh;
  e.h = mh / m_c_ - energy;
  const Eigen::VectorXd wnu2 = (weight_.array() * nu_.array().square()).matrix();
  const Eigen::MatrixXd dk = 2.0 * ky * weight_.asDiagonal(), dm = 2.0 * my * wnu2.asDiagonal();  // ∇k̂, ∇m̂ (n × F)
  const double w02 = omega0_ * omega0_;
  const double m_target = energy * m_c_;
  const double omega2 = simultaneous ? e.r : omega2_fixed;
  const double denominator = w02 * (simultaneous ? mh : m_target);
  Eigen::MatrixXd grad = (dk - omega2 * dm) / denominator;  // ∇ρ (simultaneous) or ∇Q (sequential)
  // Constraints g_ck = u_c(τ_k) − g_c (units of g_ref) [LL11 Eq. (24b)].
  const auto ms = static_cast<Eigen::Index>(options_.samples);
  e.g.resize(static_cast<Eigen::Index>(stops_.size()) * ms);
  for (size_t c = 0; c < stops_.size(); ++c) {
    e.g.segment(static_cast<Eigen::Index>(c) * ms, ms) =
        (theta_ * ym.row(stops_[c].dof).transpose()).array() - stops_[c].gap / g_ref_;
  }
  const Eigen::VectorXd lambda = al.inequality_gradient(e.g);
  for (size_t c = 0; c < stops_.size(); ++c) {
    grad.row(stops_[c].dof) += (theta_.transpose() * lambda.segment(static_cast<Eigen::Index>(c) * ms, ms)).transpose();
  }
  const double mu = al.equality_gradient(e.h);
  grad += (mu / m_c_) * dm;
  Eigen::VectorXd full = spectral::stacked(grad);
  e.gradient.resize(full.size() - 1);
  e.gradient << full.head(phase_index_), full.tail(full.size() - phase_index_ - 1);
  if (!hessian) return e;

  const Eigen::Index size = static_cast<Eigen::Index>(n_) * f_;
  Eigen::MatrixXd hs = Eigen::MatrixXd::Zero(size, size);
  for (int k = 0; k < f_; ++k) {  // (2K̃ − 2ω² M̃)/denominator, block diagonal
    hs.block(k * n_, k * n_, n_, n_) = (2.0 * weight_(k) * k_ - 2.0 * omega2 * wnu2(k) * m_) / denominator;
  }
  const Eigen::VectorXd dmv = spectral::stacked(dm);
  if (simultaneous) {  // − (∇m̂ ∇rᵀ + ∇r ∇m̂ᵀ)/(ω₀² m̂), ∇r = (∇k̂ − r ∇m̂)/m̂
    const Eigen::VectorXd dr = spectral::stacked((dk - e.r * dm) / mh);
    hs.noalias() -= (dmv * dr.transpose() + dr * dmv.transpose()) / (w02 * mh);
  }
  const Eigen::VectorXd curvature = al.inequality_curvature(e.g);
  for (size_t c = 0; c < stops_.size(); ++c) {
    const Eigen::VectorXd cc = curvature.segment(static_cast<Eigen::Index>(c) * ms, ms);
    if (cc.isZero(0.0)) continue;
    const Eigen::MatrixXd block = theta_.transpose() * cc.asDiagonal() * theta_;  // F × F
    const int d = stops_[c].dof;
    for (int k = 0; k < f_; ++k) {
      for (int l = 0; l < f_; ++l) hs(k * n_ + d, l * n_ + d) += block(k, l);
    }
  }
  // Equality: κ_e ∇h ∇hᵀ + μ ∇²h, ∇h = ∇m̂/m_c, ∇²h = 2M̃/m_c.
  hs.noalias() += (al.equality_curvature() / (m_c_ * m_c_)) * dmv * dmv.transpose();
  for (int k = 0; k < f_; ++k) hs.block(k * n_, k * n_, n_, n_) += (2.0 * mu * wnu2(k) / m_c_) * m_;
  // Remove the phase coefficient's row and column.
  const Eigen::Index p = phase_index_, rest = size - p - 1;
  e.hessian.resize(size - 1, size - 1);
  e.hessian.topLeftCorner(p, p) = hs.topLeftCorner(p, p);
  e.hessian.topRightCorner(p, rest) = hs.topRightCorner(p, rest);
  e.hessian.bottomLeftCorner(rest, p) = hs.bottomLeftCorner(rest, p);
  e.hessian.bottomRightCorner(rest, rest) = hs.bottomRightCorner(rest, rest);
  return e;
}

ModeLevel NonlinearModes::solve(double energy, const ModeLevel* start) const {
  const auto t0 = std::chrono::steady_clock::now();
  if (!(energy > 0.0) || !std::isfinite(energy)) {
    throw std::invalid_argument("NonlinearModes::solve: energy " + format_number(energy) + " must be > 0");
  }
  ModeLevel level;
  level.energy = energy;
  // Initial guess: the start level scaled by √(E/E_start), or the linear mode (cos 2πτ).
  Eigen::VectorXd y = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(n_) * f_);
  if (start != nullptr && start->coefficients.size() == y.size()) {
    y = spectral::stacked(start->coefficients) * (std::sqrt(energy / start->energy) / g_ref_);
  } else {
    y.segment(n_, n_) = onset_ * (std::sqrt(energy) / g_ref_);
  }
  y(phase_index_) = 0.0;
  auto reduce = [&](const Eigen::VectorXd& full) {
    Eigen::VectorXd x(full.size() - 1);
    x << full.head(phase_index_), full.tail(full.size() - phase_index_ - 1);
    return x;
  };
  auto expand = [&](const Eigen::VectorXd& x) { return with_phase(x); };
  contact::AugmentedLagrangian al(static_cast<int>(stops_.size()) * options_.samples, options_.powell);
  if (start != nullptr && start->multipliers.size() == static_cast<Eigen::Index>(stops_.size()) * options_.samples) {
    al.warm_start(start->multipliers, start->equality_multiplier);  // contact forces vary continuously with E
  }
  Eigen::VectorXd x = reduce(y);
  double omega2 = start != nullptr ? std::pow(2.0 * std::numbers::pi * start->frequency_hz, 2) : omega0_ * omega0_;
  const NewtonOptions primal_options{.tolerance = options_.stationarity_tolerance,
                                     .max_iterations = options_.max_newton_iterations,
                                     .max_backtracks = 3,
                                     .levenberg_marquardt = true,
                                     .norm = ResidualNorm::Max};
  NewtonReport last_primal;
  std::string why = "Powell iteration limit reached";
  for (int j = 0; j < options_.max_powell_iterations; ++j) {
    ++level.powell_iterations;
    // LL11 Alg. 3, l. 3: the primal problem ∇L_κ = 0, by the Newton core: line search on
    // ‖∇L_κ‖₂, and Levenberg–Marquardt steps on ½‖∇L_κ‖² once it stalls (a change of the active
    // set). A stalled solve is not final: the outer update changes the problem.
    struct Stationarity {
      const NonlinearModes* nm;
      double energy, omega2;
      const contact::AugmentedLagrangian* al;
      [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x) const {
        return nm->evaluate(nm->with_phase(x), energy, omega2, *al, false).gradient;
      }
      [[nodiscard]] Eigen::MatrixXd jacobian(const Eigen::VectorXd& x) const {
        return nm->evaluate(nm->with_phase(x), energy, omega2, *al, true).hessian;
      }
    };
    const NewtonResult primal = newton(Stationarity{this, energy, omega2, &al}, x, primal_options);
    level.newton_iterations += primal.report.iterations;
    x = primal.x;
    last_primal = primal.report;
    const Evaluation e = evaluate(expand(x), energy, omega2, al, false);
    // l. 4–5: constraints and Powell's measures; Alg. 2 updates ω from the Rayleigh quotient.
    bool omega_settled = true;
    if (options_.algorithm == ModeAlgorithm::Sequential) {
      omega_settled = std::abs(e.r - omega2) <= options_.powell.tolerance * omega2;
      omega2 = e.r;
    }
    level.inequality_measure = al.inequality_measure(e.g);
    level.equality_measure = contact::AugmentedLagrangian::equality_measure(e.h);
    // A level converges only on a verified stationarity residual (‖∇L_κ‖∞ ≤ tolerance).
    const bool stationary = e.gradient.lpNorm<Eigen::Infinity>() <= options_.stationarity_tolerance;
    if (al.update(e.g, e.h) && omega_settled && stationary) {
      level.status = SolveStatus::Converged;
      why = "converged";
      break;
    }
  }
  // Report on the final iterate.
  const Evaluation e = evaluate(expand(x), energy, omega2, al, false);
  level.residual_norm = e.gradient.lpNorm<Eigen::Infinity>();
  level.tolerance = options_.stationarity_tolerance;
  if (!level.converged()) {
    level.status = last_primal.converged() ? SolveStatus::MaxIterations : last_primal.status;
    why += "; last primal solve " + last_primal.brief();
  }
  level.rayleigh_frequency_hz = std::sqrt(e.r) / (2.0 * std::numbers::pi);
  // The orbit's frequency from the stationarity ∇k̂ − (r − μ ω₀² m̂/m̂_c) ∇m̂ + m̂ ω₀² Θᵀλ = 0,
  // which is the harmonic balance of the free motion with contact forces (continue_backbone).
  const double m_ratio = e.h + energy;  // m̂/m̂_c
  level.frequency_hz =
      std::sqrt(e.r - al.equality_gradient(e.h) * omega0_ * omega0_ * m_ratio) / (2.0 * std::numbers::pi);
  level.coefficients = spectral::as_coefficients(expand(x) * g_ref_, n_);
  level.max_penetration = e.g.maxCoeff();
  const Eigen::VectorXd lambda = al.inequality_gradient(e.g);
  level.multipliers = lambda;
  level.equality_multiplier = al.equality_gradient(e.h);
  level.contact_force = lambda * (0.5 * m_ratio * m_c_ / m_ref_) *
                        (options_.samples * omega0_ * omega0_ * m_ref_ * g_ref_);  // λ_AL m̂/(2 m_ref) f_ref
  const double lmax = lambda.size() > 0 ? lambda.maxCoeff() : 0.0;
  level.complementarity = lmax > 0.0 ? (lambda.array() * e.g.array()).abs().maxCoeff() / lmax : 0.0;
  level.normalization_error = std::abs(e.h);
  if (!std::isfinite(level.frequency_hz) || !level.coefficients.allFinite()) {
    level.status = SolveStatus::NonFinite;
    why = "non-finite iterate";
  }
  std::ostringstream os;
  os << why << " after " << level.powell_iterations << " Powell and " << level.newton_iterations
     << " Newton iterations: G_i = " << format_number(level.inequality_measure)
     << ", G_e = " << format_number(level.equality_measure) << ", ‖∇L‖∞ = " << format_number(level.residual_norm)
     << " (tolerances " << format_number(options_.powell.tolerance) << ", "
     << format_number(options_.stationarity_tolerance) << ")";
  level.message = os.str();
  level.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return level;
}

Backbone NonlinearModes::backbone(const BackboneOptions& o) const {
  const auto t0 = std::chrono::steady_clock::now();
  if (!(o.energy_min > 0.0 && o.energy_min < o.energy_max) || !(o.min_step > 0.0 && o.min_step <= o.initial_step &&
                                                                 o.initial_step <= o.max_step)) {
    throw std::invalid_argument("BackboneOptions: need 0 < energy_min < energy_max and 0 < min_step <= initial_step "
                                "<= max_step");
  }
  std::vector<double> include = o.include;
  std::sort(include.begin(), include.end());
  Backbone b;
  double step = o.initial_step, energy = o.energy_min;
  while (true) {
    // Secant predictor through the last two levels, scaled start from one.
    ModeLevel predictor;
    const ModeLevel* start = nullptr;
    if (b.levels.size() >= 2) {
      const auto& l0 = b.levels[b.levels.size() - 2];
      const auto& l1 = b.levels.back();
      const double s = (energy - l1.energy) / (l1.energy - l0.energy);
      predictor.energy = energy;
      predictor.coefficients = l1.coefficients + s * (l1.coefficients - l0.coefficients);
      predictor.frequency_hz = l1.frequency_hz + s * (l1.frequency_hz - l0.frequency_hz);
      predictor.multipliers = l1.multipliers + s * (l1.multipliers - l0.multipliers);
      predictor.equality_multiplier = l1.equality_multiplier + s * (l1.equality_multiplier - l0.equality_multiplier);
      start = &predictor;
    } else if (!b.levels.empty()) {
      start = &b.levels.back();
    }
    ModeLevel level = solve(energy, start);
    if (level.converged()) {
      b.levels.push_back(std::move(level));
      if (energy >= o.energy_max) break;
      if (b.levels.back().powell_iterations <= 8) step = std::min(o.max_step, 1.5 * step);
    } else {
      b.failed_energies.push_back(energy);
      if (b.levels.empty()) {
        b.message = "the first level E = " + format_number(energy) + " did not converge: " + level.message;
        break;
      }
      step *= 0.5;
      if (step < o.min_step) {
        b.message = "energy step below minimum after E = " + format_number(b.levels.back().energy) + ": " + level.message;
        break;
      }
    }
    double next = b.levels.back().energy + step;
    for (double e : include) {
      if (e > b.levels.back().energy + 1e-12 && e < next) next = e;
    }
    energy = std::min(next, o.energy_max);
  }
  if (b.message.empty()) {
    b.message = "reached E = " + format_number(o.energy_max);
    b.complete = true;
  }
  for (double e : o.include) {
    for (const auto& l : b.levels) {
      if (std::abs(l.energy - e) <= 1e-12 * e) {
        b.included.push_back(l);
        break;
      }
    }
  }
  b.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return b;
}

Eigen::MatrixXd NonlinearModes::displacement(const ModeLevel& level, int samples) const {
  return level.coefficients * basis_values(samples, 0).transpose();
}

Eigen::MatrixXd NonlinearModes::velocity(const ModeLevel& level, int samples) const {
  return level.frequency_hz * (level.coefficients * basis_values(samples, 1).transpose());  // d/dt = f d/dτ
}

}  // namespace wbm::solvers

// ---------------------------------------------------------------------------------------------
// Backbone by pseudo-arclength continuation of the KKT conditions (harmonic-balance form).

namespace wbm::solvers {

void BackboneContinuationOptions::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("BackboneContinuationOptions." + what); };
  if (!(energy_min > 0.0 && energy_min < energy_max) || !std::isfinite(energy_max)) {
    fail("energy range [" + format_number(energy_min) + ", " + format_number(energy_max) +
         "]: need 0 < energy_min < energy_max, finite");
  }
  if (!(penalty_stiffness >= 0.0) || !std::isfinite(penalty_stiffness)) {
    fail("penalty_stiffness = " + format_number(penalty_stiffness) + ": must be >= 0 [N/m] (0: exact contact)");
  }
  if (!(max_energy_step > 0.0)) fail("max_energy_step = " + format_number(max_energy_step) + ": must be > 0");
  if (!(tolerance > 0.0)) fail("tolerance = " + format_number(tolerance) + ": must be > 0");
  if (max_points < 2) fail("max_points = " + std::to_string(max_points) + ": must be >= 2");
  if (max_newton_iterations < 1) {
    fail("max_newton_iterations = " + std::to_string(max_newton_iterations) + ": must be >= 1");
  }
}

NonlinearModes::BackboneSystem::BackboneSystem(const NonlinearModes& modes, double penalty_stiffness) : nm_(&modes) {
  if (!(penalty_stiffness >= 0.0) || !std::isfinite(penalty_stiffness)) {
    throw std::invalid_argument("BackboneSystem: penalty_stiffness = " + format_number(penalty_stiffness) +
                                ": must be >= 0 [N/m]");
  }
  const auto& o = modes.options_;
  penalty_ = penalty_stiffness / (o.samples * modes.omega0_ * modes.omega0_ * modes.m_ref_);
  if (penalty_ > 0.0) penalty_law_.emplace(contact::LinearPenaltyParameters{.stiffness = penalty_, .gap = 0.0});
  ny_ = static_cast<Eigen::Index>(modes.n_) * modes.f_ - 1;
  size_ = ny_ + 1 + (penalty_ > 0.0 ? 0 : static_cast<Eigen::Index>(modes.stops_.size()) * o.samples);
}

Eigen::VectorXd NonlinearModes::BackboneSystem::linear_state(double energy) const {
  const auto& nm = *nm_;
  Eigen::VectorXd full = Eigen::VectorXd::Zero(ny_ + 1);
  full.segment(nm.n_, nm.n_) = nm.onset_ * (std::sqrt(energy) / nm.g_ref_);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(size_);
  x.head(nm.phase_index_) = full.head(nm.phase_index_);
  x.segment(nm.phase_index_, ny_ - nm.phase_index_) = full.tail(ny_ - nm.phase_index_);
  x(ny_) = 1.0;
  return x;
}

NonlinearModes::BackboneSystem::Unpacked NonlinearModes::BackboneSystem::unpack(const Eigen::VectorXd& x) const {
  const auto& nm = *nm_;
  if (x.size() != size_) {
    throw std::invalid_argument("BackboneSystem: state of length " + std::to_string(x.size()) + ", expected " +
                                std::to_string(size_));
  }
  const Eigen::Index ms = nm.options_.samples;
  Unpacked u;
  u.y = nm.with_phase(x.head(ny_));
  const Eigen::Map<const Eigen::MatrixXd> ym(u.y.data(), nm.n_, nm.f_);
  const auto n_stops = static_cast<Eigen::Index>(nm.stops_.size());
  u.g.resize(n_stops * ms);
  for (Eigen::Index c = 0; c < n_stops; ++c) {
    const auto& stop = nm.stops_[static_cast<size_t>(c)];
    u.g.segment(c * ms, ms) = (nm.theta_ * ym.row(stop.dof).transpose()).array() - stop.gap / nm.g_ref_;
  }
  if (penalty_ == 0.0) {
    u.lambda = x.tail(n_stops * ms);
  } else {  // λ = κ (g)₊ with g the normalized gap function: contact's linear penalty at gap 0
    u.lambda.resize(u.g.size());
    u.penalty_stiffness.resize(u.g.size());
    penalty_law_->evaluate(u.g, u.lambda, u.penalty_stiffness);
  }
  return u;
}

Eigen::VectorXd NonlinearModes::BackboneSystem::residual(const Eigen::VectorXd& x, double energy) const {
  return evaluate(x, energy, false).residual;
}

SparseLinearization NonlinearModes::BackboneSystem::linearize(const Eigen::VectorXd& x, double energy) const {
  return evaluate(x, energy, true);
}

SparseLinearization NonlinearModes::BackboneSystem::evaluate(const Eigen::VectorXd& x, double energy,
                                                             bool jacobian) const {
  const auto& nm = *nm_;
  const int n = nm.n_, f = nm.f_, ms = nm.options_.samples;
  const Eigen::Index p = nm.phase_index_;
  const Unpacked state = unpack(x);
  const Eigen::VectorXd& g = state.g;
  const Eigen::VectorXd& lambda = state.lambda;
  // The map full stacked index -> reduced index (−1: the phase coefficient, removed).
  auto reduced = [p](Eigen::Index i) { return i < p ? i : (i == p ? Eigen::Index{-1} : i - 1); };
  const Eigen::Map<const Eigen::MatrixXd> ym(state.y.data(), n, f);
  const double s = x(ny_);
  const bool exact = penalty_ == 0.0;
  const auto n_stops = static_cast<Eigen::Index>(nm.stops_.size());

  // Harmonic balance rows, full size: w_k (K̂ − ν_k² s M̂) Y_k + Σ_s θ_sk λ_s e_c.
  const Eigen::MatrixXd ky = nm.ks_ * ym, my = nm.ms_ * ym;
  Eigen::MatrixXd hb(n, f);
  for (int k = 0; k < f; ++k) hb.col(k) = nm.weight_(k) * (ky.col(k) - nm.nu_(k) * nm.nu_(k) * s * my.col(k));
  for (Eigen::Index c = 0; c < n_stops; ++c) {  // contact forces on the stop DOFs
    hb.row(nm.stops_[static_cast<size_t>(c)].dof) += (nm.theta_.transpose() * lambda.segment(c * ms, ms)).transpose();
  }
  double mh = 0.0;
  for (int k = 0; k < f; ++k) mh += nm.weight_(k) * nm.nu_(k) * nm.nu_(k) * ym.col(k).dot(my.col(k)) * nm.m_ref_;
  SparseLinearization out;
  out.residual.resize(size_);
  const Eigen::VectorXd hbs = spectral::stacked(hb);
  out.residual.head(p) = hbs.head(p);
  out.residual.segment(p, ny_ - p) = hbs.tail(ny_ - p);
  out.residual(ny_) = mh / nm.m_c_ - energy;
  // Signorini at every sample: min(λ_s, −g_s) = 0 (λ in units of f_ref).
  if (exact) {
    for (Eigen::Index i = 0; i < n_stops * ms; ++i) out.residual(ny_ + 1 + i) = std::min(lambda(i), -g(i));
  }
  out.parameter_derivative = Eigen::VectorXd::Zero(size_);
  out.parameter_derivative(ny_) = -1.0;
  if (!jacobian) return out;

  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<size_t>(f) * (nm.ks_.nonZeros() + nm.ms_.nonZeros() + 2 * n) +
            static_cast<size_t>(n_stops * ms) * (f + 2) + static_cast<size_t>(f * f * n_stops));
  auto add = [&](Eigen::Index row_full, Eigen::Index col_full, double v) {
    const Eigen::Index r = reduced(row_full), c = reduced(col_full);
    if (r >= 0 && c >= 0) t.emplace_back(r, c, v);
  };
  auto add_row = [&](Eigen::Index row_full, Eigen::Index col, double v) {  // column already in state units
    const Eigen::Index r = reduced(row_full);
    if (r >= 0) t.emplace_back(r, col, v);
  };
  for (int k = 0; k < f; ++k) {
    const double w = nm.weight_(k), nu2 = nm.nu_(k) * nm.nu_(k);
    for (int pass = 0; pass < 2; ++pass) {
      const Eigen::SparseMatrix<double>& a = pass == 0 ? nm.ks_ : nm.ms_;
      const double factor = pass == 0 ? w : -w * nu2 * s;
      for (Eigen::Index col = 0; col < a.outerSize(); ++col) {
        for (Eigen::SparseMatrix<double>::InnerIterator it(a, col); it; ++it) {
          add(static_cast<Eigen::Index>(k) * n + it.row(), static_cast<Eigen::Index>(k) * n + it.col(), factor * it.value());
        }
      }
    }
    for (int i = 0; i < n; ++i) {
      const Eigen::Index row = static_cast<Eigen::Index>(k) * n + i;
      add_row(row, ny_, -w * nu2 * my(i, k));                                         // ∂/∂s
      const double dn = 2.0 * w * nu2 * my(i, k) * nm.m_ref_ / nm.m_c_;                // ∂(m̂/m̂_c)/∂Y
      if (reduced(row) >= 0) t.emplace_back(ny_, reduced(row), dn);
    }
  }
  for (Eigen::Index c = 0; c < n_stops; ++c) {
    const int d = nm.stops_[static_cast<size_t>(c)].dof;
    if (exact) {
      for (int smp = 0; smp < ms; ++smp) {
        const Eigen::Index i = c * ms + smp, col = ny_ + 1 + i;
        for (int k = 0; k < f; ++k) add_row(static_cast<Eigen::Index>(k) * n + d, col, nm.theta_(smp, k));  // ∂HB/∂λ
        if (lambda(i) <= -g(i)) {
          t.emplace_back(col, col, 1.0);  // the min picks λ_s
        } else {
          for (int k = 0; k < f; ++k) {  // the min picks −g_s
            const Eigen::Index r = reduced(static_cast<Eigen::Index>(k) * n + d);
            if (r >= 0) t.emplace_back(col, r, -nm.theta_(smp, k));
          }
        }
      }
    } else {  // penalty: ∂HB(k, d)/∂Y(l, d) = Σ_s θ_sk f′(g_s) θ_sl, f′ = κ [g_s > 0]
      const Eigen::VectorXd on = state.penalty_stiffness.segment(c * ms, ms);
      if (on.isZero(0.0)) continue;
      const Eigen::MatrixXd block = nm.theta_.transpose() * on.asDiagonal() * nm.theta_;
      for (int k = 0; k < f; ++k) {
        for (int l = 0; l < f; ++l) {
          add(static_cast<Eigen::Index>(k) * n + d, static_cast<Eigen::Index>(l) * n + d, block(k, l));
        }
      }
    }
  }
  out.jacobian.resize(size_, size_);
  out.jacobian.setFromTriplets(t.begin(), t.end());
  return out;
}

ModeLevel NonlinearModes::BackboneSystem::level(const Eigen::VectorXd& x, double energy, double tolerance) const {
  const auto& nm = *nm_;
  const int n = nm.n_, f = nm.f_, ms = nm.options_.samples;
  Unpacked state = unpack(x);
  const Eigen::VectorXd& g = state.g;
  Eigen::VectorXd& lambda = state.lambda;
  const Eigen::Map<const Eigen::MatrixXd> ym(state.y.data(), n, f);
  ModeLevel l;
  l.energy = energy;
  l.residual_norm = residual(x, energy).norm();
  l.tolerance = tolerance;
  l.status = !std::isfinite(l.residual_norm) ? SolveStatus::NonFinite
             : l.residual_norm <= tolerance  ? SolveStatus::Converged
                                             : SolveStatus::MaxIterations;
  l.coefficients = ym * nm.g_ref_;
  l.frequency_hz = std::sqrt(x(ny_)) * nm.omega0_ / (2.0 * std::numbers::pi);
  double kh = 0.0, mh = 0.0;
  for (int k = 0; k < f; ++k) {
    kh += nm.weight_(k) * ym.col(k).dot(nm.k_ * ym.col(k));
    mh += nm.weight_(k) * nm.nu_(k) * nm.nu_(k) * ym.col(k).dot(nm.m_ * ym.col(k));
  }
  l.rayleigh_frequency_hz = std::sqrt(kh / mh) / (2.0 * std::numbers::pi);
  l.normalization_error = std::abs(mh / nm.m_c_ - energy);
  // Inactive samples carry rounding (|λ| ~ 1e-20 of the active ones) from the linear solves.
  const double active = 1e-12 * std::max(0.0, lambda.maxCoeff());
  lambda = (lambda.array() > active).select(lambda, 0.0);
  const double f_ref = ms * nm.omega0_ * nm.omega0_ * nm.m_ref_ * nm.g_ref_;
  l.contact_force = lambda * f_ref;
  l.max_penetration = g.maxCoeff();
  const double lmax = lambda.maxCoeff();
  l.complementarity = lmax > 0.0 ? (lambda.array() * g.array()).abs().maxCoeff() / lmax : 0.0;
  l.inequality_measure = std::max(0.0, l.max_penetration);
  l.equality_measure = l.normalization_error;
  // The Lagrangian's multipliers (see solve()): λ_AL = 2 m_ref λ/(m̂), μ = (r/ω₀² − s)/E.
  l.multipliers = lambda * (2.0 * nm.m_ref_ / (mh));
  l.equality_multiplier = (kh / mh / (nm.omega0_ * nm.omega0_) - x(ny_)) / energy;
  l.message = std::string(to_string(l.status)) + ": KKT residual ‖R‖₂ = " + format_number(l.residual_norm) +
              " (tolerance " + format_number(tolerance) + ")";
  return l;
}

ModeLevel NonlinearModes::level_at(const BackboneSystem& system, Eigen::VectorXd x, double energy,
                                   const BackboneContinuationOptions& options) const {
  const auto t0 = std::chrono::steady_clock::now();
  // Semismooth Newton at fixed E (no line search: x is a converged point of the branch less
  // than one step away), through the Newton core with sparse LU.
  struct Fixed {
    const BackboneSystem* s;
    double energy;
    [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x) const { return s->residual(x, energy); }
    [[nodiscard]] Eigen::SparseMatrix<double> jacobian(const Eigen::VectorXd& x) const {
      return s->linearize(x, energy).jacobian;
    }
  };
  const NewtonResult r = newton(Fixed{&system, energy}, std::move(x),
                                {.tolerance = options.tolerance, .max_iterations = options.max_newton_iterations,
                                 .line_search = false});
  ModeLevel l = system.level(r.x, energy, options.tolerance);
  l.newton_iterations = r.report.iterations;
  if (!r.report.converged()) {
    l.status = r.report.status;
    l.message = "semismooth Newton at fixed E = " + format_number(energy) + ": " + r.report.message;
  }
  l.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return l;
}

Backbone NonlinearModes::continue_backbone(const BackboneContinuationOptions& o) const {
  o.validate();
  const auto t0 = std::chrono::steady_clock::now();
  const BackboneSystem system(*this, o.penalty_stiffness);
  Backbone b;
  // Start below contact on the linear mode (an exact solution); above onset, from the linear
  // mode corrected by Newton at fixed E.
  const double e0 = o.energy_min;
  const Eigen::VectorXd x0 = system.linear_state(std::min(e0, 1.0));
  PseudoArclengthOptions pa;
  pa.parameter_min = 0.5 * e0;
  pa.parameter_max = o.energy_max;
  pa.parameter_scale = 1.0;
  pa.state_scale = 1.0;
  pa.initial_step = o.initial_step;
  pa.min_step = o.min_step;
  pa.max_step = o.max_step;
  pa.max_parameter_step = o.max_energy_step;
  pa.max_points = o.max_points;
  pa.corrector_tolerance = o.tolerance;
  pa.max_corrector_iterations = 12;
  pa.kink_step = 1e-5;
  pa.corner_restart = true;
  pa.initial_newton = {.tolerance = o.tolerance, .max_iterations = o.max_newton_iterations};
  Branch branch = pseudo_arclength(system, x0, e0, pa);
  // A branch that comes back below contact onset after contact has retraced the backbone (the
  // linear mode is the only solution there): keep it up to where it turned back, and say so.
  bool retraced = false;
  double highest = 0.0;
  for (size_t k = 0; k < branch.points.size(); ++k) {
    const double e = branch.points[k].parameter;
    if (highest > 1.0 + 1e-6 && e < 1.0) {
      size_t top = 0;
      for (size_t j = 1; j < k; ++j) {
        if (branch.points[j].parameter > branch.points[top].parameter) top = j;
      }
      branch.points.resize(top + 1);
      std::erase_if(branch.folds, [&](const Fold& f) { return f.after >= top; });
      branch.stop = StopReason::Retraced;
      branch.message = "the branch turned back at a corner near E = " + format_number(branch.points[top].parameter) +
                       " and retraced the backbone down to the linear mode; kept up to that energy";
      retraced = true;
      break;
    }
    highest = std::max(highest, e);
  }
  for (const auto& pt : branch.points) {
    if (pt.parameter > o.energy_max) {  // the last point overshoots the range: land on energy_max
      ModeLevel last = level_at(system, pt.x, o.energy_max, o);
      if (last.converged()) b.levels.push_back(std::move(last));
      break;
    }
    ModeLevel l = system.level(pt.x, pt.parameter, o.tolerance);
    l.newton_iterations = pt.corrector_iterations;
    b.levels.push_back(std::move(l));
  }
  for (double e : o.include) {  // first passage of the branch through e, then Newton at fixed e
    for (size_t k = 0; k + 1 < branch.points.size(); ++k) {
      const auto &p0 = branch.points[k], &p1 = branch.points[k + 1];
      if ((p0.parameter - e) * (p1.parameter - e) > 0.0) continue;
      const double t = p1.parameter == p0.parameter ? 0.0 : (e - p0.parameter) / (p1.parameter - p0.parameter);
      b.included.push_back(level_at(system, p0.x + t * (p1.x - p0.x), e, o));
      break;
    }
  }
  for (const auto& fold : branch.folds) b.folds.push_back(fold.parameter);
  b.kinks = branch.kinks;
  b.rejected_steps = branch.rejected_steps;
  b.stop = branch.stop;
  b.complete = !retraced && branch.stop == StopReason::RangeReached && !b.levels.empty() &&
               b.levels.back().energy >= o.energy_max * (1.0 - 1e-12);
  b.message = std::string(to_string(branch.stop)) + ": " + branch.message;
  b.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return b;
}

}  // namespace wbm::solvers
