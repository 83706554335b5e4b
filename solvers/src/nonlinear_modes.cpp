#include <wbm/solvers/nonlinear_modes.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

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
      throw std::invalid_argument("NonlinearModes: stop gap " + std::to_string(s.gap) + " m: must be > 0 (energies "
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
}

Eigen::MatrixXd NonlinearModes::basis_values(int samples, int derivative) const {
  Eigen::MatrixXd v(samples, f_);
  for (int s = 0; s < samples; ++s) {
    const double tau = static_cast<double>(s) / samples;
    v(s, 0) = derivative == 0 ? 1.0 : 0.0;
    for (int h = 1; h <= n_harm_; ++h) {
      const double w = 2.0 * std::numbers::pi * h, c = std::cos(w * tau), sn = std::sin(w * tau);
      v(s, 2 * h - 1) = derivative == 0 ? c : -w * sn;
      v(s, 2 * h) = derivative == 0 ? sn : w * c;
    }
  }
  return v;
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
    throw std::invalid_argument("NonlinearModes::solve: energy " + std::to_string(energy) + " must be > 0");
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
  auto expand = [&](const Eigen::VectorXd& x) {
    Eigen::VectorXd full(x.size() + 1);
    full << x.head(phase_index_), 0.0, x.tail(x.size() - phase_index_);
    return full;
  };
  contact::AugmentedLagrangian al(static_cast<int>(stops_.size()) * options_.samples, options_.powell);
  if (start != nullptr && start->multipliers.size() == static_cast<Eigen::Index>(stops_.size()) * options_.samples) {
    al.warm_start(start->multipliers, start->equality_multiplier);  // contact forces vary continuously with E
  }
  Eigen::VectorXd x = reduce(y);
  double omega2 = start != nullptr ? std::pow(2.0 * std::numbers::pi * start->frequency_hz, 2) : omega0_ * omega0_;
  std::string why = "Powell iteration limit reached";
  for (int j = 0; j < options_.max_powell_iterations; ++j) {
    ++level.powell_iterations;
    // LL11 Alg. 3, l. 3: the primal problem, ∇L_κ = 0 by Newton (line search on ‖∇L_κ‖).
    Evaluation e = evaluate(expand(x), energy, omega2, al, true);
    // Newton steps with a short line search on ‖∇L‖; when they stall (a change of the active
    // set), Levenberg–Marquardt steps on ½‖∇L‖², (H² + μI) d = −H ∇L, with μ adapted to the gain.
    double mu_lm = 0.0;
    for (int it = 0; it < options_.max_newton_iterations; ++it) {
      const double norm = e.gradient.lpNorm<Eigen::Infinity>();
      if (!(norm > options_.stationarity_tolerance)) break;
      ++level.newton_iterations;
      const double n2 = e.gradient.squaredNorm();
      bool accepted = false;
      if (mu_lm == 0.0) {
        const Eigen::VectorXd d = -Eigen::PartialPivLU<Eigen::MatrixXd>(e.hessian).solve(e.gradient);
        double t = 1.0;
        for (int b = 0; b < 4 && d.allFinite(); ++b, t *= 0.5) {
          const Evaluation trial = evaluate(expand(x + t * d), energy, omega2, al, false);
          if (trial.gradient.allFinite() && trial.gradient.squaredNorm() <= (1.0 - 1e-4 * t) * n2) {
            x += t * d;
            accepted = true;
            break;
          }
        }
        if (!accepted) mu_lm = 1e-6 * e.hessian.cwiseAbs().rowwise().sum().maxCoeff();
      }
      if (!accepted) {
        const Eigen::MatrixXd h2 = e.hessian * e.hessian;
        const Eigen::VectorXd hg = e.hessian * e.gradient;
        for (int b = 0; b < 20; ++b) {
          Eigen::MatrixXd a = h2;
          a.diagonal().array() += mu_lm * mu_lm;
          const Eigen::VectorXd d = -a.ldlt().solve(hg);
          const Evaluation trial = evaluate(expand(x + d), energy, omega2, al, false);
          if (d.allFinite() && trial.gradient.allFinite() && trial.gradient.squaredNorm() < n2) {
            x += d;
            accepted = true;
            mu_lm *= 0.3;
            break;
          }
          mu_lm *= 4.0;
        }
        if (!accepted) break;  // no decrease of ‖∇L‖: the outer update changes the problem
      }
      e = evaluate(expand(x), energy, omega2, al, true);
    }
    // l. 4–5: constraints and Powell's measures; Alg. 2 updates ω from the Rayleigh quotient.
    bool omega_settled = true;
    if (options_.algorithm == ModeAlgorithm::Sequential) {
      omega_settled = std::abs(e.r - omega2) <= options_.powell.tolerance * omega2;
      omega2 = e.r;
    }
    level.inequality_measure = al.inequality_measure(e.g);
    level.equality_measure = contact::AugmentedLagrangian::equality_measure(e.h);
    const bool stationary = !(e.gradient.lpNorm<Eigen::Infinity>() > 1e3 * options_.stationarity_tolerance);
    if (al.update(e.g, e.h) && omega_settled && stationary) {
      level.converged = true;
      why = "converged";
      break;
    }
  }
  // Report on the final iterate.
  const Evaluation e = evaluate(expand(x), energy, omega2, al, false);
  level.frequency_hz = std::sqrt(e.r) / (2.0 * std::numbers::pi);
  level.coefficients = spectral::as_coefficients(expand(x) * g_ref_, n_);
  level.max_penetration = e.g.maxCoeff();
  const Eigen::VectorXd lambda = al.inequality_gradient(e.g);
  level.multipliers = lambda;
  level.equality_multiplier = al.equality_gradient(e.h);
  const double lmax = lambda.size() > 0 ? lambda.maxCoeff() : 0.0;
  level.complementarity = lmax > 0.0 ? (lambda.array() * e.g.array()).abs().maxCoeff() / lmax : 0.0;
  level.normalization_error = std::abs(e.h);
  if (!std::isfinite(level.frequency_hz) || !level.coefficients.allFinite()) {
    level.converged = false;
    why = "non-finite iterate";
  }
  std::ostringstream os;
  os << why << " after " << level.powell_iterations << " Powell and " << level.newton_iterations
     << " Newton iterations: G_i = " << level.inequality_measure << ", G_e = " << level.equality_measure;
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
    if (level.converged) {
      b.levels.push_back(std::move(level));
      if (energy >= o.energy_max) break;
      if (b.levels.back().powell_iterations <= 8) step = std::min(o.max_step, 1.5 * step);
    } else {
      b.failed_energies.push_back(energy);
      if (b.levels.empty()) {
        b.message = "the first level E = " + std::to_string(energy) + " did not converge: " + level.message;
        break;
      }
      step *= 0.5;
      if (step < o.min_step) {
        b.message = "energy step below minimum after E = " + std::to_string(b.levels.back().energy) + ": " + level.message;
        break;
      }
    }
    double next = b.levels.back().energy + step;
    for (double e : include) {
      if (e > b.levels.back().energy + 1e-12 && e < next) next = e;
    }
    energy = std::min(next, o.energy_max);
  }
  if (b.message.empty()) b.message = "reached E = " + std::to_string(o.energy_max);
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
