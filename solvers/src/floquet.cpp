#include <wbm/solvers/floquet.hpp>

#include <algorithm>
#include <cmath>
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

}  // namespace

FloquetResult floquet_multipliers(const MechanicalSystem& system, const std::vector<ContactPoint>& contacts,
                                  const Eigen::MatrixXd& contact_displacement, double frequency_hz) {
  system.validate();
  ContactPoint::validate(contacts, system.dofs());
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
  const Eigen::Index n = system.dofs();
  const Eigen::MatrixXd mass(system.mass);
  const Eigen::PartialPivLU<Eigen::MatrixXd> mlu(mass);
  Eigen::MatrixXd a0 = Eigen::MatrixXd::Zero(2 * n, 2 * n);
  a0.topRightCorner(n, n).setIdentity();
  a0.bottomLeftCorner(n, n) = -mlu.solve(Eigen::MatrixXd(system.stiffness));
  a0.bottomRightCorner(n, n) = -mlu.solve(Eigen::MatrixXd(system.damping));
  const double h = 1.0 / (frequency_hz * static_cast<double>(p_count));
  const Eigen::MatrixXd step = (a0 * h).exp();  // e^{A₀h}

  // b_c = (0, −M⁻¹ e_c): U (2n × n_c); e_cᵀ y = y(dof_c).
  Eigen::MatrixXd u = Eigen::MatrixXd::Zero(2 * n, nc);
  for (Eigen::Index c = 0; c < nc; ++c) {
    Eigen::VectorXd e = Eigen::VectorXd::Zero(n);
    e(contacts[static_cast<size_t>(c)].dof) = 1.0;
    u.col(c).tail(n) = -mlu.solve(e);
  }
  auto stiffness = [&](Eigen::Index p) {  // k_c(t_p), periodic in p
    Eigen::VectorXd k(nc);
    const Eigen::Index q = p % p_count;
    for (Eigen::Index c = 0; c < nc; ++c) k(c) = contacts[static_cast<size_t>(c)].law->stiffness(contact_displacement(c, q));
    return k;
  };
  // Rows e_cᵀ Y (n_c × 2n).
  auto rows = [&](const Eigen::MatrixXd& y) {
    Eigen::MatrixXd r(nc, y.cols());
    for (Eigen::Index c = 0; c < nc; ++c) r.row(c) = y.row(contacts[static_cast<size_t>(c)].dof);
    return r;
  };
  // e_cᵀ b_d (n_c × n_c) for the Woodbury solve.
  const Eigen::MatrixXd eu = rows(u);

  Eigen::MatrixXd y = Eigen::MatrixXd::Identity(2 * n, 2 * n);
  // Powers e^{A₀h·2^j}, built on demand, for runs of steps without contact stiffness.
  std::vector<Eigen::MatrixXd> powers = {step};
  auto advance_free = [&](Eigen::Index steps) {
    for (size_t j = 0; steps > 0; ++j, steps >>= 1) {
      if (j == powers.size()) powers.push_back(powers.back() * powers.back());
      if (steps & 1) y = powers[j] * y;
    }
  };
  Eigen::Index free_run = 0;
  Eigen::VectorXd k_now = stiffness(0);
  for (Eigen::Index p = 0; p < p_count; ++p) {
    const Eigen::VectorXd k_next = stiffness(p + 1);
    if (k_now.isZero(0.0) && k_next.isZero(0.0)) {
      ++free_run;
      k_now = k_next;
      continue;
    }
    advance_free(free_run);
    free_run = 0;
    // (I + (h/2) K_p) Y
    if (!k_now.isZero(0.0)) y += u * ((0.5 * h) * k_now.asDiagonal() * rows(y));
    y = step * y;
    // (I − (h/2) K_{p+1})⁻¹ Z = Z + U (I − D E U)⁻¹ D E Z, D = (h/2) diag(k_{p+1})  (Woodbury)
    if (!k_next.isZero(0.0)) {
      const Eigen::MatrixXd d = (0.5 * h) * k_next.asDiagonal();
      const Eigen::MatrixXd small = Eigen::MatrixXd::Identity(nc, nc) - d * eu;
      y += u * small.partialPivLu().solve(d * rows(y));
    }
    k_now = k_next;
  }
  advance_free(free_run);

  FloquetResult out;
  out.monodromy = y;
  const Eigen::EigenSolver<Eigen::MatrixXd> eig(y, false);
  Eigen::VectorXcd mu = eig.eigenvalues();
  std::sort(mu.data(), mu.data() + mu.size(), [](const auto& a, const auto& b) { return std::abs(a) > std::abs(b); });
  out.multipliers = mu;
  out.max_modulus = mu.size() > 0 ? std::abs(mu(0)) : 0.0;
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
  const FloquetResult& unstable = b > a ? after : before;
  const std::complex<double> mu = unstable.multipliers(0);
  const double arg = std::abs(std::arg(mu));
  if (arg < 0.05) return Bifurcation::Fold;
  if (arg > std::numbers::pi - 0.05) return Bifurcation::PeriodDoubling;
  return Bifurcation::NeimarkSacker;
}

}  // namespace wbm::solvers
