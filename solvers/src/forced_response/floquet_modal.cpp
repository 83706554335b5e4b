// FloquetAnalysis (floquet.hpp): the monodromy stepping of floquet_stepping.hpp in the undamped
// modes' coordinates when the damping matrix is classical, set up once per branch.
#include <wbm/solvers/floquet.hpp>
#include <wbm/solvers/undamped_modes.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <utility>

#include <Eigen/Eigenvalues>
// GCC 12 reports a use after free inside Spectra's UpperHessenbergEigen (Eigen's aligned_free of
// a moved-from temporary) at -O3: a false positive of its late warning, in the library's code.
// Clang (the sanitizer build) has no such warning.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wuse-after-free"
#endif
#include <Spectra/GenEigsSolver.h>
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif

#include "floquet_stepping.hpp"
#include "modal_damping_structure.hpp"

namespace wbm::solvers {

// The modal state x = (q, p), q = Φᵀ M δu, p = q̇ / s (mode by mode, s_i its circular frequency,
// so that both halves of each mode's 2 × 2 flight are of order 1): u = Φ q, u̇ = Φ S p.
struct FloquetAnalysis::Modes {
  Eigen::MatrixXd phi;     // Φ, n × n, Φᵀ M Φ = I
  Eigen::ArrayXd omega2;   // ω_i² [rad²/s²], ≥ 0
  Eigen::ArrayXd damping;  // (Φᵀ C Φ)_ii [1/s]
  Eigen::ArrayXd scale;    // s_i [rad/s] > 0
  Eigen::MatrixXd b;       // e_cᵀ Φ, n_c × n
  Eigen::MatrixXd u;       // the kick per unit contact force, (0, −S⁻¹ Φᵀ e_c), 2n × n_c
  Eigen::MatrixXd mass_phi;  // M Φ (n × n), for the physical monodromy
};

namespace {

// e^{A t} of one mode, A = [[0, 1], [−ω², −d]] in (q, q̇), as the entries of the scaled flight
// (q, q̇/s): with μ = −d/2 and β² = d²/4 − ω², (A − μI)² = β² I, so
//   e^{At} = e^{μt} (ch I + sh (A − μI)),  ch = cosh βt, sh = sinh(βt)/β  (β² ≥ 0),
//                                          ch = cos νt,  sh = sin(νt)/ν   (ν² = −β² > 0),
// exact for every damping (rigid-body ω = 0 included: sh = t when d = 0).
struct ModalFlight {
  Eigen::ArrayXd a, b, c, d;  // rows q ← a q + b p, p ← c q + d p
};

ModalFlight modal_flight(const FloquetAnalysis::Modes& m, double t) {
  const Eigen::Index n = m.omega2.size();
  ModalFlight f{Eigen::ArrayXd(n), Eigen::ArrayXd(n), Eigen::ArrayXd(n), Eigen::ArrayXd(n)};
  for (Eigen::Index i = 0; i < n; ++i) {
    const double mu = -0.5 * m.damping(i), beta2 = 0.25 * m.damping(i) * m.damping(i) - m.omega2(i);
    double ch = 1.0, sh = t;  // without e^{μt}: `decay`, applied below
    double decay = std::exp(mu * t);
    if (beta2 < 0.0) {
      const double nu = std::sqrt(-beta2);
      ch = std::cos(nu * t);
      sh = std::sin(nu * t) / nu;
    } else if (beta2 > 0.0) {
      const double beta = std::sqrt(beta2);
      if (beta * t < 20.0) {
        ch = std::cosh(beta * t);
        sh = std::sinh(beta * t) / beta;
      } else {  // e^{μt} cosh βt as (e^{(μ+β)t} + e^{(μ−β)t}) / 2, without overflow
        const double up = std::exp((mu + beta) * t), down = std::exp((mu - beta) * t);
        ch = 0.5 * (up + down);
        sh = 0.5 * (up - down) / beta;
        decay = 1.0;
      }
    }
    const double e11 = decay * (ch + 0.5 * m.damping(i) * sh), e12 = decay * sh;
    const double e21 = -decay * m.omega2(i) * sh, e22 = decay * (ch - 0.5 * m.damping(i) * sh);
    f.a(i) = e11;
    f.b(i) = e12 * m.scale(i);
    f.c(i) = e21 / m.scale(i);
    f.d(i) = e22;
  }
  return f;
}

// floquet_stepping.hpp's linear part in modal coordinates: a flight costs O(n) per column.
struct ModalLinearPart {
  const FloquetAnalysis::Modes& modes;
  static constexpr bool kExactFreeRuns = true;
  [[nodiscard]] Eigen::Index states() const { return 2 * modes.phi.cols(); }
  [[nodiscard]] ModalFlight flight(double hs) const { return modal_flight(modes, hs); }
  void apply(const ModalFlight& f, Eigen::MatrixXd& z) const {  // one pass, in place
    const Eigen::Index n = modes.phi.cols();
    for (Eigen::Index j = 0; j < z.cols(); ++j) {
      double* q = z.col(j).data();
      double* p = q + n;
      for (Eigen::Index i = 0; i < n; ++i) {
        const double qi = q[i], pi = p[i];
        q[i] = f.a(i) * qi + f.b(i) * pi;
        p[i] = f.c(i) * qi + f.d(i) * pi;
      }
    }
  }
  [[nodiscard]] const Eigen::MatrixXd& u() const { return modes.u; }
  [[nodiscard]] Eigen::MatrixXd rows(const Eigen::MatrixXd& z) const { return modes.b * z.topRows(modes.phi.cols()); }
};

// Φ v for Arnoldi (Spectra's OpType): the stepping applied to one column, Φ never formed.
struct MonodromyProduct {
  using Scalar = double;
  const ModalLinearPart& linear;
  const std::vector<ContactPoint>& contacts;
  const Eigen::MatrixXd& contact_displacement;
  double frequency_hz;
  // 2n, and one state per Jenkins element (floquet_stepping.hpp)
  [[nodiscard]] Eigen::Index rows() const { return linear.states() + detail::jenkins_states(contacts); }
  [[nodiscard]] Eigen::Index cols() const { return rows(); }
  void perform_op(const double* x_in, double* y_out) const {
    const Eigen::MatrixXd v = Eigen::Map<const Eigen::VectorXd>(x_in, rows());
    Eigen::Map<Eigen::VectorXd>(y_out, rows()) =
        detail::stepped_monodromy(linear, contacts, contact_displacement, frequency_hz, &v);
  }
};

// The multipliers of largest modulus, sorted by decreasing modulus, enough that the last lies
// below kDominantBound: nev = 8 by Arnoldi (Spectra::GenEigsSolver, LargestMagn, tolerance 1e-10,
// its fixed starting vector), doubled while the last does not. Nothing when Arnoldi does not
// converge or would need nev + 2 > 2n (the caller then forms Φ).
constexpr double kDominantBound = 0.9;

std::optional<Eigen::VectorXcd> dominant_multipliers(const ModalLinearPart& linear,
                                                     const std::vector<ContactPoint>& contacts,
                                                     const Eigen::MatrixXd& contact_displacement, double frequency_hz) {
  MonodromyProduct op{linear, contacts, contact_displacement, frequency_hz};
  const Eigen::Index states = op.rows();
  for (Eigen::Index nev = 8; nev + 2 <= states; nev *= 2) {
    const Eigen::Index ncv = std::min(states, std::max<Eigen::Index>(2 * nev + 1, 20));
    Spectra::GenEigsSolver<MonodromyProduct> arnoldi(op, nev, ncv);
    arnoldi.init();
    arnoldi.compute(Spectra::SortRule::LargestMagn, 1000, 1e-10, Spectra::SortRule::LargestMagn);
    if (arnoldi.info() != Spectra::CompInfo::Successful) return std::nullopt;
    const Eigen::VectorXcd mu = arnoldi.eigenvalues();
    if (mu.size() > 0 && std::abs(mu(mu.size() - 1)) < kDominantBound) return mu;
  }
  return std::nullopt;
}

// The undamped modes of a classical C, or nothing (C not classical, M not positive definite).
std::shared_ptr<const FloquetAnalysis::Modes> modes_of(const MechanicalSystem& system,
                                                       const std::vector<ContactPoint>& contacts) {
  double c_m = 0.0, c_k = 0.0;
  const bool rayleigh = detail::rayleigh_fit(system, c_m, c_k);
  if (!rayleigh && !detail::classical_damping_probe(system)) return nullptr;
  UndampedModes modes;  // dense below 400 DOFs, O(n²) for a larger tridiagonal pencil
  try {
    modes = undamped_modes(system.stiffness, system.mass);
  } catch (const std::invalid_argument&) {
    return nullptr;
  }
  auto m = std::make_shared<FloquetAnalysis::Modes>();
  m->phi = std::move(modes.phi);
  const Eigen::Index n = m->phi.cols();
  const double largest = n > 0 ? modes.lambda.cwiseAbs().maxCoeff() : 0.0;
  // Eigenvalues below 1e-12 of the largest are rigid-body modes to rounding.
  m->omega2 = modes.lambda.array().unaryExpr([&](double l) { return l > 1e-12 * largest ? l : 0.0; });
  if (rayleigh) {
    m->damping = c_m + c_k * modes.lambda.array();
  } else {
    auto d = detail::modal_damping_of(system, m->phi);
    if (!d) return nullptr;
    m->damping = d->array();
  }
  const Eigen::ArrayXd omega = m->omega2.sqrt();
  const double fallback = n > 0 && omega.maxCoeff() > 0.0 ? omega.maxCoeff() : 1.0;
  m->scale = omega.unaryExpr([&](double w) { return w > 1e-6 * fallback ? w : fallback; });
  const auto nc = static_cast<Eigen::Index>(contacts.size());
  m->b.resize(nc, n);
  for (Eigen::Index c = 0; c < nc; ++c) {
    m->b.row(c) = contacts[static_cast<size_t>(c)].direction(static_cast<int>(n)).transpose() * m->phi;
  }
  m->u = Eigen::MatrixXd::Zero(2 * n, nc);
  if (nc > 0) {  // a block of a matrix without columns has no storage to offset
    m->u.bottomRows(n) = -(m->scale.inverse().matrix().asDiagonal() * m->b.transpose());
  }
  m->mass_phi = system.mass * m->phi;
  return m;
}

}  // namespace

FloquetAnalysis::FloquetAnalysis(const MechanicalSystem& system, std::vector<ContactPoint> contacts,
                                 FloquetOptions options)
    : system_(system), contacts_(std::move(contacts)), options_(options) {
  system_.validate();
  ContactPoint::validate(contacts_, system_.dofs());
  detail::check_floquet_contacts(contacts_);
  if (options_.path != FloquetPath::Balanced) modes_ = modes_of(system_, contacts_);
  if (modes_) {
    flexibility_ = modes_->b * modes_->b.transpose();  // M⁻¹ = Φ Φᵀ
  } else {
    balanced_ = std::make_shared<const detail::Balanced>(detail::balanced_system(system_, contacts_));
    flexibility_ = balanced_->flexibility;
  }
  if (options_.path == FloquetPath::Modal && !modes_) {
    throw std::invalid_argument("FloquetPath::Modal needs a damping matrix the undamped modes diagonalize (Rayleigh "
                                "or classical: C M⁻¹ K = K M⁻¹ C) and M positive definite; use FloquetPath::Automatic "
                                "(the balanced dense path for any C)");
  }
}

FloquetResult FloquetAnalysis::operator()(const Eigen::MatrixXd& contact_displacement, double frequency_hz) const {
  detail::check_floquet_input(contacts_, contact_displacement, frequency_hz);
  if (!modes_) return detail::balanced_floquet(*balanced_, contacts_, contact_displacement, frequency_hz);
  const Eigen::MatrixXd samples =
      detail::resolved_samples(contacts_, contact_displacement, frequency_hz, flexibility_);
  const Eigen::Index p_count = samples.cols();
  FloquetResult out;
  out.steps = static_cast<int>(p_count);
  const ModalLinearPart linear{*modes_};
  if (linear.states() + detail::jenkins_states(contacts_) > options_.dense_states) {
    if (auto mu = dominant_multipliers(linear, contacts_, samples, frequency_hz)) {
      out.multipliers = std::move(*mu);
      out.max_modulus = std::abs(out.multipliers(0));
      out.dominant_only = true;
      // Richardson on each multiplier: μ_P − μ_{P/2} ≈ −3 (μ_P − μ), the P/2 multiplier nearest.
      out.multiplier_errors =
          Eigen::VectorXd::Constant(out.multipliers.size(), std::numeric_limits<double>::infinity());
      if (p_count % 2 == 0 && p_count >= 16) {
        const auto coarse =
            dominant_multipliers(linear, contacts_, detail::even_samples(samples), frequency_hz);
        for (Eigen::Index i = 0; coarse && i < out.multipliers.size(); ++i) {
          out.multiplier_errors(i) = (coarse->array() - out.multipliers(i)).abs().minCoeff() / 3.0;
        }
      }
      return out;
    }
  }
  const Eigen::MatrixXd phi = detail::stepped_monodromy(linear, contacts_, samples, frequency_hz);
  Eigen::MatrixXd phi_half;
  if (p_count % 2 == 0 && p_count >= 16) {
    phi_half = detail::stepped_monodromy(linear, contacts_, detail::even_samples(samples), frequency_hz);
  }
  detail::analyse_monodromy(phi, phi_half, out);
  if (options_.monodromy) {
    // Φ = T Φ_x T⁻¹ with T = diag(Φ, Φ S, I) and T⁻¹ = diag(Φᵀ M, S⁻¹ Φᵀ M, I) (I on the
    // Jenkins forces, if any).
    const Eigen::Index n = modes_->phi.cols(), nj = phi.rows() - 2 * n;
    Eigen::MatrixXd left(2 * n + nj, 2 * n + nj), right(2 * n + nj, 2 * n + nj);
    left.topRows(n) = modes_->phi * phi.topRows(n);
    left.middleRows(n, n) = modes_->phi * (modes_->scale.matrix().asDiagonal() * phi.middleRows(n, n));
    left.bottomRows(nj) = phi.bottomRows(nj);
    right.leftCols(n) = left.leftCols(n) * modes_->mass_phi.transpose();
    right.middleCols(n, n) =
        left.middleCols(n, n) * (modes_->scale.inverse().matrix().asDiagonal() * modes_->mass_phi.transpose());
    right.rightCols(nj) = left.rightCols(nj);
    out.monodromy = std::move(right);
  }
  return out;
}

bool FloquetAnalysis::modal() const noexcept { return modes_ != nullptr; }

Eigen::Index FloquetAnalysis::resolved_steps(const Eigen::MatrixXd& contact_displacement, double frequency_hz) const {
  detail::check_floquet_input(contacts_, contact_displacement, frequency_hz);
  return contact_displacement.cols() *
         detail::resolution_factor(contacts_, contact_displacement, frequency_hz, flexibility_);
}

}  // namespace wbm::solvers
