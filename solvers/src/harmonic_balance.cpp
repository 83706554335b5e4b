#include <wbm/solvers/harmonic_balance.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>

#include <Eigen/SparseLU>
#include <unsupported/Eigen/KroneckerProduct>

#include <wbm/spectral/aft.hpp>
#include <wbm/spectral/layout.hpp>

namespace wbm::solvers {

struct HarmonicBalance::Impl {
  MechanicalSystem system;
  HarmonicForcing forcing;
  std::vector<ContactPoint> contacts;
  HarmonicBalanceOptions options;
  spectral::FourierBasis basis;
  spectral::Aft aft;
  int n, m, q, nc;
  Eigen::SparseMatrix<double> g;  // n·M × n·M, Kronecker sum [JL14 Eq. (17)]
  Eigen::SparseLU<Eigen::SparseMatrix<double>, Eigen::COLAMDOrdering<int>> lu;
  bool factorized = false;
  Eigen::VectorXd b;                        // projected forcing, n·M
  Eigen::VectorXd a_lin;                    // G⁻¹ b
  Eigen::MatrixXd h;                        // P G⁻¹ Pᵀ, n_c·M square
  Eigen::VectorXd x_lin;                    // P a_lin
  double scale = 1.0;                       // s of the header
  Eigen::MatrixXd theta_t;                  // M × Q: theta_t(k, q) = q_k(τ_q)
  std::vector<Eigen::Index> contact_rows;   // row in a of contact unknown x(k·n_c + c)

  static int default_samples(const HarmonicBalanceOptions& o) {
    return o.time_samples > 0 ? o.time_samples : std::max(256, 2 * o.dimension);
  }

  Impl(MechanicalSystem s, HarmonicForcing f, std::vector<ContactPoint> c, HarmonicBalanceOptions o)
      : system(std::move(s)), forcing(f), contacts(std::move(c)), options(o),
        basis(o.dimension), aft(o.dimension, default_samples(o)) {
    system.validate();
    forcing.validate(system.dofs());
    ContactPoint::validate(contacts, system.dofs());
    if (options.time_samples < 0) {
      throw std::invalid_argument("HarmonicBalanceOptions.time_samples = " +
                                  std::to_string(options.time_samples) +
                                  ": must be 0 (automatic) or >= M");
    }
    n = system.dofs();
    m = basis.dimension();
    q = aft.samples();
    nc = static_cast<int>(contacts.size());

    // G = f² A₂ ⊗ M + f A₁ ⊗ C + A₀ ⊗ K (d/dt = f d/dτ).
    const double fr = forcing.frequency_hz;
    g = fr * fr * Eigen::kroneckerProduct(basis.galerkin_operator(2), system.mass).eval();
    g += fr * Eigen::kroneckerProduct(basis.galerkin_operator(1), system.damping).eval();
    g += Eigen::kroneckerProduct(basis.galerkin_operator(0), system.stiffness).eval();
    g.makeCompressed();

    // b: the forcing F cos 2πτ on DOF `dof`, projected on the weighting functions.
    Eigen::MatrixXd force_samples = Eigen::MatrixXd::Zero(n, q);
    for (int k = 0; k < q; ++k) {
      force_samples(forcing.dof, k) =
          forcing.amplitude * std::cos(2.0 * std::numbers::pi * k / static_cast<double>(q));
    }
    b = spectral::stacked(aft.project(force_samples));

    theta_t = aft.to_time(Eigen::MatrixXd::Identity(m, m));
    contact_rows.resize(static_cast<size_t>(nc) * m);
    for (int k = 0; k < m; ++k) {
      for (int c = 0; c < nc; ++c) {
        contact_rows[static_cast<size_t>(k) * nc + c] = spectral::stacked_index(k, contacts[c].dof, n);
      }
    }

    lu.analyzePattern(g);
    lu.factorize(g);
    factorized = lu.info() == Eigen::Success;
    if (!factorized) return;
    a_lin = lu.solve(b);
    x_lin = gather(a_lin);
    if (nc > 0) {
      Eigen::MatrixXd selection = Eigen::MatrixXd::Zero(n * m, nc * m);
      for (int j = 0; j < nc * m; ++j) selection(contact_rows[j], j) = 1.0;
      const Eigen::MatrixXd z = lu.solve(selection);
      h.resize(nc * m, nc * m);
      for (int i = 0; i < nc * m; ++i) h.row(i) = z.row(contact_rows[i]);
      // Displacement scale: the largest gap, else the no-contact response, else 1 m. Not
      // x_lin first: near an undamped resonance it is orders of magnitude off the solution.
      double gmax = 0.0;
      for (const auto& c : contacts) gmax = std::max(gmax, std::abs(c.law->gap()));
      scale = gmax > 0.0 ? gmax : x_lin.lpNorm<Eigen::Infinity>();
      if (!(scale > 0.0) || !std::isfinite(scale)) scale = 1.0;
    }
  }

  [[nodiscard]] Eigen::VectorXd gather(const Eigen::VectorXd& a) const {
    Eigen::VectorXd x(contact_rows.size());
    for (size_t j = 0; j < contact_rows.size(); ++j) x(j) = a(contact_rows[j]);
    return x;
  }

  // Contact displacement samples U (n_c × Q) for stacked contact unknowns x.
  [[nodiscard]] Eigen::MatrixXd contact_samples(const Eigen::VectorXd& x) const {
    return aft.to_time(spectral::as_coefficients(x, nc));
  }

  // n_c(x): ∫ q_j f_c(u_c) dτ stacked like x; optionally N(x) (n_c·M square).
  Eigen::VectorXd contact_forces(const Eigen::VectorXd& x, Eigen::MatrixXd* jac) const {
    const Eigen::MatrixXd u = contact_samples(x);
    Eigen::MatrixXd force(nc, q), stiff(nc, q);
    for (int c = 0; c < nc; ++c) {
      Eigen::VectorXd fc(q), kc(q);
      contacts[c].law->evaluate(u.row(c).transpose(), fc, kc);
      force.row(c) = fc.transpose();
      stiff.row(c) = kc.transpose();
    }
    if (jac != nullptr) {
      jac->setZero(nc * m, nc * m);
      for (int c = 0; c < nc; ++c) {
        // Rows k of W = q_k(τ) f_c'(u_c(τ)); projecting gives ∫ q_j f_c' q_k (symmetric).
        const Eigen::MatrixXd w = theta_t.array().rowwise() * stiff.row(c).array();
        const Eigen::MatrixXd block = aft.project(w);
        for (int k = 0; k < m; ++k) {
          for (int j = 0; j < m; ++j) (*jac)(j * nc + c, k * nc + c) = block(k, j);
        }
      }
    }
    return spectral::stacked(aft.project(force));
  }

  // r(x; s) = (x − s·x_lin + H n_c(x)) / scale: the condensed residual at load factor s.
  [[nodiscard]] Eigen::VectorXd contact_residual(const Eigen::VectorXd& x, double load) const {
    require_factorized();
    Eigen::VectorXd r = x - load * x_lin + h * contact_forces(x, nullptr);
    return r / scale;
  }

  void require_factorized() const {
    if (!factorized) {
      std::ostringstream os;
      os << "harmonic balance: the linear operator G is singular at f = " << forcing.frequency_hz
         << " Hz (forcing at an undamped natural frequency?); add damping or move the frequency";
      throw std::runtime_error(os.str());
    }
  }
};

HarmonicBalance::HarmonicBalance(MechanicalSystem system, HarmonicForcing forcing,
                                 std::vector<ContactPoint> contacts, HarmonicBalanceOptions options)
    : impl_(std::make_unique<Impl>(std::move(system), forcing, std::move(contacts), options)) {}
HarmonicBalance::~HarmonicBalance() = default;
HarmonicBalance::HarmonicBalance(HarmonicBalance&&) noexcept = default;
HarmonicBalance& HarmonicBalance::operator=(HarmonicBalance&&) noexcept = default;

int HarmonicBalance::dofs() const { return impl_->n; }
int HarmonicBalance::dimension() const { return impl_->m; }
int HarmonicBalance::time_samples() const { return impl_->q; }
const spectral::FourierBasis& HarmonicBalance::basis() const { return impl_->basis; }

Eigen::VectorXd HarmonicBalance::residual(const Eigen::VectorXd& a) const {
  const auto& p = *impl_;
  Eigen::VectorXd r = p.g * a - p.b;
  if (p.nc > 0) {
    const Eigen::VectorXd nx = p.contact_forces(p.gather(a), nullptr);
    for (size_t j = 0; j < p.contact_rows.size(); ++j) r(p.contact_rows[j]) += nx(j);
  }
  return r;
}

Eigen::MatrixXd HarmonicBalance::jacobian(const Eigen::VectorXd& a) const {
  const auto& p = *impl_;
  Eigen::MatrixXd jac(p.g);
  if (p.nc > 0) {
    Eigen::MatrixXd nj;
    (void)p.contact_forces(p.gather(a), &nj);
    for (size_t i = 0; i < p.contact_rows.size(); ++i) {
      for (size_t j = 0; j < p.contact_rows.size(); ++j) {
        jac(p.contact_rows[i], p.contact_rows[j]) += nj(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
      }
    }
  }
  return jac;
}

Eigen::VectorXd HarmonicBalance::linear_response() const {
  impl_->require_factorized();
  return impl_->a_lin;
}

Eigen::VectorXd HarmonicBalance::contact_unknowns(const Eigen::VectorXd& a) const {
  return impl_->gather(a);
}

Eigen::VectorXd HarmonicBalance::contact_residual(const Eigen::VectorXd& x) const {
  return impl_->contact_residual(x, 1.0);
}

Eigen::MatrixXd HarmonicBalance::contact_jacobian(const Eigen::VectorXd& x) const {
  const auto& p = *impl_;
  p.require_factorized();
  Eigen::MatrixXd nj;
  (void)p.contact_forces(x, &nj);
  Eigen::MatrixXd jac = p.h * nj;
  jac.diagonal().array() += 1.0;
  return jac / p.scale;
}

Eigen::VectorXd HarmonicBalance::expand(const Eigen::VectorXd& x) const {
  const auto& p = *impl_;
  p.require_factorized();
  Eigen::VectorXd rhs = p.b;
  if (p.nc > 0) {
    const Eigen::VectorXd nx = p.contact_forces(x, nullptr);
    for (size_t j = 0; j < p.contact_rows.size(); ++j) rhs(p.contact_rows[j]) -= nx(j);
  }
  return p.lu.solve(rhs);
}

// The condensed system at load factor s (forcing s·F) as a NonlinearSystem.
struct HarmonicBalance::Condensed {
  const HarmonicBalance* hb;
  double load;
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x) const {
    return hb->impl_->contact_residual(x, load);
  }
  [[nodiscard]] Eigen::MatrixXd jacobian(const Eigen::VectorXd& x) const { return hb->contact_jacobian(x); }
};

NewtonResult HarmonicBalance::solve_with_load_stepping(Eigen::VectorXd x, int& steps) const {
  // Forcing s·F for s from 0 to 1; the step ds doubles after a success (at most ½) and is
  // quartered after a failure; predictor x + ds·x_lin (the linear part of the response).
  const auto& p = *impl_;
  double s = 0.0, ds = 0.125;
  NewtonResult last{std::move(x), {}};
  int iterations = 0;
  steps = 0;
  while (s < 1.0) {
    const double target = std::min(1.0, s + ds);
    Eigen::VectorXd guess = last.x + (target - s) * p.x_lin;
    NewtonResult trial = newton(Condensed{this, target}, std::move(guess), p.options.newton);
    iterations += trial.report.iterations;
    ++steps;
    if (trial.report.converged()) {
      s = target;
      last = std::move(trial);
      ds = std::min(0.5, 2.0 * ds);
    } else {
      ds *= 0.25;
      if (ds < 1e-6) {
        trial.report.iterations = iterations;
        trial.report.message = "load stepping stalled at s = " + std::to_string(s) + " of F: " +
                               trial.report.message;
        return trial;
      }
    }
  }
  last.report.iterations = iterations;
  return last;
}

HarmonicBalanceSolution HarmonicBalance::solve(const Eigen::VectorXd* x0) const {
  const auto start = std::chrono::steady_clock::now();
  const auto& p = *impl_;
  HarmonicBalanceSolution s;
  s.frequency_hz = p.forcing.frequency_hz;
  s.contact_unknowns = p.nc * p.m;
  if (!p.factorized) {
    s.report.status = SolveStatus::SingularJacobian;
    s.report.message = "linear operator G is singular (forcing at an undamped natural frequency?)";
    s.coefficients = Eigen::MatrixXd::Zero(p.n, p.m);
    s.relative_residual = std::numeric_limits<double>::infinity();
    return s;
  }
  Eigen::VectorXd x;
  if (p.nc > 0) {
    Eigen::VectorXd start_x = x0 != nullptr ? *x0 : p.x_lin;
    if (start_x.size() != p.nc * p.m) {
      throw std::invalid_argument("HarmonicBalance::solve: initial guess has length " +
                                  std::to_string(start_x.size()) + ", expected n_c*M = " +
                                  std::to_string(p.nc * p.m));
    }
    NewtonResult result = newton(Condensed{this, 1.0}, start_x, p.options.newton);
    if (!result.report.converged() && x0 == nullptr) {
      // Fallback for stiff laws and near-resonant forcing: continuation in the load.
      int steps = 0;
      NewtonResult stepped = solve_with_load_stepping(Eigen::VectorXd::Zero(start_x.size()), steps);
      const std::string first = result.report.message;
      stepped.report.iterations += result.report.iterations;
      stepped.report.message = "direct Newton: " + first + "; load stepping (" +
                               std::to_string(steps) + " steps): " + stepped.report.message;
      result = std::move(stepped);
    }
    x = std::move(result.x);
    s.report = std::move(result.report);
  } else {
    s.report.status = SolveStatus::Converged;
    s.report.message = "linear problem (no contact): one solve";
    s.report.residual_norms = {0.0};
  }
  const Eigen::VectorXd a = p.nc > 0 ? expand(x) : p.a_lin;
  s.coefficients = spectral::as_coefficients(a, p.n);
  const double bnorm = p.b.norm();
  s.relative_residual = residual(a).norm() / (bnorm > 0.0 ? bnorm : 1.0);
  if (p.nc > 0) {
    const Eigen::MatrixXd u = p.contact_samples(x);
    s.max_penetration = -std::numeric_limits<double>::infinity();
    for (int c = 0; c < p.nc; ++c) {
      for (int k = 0; k < p.q; ++k) {
        s.max_penetration = std::max(s.max_penetration, u(c, k) - p.contacts[c].law->gap());
        s.max_contact_force = std::max(s.max_contact_force, p.contacts[c].law->force(u(c, k)));
      }
    }
  }
  if (s.report.converged() && !std::isfinite(s.relative_residual)) {
    s.report.status = SolveStatus::NonFinite;
    s.report.message = "non-finite full residual after convergence of the condensed system";
  }
  s.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return s;
}

HarmonicBalanceSolution solve_harmonic_balance(const MechanicalSystem& system,
                                               const HarmonicForcing& forcing,
                                               const std::vector<ContactPoint>& contacts,
                                               const HarmonicBalanceOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const HarmonicBalance hb(system, forcing, contacts, options);
  HarmonicBalanceSolution s = hb.solve();
  s.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return s;
}

Eigen::VectorXd evaluate_dof(const Eigen::MatrixXd& coefficients, int dof,
                             const Eigen::VectorXd& tau, double frequency_hz, int derivative) {
  if (dof < 0 || dof >= coefficients.rows()) {
    throw std::invalid_argument("evaluate_dof: dof = " + std::to_string(dof) + " outside [0, " +
                                std::to_string(coefficients.rows()) + ")");
  }
  const spectral::FourierBasis basis(static_cast<int>(coefficients.cols()));
  const Eigen::MatrixXd v = basis.values(tau, derivative);
  return std::pow(frequency_hz, derivative) * (v * coefficients.row(dof).transpose());
}

}  // namespace wbm::solvers
