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

#include <wbm/contact/friction.hpp>

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

// Φ = D⁻¹ Φ̃ D: the monodromy matrix of (δu, δu̇, φ) from that of the balanced state (n DOFs;
// the Jenkins forces φ, if any, are not scaled).
Eigen::MatrixXd unbalanced(Eigen::MatrixXd phi, double sigma, Eigen::Index n) {
  phi.middleCols(n, n) /= sigma;
  phi.middleRows(n, n) *= sigma;
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
    if (c.second_tangent >= 0) {
      throw std::invalid_argument("floquet_multipliers: the contact at DOF " + std::to_string(c.dof) + " is a " +
                                  c.law->describe() + ": the monodromy matrix of an element whose slip direction "
                                  "turns with the motion is not computed; continue without stability "
                                  "(ResponseCurveOptions::stability = false; scene: analysis.stability = false)");
    }
    if (c.law->hysteretic() && c.law->rigid()) {
      throw std::invalid_argument("floquet_multipliers: the contact at DOF " + std::to_string(c.dof) + " is " +
                                  c.law->describe() + ", rigid-plastic: the monodromy matrix of its orbit needs a "
                                  "saltation matrix at every stick/slip switch of its impulses, which is not "
                                  "implemented: stability is not computed for exact friction (give the contact a "
                                  "stiff Jenkins element, contact::JenkinsLaw, whose stability is computed)");
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
    const auto* jenkins = dynamic_cast<const contact::JenkinsLaw*>(contacts[static_cast<size_t>(c)].law.get());
    for (Eigen::Index p = 0; jenkins == nullptr && p < p_count; ++p) {
      k = std::max(k, contacts[static_cast<size_t>(c)].law->stiffness(contact_displacement(c, p)));
    }
    if (jenkins != nullptr) k = jenkins->parameters().tangential_stiffness;  // its stiffness in stick
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
  // The samples of the next period are moved by −d for a drifting counter-surface (friction).
  Eigen::VectorXd shift(nc);
  for (Eigen::Index c = 0; c < nc; ++c) shift(c) = -contacts[static_cast<size_t>(c)].obstacle.drift;
  Eigen::MatrixXd fine(nc, s * p_count);
  for (Eigen::Index p = 0; p < p_count; ++p) {
    const Eigen::VectorXd next =
        p + 1 == p_count ? Eigen::VectorXd(contact_displacement.col(0) + shift) : contact_displacement.col(p + 1);
    for (Eigen::Index j = 0; j < s; ++j) {
      const double t = static_cast<double>(j) / static_cast<double>(s);
      fine.col(p * s + j) = (1.0 - t) * contact_displacement.col(p) + t * next;
    }
  }
  return fine;
}

std::vector<JenkinsSamples> jenkins_samples(const std::vector<ContactPoint>& contacts,
                                            const Eigen::MatrixXd& contact_displacement) {
  std::vector<JenkinsSamples> out;
  const Eigen::Index p_count = contact_displacement.cols();
  for (size_t c = 0; c < contacts.size(); ++c) {
    if (!contacts[c].law->hysteretic()) continue;
    const auto* law = dynamic_cast<const contact::JenkinsLaw*>(contacts[c].law.get());
    if (law == nullptr) {
      throw std::invalid_argument("floquet_multipliers: the contact at DOF " + std::to_string(contacts[c].dof) +
                                  " is " + contacts[c].law->describe() + ", a hysteretic law other than "
                                  "contact::JenkinsLaw: its monodromy matrix is not computed");
    }
    JenkinsSamples e;
    e.contact = static_cast<Eigen::Index>(c);
    e.normal = contacts[c].normal;
    const double kt = law->parameters().tangential_stiffness;
    e.tangential_stiffness = kt;
    Eigen::VectorXd force(p_count), stiffness(p_count);
    Eigen::VectorXi anchor(p_count);
    e.load_sensitivity.resize(p_count);
    evaluate_contact_period(contacts, static_cast<int>(c), contact_displacement, force, stiffness, anchor,
                            e.load_sensitivity);
    Eigen::VectorXd normal = Eigen::VectorXd::Zero(p_count);
    if (e.normal >= 0) {
      Eigen::VectorXd slope(p_count);
      contacts[static_cast<size_t>(e.normal)].law->evaluate(contact_displacement.row(e.normal).transpose(), normal,
                                                              slope);
    }
    const Eigen::VectorXd slip_force =
        law->parameters().friction_coefficient * (law->parameters().normal_load + normal.array());
    e.stick.resize(static_cast<size_t>(p_count));
    for (Eigen::Index q = 0; q < p_count; ++q) e.stick[static_cast<size_t>(q)] = stiffness(q) != 0.0 ? 1 : 0;
    e.full_stick = std::all_of(e.stick.begin(), e.stick.end(), [](char x) { return x != 0; });
    const bool full_slip = std::none_of(e.stick.begin(), e.stick.end(), [](char x) { return x != 0; });
    // w at sample q of any period (the next period's samples moved by −drift).
    const double shift = -contacts[c].obstacle.drift;
    auto w = [&](Eigen::Index q) {
      const Eigen::Index wrapped = ((q % p_count) + p_count) % p_count;
      const double periods = static_cast<double>((q - wrapped) / p_count);
      return contact_displacement(e.contact, wrapped) + periods * shift;
    };
    auto at = [&](const Eigen::VectorXd& v, Eigen::Index q) { return v(((q % p_count) + p_count) % p_count); };
    // A slip begins in step q (stick at q, slip at q + 1) where the elastic trial f_q + k_t θ Δw
    // meets σ F_s(θ), F_s interpolated linearly (second order in the step), σ that of the slip.
    std::vector<double> onset(static_cast<size_t>(p_count), -1.0);
    for (Eigen::Index q = 0; !e.full_stick && !full_slip && q < p_count; ++q) {
      if (e.stick[static_cast<size_t>(q)] == 0 || e.stick[static_cast<size_t>((q + 1) % p_count)] != 0) continue;
      const double sigma = at(force, q + 1) >= 0.0 ? 1.0 : -1.0;
      const double denominator = sigma * kt * (w(q + 1) - w(q)) - (at(slip_force, q + 1) - slip_force(q));
      const double theta = denominator > 0.0 ? (slip_force(q) - sigma * force(q)) / denominator : 1.0;
      onset[static_cast<size_t>(q)] = std::clamp(theta, 0.0, 1.0);
      e.switches.emplace_back(static_cast<double>(q) + onset[static_cast<size_t>(q)], false);
    }
    // A slip ends (slip at q, stick at q + 1) where g = σ k_t w − F_s is largest: in slip the
    // trial moves with w against the slip force, and returns inside the cone after g's maximum.
    // The vertex of the parabola through g at q − 1, q, q + 1 (second order), within
    // [q − ½, q + 1) and not before the onset of step q − 1; at q if g is not concave there.
    for (Eigen::Index q = 0; !e.full_stick && !full_slip && q < p_count; ++q) {
      if (e.stick[static_cast<size_t>(q)] != 0 || e.stick[static_cast<size_t>((q + 1) % p_count)] == 0) continue;
      const double sigma = force(q) >= 0.0 ? 1.0 : -1.0;
      auto g = [&](Eigen::Index r) { return sigma * kt * w(r) - at(slip_force, r); };
      const double gm = g(q - 1), g0 = g(q), gp = g(q + 1), curvature = gm - 2.0 * g0 + gp;
      double delta = curvature < 0.0 ? std::clamp(0.5 * (gm - gp) / curvature, -0.5, 0.999) : 0.0;
      const double before = onset[static_cast<size_t>((q + p_count - 1) % p_count)];
      if (before >= 0.0) delta = std::max(delta, before - 1.0);
      e.switches.emplace_back(std::fmod(static_cast<double>(q) + delta + static_cast<double>(p_count),
                                        static_cast<double>(p_count)),
                              true);
    }
    std::sort(e.switches.begin(), e.switches.end());
    out.push_back(std::move(e));
  }
  return out;
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
  out.monodromy = unbalanced(phi, balanced.sigma, balanced.a0.rows() / 2);
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
