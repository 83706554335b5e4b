// The Haar weighted residual with Newton's impact law at rigid stops (haar_impact.hpp): the causal
// sweep of the boxes' equations, its sensitivities, and the fixed point of the period through the
// project's Newton core.
#include <wbm/solvers/haar_impact.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <wbm/contact/signorini.hpp>

#include "core/lcp_step.hpp"

namespace wbm::solvers {
namespace {

std::string num(double v) { return format_number(v); }

// The largest model solve_haar_impact takes: its matrices are dense and a step's sensitivities
// cost O(n³).
constexpr int kMaxDofs = 400;
// The most cells per period: 2^22, far beyond the convergence the error tables need (an M + 1
// column count and the n × M results stay far from int's range).
constexpr int kMaxCells = 1 << 22;

// The boxes' matrices and loads of one problem (haar_impact.hpp's notation).
struct Scheme {
  int n = 0, nc = 0, cells = 0;
  double h = 0.0, restitution = 0.0;
  Eigen::MatrixXd a_plus, b0, a_minus;  // A₊, B₀, A₋ (n × n)
  Eigen::MatrixXd e0, em;               // −A₊⁻¹ B₀, −A₊⁻¹ A₋
  Eigen::MatrixXd w;                    // W (n × n_c)
  Eigen::MatrixXd g_impulse;            // G = A₊⁻¹ W / h (n × n_c): u_{k+1} = a_k − G P_k
  Eigen::MatrixXd delassus;             // Wᵀ G / (1 + e) (n_c × n_c)
  Eigen::VectorXd gaps;                 // g (n_c)
  Eigen::MatrixXd loads;                // f̄_k (n × M)
  Eigen::MatrixXd free_loads;           // A₊⁻¹ f̄_k (n × M)
};

// One sweep from s = (u_{−1}, u_0): the cell values u_0 … u_M, the impulses, and (when asked) the
// sensitivities of u_{M−1} and u_M to s.
struct Sweep {
  Eigen::MatrixXd u;         // n × (M + 1)
  Eigen::MatrixXd impulses;  // n_c × M
  Eigen::MatrixXd d_last, d_end;  // ∂u_{M−1}/∂s, ∂u_M/∂s (n × 2n)
  int lcp_failures = 0;
  double lcp_error = 0.0;
};

Sweep sweep(const Scheme& sc, const Eigen::VectorXd& s, bool sensitivities, detail::LcpStep& lcp) {
  const int n = sc.n, m = sc.cells;
  Sweep out;
  out.u.resize(n, m + 1);
  out.impulses.setZero(sc.nc, m);
  Eigen::VectorXd prev = s.head(n);
  out.u.col(0) = s.tail(n);
  Eigen::MatrixXd d_prev, d_cur;
  if (sensitivities) {
    d_prev = Eigen::MatrixXd::Zero(n, 2 * n);
    d_cur = Eigen::MatrixXd::Zero(n, 2 * n);
    d_prev.leftCols(n).setIdentity();
    d_cur.rightCols(n).setIdentity();
  }
  Eigen::VectorXd p;
  for (int k = 0; k < m; ++k) {
    const Eigen::VectorXd cur = out.u.col(k);
    const Eigen::VectorXd a = sc.free_loads.col(k) + sc.e0 * cur + sc.em * prev;
    // The law's gap without impulse: g − Wᵀ (a + e u_{k−1})/(1 + e).
    const Eigen::VectorXd q = sc.gaps - sc.w.transpose() * (a + sc.restitution * prev) / (1.0 + sc.restitution);
    const auto outcome = lcp.solve(sc.delassus, q, p);
    if (outcome.info != 0) ++out.lcp_failures;
    out.lcp_error = std::max(out.lcp_error, outcome.error);
    out.impulses.col(k) = p;
    out.u.col(k + 1) = a - sc.g_impulse * p;
    if (sensitivities) {
      Eigen::MatrixXd d_next = sc.e0 * d_cur + sc.em * d_prev;  // ∂a/∂s
      std::vector<int> active;
      for (int c = 0; c < sc.nc; ++c) {
        if (p(c) > 0.0) active.push_back(c);
      }
      if (!active.empty()) {
        const auto na = static_cast<Eigen::Index>(active.size());
        Eigen::MatrixXd daa(na, na), wa(n, na), ga(n, na);
        for (Eigen::Index i = 0; i < na; ++i) {
          wa.col(i) = sc.w.col(active[i]);
          ga.col(i) = sc.g_impulse.col(active[i]);
          for (Eigen::Index j = 0; j < na; ++j) daa(i, j) = sc.delassus(active[i], active[j]);
        }
        // The active rows hold q_A + D_AA P_A = 0: ∂P_A = D_AA⁻¹ W_Aᵀ (∂a + e ∂u_{k−1})/(1 + e).
        const Eigen::MatrixXd dq = wa.transpose() * (d_next + sc.restitution * d_prev) / (1.0 + sc.restitution);
        d_next -= ga * daa.partialPivLu().solve(dq);
      }
      d_prev = std::move(d_cur);
      d_cur = std::move(d_next);
    }
    prev = cur;
  }
  if (sensitivities) {
    out.d_last = std::move(d_prev);
    out.d_end = std::move(d_cur);
  }
  return out;
}

// The fixed point R(s) = ((u_{M−1}, u_M)(s) − s)/u_ref for the Newton core, one sweep per new s.
struct PeriodMap {
  const Scheme* scheme = nullptr;
  double reference = 1.0;
  detail::LcpStep* lcp = nullptr;
  mutable Eigen::VectorXd last_s;
  mutable Sweep last;

  const Sweep& at(const Eigen::VectorXd& s) const {
    if (last_s.size() != s.size() || last_s != s) {
      last = sweep(*scheme, s, true, *lcp);
      last_s = s;
    }
    return last;
  }
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& z) const {
    const Eigen::VectorXd s = z * reference;
    const Sweep& w = at(s);
    const int n = scheme->n, m = scheme->cells;
    Eigen::VectorXd r(2 * n);
    r.head(n) = w.u.col(m - 1) - s.head(n);
    r.tail(n) = w.u.col(m) - s.tail(n);
    return r / reference;
  }
  [[nodiscard]] Eigen::MatrixXd jacobian(const Eigen::VectorXd& z) const {
    const Sweep& w = at(z * reference);
    const int n = scheme->n;
    Eigen::MatrixXd j(2 * n, 2 * n);
    j.topRows(n) = w.d_last;
    j.bottomRows(n) = w.d_end;
    j -= Eigen::MatrixXd::Identity(2 * n, 2 * n);
    return j;  // ∂R/∂z: the scale cancels
  }
};

double largest_natural_angular_frequency(const Eigen::MatrixXd& k, const Eigen::MatrixXd& m) {
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(k, m, Eigen::EigenvaluesOnly);
  if (eig.info() != Eigen::Success) {
    throw std::invalid_argument("solve_haar_impact: the generalized eigenproblem K φ = ω² M φ failed: M must be "
                                "symmetric positive definite");
  }
  return std::sqrt(std::max(0.0, eig.eigenvalues().maxCoeff()));
}

Scheme build(const MechanicalSystem& system, const HarmonicForcing& forcing, const std::vector<ContactPoint>& stops,
             const HaarImpactOptions& options) {
  system.validate();
  const int n = static_cast<int>(system.mass.rows());
  if (n > kMaxDofs) {
    throw std::invalid_argument("solve_haar_impact: the model has " + std::to_string(n) + " DOFs, more than " +
                                std::to_string(kMaxDofs) + ": its sweep is dense, for point-mass models; reduce "
                                "the model (wbm reduce, Craig–Bampton) or use the weighted residual with a penalty law");
  }
  forcing.validate(n);
  forcing.require_resolved(options.cells, "the Haar weighted residual's M = " + std::to_string(options.cells) + " cells",
                           "raise HaarImpactOptions.cells");
  if (stops.empty()) {
    throw std::invalid_argument("solve_haar_impact: the stop list is empty: give at least one contact::RigidStop "
                                "(without contact the response is linear: harmonic_balance.hpp)");
  }
  ContactPoint::validate(stops, n);
  Scheme sc;
  sc.n = n;
  sc.nc = static_cast<int>(stops.size());
  sc.cells = options.cells;
  sc.restitution = options.restitution;
  const double period = 1.0 / forcing.frequency_hz;
  sc.h = period / options.cells;
  sc.w.resize(n, sc.nc);
  sc.gaps.resize(sc.nc);
  for (int c = 0; c < sc.nc; ++c) {
    const auto& stop = stops[static_cast<size_t>(c)];
    if (stop.law == nullptr || !stop.law->rigid()) {
      throw std::invalid_argument("solve_haar_impact: contact " + std::to_string(c) + " is " +
                                  (stop.law ? stop.law->describe() : std::string("without a law")) +
                                  ": only contact::RigidStop takes an impact law (penalty laws: "
                                  "weighted_residual.hpp; friction: Moreau–Jean)");
    }
    if (stop.obstacle.moving()) {
      throw std::invalid_argument("solve_haar_impact: contact " + std::to_string(c) +
                                  " has a moving counter-surface: the stops here are fixed (use Moreau–Jean's "
                                  "time stepping, or the weighted residual with a penalty law)");
    }
    sc.w.col(c) = stop.direction(n);
    sc.gaps(c) = stop.law->gap();
  }
  const Eigen::MatrixXd mm(system.mass), cc(system.damping), kk(system.stiffness);
  const double omega_max = largest_natural_angular_frequency(kk, mm);
  if (!(sc.h * omega_max < 2.0)) {
    // As a double: T ω_max/2 may exceed any int (a tiny frequency), and its cast would be undefined.
    const double least = std::floor(period * omega_max / 2.0) + 1.0;
    throw std::invalid_argument("HaarImpactOptions.cells = " + std::to_string(options.cells) + ": the sweep (central "
                                "differences) needs h ω_max < 2, here h ω_max = " + num(sc.h * omega_max) +
                                " (ω_max = " + num(omega_max) + " rad/s); use cells ≥ " + num(least) +
                                ", or a reduced model without its stiff modes");
  }
  const double h2 = sc.h * sc.h;
  sc.a_plus = mm / h2 + cc / (2.0 * sc.h);
  sc.b0 = kk - 2.0 * mm / h2;
  sc.a_minus = mm / h2 - cc / (2.0 * sc.h);
  const Eigen::PartialPivLU<Eigen::MatrixXd> lu(sc.a_plus);
  sc.e0 = -lu.solve(sc.b0);
  sc.em = -lu.solve(sc.a_minus);
  sc.g_impulse = lu.solve(sc.w) / sc.h;
  sc.delassus = sc.w.transpose() * sc.g_impulse / (1.0 + sc.restitution);
  // f̄_k: the exact mean of F cos(Ω t + φ) over [k h, (k + 1) h], Ω = 2π h_j f.
  sc.loads = Eigen::MatrixXd::Zero(n, options.cells);
  for (const auto& load : forcing.loads()) {
    const double big_omega = 2.0 * std::numbers::pi * load.harmonic * forcing.frequency_hz;
    for (int k = 0; k < options.cells; ++k) {
      const double t0 = k * sc.h;
      sc.loads(load.dof, k) += load.harmonic == 0 ? load.amplitude * std::cos(load.phase_rad)
                                                  : load.amplitude *
                                                        (std::sin(big_omega * (t0 + sc.h) + load.phase_rad) -
                                                         std::sin(big_omega * t0 + load.phase_rad)) /
                                                        (big_omega * sc.h);
    }
  }
  sc.free_loads = lu.solve(sc.loads);
  return sc;
}

// The periodic Galerkin residual and complementarity from the cell values, indices modulo M.
void verify(const Scheme& sc, HaarImpactSolution& out) {
  const int m = sc.cells;
  const double na = sc.a_plus.lpNorm<Eigen::Infinity>(), nb = sc.b0.lpNorm<Eigen::Infinity>(),
               nm = sc.a_minus.lpNorm<Eigen::Infinity>();
  const auto& u = out.displacement;
  double residual = 0.0, complementarity = 0.0, penetration = -INFINITY;
  for (int k = 0; k < m; ++k) {
    const Eigen::VectorXd& next = u.col((k + 1) % m);
    const Eigen::VectorXd& prev = u.col((k + m - 1) % m);
    const Eigen::VectorXd force = sc.w * out.impulses.col(k) / sc.h;
    const Eigen::VectorXd r = sc.a_plus * next + sc.b0 * u.col(k) + sc.a_minus * prev - sc.loads.col(k) + force;
    const double scale = na * next.lpNorm<Eigen::Infinity>() + nb * u.col(k).lpNorm<Eigen::Infinity>() +
                         nm * prev.lpNorm<Eigen::Infinity>() + sc.loads.col(k).lpNorm<Eigen::Infinity>() +
                         force.lpNorm<Eigen::Infinity>();
    residual = std::max(residual, scale > 0.0 ? r.lpNorm<Eigen::Infinity>() / scale : 0.0);
    const Eigen::VectorXd gamma =
        sc.gaps - sc.w.transpose() * (next + sc.restitution * prev) / (1.0 + sc.restitution);
    for (int c = 0; c < sc.nc; ++c) {
      const double d = sc.delassus(c, c) * out.impulses(c, k);
      complementarity = std::max(complementarity, std::abs(std::min(gamma(c), d)) / out.reference_displacement);
      complementarity = std::max(complementarity, std::max(-out.impulses(c, k) * sc.delassus(c, c), 0.0) /
                                                       out.reference_displacement);
      penetration = std::max(penetration, (sc.w.col(c).dot(u.col(k)) - sc.gaps(c)) / out.reference_displacement);
    }
    if (out.impulses.col(k).maxCoeff() > 0.0) ++out.impact_cells;
  }
  out.residual = residual;
  out.complementarity = complementarity;
  out.penetration = penetration;
}

}  // namespace

void HaarImpactOptions::validate() const {
  if (cells < 8 || cells > kMaxCells) {
    throw std::invalid_argument("HaarImpactOptions.cells = " + std::to_string(cells) + ": must lie in [8, " +
                                std::to_string(kMaxCells) + "] (Haar scaling functions per period)");
  }
  if (!(restitution >= 0.0 && restitution <= 1.0)) {
    throw std::invalid_argument("HaarImpactOptions.restitution = " + num(restitution) +
                                ": Newton's coefficient must lie in [0, 1] (0 plastic, 1 elastic)");
  }
  if (transient_periods < 0) {
    throw std::invalid_argument("HaarImpactOptions.transient_periods = " + std::to_string(transient_periods) +
                                ": must be ≥ 0 (0 starts Newton from the start itself)");
  }
  if (!(residual_tolerance > 0.0 && std::isfinite(residual_tolerance))) {
    throw std::invalid_argument("HaarImpactOptions.residual_tolerance = " + num(residual_tolerance) +
                                ": must be finite and > 0 (1e-10 by default)");
  }
  newton.validate();
}

HaarImpactSolution solve_haar_impact(const MechanicalSystem& system, const HarmonicForcing& forcing,
                                     const std::vector<ContactPoint>& stops, const HaarImpactOptions& options,
                                     const std::optional<Eigen::MatrixXd>& guess) {
  options.validate();
  const Scheme sc = build(system, forcing, stops, options);
  const int n = sc.n, m = sc.cells;
  Eigen::VectorXd s = Eigen::VectorXd::Zero(2 * n);
  if (guess) {
    if (guess->rows() != n || guess->cols() != 2 || !guess->allFinite()) {
      throw std::invalid_argument("solve_haar_impact: the guess is " + std::to_string(guess->rows()) + " x " +
                                  std::to_string(guess->cols()) + (guess->allFinite() ? "" : " with non-finite entries") +
                                  ": it must be n x 2 (u_{-1}, u_0) and finite, n = " + std::to_string(n));
    }
    s.head(n) = guess->col(0);
    s.tail(n) = guess->col(1);
  }
  detail::LcpStep lcp;
  HaarImpactSolution out;
  // The transient: the scheme's own time stepping, s ← (u_{M−1}, u_M).
  Sweep w = sweep(sc, s, false, lcp);
  for (int p = 0; p < options.transient_periods && w.u.allFinite(); ++p) {
    s.head(n) = w.u.col(m - 1);
    s.tail(n) = w.u.col(m);
    w = sweep(sc, s, false, lcp);
  }
  if (!w.u.allFinite()) {
    out.status = SolveStatus::NonFinite;
    out.message = "the time stepping of the transient left non-finite values (raise HaarImpactOptions.cells)";
    return out;
  }
  out.reference_displacement = std::max(sc.gaps.cwiseAbs().maxCoeff(), w.u.cwiseAbs().maxCoeff());
  if (!(out.reference_displacement > 0.0)) out.reference_displacement = 1.0;  // no gap, no load: u = 0
  PeriodMap map{&sc, out.reference_displacement, &lcp, {}, {}};
  const NewtonResult solved = newton(map, s / out.reference_displacement, options.newton);
  out.report = solved.report;
  const Sweep& last = map.at(solved.x * out.reference_displacement);
  out.displacement = last.u.leftCols(m);
  out.impulses = last.impulses;
  if (!out.displacement.allFinite() || !out.impulses.allFinite()) {
    out.status = SolveStatus::NonFinite;
    out.message = "the sweep left non-finite values: " + solved.report.brief();
    out.displacement.resize(0, 0);
    out.impulses.resize(0, 0);
    return out;
  }
  verify(sc, out);
  if (!solved.report.converged()) {
    out.status = solved.report.status;
    out.message = "the fixed point of the period: " + solved.report.brief() +
                  " (raise HaarImpactOptions.transient_periods or newton.max_iterations, or give a guess)";
  } else if (last.lcp_failures > 0) {
    out.status = SolveStatus::ResidualNotVerified;
    out.message = "Siconos' Lemke failed in " + std::to_string(last.lcp_failures) + " steps (error up to " +
                  num(last.lcp_error) + ")";
  } else if (out.residual > options.residual_tolerance || out.complementarity > options.residual_tolerance) {
    out.status = SolveStatus::ResidualNotVerified;
    out.message = "the verified residual " + num(out.residual) + " or complementarity " + num(out.complementarity) +
                  " exceeds residual_tolerance = " + num(options.residual_tolerance) +
                  " (raise HaarImpactOptions.residual_tolerance, or tighten newton.tolerance)";
  } else {
    out.status = SolveStatus::Converged;
    out.message = "converged: " + solved.report.brief() + "; verified residual " + num(out.residual) +
                  ", complementarity " + num(out.complementarity) + " (tolerance " + num(options.residual_tolerance) +
                  "); " + std::to_string(out.impact_cells) + " cells with an impulse";
  }
  return out;
}

}  // namespace wbm::solvers
