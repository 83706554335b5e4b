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

namespace wbm::solvers {
namespace {

int count_outside(const FloquetResult& r, double tolerance) {
  int k = 0;
  for (Eigen::Index i = 0; i < r.multipliers.size(); ++i) {
    if (std::abs(r.multipliers(i)) > 1.0 + tolerance) ++k;
  }
  return k;
}

// The balanced state ỹ = (δu, δu̇ / σ), σ = √‖M⁻¹K‖₁ [1/s] (1 without stiffness): Ã₀ = D A₀ D⁻¹
// with D = diag(I, I/σ) has the blocks [[0, σI], [−M⁻¹K/σ, −M⁻¹C]], whose norms are both about the
// highest natural frequency, while ‖A₀‖₁ is its square. Scaling and squaring takes
// log₂(‖A₀h‖₁ / 5.4) squarings, each losing accuracy: for the rod of jl14_case2 (25 elements,
// h = T/8192) ‖A₀h‖₁ = 8.1e3 gave blocks of e^{A₀h} wrong by 3e-13 relative, in 0.63 ms, and
// ‖Ã₀h‖₁ = 0.057 gives them to 3e-16, in 0.12 ms (Padé without squaring).
struct Balanced {
  Eigen::MatrixXd a0;  // Ã₀, 2n × 2n
  Eigen::MatrixXd u;   // D b_c = (0, −M⁻¹ e_c / σ), 2n × n_c
  double sigma = 1.0;
};

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
  return b;
}

// Φ = D⁻¹ Φ̃ D: the monodromy matrix of (δu, δu̇) from that of the balanced state.
Eigen::MatrixXd unbalanced(Eigen::MatrixXd phi, double sigma) {
  const Eigen::Index n = phi.rows() / 2;
  phi.topRightCorner(n, n) /= sigma;
  phi.bottomLeftCorner(n, n) *= sigma;
  return phi;
}

// Φ̃ = Ỹ(T), of the balanced state, by the stepping of floquet.hpp on the P =
// contact_displacement.cols() samples.
Eigen::MatrixXd monodromy_of(const Balanced& balanced, const std::vector<ContactPoint>& contacts,
                             const Eigen::MatrixXd& contact_displacement, double frequency_hz) {
  const auto nc = static_cast<Eigen::Index>(contacts.size());
  const Eigen::Index p_count = contact_displacement.cols();
  const Eigen::Index n = balanced.a0.rows() / 2;
  const Eigen::MatrixXd& a0 = balanced.a0;
  const Eigen::MatrixXd& u = balanced.u;
  const double h = 1.0 / (frequency_hz * static_cast<double>(p_count));
  const Eigen::MatrixXd step = (a0 * h).exp();  // e^{Ã₀h}
  auto stiffness = [&](Eigen::Index p) {  // k_c(t_p), periodic in p
    Eigen::VectorXd k(nc);
    const Eigen::Index q = p % p_count;
    for (Eigen::Index c = 0; c < nc; ++c) k(c) = contacts[static_cast<size_t>(c)].law->stiffness(contact_displacement(c, q));
    return k;
  };
  // Rows e_cᵀ Y (n_c × 2n).
  auto rows = [&](const Eigen::MatrixXd& y) {
    Eigen::MatrixXd r(nc, y.cols());
    for (Eigen::Index c = 0; c < nc; ++c) {
      r.row(c).setZero();
      for (const auto& [dof, w] : contacts[static_cast<size_t>(c)].terms()) r.row(c) += w * y.row(dof);
    }
    return r;
  };
  // e_cᵀ b_d (n_c × n_c) for the Woodbury solve.
  const Eigen::MatrixXd eu = rows(u);

  Eigen::MatrixXd y = Eigen::MatrixXd::Identity(2 * n, 2 * n);
  // One trapezoidal step of length hs from stiffnesses ka (start) to kb (end), applied to z:
  //   (I − (hs/2) K_b) Z ← e^{A₀ hs} (I + (hs/2) K_a) Z, the inverse by Woodbury.
  auto trapezoid_on = [&](Eigen::MatrixXd& z, const Eigen::MatrixXd& exp_step, double hs, const Eigen::VectorXd& ka,
                          const Eigen::VectorXd& kb) {
    if (!ka.isZero(0.0)) z += u * ((0.5 * hs) * ka.asDiagonal() * rows(z));
    z = exp_step * z;
    if (!kb.isZero(0.0)) {
      const Eigen::MatrixXd d = (0.5 * hs) * kb.asDiagonal();
      const Eigen::MatrixXd small = Eigen::MatrixXd::Identity(nc, nc) - d * eu;
      z += u * small.partialPivLu().solve(d * rows(z));
    }
  };
  auto trapezoid = [&](const Eigen::MatrixXd& exp_step, double hs, const Eigen::VectorXd& ka, const Eigen::VectorXd& kb) {
    trapezoid_on(y, exp_step, hs, ka, kb);
  };
  // Runs of whole steps over which no contact crosses its gap and every contact's stiffness is
  // the same at both ends of each step: each step is one matrix T_k, e^{A₀h} without contact
  // stiffness, the trapezoidal step at k otherwise (a linear penalty stop keeps k over a whole
  // contact phase). A run of L steps is T_k^L by binary powers T_k^{2^j}, kept per k (at most
  // kMaxRuns of them): O(log L) products instead of L.
  struct RunPowers {
    Eigen::VectorXd k;
    std::vector<Eigen::MatrixXd> powers;  // T_k^{2^j}
  };
  constexpr size_t kMaxRuns = 8;
  std::vector<RunPowers> runs = {{Eigen::VectorXd::Zero(nc), {step}}};
  Eigen::VectorXd run_k = Eigen::VectorXd::Zero(nc);
  Eigen::Index run_length = 0;
  auto advance_run = [&] {
    if (run_length == 0) return;
    if (run_length == 1 && !run_k.isZero(0.0)) {
      trapezoid(step, h, run_k, run_k);  // one step: no power to form
      run_length = 0;
      return;
    }
    auto it = std::find_if(runs.begin(), runs.end(), [&](const RunPowers& r) { return r.k == run_k; });
    if (it == runs.end()) {
      if (runs.size() == kMaxRuns) runs.resize(1);  // e^{A₀h}'s powers are kept
      Eigen::MatrixXd t = Eigen::MatrixXd::Identity(2 * n, 2 * n);
      trapezoid_on(t, step, h, run_k, run_k);
      runs.push_back({run_k, {std::move(t)}});
      it = runs.end() - 1;
    }
    std::vector<Eigen::MatrixXd>& powers = it->powers;
    for (size_t j = 0; run_length > 0; ++j, run_length >>= 1) {
      if (j == powers.size()) powers.push_back(powers.back() * powers.back());
      if (run_length & 1) y = powers[j] * y;
    }
  };
  // Fractions θ ∈ (0, 1) of step p where a contact displacement, interpolated linearly between
  // the samples, crosses its gap (where the law's stiffness jumps), sorted.
  auto crossings = [&](Eigen::Index p) {
    std::vector<double> theta;
    const Eigen::Index q0 = p % p_count, q1 = (p + 1) % p_count;
    for (Eigen::Index c = 0; c < nc; ++c) {
      const double g = contacts[static_cast<size_t>(c)].law->gap();
      const double d0 = contact_displacement(c, q0) - g, d1 = contact_displacement(c, q1) - g;
      if ((d0 > 0.0) != (d1 > 0.0) && d0 != d1) {
        const double t = d0 / (d0 - d1);
        if (t > 0.0 && t < 1.0) theta.push_back(t);
      }
    }
    std::sort(theta.begin(), theta.end());
    return theta;
  };
  // Stiffnesses at fraction θ of step p, from the linear interpolant of the samples.
  auto stiffness_at = [&](Eigen::Index p, double theta) {
    Eigen::VectorXd k(nc);
    const Eigen::Index q0 = p % p_count, q1 = (p + 1) % p_count;
    for (Eigen::Index c = 0; c < nc; ++c) {
      const double uc = (1.0 - theta) * contact_displacement(c, q0) + theta * contact_displacement(c, q1);
      k(c) = contacts[static_cast<size_t>(c)].law->stiffness(uc);
    }
    return k;
  };
  Eigen::VectorXd k_now = stiffness(0);
  for (Eigen::Index p = 0; p < p_count; ++p) {
    const Eigen::VectorXd k_next = stiffness(p + 1);
    const std::vector<double> theta = crossings(p);
    if (!theta.empty()) {
      // A contact opens or closes inside the step: the jump of its stiffness is placed at the
      // interpolated crossing, each piece integrated with one-sided stiffnesses (evaluated a
      // relative 1e-9 inside the piece). Without this split the switch sits at a sample, which
      // is first order in h, with an error growing with the stop's stiffness (issue #19).
      advance_run();
      std::vector<double> edges = {0.0};
      edges.insert(edges.end(), theta.begin(), theta.end());
      edges.push_back(1.0);
      for (size_t i = 0; i + 1 < edges.size(); ++i) {
        const double a = edges[i], b = edges[i + 1], inside = 1e-9 * (b - a);
        if (!(b > a)) continue;
        const double hs = (b - a) * h;
        trapezoid((a0 * hs).exp(), hs, i == 0 ? k_now : stiffness_at(p, a + inside),
                  i + 2 == edges.size() ? k_next : stiffness_at(p, b - inside));
      }
      k_now = k_next;
      continue;
    }
    if (k_now == k_next) {
      if (run_length > 0 && k_now != run_k) advance_run();
      run_k = k_now;
      ++run_length;
      continue;
    }
    advance_run();
    // (I + (h/2) K_p), e^{A₀h}, then (I − (h/2) K_{p+1})⁻¹ Z = Z + U (I − D E U)⁻¹ D E Z,
    // D = (h/2) diag(k_{p+1}) (Woodbury)
    trapezoid(step, h, k_now, k_next);
    k_now = k_next;
  }
  advance_run();

  return y;
}
}  // namespace

FloquetResult floquet_multipliers(const MechanicalSystem& system, const std::vector<ContactPoint>& contacts,
                                  const Eigen::MatrixXd& contact_displacement, double frequency_hz) {
  system.validate();
  ContactPoint::validate(contacts, system.dofs());
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
  FloquetResult out;
  out.steps = static_cast<int>(p_count);
  // Φ̃ = D Φ D⁻¹ has Φ's eigenvalues; its eigenvectors and error estimate are those of the
  // balanced state, which the first-order perturbation below maps alike.
  const Balanced balanced = balanced_system(system, contacts);
  const Eigen::MatrixXd phi = monodromy_of(balanced, contacts, contact_displacement, frequency_hz);
  out.monodromy = unbalanced(phi, balanced.sigma);
  const Eigen::EigenSolver<Eigen::MatrixXd> eig(phi, true);
  const Eigen::VectorXcd mu = eig.eigenvalues();
  std::vector<Eigen::Index> order(static_cast<size_t>(mu.size()));
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<Eigen::Index>(i);
  std::sort(order.begin(), order.end(), [&](Eigen::Index a, Eigen::Index b) { return std::abs(mu(a)) > std::abs(mu(b)); });
  out.multipliers.resize(mu.size());
  for (size_t i = 0; i < order.size(); ++i) out.multipliers(static_cast<Eigen::Index>(i)) = mu(order[i]);
  out.max_modulus = mu.size() > 0 ? std::abs(out.multipliers(0)) : 0.0;
  // Error estimate: Φ_P − Φ_{P/2} ≈ 3 (Φ_P − Φ) for a second-order scheme (Richardson), mapped to
  // each multiplier by first-order perturbation, δμ_i = (V⁻¹ δΦ V)_ii (V: right eigenvectors,
  // rows of V⁻¹: left ones). Near a collision of two multipliers V is ill-conditioned and the
  // estimate grows, as the multipliers' sensitivity does. Comparing |μ| of P and P/2 would not
  // do: a complex pair has |μ|² = det Φ, which is nearly the same for every P.
  out.multiplier_errors = Eigen::VectorXd::Constant(mu.size(), std::numeric_limits<double>::infinity());
  if (p_count % 2 == 0 && p_count >= 16 && mu.size() > 0) {
    Eigen::MatrixXd half(contact_displacement.rows(), p_count / 2);
    for (Eigen::Index q = 0; q < p_count / 2; ++q) half.col(q) = contact_displacement.col(2 * q);
    const Eigen::MatrixXcd delta = (phi - monodromy_of(balanced, contacts, half, frequency_hz)).cast<std::complex<double>>() / 3.0;
    const Eigen::MatrixXcd v = eig.eigenvectors();
    const Eigen::PartialPivLU<Eigen::MatrixXcd> vlu(v);
    const double rcond = vlu.rcond();
    if (rcond > 1e-14) {
      const Eigen::MatrixXcd projected = vlu.solve(delta * v);
      for (size_t i = 0; i < order.size(); ++i) {
        out.multiplier_errors(static_cast<Eigen::Index>(i)) = std::abs(projected(order[i], order[i]));
      }
    }
  }
  return out;
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
