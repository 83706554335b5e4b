// Nonlinear modes by the augmented Lagrangian with Powell's updates [LL11 Secs. 3–4, Algs. 1–3]:
// the primal evaluation (gradient and Hessian of L_κ), one energy level, and the energy-stepping
// backbone.
#include <wbm/solvers/nonlinear_modes.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCore>

#include <wbm/solvers/detail/rounding_floor.hpp>
#include <wbm/solvers/natural_parameter.hpp>
#include <wbm/spectral/fourier_basis.hpp>
#include <wbm/spectral/layout.hpp>

namespace wbm::solvers {

struct NonlinearModes::Evaluation {
  Eigen::VectorXd gradient;   // reduced (phase coefficient removed)
  SparseLowRankHessian hessian;  // reduced (phase row and column removed), if asked
  Eigen::VectorXd g;          // constraint values, stop-major: g(c·m + k)
  double h = 0.0;             // ½m̂/γ_c − E
  double r = 0.0;             // Rayleigh quotient [(rad/s)²]
};

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
  e.g = gaps(ym);
  const Eigen::VectorXd lambda = al.inequality_gradient(e.g);
  add_contact_forces(grad, lambda);
  const double mu = al.equality_gradient(e.h);
  grad += (mu / m_c_) * dm;
  Eigen::VectorXd full = spectral::stacked(grad);
  e.gradient.resize(full.size() - 1);
  e.gradient << full.head(phase_index_), full.tail(full.size() - phase_index_ - 1);
  if (!hessian) return e;

  // The Hessian as H = S + U C Uᵀ (SparseLowRankHessian): S block diagonal in the harmonics plus
  // the contact curvature on the stops' DOFs, U C Uᵀ the rank-one terms of the Rayleigh quotient
  // and the normalization; the phase coefficient's row and column removed.
  const auto p = static_cast<Eigen::Index>(phase_index_);
  auto reduced = [p](Eigen::Index i) { return i < p ? i : i - 1; };
  std::vector<Eigen::Triplet<double>> t = contact_curvature(al.inequality_curvature(e.g));
  for (int k = 0; k < f_; ++k) {  // (2K̃ − 2ω² M̃)/denominator + (2μ/m_c) M̃, block k
    const double ck = 2.0 * weight_(k) / denominator, cm = (2.0 * mu / m_c_ - 2.0 * omega2 / denominator) * wnu2(k);
    for (const auto& [matrix, c] : {std::pair{&system_.stiffness, ck}, std::pair{&system_.mass, cm}}) {
      if (c == 0.0) continue;
      for (Eigen::Index j = 0; j < matrix->outerSize(); ++j) {
        for (Eigen::SparseMatrix<double>::InnerIterator it(*matrix, j); it; ++it) {
          t.emplace_back(k * n_ + it.row(), k * n_ + it.col(), c * it.value());
        }
      }
    }
  }
  const Eigen::Index size = static_cast<Eigen::Index>(n_) * f_;
  std::vector<Eigen::Triplet<double>> kept;
  kept.reserve(t.size());
  for (const auto& entry : t) {
    if (entry.row() != p && entry.col() != p) {
      kept.emplace_back(reduced(entry.row()), reduced(entry.col()), entry.value());
    }
  }
  e.hessian.sparse.resize(size - 1, size - 1);
  e.hessian.sparse.setFromTriplets(kept.begin(), kept.end());
  auto drop_phase = [p](const Eigen::VectorXd& v) {
    Eigen::VectorXd out(v.size() - 1);
    out << v.head(p), v.tail(v.size() - p - 1);
    return out;
  };
  // Equality: κ_e ∇h ∇hᵀ, ∇h = ∇m̂/m_c; simultaneous also − (∇m̂ ∇rᵀ + ∇r ∇m̂ᵀ)/(ω₀² m̂),
  // ∇r = (∇k̂ − r ∇m̂)/m̂.
  const Eigen::VectorXd dmv = spectral::stacked(dm);
  const double ce = al.equality_curvature() / (m_c_ * m_c_);
  if (simultaneous) {
    const Eigen::VectorXd dr = spectral::stacked((dk - e.r * dm) / mh);
    e.hessian.u.resize(size - 1, 2);
    e.hessian.u << drop_phase(dmv), drop_phase(dr);
    const double a = 1.0 / (w02 * mh);
    e.hessian.core.resize(2, 2);
    e.hessian.core << ce, -a, -a, 0.0;
  } else {
    e.hessian.u = drop_phase(dmv);
    e.hessian.core = Eigen::MatrixXd::Constant(1, 1, ce);
  }
  return e;
}

ModeLevel NonlinearModes::solve(double energy, const ModeLevel* start, double max_wall_time_s) const {
  const auto t0 = std::chrono::steady_clock::now();
  auto spent = [&] {
    return max_wall_time_s > 0.0 &&
           std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > max_wall_time_s;
  };
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
  double tolerance = options_.stationarity_tolerance;  // the one the level is verified against
  for (int j = 0; j < options_.max_powell_iterations; ++j) {
    if (spent()) {
      why = "wall-time budget spent (" + format_number(max_wall_time_s) + " s)";
      break;
    }
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
      [[nodiscard]] SparseLowRankHessian jacobian(const Eigen::VectorXd& x) const {
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
    const double stationarity = e.gradient.lpNorm<Eigen::Infinity>();
    const bool stationary = stationarity <= options_.stationarity_tolerance;
    const bool measures_met = al.update(e.g, e.h).measures_met;
    if (measures_met && omega_settled && stationary) {
      level.status = SolveStatus::Converged;
      why = "converged";
      break;
    }
    // With the measures met the update changed no multiplier or penalty (and ω² is settled): only
    // the primal solve can make progress, and if it made none (‖∇L_κ‖∞ down by less than 0.1 %)
    // the next iteration would repeat this one. Within 10 times the rounding floor of ∇L_κ at x
    // (the larger over two sign patterns of ‖∇L_κ(x ⊙ (1 ± ε)) − ∇L_κ(x)‖∞, detail::rounded) the
    // level is converged, with that tolerance reported; above it Newton stalls at a nonsmooth point
    // and the level fails.
    const auto& norms = primal.report.residual_norms;
    if (measures_met && omega_settled && norms.back() >= (1.0 - 1e-3) * norms.front()) {
      auto gradient = [&](const Eigen::VectorXd& v) { return evaluate(expand(v), energy, omega2, al, false).gradient; };
      double floor = 0.0;
      for (int pattern = 0; pattern < 2; ++pattern) {
        floor = std::max(floor, (gradient(detail::rounded(x, pattern)) - e.gradient).lpNorm<Eigen::Infinity>());
      }
      if (stationarity <= 10.0 * floor) {
        level.status = SolveStatus::Converged;
        tolerance = 10.0 * floor;
        why = "converged at the rounding floor of ∇L_κ (10 × " + format_number(floor) +
              ", above stationarity_tolerance " + format_number(options_.stationarity_tolerance) + ")";
      } else {
        why = "the primal Newton stalled with Powell's measures met, ‖∇L_κ‖∞ = " + format_number(stationarity) +
              " above 10 times its rounding floor (" + format_number(floor) + "): a nonsmooth point it cannot cross";
      }
      break;
    }
  }
  // Report on the final iterate.
  const Evaluation e = evaluate(expand(x), energy, omega2, al, false);
  level.residual_norm = e.gradient.lpNorm<Eigen::Infinity>();
  level.tolerance = tolerance;
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
     << format_number(tolerance) << ")";
  level.message = os.str();
  level.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return level;
}

void BackboneOptions::validate() const {
  if (!(energy_min > 0.0 && energy_min < energy_max)) {
    throw std::invalid_argument("BackboneOptions.energy_min = " + format_number(energy_min) + ", energy_max = " +
                                format_number(energy_max) + ": need 0 < energy_min < energy_max (normalized "
                                "energies, 1 = contact onset; e.g. 0.5 and 10)");
  }
  if (!(min_step > 0.0 && min_step <= initial_step && initial_step <= max_step)) {
    throw std::invalid_argument("BackboneOptions.min_step = " + format_number(min_step) + ", initial_step = " +
                                format_number(initial_step) + ", max_step = " + format_number(max_step) +
                                ": need 0 < min_step <= initial_step <= max_step (energy steps; defaults 1e-4, "
                                "0.05, 0.1)");
  }
  if (!(max_wall_time_s >= 0.0)) {
    throw std::invalid_argument("BackboneOptions.max_wall_time_s = " + format_number(max_wall_time_s) +
                                ": must be >= 0 (0: no budget)");
  }
}

Backbone NonlinearModes::backbone(const BackboneOptions& o) const {
  const auto t0 = std::chrono::steady_clock::now();
  o.validate();
  std::vector<double> include = o.include;
  std::sort(include.begin(), include.end());
  // Natural-parameter continuation in E (natural_parameter.hpp): the state is a level's
  // unknowns packed as [vec Y, f, λ, μ], so that the layer's secant predictor is LL11's; the
  // corrector is Powell's augmented Lagrangian at fixed E (solve); the step grows ×1.5 after a
  // level that took ≤ 8 Powell iterations and is halved after a failure; the steps end on the
  // energies of `include` and on energy_max.
  Backbone b;
  const Eigen::Index ny = static_cast<Eigen::Index>(n_) * f_, nl = static_cast<Eigen::Index>(stops_.size()) * options_.samples;
  auto pack = [&](const ModeLevel& l) {
    Eigen::VectorXd x(ny + 2 + nl);
    x.head(ny) = spectral::stacked(l.coefficients);
    x(ny) = l.frequency_hz;
    x.segment(ny + 1, nl) = l.multipliers.size() == nl ? l.multipliers : Eigen::VectorXd::Zero(nl);
    x(ny + 1 + nl) = l.equality_multiplier;
    return x;
  };
  ModeLevel pending;  // the level of the last successful correction, kept by on_point
  auto correct = [&](double energy, Eigen::VectorXd guess) {
    ModeLevel predictor;
    const ModeLevel* start = nullptr;
    if (guess.size() == ny + 2 + nl) {
      // One level behind: its own energy (solve scales Y by √(E/E_start)); two: the secant's at E.
      predictor.energy = b.levels.size() >= 2 ? energy : b.levels.back().energy;
      predictor.coefficients = spectral::as_coefficients(guess.head(ny), n_);
      predictor.frequency_hz = guess(ny);
      predictor.multipliers = guess.segment(ny + 1, nl);
      predictor.equality_multiplier = guess(ny + 1 + nl);
      start = &predictor;
    }
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    // The level gets what is left of the budget; a level cut by it is no failed attempt.
    ModeLevel level = solve(energy, start, o.max_wall_time_s > 0.0 ? std::max(o.max_wall_time_s - elapsed, 1e-300) : 0.0);
    Correction c;
    c.status = level.status;
    c.iterations = level.powell_iterations;
    c.residual_norm = level.residual_norm;
    c.message = level.message;
    const bool cut = o.max_wall_time_s > 0.0 &&
                     std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() >= o.max_wall_time_s;
    c.interrupted = !c.converged() && cut;
    if (c.converged()) {
      c.x = pack(level);
      pending = std::move(level);
    } else if (!cut) {
      b.failed_energies.push_back(energy);
    }
    return c;
  };
  NaturalParameterOptions np;
  np.parameter_name = "E";
  np.parameter_min = o.energy_min;
  np.parameter_max = o.energy_max;
  np.initial_step = o.initial_step;
  np.min_step = o.min_step;
  np.max_step = o.max_step;
  np.max_wall_time_s = o.max_wall_time_s;
  np.land_on = include;
  np.grow = [](double h, int powell_iterations) { return powell_iterations <= 8 ? 1.5 * h : h; };
  np.on_point = [&](size_t, const BranchPoint&) {
    b.levels.push_back(std::move(pending));
    if (o.on_level) o.on_level(b.levels.back());
  };
  const Branch branch = natural_parameter(correct, Eigen::VectorXd(), o.energy_min, np);
  b.stop = branch.stop;
  b.rejected_steps = branch.rejected_steps;
  b.status = branch_status(branch.stop);
  if (branch.stop == StopReason::InitialPointFailed) {
    b.message = "the first level E = " + format_number(o.energy_min) + " did not converge: " + branch.message;
  } else if (branch.stop == StopReason::TimeBudget) {
    b.message = branch.message + "; raise BackboneOptions::max_wall_time_s (0: no budget)";
  } else if (branch.stop == StopReason::StepBelowMinimum) {
    b.message = "energy " + branch.message;
  } else {
    b.message = branch.message;
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

}  // namespace wbm::solvers
