#include <wbm/solvers/floquet.hpp>

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <unsupported/Eigen/MatrixFunctions>

#include "floquet_stepping.hpp"

namespace wbm::solvers {
namespace {

int count_outside(const FloquetResult& r, double tolerance) {
  int k = 0;
  for (Eigen::Index i = 0; i < r.multipliers.size(); ++i) {
    if (std::abs(r.multipliers(i)) > 1.0 + tolerance) ++k;
  }
  return k;
}

// Φ = D⁻¹ Φ̃ D: the monodromy matrix of (δu, δu̇) from that of the balanced state.
Eigen::MatrixXd unbalanced(Eigen::MatrixXd phi, double sigma) {
  const Eigen::Index n = phi.rows() / 2;
  phi.topRightCorner(n, n) /= sigma;
  phi.bottomLeftCorner(n, n) *= sigma;
  return phi;
}

// The balanced state as floquet_stepping.hpp's linear part: e^{Ã₀h} by Eigen's Padé exponential
// of the dense 2n × 2n matrix, the contact rows from the contacts' sparse directions.
struct BalancedLinearPart {
  const detail::Balanced& balanced;
  const std::vector<ContactPoint>& contacts;
  static constexpr bool kExactFreeRuns = false;  // e^{A₀h}'s binary powers, as before the modal path
  [[nodiscard]] Eigen::Index states() const { return balanced.a0.rows(); }
  [[nodiscard]] Eigen::MatrixXd flight(double hs) const { return (balanced.a0 * hs).exp(); }
  void apply(const Eigen::MatrixXd& flight, Eigen::MatrixXd& z) const { z = flight * z; }
  [[nodiscard]] const Eigen::MatrixXd& u() const { return balanced.u; }
  [[nodiscard]] Eigen::MatrixXd rows(const Eigen::MatrixXd& y) const {  // e_cᵀ Y, n_c × cols
    Eigen::MatrixXd r(static_cast<Eigen::Index>(contacts.size()), y.cols());
    for (size_t c = 0; c < contacts.size(); ++c) {
      const auto row = static_cast<Eigen::Index>(c);
      r.row(row).setZero();
      for (const auto& [dof, w] : contacts[c].terms()) r.row(row) += w * y.row(dof);
    }
    return r;
  }
};

}  // namespace

namespace detail {

Balanced balanced_system(const MechanicalSystem& system, const std::vector<ContactPoint>& contacts) {
  const auto nc = static_cast<Eigen::Index>(contacts.size());
  const Eigen::Index n = system.dofs();
  const Eigen::MatrixXd mass(system.mass);
  const Eigen::PartialPivLU<Eigen::MatrixXd> mlu(mass);
  Balanced b;
  const Eigen::MatrixXd mk = mlu.solve(Eigen::MatrixXd(system.stiffness));
  const double norm = n > 0 ? mk.cwiseAbs().colwise().sum().maxCoeff() : 0.0;
  b.sigma = norm > 0.0 && std::isfinite(norm) ? std::sqrt(norm) : 1.0;
  b.a0 = Eigen::MatrixXd::Zero(2 * n, 2 * n);
  b.a0.topRightCorner(n, n) = b.sigma * Eigen::MatrixXd::Identity(n, n);
  b.a0.bottomLeftCorner(n, n) = -mk / b.sigma;
  b.a0.bottomRightCorner(n, n) = -mlu.solve(Eigen::MatrixXd(system.damping));
  // e_cᵀ y = Σ w y(dof) over the contact's direction reads displacements only, which D keeps.
  b.u = Eigen::MatrixXd::Zero(2 * n, nc);
  for (Eigen::Index c = 0; c < nc; ++c) {
    b.u.col(c).tail(n) = -mlu.solve(contacts[static_cast<size_t>(c)].direction(static_cast<int>(n))) / b.sigma;
  }
  b.flexibility.resize(nc, nc);
  for (Eigen::Index c = 0; c < nc; ++c) {
    const Eigen::VectorXd e_c = contacts[static_cast<size_t>(c)].direction(static_cast<int>(n));
    for (Eigen::Index d = 0; d < nc; ++d) b.flexibility(c, d) = -b.sigma * e_c.dot(b.u.col(d).tail(n));
  }
  return b;
}


void check_floquet_contacts(const std::vector<ContactPoint>& contacts) {
  for (const auto& c : contacts) {
    if (c.law->hysteretic()) {
      throw std::invalid_argument("floquet_multipliers: the contact at DOF " + std::to_string(c.dof) + " is a " +
                                  c.law->describe() + "; its monodromy matrix needs the slider's stick/slip state "
                                  "along the orbit, which is not implemented: stability is not computed for friction");
    }
    if (c.law->rigid()) {
      throw std::invalid_argument("floquet_multipliers: the contact at DOF " + std::to_string(c.dof) + " is a " +
                                  c.law->describe() + "; the monodromy matrix of an impacting orbit needs a saltation "
                                  "matrix at every impact, which is not implemented: stability is not computed for "
                                  "rigid stops (use a LinearPenalty for a stiff-stop stability estimate)");
    }
  }
}

void check_floquet_input(const std::vector<ContactPoint>& contacts, const Eigen::MatrixXd& contact_displacement,
                         double frequency_hz) {
  const auto nc = static_cast<Eigen::Index>(contacts.size());
  const Eigen::Index p_count = contact_displacement.cols();
  if (p_count < 8) {
    throw std::invalid_argument("floquet_multipliers: " + std::to_string(p_count) +
                                " samples per period; need P >= 8 (the steps of the monodromy integration)");
  }
  if (contact_displacement.rows() != nc) {
    throw std::invalid_argument("floquet_multipliers: contact_displacement has " +
                                std::to_string(contact_displacement.rows()) + " rows for " + std::to_string(nc) +
                                " contacts");
  }
  if (!contact_displacement.allFinite()) throw std::invalid_argument("floquet_multipliers: non-finite samples");
  if (!(frequency_hz > 0.0) || !std::isfinite(frequency_hz)) {
    throw std::invalid_argument("floquet_multipliers: f = " + std::to_string(frequency_hz) + " Hz; must be > 0");
  }
}

Eigen::Index resolution_factor(const std::vector<ContactPoint>& contacts, const Eigen::MatrixXd& contact_displacement,
                               double frequency_hz, const Eigen::MatrixXd& flexibility) {
  const Eigen::Index nc = contact_displacement.rows(), p_count = contact_displacement.cols();
  double omega2 = 0.0, k_worst = 0.0;
  Eigen::Index worst = -1;
  for (Eigen::Index c = 0; c < nc; ++c) {
    double k = 0.0;
    for (Eigen::Index p = 0; p < p_count; ++p) {
      k = std::max(k, contacts[static_cast<size_t>(c)].law->stiffness(contact_displacement(c, p)));
    }
    const double w2 = k * flexibility.row(c).cwiseAbs().sum();
    if (w2 > omega2) {
      omega2 = w2;
      worst = c;
      k_worst = k;
    }
  }
  const double phase = std::sqrt(omega2) / (frequency_hz * static_cast<double>(p_count));  // h ω_c
  Eigen::Index s = 1;
  while (phase / static_cast<double>(s) > kResolvedPhase && s * p_count <= kMaxResolvedSteps) s *= 2;
  if (phase / static_cast<double>(s) > kResolvedPhase) {
    const auto& c = contacts[static_cast<size_t>(worst)];
    throw std::invalid_argument(
        "floquet_multipliers: the contact at DOF " + std::to_string(c.dof) + " (" + c.law->describe() +
        ") reaches a stiffness k = " + std::to_string(k_worst) +
        " N/m on this orbit; with its inverse mass e_c' M^-1 e_c = " + std::to_string(flexibility(worst, worst)) +
        " 1/kg it vibrates at omega_c = " + std::to_string(std::sqrt(omega2)) +
        " rad/s, and the monodromy's contact kicks resolve it (h omega_c <= " + std::to_string(kResolvedPhase) +
        ") only with more than " + std::to_string(kMaxResolvedSteps) + " steps per period (h omega_c = " +
        std::to_string(phase) + " at P = " + std::to_string(p_count) +
        "): stability is not computed for a stop this stiff against its mass; lower the penalty stiffness or "
        "leave stability off");
  }
  return s;
}

Eigen::MatrixXd resolved_samples(const std::vector<ContactPoint>& contacts, const Eigen::MatrixXd& contact_displacement,
                                 double frequency_hz, const Eigen::MatrixXd& flexibility) {
  const Eigen::Index s = resolution_factor(contacts, contact_displacement, frequency_hz, flexibility);
  const Eigen::Index nc = contact_displacement.rows(), p_count = contact_displacement.cols();
  if (s == 1) return contact_displacement;
  Eigen::MatrixXd fine(nc, s * p_count);
  for (Eigen::Index p = 0; p < p_count; ++p) {
    for (Eigen::Index j = 0; j < s; ++j) {
      const double t = static_cast<double>(j) / static_cast<double>(s);
      fine.col(p * s + j) = (1.0 - t) * contact_displacement.col(p) + t * contact_displacement.col((p + 1) % p_count);
    }
  }
  return fine;
}

void analyse_monodromy(const Eigen::MatrixXd& phi, const Eigen::MatrixXd& phi_half, FloquetResult& out) {
  const bool estimate = phi_half.size() > 0;
  const Eigen::EigenSolver<Eigen::MatrixXd> eig(phi, estimate);
  const Eigen::VectorXcd mu = eig.eigenvalues();
  std::vector<Eigen::Index> order(static_cast<size_t>(mu.size()));
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<Eigen::Index>(i);
  std::sort(order.begin(), order.end(),
            [&](Eigen::Index a, Eigen::Index b) { return std::abs(mu(a)) > std::abs(mu(b)); });
  out.multipliers.resize(mu.size());
  for (size_t i = 0; i < order.size(); ++i) out.multipliers(static_cast<Eigen::Index>(i)) = mu(order[i]);
  out.max_modulus = mu.size() > 0 ? std::abs(out.multipliers(0)) : 0.0;
  // Error estimate: Φ_P − Φ_{P/2} ≈ 3 (Φ_P − Φ) for a second-order scheme (Richardson), mapped to
  // each multiplier by first-order perturbation, δμ_i = w_iᵀ δΦ v_i (v_i, w_i right and left
  // eigenvectors, w_iᵀ v_i = 1). Near a collision of two multipliers the eigenvectors are
  // ill-conditioned and the estimate grows, as the multipliers' sensitivity does. Comparing |μ|
  // of P and P/2 would not do: a complex pair has |μ|² = det Φ, nearly the same for every P.
  // In real arithmetic, from the real pseudo-eigenvectors V (Φ V = V D, D block diagonal with
  // 1 × 1 blocks μ and 2 × 2 blocks [[a, b], [−b, a]] for a ± ib) and E = V⁻¹ δΦ V: δμ = E_ii for
  // a real μ, and for a pair (1, ±i) E (1, ±i)ᵀ / 2 = (E_ii + E_jj)/2 ± i (E_ij − E_ji)/2, j = i + 1
  // (the complex eigenvectors v = x ± i y from V's columns (x, y), their left ones (1, ∓i) V⁻¹ / 2).
  out.multiplier_errors = Eigen::VectorXd::Constant(mu.size(), std::numeric_limits<double>::infinity());
  if (estimate && mu.size() > 0) {
    const Eigen::MatrixXd v = eig.pseudoEigenvectors();
    const Eigen::MatrixXd d = eig.pseudoEigenvalueMatrix();
    const Eigen::PartialPivLU<Eigen::MatrixXd> vlu(v);
    if (vlu.rcond() > 1e-14) {
      const Eigen::MatrixXd e = vlu.solve((phi - phi_half) * v) / 3.0;
      Eigen::VectorXd error(mu.size());
      for (Eigen::Index i = 0; i < mu.size(); ++i) {
        if (i + 1 < mu.size() && d(i + 1, i) != 0.0) {  // a 2 × 2 block: the pair (i, i + 1)
          const double re = 0.5 * (e(i, i) + e(i + 1, i + 1)), im = 0.5 * (e(i, i + 1) - e(i + 1, i));
          error(i) = error(i + 1) = std::hypot(re, im);
          ++i;
        } else {
          error(i) = std::abs(e(i, i));
        }
      }
      for (size_t i = 0; i < order.size(); ++i) out.multiplier_errors(static_cast<Eigen::Index>(i)) = error(order[i]);
    }
  }
}

FloquetResult balanced_floquet(const Balanced& balanced, const std::vector<ContactPoint>& contacts,
                               const Eigen::MatrixXd& contact_displacement, double frequency_hz) {
  // Φ̃ = D Φ D⁻¹ has Φ's eigenvalues; its eigenvectors and error estimate are those of the
  // balanced state, which the first-order perturbation maps alike.
  const Eigen::MatrixXd samples = resolved_samples(contacts, contact_displacement, frequency_hz, balanced.flexibility);
  const Eigen::Index p_count = samples.cols();
  FloquetResult out;
  out.steps = static_cast<int>(p_count);
  const BalancedLinearPart linear{balanced, contacts};
  const Eigen::MatrixXd phi = stepped_monodromy(linear, contacts, samples, frequency_hz);
  out.monodromy = unbalanced(phi, balanced.sigma);
  Eigen::MatrixXd phi_half;
  if (p_count % 2 == 0 && p_count >= 16) {
    phi_half = stepped_monodromy(linear, contacts, even_samples(samples), frequency_hz);
  }
  analyse_monodromy(phi, phi_half, out);
  return out;
}

}  // namespace detail

FloquetResult floquet_multipliers(const MechanicalSystem& system, const std::vector<ContactPoint>& contacts,
                                  const Eigen::MatrixXd& contact_displacement, double frequency_hz) {
  system.validate();
  ContactPoint::validate(contacts, system.dofs());
  detail::check_floquet_contacts(contacts);
  detail::check_floquet_input(contacts, contact_displacement, frequency_hz);
  return detail::balanced_floquet(detail::balanced_system(system, contacts), contacts, contact_displacement,
                                  frequency_hz);
}

std::string_view to_string(Bifurcation b) noexcept {
  switch (b) {
    case Bifurcation::Fold: return "fold";
    case Bifurcation::PeriodDoubling: return "period-doubling";
    case Bifurcation::NeimarkSacker: return "Neimark-Sacker";
    case Bifurcation::None: break;
  }
  return "none";
}

Bifurcation classify_crossing(const FloquetResult& before, const FloquetResult& after, double tolerance) {
  const int a = count_outside(before, tolerance), b = count_outside(after, tolerance);
  if (a == b) return Bifurcation::None;
  // The crossing multiplier: of those outside the circle at the less stable point, the one
  // nearest it. The largest could have left earlier (a Neimark–Sacker pair far outside while a
  // real multiplier passes +1 at a fold).
  const FloquetResult& unstable = b > a ? after : before;
  Eigen::Index nearest = 0;
  double modulus = std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 0; i < unstable.multipliers.size(); ++i) {
    const double r = std::abs(unstable.multipliers(i));
    if (r > 1.0 + tolerance && r < modulus) {
      modulus = r;
      nearest = i;
    }
  }
  const std::complex<double> mu = unstable.multipliers(nearest);
  const double arg = std::abs(std::arg(mu));
  if (arg < 0.05) return Bifurcation::Fold;
  if (arg > std::numbers::pi - 0.05) return Bifurcation::PeriodDoubling;
  return Bifurcation::NeimarkSacker;
}

}  // namespace wbm::solvers
