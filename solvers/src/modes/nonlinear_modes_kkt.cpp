// Nonlinear modes by pseudo-arclength continuation of the KKT conditions (harmonic-balance form):
// BackboneSystem, level_at and continue_backbone [LL11 Eqs. (21)–(24), nonlinear_modes.hpp].
#include <wbm/solvers/nonlinear_modes.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include <Eigen/Eigenvalues>

#include <wbm/solvers/natural_parameter.hpp>

#include <wbm/spectral/fourier_basis.hpp>
#include <wbm/spectral/layout.hpp>

#include "core/triplet_pattern.hpp"
#include "modes/backbone_arclength.hpp"

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
  if (direction != 1 && direction != -1) fail("direction = " + std::to_string(direction) + ": must be +1 or -1");
  if (start && (!(start->frequency_hz > 0.0) || !std::isfinite(start->frequency_hz))) {
    fail("start.frequency_hz = " + format_number(start->frequency_hz) + ": must be > 0 [Hz]");
  }
  if (!(start_penalty_stiffness >= 0.0) || !std::isfinite(start_penalty_stiffness)) {
    fail("start_penalty_stiffness = " + format_number(start_penalty_stiffness) +
         ": must be >= 0 [N/m] (0: no homotopy)");
  }
  if (start_penalty_stiffness > 0.0 && (!start || penalty_stiffness > 0.0)) {
    fail("start_penalty_stiffness = " + format_number(start_penalty_stiffness) +
         ": a homotopy to exact contact needs a start orbit and exact contact (penalty_stiffness = 0, here " +
         format_number(penalty_stiffness) + "); set it to 0 or give a start");
  }
}

namespace {

// The backbone system at fixed E as a square system for the Newton core.
struct FixedEnergy {
  const NonlinearModes::BackboneSystem* s;
  double energy;
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x) const { return s->residual(x, energy); }
  [[nodiscard]] Eigen::SparseMatrix<double> jacobian(const Eigen::VectorXd& x) const {
    return s->linearize(x, energy).jacobian;
  }
};

// Semismooth Newton at fixed E (the system's KktSolver), without line search unless asked (a
// start far from the branch).
NewtonResult solve_at(const NonlinearModes::BackboneSystem& system, Eigen::VectorXd x, double energy,
                      const BackboneContinuationOptions& o, bool line_search = false, double tolerance = 0.0) {
  auto solver = system.linear_solver();
  return newton(FixedEnergy{&system, energy}, std::move(x),
                {.tolerance = tolerance > 0.0 ? tolerance : o.tolerance, .max_iterations = o.max_newton_iterations,
                 .line_search = line_search},
                solver);
}

// The Newton homotopy [Allgower & Georg 1990, Sec. 1.2] at fixed E from x₀:
//   H(x, t) = R(x) − (1 − t) R(x₀) = 0,  t from 0 (x = x₀, exactly) to 1 (R(x) = 0),
// stepped in t by natural_parameter (steps of at most 1/4, halved after a failure down to 1e-4),
// each stage semismooth Newton without line search from the last. It follows the solution
// connected to x₀ instead of letting a line search decide, at a kink, where a far start goes.
// The result: the Newton result at t = 1, or a MaxIterations result whose report.message says
// where the stepping in t stopped.
NewtonResult newton_homotopy(const NonlinearModes::BackboneSystem& system, Eigen::VectorXd x0, double energy,
                             const BackboneContinuationOptions& o, double tolerance) {
  struct Offset {
    const NonlinearModes::BackboneSystem* s;
    double energy;
    Eigen::VectorXd offset;
    [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x) const { return s->residual(x, energy) - offset; }
    [[nodiscard]] Eigen::SparseMatrix<double> jacobian(const Eigen::VectorXd& x) const {
      return s->linearize(x, energy).jacobian;
    }
  };
  const Eigen::VectorXd r0 = system.residual(x0, energy);
  NewtonResult last;
  last.x = x0;
  auto correct = [&](double t, Eigen::VectorXd guess) {
    auto solver = system.linear_solver();
    last = newton(Offset{&system, energy, (1.0 - t) * r0}, std::move(guess),
                  {.tolerance = tolerance, .max_iterations = o.max_newton_iterations, .line_search = false}, solver);
    return to_correction(NewtonResult(last));
  };
  NaturalParameterOptions np;
  np.parameter_name = "t (Newton homotopy)";
  np.parameter_min = 0.0;
  np.parameter_max = 1.0;
  np.initial_step = 0.25;
  np.max_step = 0.25;
  np.min_step = 1e-4;
  const Branch branch = natural_parameter(
      correct, [](const Branch& br, double) { return br.points.back().x; }, x0, 0.0, np);
  if (branch.stop == StopReason::RangeReached && branch.points.back().parameter == 1.0) {
    last.x = branch.points.back().x;
    return last;
  }
  last.x = branch.points.back().x;
  last.report.status = SolveStatus::MaxIterations;
  last.report.message = "Newton homotopy from the start: " + branch.message;
  return last;
}

}  // namespace

NonlinearModes::BackboneSystem::BackboneSystem(const NonlinearModes& modes, double penalty_stiffness)
    : nm_(&modes), pattern_(std::make_shared<const detail::TripletPattern>()) {
  if (!(penalty_stiffness >= 0.0) || !std::isfinite(penalty_stiffness)) {
    throw std::invalid_argument("BackboneSystem: penalty_stiffness = " + format_number(penalty_stiffness) +
                                ": must be >= 0 [N/m]");
  }
  const auto& o = modes.options_;
  penalty_ = penalty_stiffness / (o.samples * modes.omega0_ * modes.omega0_ * modes.m_ref_);
  if (penalty_ > 0.0) penalty_law_.emplace(contact::LinearPenaltyParameters{.stiffness = penalty_, .gap = 0.0});
  ny_ = static_cast<Eigen::Index>(modes.n_) * modes.f_ - 1;
  size_ = ny_ + 1 + (penalty_ > 0.0 ? 0 : static_cast<Eigen::Index>(modes.stops_.size()) * o.samples);
  if (penalty_ == 0.0) exact_layout_ = make_exact_layout();
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

Eigen::VectorXd NonlinearModes::BackboneSystem::state(const Eigen::MatrixXd& coefficients, double frequency_hz) const {
  const auto& nm = *nm_;
  if (coefficients.rows() != nm.n_ || coefficients.cols() < 1 || !coefficients.allFinite()) {
    throw std::invalid_argument("BackboneSystem::state: coefficients " + std::to_string(coefficients.rows()) + " × " +
                                std::to_string(coefficients.cols()) + ": need " + std::to_string(nm.n_) +
                                " rows (one per DOF), at least one column, finite values");
  }
  if (!(frequency_hz > 0.0) || !std::isfinite(frequency_hz)) {
    throw std::invalid_argument("BackboneSystem::state: frequency_hz = " + format_number(frequency_hz) + ": must be > 0");
  }
  const Eigen::Index keep = std::min<Eigen::Index>(coefficients.cols(), nm.f_);
  Eigen::MatrixXd y = Eigen::MatrixXd::Zero(nm.n_, nm.f_);
  y.leftCols(keep) = coefficients.leftCols(keep) / nm.g_ref_;
  // Time shift τ → τ + θ₀/2π: (a_k, b_k) of harmonic k rotate by k θ₀, θ₀ = atan2(b₁, a₁) at the phase DOF.
  const Eigen::Index c = nm.phase_index_ - 2 * static_cast<Eigen::Index>(nm.n_);
  const double theta0 = std::atan2(y(c, 2), y(c, 1));
  for (int k = 1; k <= nm.n_harm_; ++k) {
    const double cs = std::cos(k * theta0), sn = std::sin(k * theta0);
    const Eigen::VectorXd a = y.col(2 * k - 1), b = y.col(2 * k);
    y.col(2 * k - 1) = a * cs + b * sn;
    y.col(2 * k) = b * cs - a * sn;
  }
  const Eigen::VectorXd full = spectral::stacked(y);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(size_);
  x.head(nm.phase_index_) = full.head(nm.phase_index_);
  x.segment(nm.phase_index_, ny_ - nm.phase_index_) = full.tail(ny_ - nm.phase_index_);
  const double ratio = 2.0 * std::numbers::pi * frequency_hz / nm.omega0_;
  x(ny_) = ratio * ratio;
  return x;
}

NonlinearModes::BackboneSystem::Unpacked NonlinearModes::BackboneSystem::unpack(const Eigen::VectorXd& x,
                                                                              const ActiveSet* active) const {
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
  u.g = nm.gaps(ym);
  if (penalty_ == 0.0) {
    u.lambda = x.tail(n_stops * ms);
  } else {  // λ = κ (g)₊ with g the normalized gap function: contact's linear penalty at gap 0
    u.lambda.resize(u.g.size());
    u.penalty_stiffness.resize(u.g.size());
    penalty_law_->evaluate(u.g, u.lambda, u.penalty_stiffness);
    if (active != nullptr) {  // the piece's branch of the law, whatever the sign of g
      for (Eigen::Index i = 0; i < u.g.size(); ++i) {
        const bool on = (*active)[static_cast<size_t>(i)] != 0;
        u.penalty_stiffness(i) = on ? penalty_ : 0.0;
        u.lambda(i) = on ? penalty_ * u.g(i) : 0.0;
      }
    }
  }
  return u;
}

Eigen::VectorXd NonlinearModes::BackboneSystem::residual(const Eigen::VectorXd& x, double energy) const {
  return evaluate(x, energy, false).residual;
}

SparseLinearization NonlinearModes::BackboneSystem::linearize(const Eigen::VectorXd& x, double energy) const {
  return evaluate(x, energy, true);
}

void NonlinearModes::BackboneSystem::check(const ActiveSet& active) const {
  const auto expected = nm_->stops_.size() * static_cast<size_t>(nm_->options_.samples);
  if (active.size() != expected) {
    throw std::invalid_argument("BackboneSystem: active set of length " + std::to_string(active.size()) +
                                ", expected " + std::to_string(expected) + " (stops × samples)");
  }
}

ActiveSet NonlinearModes::BackboneSystem::active_set(const Eigen::VectorXd& x, double /*energy*/) const {
  const Unpacked u = unpack(x);
  ActiveSet a(static_cast<size_t>(u.g.size()));
  for (Eigen::Index i = 0; i < u.g.size(); ++i) {
    // The branch the nonsmooth residual picks (evaluate: λ <= −g picks λ, i.e. inactive).
    a[static_cast<size_t>(i)] = penalty_ > 0.0 ? static_cast<std::uint8_t>(u.g(i) > 0.0)
                                               : static_cast<std::uint8_t>(!(u.lambda(i) <= -u.g(i)));
  }
  return a;
}

Eigen::VectorXd NonlinearModes::BackboneSystem::residual(const Eigen::VectorXd& x, double energy,
                                                         const ActiveSet& active) const {
  check(active);
  return evaluate(x, energy, false, &active).residual;
}

SparseLinearization NonlinearModes::BackboneSystem::linearize(const Eigen::VectorXd& x, double energy,
                                                              const ActiveSet& active) const {
  check(active);
  return evaluate(x, energy, true, &active);
}

Eigen::VectorXd NonlinearModes::BackboneSystem::events(const Eigen::VectorXd& x, double /*energy*/,
                                                       const ActiveSet& active) const {
  check(active);
  const Unpacked u = unpack(x, &active);
  Eigen::VectorXd e(u.g.size());
  for (Eigen::Index i = 0; i < u.g.size(); ++i) {
    const bool on = active[static_cast<size_t>(i)] != 0;
    e(i) = penalty_ > 0.0 ? (on ? u.g(i) : -u.g(i)) : (on ? u.lambda(i) : -u.g(i));
  }
  return e;
}

SparseLinearization NonlinearModes::BackboneSystem::evaluate(const Eigen::VectorXd& x, double energy,
                                                             bool jacobian, const ActiveSet* active) const {
  const auto& nm = *nm_;
  const int n = nm.n_, f = nm.f_, ms = nm.options_.samples;
  const Eigen::Index p = nm.phase_index_;
  const Unpacked state = unpack(x, active);
  const Eigen::VectorXd& g = state.g;
  const Eigen::VectorXd& lambda = state.lambda;
  // Whether sample i's Signorini row is −g_s (active) or f_s (inactive): the piece's, or the min's.
  auto picks_gap = [&](Eigen::Index i) {
    return active != nullptr ? (*active)[static_cast<size_t>(i)] != 0 : !(lambda(i) <= -g(i));
  };
  const Eigen::Map<const Eigen::MatrixXd> ym(state.y.data(), n, f);
  const double s = x(ny_);
  const bool exact = penalty_ == 0.0;
  const auto n_stops = static_cast<Eigen::Index>(nm.stops_.size());

  // Harmonic balance rows, full size: w_k (K̂ − ν_k² s M̂) Y_k + Σ_s θ_sk λ_s e_c.
  const Eigen::MatrixXd ky = nm.ks_ * ym, my = nm.ms_ * ym;
  Eigen::MatrixXd hb(n, f);
  for (int k = 0; k < f; ++k) hb.col(k) = nm.weight_(k) * (ky.col(k) - nm.nu_(k) * nm.nu_(k) * s * my.col(k));
  nm.add_contact_forces(hb, lambda);  // Θᵀλ_c along each stop's direction
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
    for (Eigen::Index i = 0; i < n_stops * ms; ++i) {
      out.residual(ny_ + 1 + i) = active != nullptr ? (picks_gap(i) ? -g(i) : lambda(i)) : std::min(lambda(i), -g(i));
    }
  }
  out.parameter_derivative = Eigen::VectorXd::Zero(size_);
  out.parameter_derivative(ny_) = -1.0;
  if (!jacobian) return out;

  // J (nonlinear_modes_kkt_jacobian.cpp), built in place and swapped in (Eigen 3.4's SparseMatrix
  // has no move assignment: operator= would copy it).
  ActiveSet gap_rows;  // exact contact: sample i's row is −g_s (1) or f_s (0)
  if (exact) {
    gap_rows.resize(static_cast<size_t>(n_stops * ms));
    for (Eigen::Index i = 0; i < n_stops * ms; ++i) gap_rows[static_cast<size_t>(i)] = picks_gap(i) ? 1 : 0;
  }
  Eigen::SparseMatrix<double> jacobian_matrix =
      exact ? exact_jacobian(my, s, gap_rows) : penalty_jacobian(my, s, state.penalty_stiffness);
  out.jacobian.swap(jacobian_matrix);
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
  const NewtonResult r = solve_at(system, std::move(x), energy, options);
  ModeLevel l = system.level(r.x, energy, options.tolerance);
  l.newton_iterations = r.report.iterations;
  if (!r.report.converged()) {
    l.status = r.report.status;
    l.message = "semismooth Newton at fixed E = " + format_number(energy) + ": " + r.report.message;
  }
  l.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return l;
}

std::optional<Eigen::VectorXd> NonlinearModes::homotopy_start(const BackboneSystem& exact, double energy,
                                                              const BackboneContinuationOptions& o, Backbone& b) const {
  // Natural-parameter continuation (natural_parameter.hpp) of the penalty orbit at fixed E in
  // μ = log₁₀(k/k₀), from k₀ to 10¹² k₀: steps of one decade, halved after a failure (a factor
  // below 1.2 is not tried), each orbit started from the last (constant predictor). Its goal:
  // after each penalty orbit, Signorini from it, the multipliers at its penalty forces
  // λ_s = κ (g_s)₊; the first that converges ends the homotopy.
  const double k0 = o.start_penalty_stiffness;
  const Eigen::Index ny = exact.size() - static_cast<Eigen::Index>(stops_.size()) * options_.samples;  // Y and ω²
  const double to_lambda = 1.0 / (options_.samples * omega0_ * omega0_ * m_ref_);  // k [N/m] → κ of λ = κ g₊
  auto stiffness = [&](double mu) { return k0 * std::pow(10.0, mu); };
  // Intermediate orbits are corrected to √tolerance only (the Signorini point is verified at
  // `tolerance`); the start orbit with a line search (it may be far from the branch: without
  // one, Newton can land on another mode's branch), the next stages without.
  const double stage_tolerance = std::sqrt(o.tolerance);
  bool first = true;
  std::string last_exact;
  auto correct = [&](double mu, Eigen::VectorXd guess) {
    const BackboneSystem penalty(*this, stiffness(mu));
    Eigen::VectorXd start = guess;
    NewtonResult rp = solve_at(penalty, std::move(guess), energy, o, first, stage_tolerance);
    if (first && !rp.report.converged()) {
      // Damped Newton from a far start can stall at a kink of the penalty law (a sample at
      // g = 0, where the piece's Newton direction need not decrease ‖R‖), and whether it does
      // depends on the start's last bits (the blade's N = 3 start at E = 3.6: stagnated as is,
      // converged with the start scaled by 1 + 1e-12). The Newton homotopy from the start instead.
      const int spent = rp.report.iterations;
      rp = newton_homotopy(penalty, std::move(start), energy, o, stage_tolerance);
      rp.report.iterations += spent;
    }
    first = false;
    Correction c;
    // A stage is converged to the stage tolerance √tol (its residual verified against it).
    const bool staged = !rp.report.residual_norms.empty() && rp.report.residual_norms.back() <= stage_tolerance;
    c.status = rp.report.converged() || staged ? SolveStatus::Converged : rp.report.status;
    c.iterations = rp.report.iterations;
    c.message = "the penalty orbit at k = " + format_number(stiffness(mu)) + " N/m, E = " + format_number(energy) +
                " did not converge (" + rp.report.brief() + ")";
    if (!rp.report.residual_norms.empty()) c.residual_norm = rp.report.residual_norms.back();
    c.x = rp.x;
    return c;
  };
  std::optional<Eigen::VectorXd> reached;
  NaturalParameterOptions np;
  np.parameter_name = "log10(k/k0)";
  np.parameter_min = 0.0;
  np.parameter_max = 12.0;
  np.initial_step = 1.0;
  np.max_step = 1.0;
  np.min_step = 0.5 * std::log10(1.2);  // a failed step below log₁₀ 1.2 ends it
  np.grow = [](double h, int) { return h; };
  np.goal = [&](const BranchPoint& point) {
    ++b.homotopy_stages;
    const double k = stiffness(point.parameter);
    const Eigen::VectorXd y = with_phase(point.x.head(ny - 1));
    const Eigen::Map<const Eigen::MatrixXd> ym(y.data(), n_, f_);
    Eigen::VectorXd xe(exact.size());
    xe.head(ny) = point.x;
    xe.tail(xe.size() - ny) = (k * to_lambda) * gaps(ym).cwiseMax(0.0);
    NewtonResult re = solve_at(exact, std::move(xe), energy, o);
    if (!re.report.converged()) {
      last_exact = "from k = " + format_number(k) + " N/m: " + re.report.brief();
      return false;
    }
    b.homotopy_stiffness = k;
    reached = std::move(re.x);
    return true;
  };
  const Eigen::VectorXd xp = BackboneSystem(*this, k0).state(o.start->coefficients, o.start->frequency_hz);
  const Branch branch = natural_parameter(
      correct, [](const Branch& br, double) { return br.points.back().x; }, xp, 0.0, np);
  if (reached) return reached;
  const std::string exact_note = last_exact.empty() ? std::string() : "; last Signorini attempt: " + last_exact;
  if (branch.stop == StopReason::RangeReached) {
    b.message = "penalty homotopy: Signorini did not converge from any penalty orbit up to k = " +
                format_number(stiffness(branch.points.back().parameter)) + " N/m (" +
                std::to_string(b.homotopy_stages) + " stages from " + format_number(k0) + " N/m)" + exact_note;
  } else {
    b.message = "penalty homotopy: " + branch.message + exact_note;
  }
  return std::nullopt;
}

Backbone NonlinearModes::continue_backbone(const BackboneContinuationOptions& o) const {
  o.validate();
  const auto t0 = std::chrono::steady_clock::now();
  const BackboneSystem system(*this, o.penalty_stiffness);
  Backbone b;
  // Start below contact on the linear mode (an exact solution); above onset, from the linear
  // mode corrected by Newton at fixed E; or from the orbit given, at its own energy.
  const double e0 = o.start ? energy(o.start->coefficients) : o.energy_min;
  if (o.start && !(e0 >= o.energy_min && e0 <= o.energy_max)) {
    throw std::invalid_argument("BackboneContinuationOptions.start: the orbit's energy E = " + format_number(e0) +
                                " lies outside [energy_min, energy_max] = [" + format_number(o.energy_min) + ", " +
                                format_number(o.energy_max) + "]; widen the range to include it");
  }
  Eigen::VectorXd x0;
  if (o.start_penalty_stiffness > 0.0) {
    auto reached = homotopy_start(system, e0, o, b);
    if (!reached) {
      b.stop = StopReason::InitialPointFailed;
      b.message = std::string(to_string(b.stop)) + ": " + b.message;
      b.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      return b;
    }
    x0 = std::move(*reached);
  } else {
    x0 = o.start ? system.state(o.start->coefficients, o.start->frequency_hz) : system.linear_state(std::min(e0, 1.0));
  }
  // BackboneSystem is a PiecewiseSmoothSystem: pseudo_arclength corrects on one piece (active
  // set) at a time and locates and crosses the events where samples switch (continuation.hpp).
  PseudoArclengthOptions pa = detail::backbone_arclength(o, o.start ? o.energy_min : 0.5 * e0);
  pa.direction = o.start ? o.direction : +1;
  if (o.start) pa.land_on.push_back(o.energy_min);
  Branch branch = pseudo_arclength(system, x0, e0, pa);
  auto landing = [&](double energy) -> const BranchPoint* {
    for (const auto& l : branch.landings) {
      if (l.parameter == energy) return &l;
    }
    return nullptr;
  };
  // A branch that comes back below contact onset after contact has retraced the backbone (the
  // linear mode is the only solution there): keep it up to where it turned back, and say so.
  bool retraced = false;
  double highest = 0.0;
  for (size_t k = 0; k < (o.start ? 0 : branch.points.size()); ++k) {
    const double e = branch.points[k].parameter;
    if (highest > 1.0 + 1e-6 && e < 1.0) {
      size_t top = 0;
      for (size_t j = 1; j < k; ++j) {
        if (branch.points[j].parameter > branch.points[top].parameter) top = j;
      }
      branch.points.resize(top + 1);
      std::erase_if(branch.folds, [&](const Fold& f) { return f.after >= top; });
      std::erase_if(branch.landings, [&](const BranchPoint& l) { return l.arclength > branch.points[top].arclength; });
      branch.stop = StopReason::Retraced;
      branch.message = "the branch turned back at a corner near E = " + format_number(branch.points[top].parameter) +
                       " and retraced the backbone down to the linear mode; kept up to that energy";
      retraced = true;
      break;
    }
    highest = std::max(highest, e);
  }
  for (const auto& pt : branch.points) {
    if (pt.parameter > o.energy_max || (o.start && pt.parameter < o.energy_min)) {
      // The last point overshoots the range: its end, as landed on.
      const double end = pt.parameter > o.energy_max ? o.energy_max : o.energy_min;
      if (const BranchPoint* l = landing(end)) {
        ModeLevel last = system.level(l->x, end, o.tolerance);
        last.newton_iterations = l->corrector_iterations;
        b.levels.push_back(std::move(last));
      }
      break;
    }
    ModeLevel l = system.level(pt.x, pt.parameter, o.tolerance);
    l.newton_iterations = pt.corrector_iterations;
    b.levels.push_back(std::move(l));
  }
  for (double e : o.include) {  // first passage of the branch through e, landed on by the continuation
    if (const BranchPoint* l = landing(e)) {
      ModeLevel level = system.level(l->x, e, o.tolerance);
      level.newton_iterations = l->corrector_iterations;
      b.included.push_back(std::move(level));
    }
  }
  for (const auto& fold : branch.folds) {
    b.folds.push_back(fold.parameter);
    b.fold_levels.push_back(system.level(fold.x, fold.parameter, o.tolerance));
  }
  b.kinks = branch.events;
  b.switches = branch.switches;
  b.rejected_steps = branch.rejected_steps;
  b.stop = branch.stop;
  b.stalled_residual = branch.stalled_residual;
  const bool complete = !retraced && branch.stop == StopReason::RangeReached && !b.levels.empty() &&
                        (b.levels.back().energy >= o.energy_max * (1.0 - 1e-12) ||
                         (o.start && b.levels.back().energy <= o.energy_min * (1.0 + 1e-12)));
  b.status = complete ? SolveStatus::Converged : SolveStatus::PathEnded;
  b.message = std::string(to_string(branch.stop)) + ": " + branch.message;
  if (b.homotopy_stages > 0) {
    b.message += "; started by a penalty homotopy (" + std::to_string(b.homotopy_stages) +
                 " penalty orbits, Signorini converged from k = " + format_number(b.homotopy_stiffness) + " N/m)";
  }
  b.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return b;
}

}  // namespace wbm::solvers
