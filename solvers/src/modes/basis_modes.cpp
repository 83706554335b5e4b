// Nonlinear normal modes with exact contact in any time basis: LL11's KKT conditions in the
// Galerkin form of a TimeBasis, continued in energy (basis_modes.hpp, issue #38 item 5).
#include <wbm/solvers/basis_modes.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include <Eigen/QR>
#include <unsupported/Eigen/KroneckerProduct>

#include <wbm/solvers/continuation.hpp>

#include "modes/backbone_arclength.hpp"

namespace wbm::solvers {

void BasisModeOptions::validate() const {
  if (samples < 0) {
    throw std::invalid_argument("BasisModeOptions.samples = " + std::to_string(samples) +
                                ": must be >= 0 (0: one instant per basis function, m = M)");
  }
  if (sample_offset && !(*sample_offset >= 0.0 && *sample_offset < 1.0)) {
    throw std::invalid_argument("BasisModeOptions.sample_offset = " + format_number(*sample_offset) +
                                ": must lie in [0, 1) (0.5: midpoints), or be unset");
  }
}

const BasisModeLevel* BasisBackbone::included_at(double energy) const {
  const auto it = std::find_if(included.begin(), included.end(), [&](const BasisModeLevel& l) {
    return std::abs(l.level.energy - energy) <= 1e-12 * std::abs(energy);
  });
  return it == included.end() ? nullptr : &*it;
}

namespace {

bool is_haar(const TimeBasis& basis) {
  const auto* w = basis.wavelet_basis();
  return w != nullptr && w->family().kind == wavelets::FamilyKind::Haar;
}

// B = (1/4π²) ∫ q̇_j q̇_k: exact operators, or Haar's delta pairs in box form (basis_modes.hpp):
// with V(k, j) = q_j at the midpoint of cell k and Δ the periodic backward difference,
// ∫ u̇² = M ‖Δ V a‖², so B = M (ΔV)ᵀ(ΔV)/4π².
Eigen::SparseMatrix<double> velocity_operator(const TimeBasis& basis) {
  const double c = 1.0 / (4.0 * std::numbers::pi * std::numbers::pi);
  if (is_haar(basis)) {
    const int m = basis.dimension();
    const Eigen::MatrixXd v = basis.grid_values(m, true);
    Eigen::MatrixXd dv(m, m);
    for (int k = 0; k < m; ++k) dv.row(k) = v.row(k) - v.row((k + m - 1) % m);
    return (c * m * (dv.transpose() * dv)).sparseView(1.0, 1e-14);
  }
  try {
    return c * basis.exact_operator(1, 1);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("BasisModes: the basis " + basis.name() + " has no ∫ q̇_j q̇_k (" + e.what() +
                                "); nonlinear modes need the kinetic energy: use Fourier, B-spline, DB6 (or a "
                                "smoother Daubechies family) or Haar (delta-pair velocity)");
  }
}

}  // namespace

BasisModes::BasisModes(const NonlinearModes& problem, TimeBasis basis, BasisModeOptions options)
    : system_(problem.system()), stops_(problem.stops()), basis_(std::move(basis)) {
  options.validate();
  n_ = problem.dofs();
  dim_ = basis_.dimension();
  samples_ = options.samples == 0 ? dim_ : options.samples;
  if (dim_ < 2) {
    throw std::invalid_argument("BasisModes: the basis " + basis_.name() + " has M = " + std::to_string(dim_) +
                                " function: a periodic orbit needs M >= 2 (use 16 or more)");
  }
  if (samples_ < dim_) {
    throw std::invalid_argument("BasisModeOptions.samples = " + std::to_string(samples_) + ": must be >= M = " +
                                std::to_string(dim_) + " (the basis' functions), or 0 for m = M");
  }
  if (static_cast<double>(samples_) * dim_ > 16777216.0) {
    throw std::invalid_argument("BasisModes: m × M = " + std::to_string(samples_) + " × " + std::to_string(dim_) +
                                " exceeds 2^24 (the instants' values, 128 MiB); use a smaller M or samples = 0");
  }
  phase_dof_ = problem.phase_dof();
  omega0_ = 2.0 * std::numbers::pi * problem.linear_frequency_hz();
  g_ref_ = stops_[static_cast<size_t>(problem.onset_stop())].gap;
  onset_ = problem.onset_mode();
  const Eigen::VectorXd on = onset_ / g_ref_;
  m_ref_ = on.dot(system_.mass * on);  // 2 m̂_c / g_ref² [kg]
  b_ = velocity_operator(basis_);
  a0_ = basis_.exact_operator(0, 0);
  ks_ = system_.stiffness / (omega0_ * omega0_ * m_ref_);
  ms_ = system_.mass / m_ref_;
  stiffness_ = Eigen::SparseMatrix<double>(Eigen::kroneckerProduct(a0_, ks_));
  inertia_ = Eigen::SparseMatrix<double>(Eigen::kroneckerProduct(b_, ms_));
  stiffness_.makeCompressed();
  inertia_.makeCompressed();
  Eigen::VectorXd tau(samples_);
  offset_ = options.sample_offset.value_or(is_haar(basis_) ? 0.5 : 0.0);
  for (int s = 0; s < samples_; ++s) tau(s) = (s + offset_) / samples_;
  theta_ = basis_.values(tau, 0);
  const int p = 16 * dim_;
  const Eigen::MatrixXd v = basis_.grid_values(p, true);
  Eigen::VectorXd sine(p);
  for (int i = 0; i < p; ++i) sine(i) = std::sin(2.0 * std::numbers::pi * (i + 0.5) / p);
  phase_ = v.transpose() * sine / p;
  ny_ = static_cast<Eigen::Index>(n_) * dim_;
  size_ = ny_ + 1 + static_cast<Eigen::Index>(stops_.size()) * samples_ + 1;
}

BasisModes::Unpacked BasisModes::unpack(const Eigen::VectorXd& x) const {
  if (x.size() != size_) {
    throw std::invalid_argument("BasisModes: state of length " + std::to_string(x.size()) + ", expected " +
                                std::to_string(size_));
  }
  Unpacked u;
  u.y = Eigen::Map<const Eigen::MatrixXd>(x.data(), n_, dim_);
  const auto ms = static_cast<Eigen::Index>(samples_);
  u.g.resize(static_cast<Eigen::Index>(stops_.size()) * ms);
  for (size_t c = 0; c < stops_.size(); ++c) {
    Eigen::RowVectorXd row = Eigen::RowVectorXd::Zero(dim_);
    for (const auto& [j, w] : stops_[c].terms()) row += w * u.y.row(j);
    u.g.segment(static_cast<Eigen::Index>(c) * ms, ms) = (theta_ * row.transpose()).array() - stops_[c].gap / g_ref_;
  }
  u.lambda = x.segment(ny_ + 1, u.g.size());
  return u;
}

void BasisModes::check(const ActiveSet& active) const {
  const auto expected = stops_.size() * static_cast<size_t>(samples_);
  if (active.size() != expected) {
    throw std::invalid_argument("BasisModes: active set of length " + std::to_string(active.size()) + ", expected " +
                                std::to_string(expected) + " (stops × samples)");
  }
}

Eigen::VectorXd BasisModes::residual(const Eigen::VectorXd& x, double energy) const {
  return evaluate(x, energy, false, nullptr).residual;
}
SparseLinearization BasisModes::linearize(const Eigen::VectorXd& x, double energy) const {
  return evaluate(x, energy, true, nullptr);
}
Eigen::VectorXd BasisModes::residual(const Eigen::VectorXd& x, double energy, const ActiveSet& active) const {
  check(active);
  return evaluate(x, energy, false, &active).residual;
}
SparseLinearization BasisModes::linearize(const Eigen::VectorXd& x, double energy, const ActiveSet& active) const {
  check(active);
  return evaluate(x, energy, true, &active);
}

ActiveSet BasisModes::active_set(const Eigen::VectorXd& x, double /*energy*/) const {
  const Unpacked u = unpack(x);
  ActiveSet a(static_cast<size_t>(u.g.size()));
  for (Eigen::Index i = 0; i < u.g.size(); ++i) a[static_cast<size_t>(i)] = !(u.lambda(i) <= -u.g(i));
  return a;
}

Eigen::VectorXd BasisModes::events(const Eigen::VectorXd& x, double /*energy*/, const ActiveSet& active) const {
  check(active);
  const Unpacked u = unpack(x);
  Eigen::VectorXd e(u.g.size());
  for (Eigen::Index i = 0; i < u.g.size(); ++i) e(i) = active[static_cast<size_t>(i)] != 0 ? u.lambda(i) : -u.g(i);
  return e;
}

SparseLinearization BasisModes::evaluate(const Eigen::VectorXd& x, double energy, bool jacobian,
                                         const ActiveSet* active) const {
  const Unpacked u = unpack(x);
  const double s = x(ny_), sigma = x(size_ - 1);
  const Eigen::Index ms = samples_, nc = static_cast<Eigen::Index>(stops_.size());
  auto picks_gap = [&](Eigen::Index i) {
    return active != nullptr ? (*active)[static_cast<size_t>(i)] != 0 : !(u.lambda(i) <= -u.g(i));
  };
  const Eigen::Map<const Eigen::VectorXd> y(x.data(), ny_);
  const Eigen::VectorXd ky = stiffness_ * y, my = inertia_ * y;
  SparseLinearization out;
  out.residual.resize(size_);
  Eigen::MatrixXd galerkin = Eigen::Map<const Eigen::MatrixXd>(Eigen::VectorXd(ky - s * my).data(), n_, dim_);
  for (Eigen::Index c = 0; c < nc; ++c) {  // Σ_s Θ(s, :)ᵀ f_cs along e_c
    const Eigen::RowVectorXd force = (theta_.transpose() * u.lambda.segment(c * ms, ms)).transpose();
    for (const auto& [j, w] : stops_[static_cast<size_t>(c)].terms()) galerkin.row(j) += w * force;
  }
  galerkin.row(phase_dof_) += sigma * phase_.transpose();
  out.residual.head(ny_) = Eigen::Map<const Eigen::VectorXd>(galerkin.data(), ny_);
  out.residual(ny_) = 2.0 * y.dot(my) - energy;
  for (Eigen::Index i = 0; i < nc * ms; ++i) {
    out.residual(ny_ + 1 + i) =
        active != nullptr ? (picks_gap(i) ? -u.g(i) : u.lambda(i)) : std::min(u.lambda(i), -u.g(i));
  }
  out.residual(size_ - 1) = u.y.row(phase_dof_).dot(phase_);
  out.parameter_derivative = Eigen::VectorXd::Zero(size_);
  out.parameter_derivative(ny_) = -1.0;
  if (!jacobian) return out;

  std::vector<Eigen::Triplet<double>> t;
  const Eigen::SparseMatrix<double> galerkin_jacobian = stiffness_ - s * inertia_;
  t.reserve(static_cast<size_t>(galerkin_jacobian.nonZeros() + 4 * ny_ + 2 * nc * ms * dim_ + 2 * dim_));
  for (int k = 0; k < galerkin_jacobian.outerSize(); ++k) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(galerkin_jacobian, k); it; ++it) {
      t.emplace_back(it.row(), it.col(), it.value());
    }
  }
  for (Eigen::Index i = 0; i < ny_; ++i) {
    t.emplace_back(i, ny_, -my(i));       // ∂/∂(ω²/ω₀²)
    t.emplace_back(ny_, i, 4.0 * my(i));  // ∂(m̂/m̂_c)/∂y
  }
  for (Eigen::Index c = 0; c < nc; ++c) {
    const auto terms = stops_[static_cast<size_t>(c)].terms();
    for (Eigen::Index smp = 0; smp < ms; ++smp) {
      const Eigen::Index i = c * ms + smp, col = ny_ + 1 + i;
      const bool gap_row = picks_gap(i);
      if (!gap_row) t.emplace_back(col, col, 1.0);
      for (int k = 0; k < dim_; ++k) {
        const double th = theta_(smp, k);
        if (th == 0.0) continue;  // compact support
        for (const auto& [d, w] : terms) {
          const Eigen::Index row = static_cast<Eigen::Index>(k) * n_ + d;
          t.emplace_back(row, col, w * th);
          if (gap_row) t.emplace_back(col, row, -w * th);
        }
      }
    }
  }
  for (int k = 0; k < dim_; ++k) {
    if (phase_(k) == 0.0) continue;
    const Eigen::Index row = static_cast<Eigen::Index>(k) * n_ + phase_dof_;
    t.emplace_back(row, size_ - 1, phase_(k));
    t.emplace_back(size_ - 1, row, phase_(k));
  }
  out.jacobian.resize(size_, size_);
  out.jacobian.setFromTriplets(t.begin(), t.end());
  return out;
}

Eigen::VectorXd BasisModes::linear_guess(double energy) const {
  const int p = 4 * dim_;
  const Eigen::MatrixXd v = basis_.grid_values(p, true);
  Eigen::VectorXd cosine(p);
  for (int i = 0; i < p; ++i) cosine(i) = std::cos(2.0 * std::numbers::pi * (i + 0.5) / p);
  const Eigen::VectorXd a = v.colPivHouseholderQr().solve(cosine);  // cos 2πτ ≈ Σ_k a_k q_k
  Eigen::VectorXd x = Eigen::VectorXd::Zero(size_);
  Eigen::Map<Eigen::MatrixXd> ym(x.data(), n_, dim_);
  ym = (onset_ / g_ref_) * a.transpose();
  const Eigen::Map<const Eigen::VectorXd> y(x.data(), ny_);
  ym *= std::sqrt(energy / (2.0 * y.dot(inertia_ * y)));
  x(ny_) = y.dot(stiffness_ * y) / y.dot(inertia_ * y);  // Rayleigh quotient, ω²/ω₀²
  return x;
}

BasisModeLevel BasisModes::level(const Eigen::VectorXd& x, double energy, double tolerance) const {
  Unpacked u = unpack(x);
  BasisModeLevel out;
  ModeLevel& l = out.level;
  l.energy = energy;
  l.residual_norm = residual(x, energy).norm();
  l.tolerance = tolerance;
  l.status = !std::isfinite(l.residual_norm) ? SolveStatus::NonFinite
             : l.residual_norm <= tolerance  ? SolveStatus::Converged
                                             : SolveStatus::MaxIterations;
  l.coefficients = u.y * g_ref_;
  l.frequency_hz = std::sqrt(std::max(0.0, x(ny_))) * omega0_ / (2.0 * std::numbers::pi);
  const Eigen::Map<const Eigen::VectorXd> y(x.data(), ny_);
  const double kh = y.dot(stiffness_ * y), mh = y.dot(inertia_ * y);
  l.rayleigh_frequency_hz = std::sqrt(kh / mh) * omega0_ / (2.0 * std::numbers::pi);
  l.normalization_error = std::abs(2.0 * mh - energy);
  // An inactive sample (the min picks f_s) has f_s = 0; what Newton left there is rounding.
  for (Eigen::Index i = 0; i < u.lambda.size(); ++i) {
    if (u.lambda(i) <= -u.g(i)) u.lambda(i) = 0.0;
  }
  l.contact_force = u.lambda * (samples_ * omega0_ * omega0_ * m_ref_ * g_ref_);
  l.max_penetration = u.g.maxCoeff();
  const double lmax = u.lambda.maxCoeff();
  l.complementarity = lmax > 0.0 ? (u.lambda.array() * u.g.array()).abs().maxCoeff() / lmax : 0.0;
  l.inequality_measure = std::max(0.0, l.max_penetration);
  l.equality_measure = l.normalization_error;
  l.message = std::string(to_string(l.status)) + ": KKT residual ‖R‖₂ = " + format_number(l.residual_norm) +
              " (tolerance " + format_number(tolerance) + ")";
  out.phase_multiplier = x(size_ - 1);
  return out;
}

BasisBackbone BasisModes::continue_backbone(const BackboneContinuationOptions& o) const {
  o.validate();
  auto refuse = [](const std::string& what) {
    throw std::invalid_argument("BasisModes::continue_backbone: " + what +
                                " is not offered in a time basis; use NonlinearModes::continue_backbone");
  };
  if (o.start) refuse("a start orbit (options.start)");
  if (o.penalty_stiffness > 0.0) refuse("a penalty stiffness (options.penalty_stiffness)");
  if (!(o.energy_min < 1.0)) {
    throw std::invalid_argument("BackboneContinuationOptions.energy_min = " + format_number(o.energy_min) +
                                ": a backbone in a time basis starts on the linear mode below contact onset; "
                                "set energy_min < 1 (e.g. 0.5)");
  }
  const auto t0 = std::chrono::steady_clock::now();
  const Branch branch =
      pseudo_arclength(*this, linear_guess(o.energy_min), o.energy_min, detail::backbone_arclength(o, 0.5 * o.energy_min));
  BasisBackbone b;
  for (const auto& pt : branch.points) {
    if (pt.parameter > o.energy_max) break;  // the landing at energy_max below replaces it
    BasisModeLevel l = level(pt.x, pt.parameter, o.tolerance);
    l.level.newton_iterations = pt.corrector_iterations;
    b.levels.push_back(std::move(l));
  }
  bool reached_end = false;
  for (const auto& landing : branch.landings) {
    BasisModeLevel l = level(landing.x, landing.parameter, o.tolerance);
    l.level.newton_iterations = landing.corrector_iterations;
    if (landing.parameter == o.energy_max) {
      reached_end = l.level.converged();
      b.levels.push_back(l);
    }
    if (std::find(o.include.begin(), o.include.end(), landing.parameter) != o.include.end()) {
      b.included.push_back(std::move(l));
    }
  }
  b.kinks = branch.events;
  b.rejected_steps = branch.rejected_steps;
  b.stop = branch.stop;
  b.status = reached_end && branch.stop == StopReason::RangeReached ? SolveStatus::Converged : SolveStatus::PathEnded;
  b.message = std::string(to_string(branch.stop)) + ": " + branch.message;
  if (branch.stop == StopReason::Retraced) {
    b.message += "; a corner where two Signorini instants switch almost together can close such a loop: "
                 "move the instants (BasisModeOptions::sample_offset, 0 for LL11's τ_s = s/m) or change M";
  }
  b.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return b;
}

Eigen::MatrixXd BasisModes::displacement(const BasisModeLevel& level, int samples) const {
  if (samples < 1) throw std::invalid_argument("BasisModes::displacement: samples = " + std::to_string(samples) + ": must be >= 1");
  if (level.level.coefficients.rows() != n_ || level.level.coefficients.cols() != dim_) {
    throw std::invalid_argument("BasisModes::displacement: coefficients " +
                                std::to_string(level.level.coefficients.rows()) + " × " +
                                std::to_string(level.level.coefficients.cols()) + ": need " + std::to_string(n_) +
                                " × " + std::to_string(dim_));
  }
  return level.level.coefficients * basis_.grid_values(samples, false).transpose();
}

}  // namespace wbm::solvers
