// FloquetAnalysis (floquet.hpp): the monodromy stepping of floquet_stepping.hpp in the undamped
// modes' coordinates when the damping matrix is classical, set up once per branch.
#include <wbm/solvers/floquet.hpp>
#include <wbm/solvers/undamped_modes.hpp>

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <utility>
#include <vector>

#include <wbm/contact/penalty.hpp>

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
  // Exact flights (FloquetOptions::exact_flights): e^{A_S t} = V_S e^{Λ_S t} V_S⁻¹ of each contact
  // configuration S met so far on the branch (the points share them), formed on first use.
  struct ConfigurationFlight {
    Eigen::MatrixXcd v, v_inverse;  // eigenvectors of A_S and their inverse, 2n × 2n
    Eigen::VectorXcd lambda;        // eigenvalues of A_S [1/s]
    bool usable = false;            // false: A_S defective or its eigenvectors ill-conditioned
  };
  mutable std::mutex flights_mutex;
  mutable std::map<std::vector<char>, std::shared_ptr<const ConfigurationFlight>> flights;
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

template <class Product>
std::optional<Eigen::VectorXcd> dominant_multipliers(Product& op) {
  const Eigen::Index states = op.rows();
  for (Eigen::Index nev = 8; nev + 2 <= states; nev *= 2) {
    const Eigen::Index ncv = std::min(states, std::max<Eigen::Index>(2 * nev + 1, 20));
    Spectra::GenEigsSolver<Product> arnoldi(op, nev, ncv);
    arnoldi.init();
    arnoldi.compute(Spectra::SortRule::LargestMagn, 1000, 1e-10, Spectra::SortRule::LargestMagn);
    if (arnoldi.info() != Spectra::CompInfo::Successful) return std::nullopt;
    const Eigen::VectorXcd mu = arnoldi.eigenvalues();
    if (mu.size() > 0 && std::abs(mu(mu.size() - 1)) < kDominantBound) return mu;
  }
  return std::nullopt;
}

// ---- Exact flights for piecewise-linear contacts (FloquetOptions::exact_flights) -------------
// With every contact a contact::LinearPenalty, the stiffness of contact c is k_c in contact and 0
// out of it, so between two crossings of the gaps the variational equation is the constant
// ż = A_S z, A_S = A₀ + Σ_{c ∈ S} k_c u_c [b_c, 0] in the modal state (q, p), and its flight is
// exactly e^{A_S t}. A penalty law's force is continuous at its crossing, so the vector field is
// too and no saltation matrix enters: Φ = Π e^{A_S Δt} over the intervals of one period, the
// crossings located between the samples (configuration_intervals).

// True when the exact flights apply: at least one contact, each a contact::LinearPenalty.
bool piecewise_constant_stiffness(const std::vector<ContactPoint>& contacts) {
  if (contacts.empty()) return false;
  return std::all_of(contacts.begin(), contacts.end(), [](const ContactPoint& c) {
    return dynamic_cast<const contact::LinearPenalty*>(c.law.get()) != nullptr;
  });
}

// The eigendecomposition of A_S for the configuration `active` (one flag per contact) with the
// stiffnesses k (n_c, 0 where not in contact; a linear penalty's k_c is the same wherever it is in
// contact, so the flags name the configuration), cached on the modes; computed outside the lock,
// so two threads may form the same one (the same bits).
// Unusable when Eigen's real Schur iteration fails or κ₁(V) > 1e8: a defective A_S (a rigid-body
// mode the contacts do not hold, critical damping) has no eigenvector basis to flow in.
std::shared_ptr<const FloquetAnalysis::Modes::ConfigurationFlight> configuration_flight(
    const FloquetAnalysis::Modes& m, const std::vector<char>& active, const Eigen::VectorXd& k) {
  {
    const std::lock_guard<std::mutex> lock(m.flights_mutex);
    if (auto it = m.flights.find(active); it != m.flights.end()) return it->second;
  }
  const Eigen::Index n = m.phi.cols();
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(2 * n, 2 * n);
  a.topRightCorner(n, n).diagonal() = m.scale.matrix();  // q̇ = S p
  a.bottomLeftCorner(n, n).diagonal() = -(m.omega2 / m.scale).matrix();
  a.bottomRightCorner(n, n).diagonal() = -m.damping.matrix();
  a.bottomLeftCorner(n, n) += m.u.bottomRows(n) * k.asDiagonal() * m.b;  // ṗ += −S⁻¹ Bᵀ K_S B q
  auto flight = std::make_shared<FloquetAnalysis::Modes::ConfigurationFlight>();
  const Eigen::EigenSolver<Eigen::MatrixXd> eigen(a, true);
  if (eigen.info() == Eigen::Success) {
    flight->v = eigen.eigenvectors();
    flight->lambda = eigen.eigenvalues();
    flight->v_inverse = flight->v.partialPivLu().inverse();
    auto norm1 = [](const Eigen::MatrixXcd& x) { return x.cwiseAbs().colwise().sum().maxCoeff(); };
    const double kappa = norm1(flight->v) * norm1(flight->v_inverse);
    flight->usable = std::isfinite(kappa) && kappa <= 1e8 && flight->lambda.allFinite();
  }
  const std::lock_guard<std::mutex> lock(m.flights_mutex);
  if (m.flights.size() >= 512) m.flights.clear();  // bounded memory: 512 configurations of 2n × 2n
  return m.flights.emplace(active, std::move(flight)).first->second;
}

// One period as intervals of constant contact configuration, in time order from τ = 0.
struct ConfigurationIntervals {
  std::vector<double> durations;  // [s], summing to T
  std::vector<std::shared_ptr<const FloquetAnalysis::Modes::ConfigurationFlight>> flights;  // null: no contact
};

// u_c at fraction s ∈ [0, 1] of step p by the cubic through the samples p − 1 … p + 2 (cyclic):
// fourth order in h where the orbit is smooth, and equal to the samples at s = 0 and 1.
double cubic_sample(const Eigen::MatrixXd& u, Eigen::Index c, Eigen::Index p, double s) {
  const Eigen::Index n = u.cols();
  const double a = u(c, (p + n - 1) % n), b = u(c, p), d = u(c, (p + 1) % n), e = u(c, (p + 2) % n);
  return -s * (s - 1.0) * (s - 2.0) / 6.0 * a + (s + 1.0) * (s - 1.0) * (s - 2.0) / 2.0 * b -
         (s + 1.0) * s * (s - 2.0) / 2.0 * d + (s + 1.0) * s * (s - 1.0) / 6.0 * e;
}

// The intervals on the samples (n_c × P at τ_p = p/P): a crossing inside step p wherever the
// samples' signs of u_c − g_c differ (the stepping's rule), located on the cubic through the four
// nearest samples by bisection (its root; at a sample when the sample lies on the gap), each
// interval's configuration from the law's stiffness at its midpoint (on the side of the step's
// crossing, or on the linear interpolant where the step has none); nothing when a
// configuration's flight is unusable. The cubic makes the crossings, and so Φ, fourth order in
// the samples' spacing (the linear interpolant the stepping uses is second order: on the
// oscillator of examples/scenes/stiff_stop_continuation.toml at P = 512 its crossings left |μ|
// off by 4.9e-3, beyond twice the Richardson estimate).
std::optional<ConfigurationIntervals> configuration_intervals(const FloquetAnalysis::Modes& m,
                                                              const std::vector<ContactPoint>& contacts,
                                                              const Eigen::MatrixXd& u, double frequency_hz) {
  const Eigen::Index p_count = u.cols(), nc = u.rows();
  const double h = 1.0 / (frequency_hz * static_cast<double>(p_count));
  std::vector<double> edges = {0.0};
  std::vector<std::vector<std::pair<Eigen::Index, double>>> crossing(static_cast<size_t>(p_count));  // (c, t) per step
  for (Eigen::Index p = 0; p < p_count; ++p) {
    for (Eigen::Index c = 0; c < nc; ++c) {
      const double g = contacts[static_cast<size_t>(c)].law->gap();
      const double d0 = u(c, p) - g, d1 = u(c, (p + 1) % p_count) - g;
      if ((d0 > 0.0) == (d1 > 0.0) || d0 == d1) continue;
      double t = d0 == 0.0 ? 0.0 : 1.0;  // on the gap at a sample: the edge there
      if (d0 != 0.0 && d1 != 0.0) {
        double lo = 0.0, hi = 1.0;  // cubic(lo) has d0's sign, cubic(hi) d1's
        for (int it = 0; it < 60 && hi - lo > 1e-15; ++it) {
          const double mid = 0.5 * (lo + hi);
          ((cubic_sample(u, c, p, mid) - g > 0.0) == (d0 > 0.0) ? lo : hi) = mid;
        }
        t = 0.5 * (lo + hi);
      }
      edges.push_back((static_cast<double>(p) + t) * h);
      crossing[static_cast<size_t>(p)].emplace_back(c, t);
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.push_back(static_cast<double>(p_count) * h);
  ConfigurationIntervals out;
  std::vector<char> last;
  for (size_t i = 0; i + 1 < edges.size(); ++i) {
    const double a = edges[i], b = edges[i + 1];
    if (!(b > a)) continue;
    const double at = 0.5 * (a + b) / h;
    const auto p = std::min(static_cast<Eigen::Index>(at), p_count - 1);
    const double theta = at - static_cast<double>(p);
    std::vector<char> active(static_cast<size_t>(nc));
    Eigen::VectorXd k(nc);
    for (Eigen::Index c = 0; c < nc; ++c) {
      // The side of c's crossing in this step, if it has one (its sample there); else the linear
      // interpolant, of one sign between samples of one sign (a dip of the cubic is not a switch).
      double uc = (1.0 - theta) * u(c, p) + theta * u(c, (p + 1) % p_count);
      for (const auto& [contact, t] : crossing[static_cast<size_t>(p)]) {
        if (contact == c) uc = theta < t ? u(c, p) : u(c, (p + 1) % p_count);
      }
      k(c) = contacts[static_cast<size_t>(c)].law->stiffness(uc);
      active[static_cast<size_t>(c)] = k(c) != 0.0 ? 1 : 0;
    }
    if (!out.durations.empty() && active == last) {
      out.durations.back() += b - a;
      continue;
    }
    std::shared_ptr<const FloquetAnalysis::Modes::ConfigurationFlight> flight;
    if (std::find(active.begin(), active.end(), 1) != active.end()) {
      flight = configuration_flight(m, active, k);
      if (!flight->usable) return std::nullopt;
    }
    out.durations.push_back(b - a);
    out.flights.push_back(std::move(flight));
    last = std::move(active);
  }
  return out;
}

// z ← Φ z over the intervals: a contact-free interval by the modes' closed-form flight, the
// others by V_S e^{Λ_S Δt} V_S⁻¹ (complex, the real part kept: the imaginary one is rounding).
void apply_intervals(const FloquetAnalysis::Modes& m, const ConfigurationIntervals& intervals, Eigen::MatrixXd& z) {
  const ModalLinearPart linear{m};
  for (size_t i = 0; i < intervals.durations.size(); ++i) {
    const double t = intervals.durations[i];
    if (!intervals.flights[i]) {
      linear.apply(linear.flight(t), z);
      continue;
    }
    const auto& f = *intervals.flights[i];
    Eigen::MatrixXcd w = f.v_inverse * z.cast<std::complex<double>>();
    for (Eigen::Index r = 0; r < w.rows(); ++r) w.row(r) *= std::exp(f.lambda(r) * t);
    z = (f.v * w).real();
  }
}

// Φ v for Arnoldi over the exact flights.
struct ExactMonodromyProduct {
  using Scalar = double;
  const FloquetAnalysis::Modes& modes;
  const ConfigurationIntervals& intervals;
  [[nodiscard]] Eigen::Index rows() const { return 2 * modes.phi.cols(); }
  [[nodiscard]] Eigen::Index cols() const { return rows(); }
  void perform_op(const double* x_in, double* y_out) const {
    Eigen::MatrixXd v = Eigen::Map<const Eigen::VectorXd>(x_in, rows());
    apply_intervals(modes, intervals, v);
    Eigen::Map<Eigen::VectorXd>(y_out, rows()) = v.col(0);
  }
};

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
  // Exact flights on the given samples (their P/2 even samples for the estimate), or the stepping
  // on samples refined for the stiffest contact.
  std::optional<ConfigurationIntervals> exact, exact_half;
  if (options_.exact_flights && piecewise_constant_stiffness(contacts_)) {
    exact = configuration_intervals(*modes_, contacts_, contact_displacement, frequency_hz);
  }
  const Eigen::MatrixXd samples =
      exact ? contact_displacement : detail::resolved_samples(contacts_, contact_displacement, frequency_hz, flexibility_);
  const Eigen::Index p_count = samples.cols();
  const bool estimate = p_count % 2 == 0 && p_count >= 16;
  if (exact && estimate) {
    exact_half = configuration_intervals(*modes_, contacts_, detail::even_samples(samples), frequency_hz);
  }
  FloquetResult out;
  out.steps = static_cast<int>(p_count);
  const ModalLinearPart linear{*modes_};
  // The multipliers of largest modulus on the full samples (half = false) or the P/2 even ones.
  auto dominant = [&](bool half) -> std::optional<Eigen::VectorXcd> {
    if (exact) {
      if (half && !exact_half) return std::nullopt;
      ExactMonodromyProduct op{*modes_, half ? *exact_half : *exact};
      return dominant_multipliers(op);
    }
    const Eigen::MatrixXd even = half ? detail::even_samples(samples) : Eigen::MatrixXd();
    MonodromyProduct op{linear, contacts_, half ? even : samples, frequency_hz};
    return dominant_multipliers(op);
  };
  auto monodromy = [&](bool half) -> Eigen::MatrixXd {
    if (exact) {
      if (half && !exact_half) return {};
      Eigen::MatrixXd phi = Eigen::MatrixXd::Identity(linear.states(), linear.states());
      apply_intervals(*modes_, half ? *exact_half : *exact, phi);
      return phi;
    }
    return detail::stepped_monodromy(linear, contacts_, half ? detail::even_samples(samples) : samples, frequency_hz);
  };
  if (linear.states() + detail::jenkins_states(contacts_) > options_.dense_states) {
    if (auto mu = dominant(false)) {
      out.multipliers = std::move(*mu);
      out.max_modulus = std::abs(out.multipliers(0));
      out.dominant_only = true;
      // Richardson on each multiplier: μ_P − μ_{P/2} ≈ −3 (μ_P − μ), the P/2 multiplier nearest.
      out.multiplier_errors =
          Eigen::VectorXd::Constant(out.multipliers.size(), std::numeric_limits<double>::infinity());
      if (estimate) {
        const auto coarse = dominant(true);
        for (Eigen::Index i = 0; coarse && i < out.multipliers.size(); ++i) {
          out.multiplier_errors(i) = (coarse->array() - out.multipliers(i)).abs().minCoeff() / 3.0;
        }
      }
      return out;
    }
  }
  const Eigen::MatrixXd phi = monodromy(false);
  Eigen::MatrixXd phi_half;
  if (estimate) phi_half = monodromy(true);
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
  // Exact flights resolve any stiffness: the samples need only locate the crossings.
  if (modes_ && options_.exact_flights && piecewise_constant_stiffness(contacts_)) return contact_displacement.cols();
  return contact_displacement.cols() *
         detail::resolution_factor(contacts_, contact_displacement, frequency_hz, flexibility_);
}

}  // namespace wbm::solvers
