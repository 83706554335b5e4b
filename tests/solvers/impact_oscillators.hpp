// Impact oscillators in closed form, shared by the rigid-stop tests (test_rigid_contact.cpp,
// test_impact_shooting.cpp, test_impact_stability.cpp): the 1-DOF oscillator against a rigid stop with a plastic impact
// (a contact phase every period) and with Newton's restitution e > 0 (one impact per period).
#pragma once

#include <algorithm>
#include <cmath>
#include <complex>
#include <memory>
#include <numbers>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_roots.h>

#include <wbm/contact/signorini.hpp>
#include <wbm/solvers/mechanical_system.hpp>

namespace wbm::testing {

// m ü + c u̇ + k u: 1 × 1 matrices [kg, N·s/m, N/m].
inline wbm::solvers::MechanicalSystem one_dof_system(double m, double c, double k) {
  wbm::solvers::MechanicalSystem s;
  s.mass = Eigen::MatrixXd::Constant(1, 1, m).sparseView();
  s.damping = Eigen::MatrixXd::Constant(1, 1, c).sparseView();
  s.stiffness = Eigen::MatrixXd::Constant(1, 1, k).sparseView();
  return s;
}

// One rigid stop at `dof` with initial gap g0 [m] (the contact list of the impact tests).
inline std::vector<wbm::solvers::ContactPoint> stop_at(int dof, double gap) {
  return {{dof, std::make_shared<wbm::contact::RigidStop>(gap)}};
}

// The 1-DOF impact oscillator m ü + c u̇ + k u = F cos ωt against a rigid stop at u = g0 with a
// plastic impact (e = 0), in closed form. Once the mass is on the stop it stays there while the
// load pushes it on (contact force F cos ωt − k g0 ≥ 0) and leaves it at the instant t₁ with
// F cos ωt₁ = k g0, ωt₁ = arccos(k g0/F) ∈ (0, π/2): the state (g0, 0) at t₁ is the same every
// period, whatever came before. From it the free flight is the linear response
//   u(t) = u_p(t) + e^{−ζω_n s}(A cos ω_d s + B sin ω_d s),  s = t − t₁,
// u_p = Re(F e^{iωt}/(k − mω² + iωc)), A = g0 − u_p(t₁), B = (ζω_n A − u̇_p(t₁))/ω_d, until its
// first return to g0 at t_i (a bracketed root, GSL's Brent). The orbit with one impact per
// period is: flight on [t₁, t_i], rest on the stop on [t_i, t₁ + T]; it exists when t_i − T lies
// in the sticking window ω(t_i − T) ≥ −arccos(k g0/F), which the test checks.
struct PlasticImpactOscillator {
  double m = 1.0, k = std::pow(2.0 * std::numbers::pi * 10.0, 2), zeta = 0.05, f = 8.0, amplitude = 10.0;
  double c = 2.0 * zeta * std::sqrt(k * m), gap = 0.5 * amplitude / k;  // k g0 / F = ½
  double omega = 2.0 * std::numbers::pi * f, wn = std::sqrt(k / m), wd = wn * std::sqrt(1.0 - zeta * zeta);
  std::complex<double> u_amp = amplitude / std::complex<double>(k - m * omega * omega, omega* c);
  double t1 = std::acos(k * gap / amplitude) / omega, t_impact = 0.0, a = 0.0, b = 0.0;

  [[nodiscard]] double particular(double t) const {
    return std::real(u_amp * std::exp(std::complex<double>(0.0, omega * t)));
  }
  [[nodiscard]] double flight(double t) const {
    const double s = t - t1;
    return particular(t) + std::exp(-zeta * wn * s) * (a * std::cos(wd * s) + b * std::sin(wd * s));
  }
  PlasticImpactOscillator() {
    const double v_p =
        std::real(std::complex<double>(0.0, omega) * u_amp * std::exp(std::complex<double>(0.0, omega * t1)));
    a = gap - particular(t1);
    b = (zeta * wn * a - v_p) / wd;
    // First return: the first sign change of u − g0 after the mass has left (a fine scan), then Brent.
    const double period = 1.0 / f;
    double lo = t1 + 1e-6 * period, hi = lo;
    for (int i = 1; i <= 100000; ++i) {
      hi = t1 + period * 1.25 * i / 100000.0;
      if (flight(hi) > gap) break;
      lo = hi;
    }
    gsl_function fn{[](double t, void* p) {
                      const auto* o = static_cast<const PlasticImpactOscillator*>(p);
                      return o->flight(t) - o->gap;
                    },
                    this};
    gsl_root_fsolver* solver = gsl_root_fsolver_alloc(gsl_root_fsolver_brent);
    gsl_root_fsolver_set(solver, &fn, lo, hi);
    for (int i = 0; i < 200; ++i) {
      gsl_root_fsolver_iterate(solver);
      if (gsl_root_test_interval(gsl_root_fsolver_x_lower(solver), gsl_root_fsolver_x_upper(solver), 0.0, 1e-15) ==
          GSL_SUCCESS)
        break;
    }
    t_impact = gsl_root_fsolver_root(solver);
    gsl_root_fsolver_free(solver);
  }
  [[nodiscard]] wbm::solvers::MechanicalSystem system() const { return one_dof_system(m, c, k); }
  // u at τ = t f ∈ [0, 1).
  [[nodiscard]] double displacement(double tau) const {
    const double period = 1.0 / f;
    double t = tau * period;
    while (t < t1) t += period;
    return t <= t_impact ? flight(t) : gap;
  }
};

// The same oscillator with Newton's impact law u̇⁺ = −e u̇⁻ (0 < e ≤ 1) and an orbit with one
// impact per period [Shaw & Holmes 1983, J. Sound Vib. 90(1) 129–155]: the mass hits the stop at
// t_i with velocity V > 0, leaves it with −eV, and the free flight over one period T,
//   u(t_i + s) = u_p(t_i + s) + e^{−ζω_n s}(A cos ω_d s + B sin ω_d s),
//   A = g0 − u_p(t_i),  B = (−eV − u̇_p(t_i) + ζω_n A)/ω_d,
// returns to (g0, V): two equations in (t_i, V), solved here by Newton with a central-difference
// Jacobian from `guess`. The monodromy matrix over the period that starts just after the impact
// is S Φ_f in closed form: Φ_f the free flight's over T (the damped 2 × 2 exponential), and the
// saltation matrix of the impact at the surface h = g0 − u,
//   S = [[−e, 0], [(a⁺ + e a⁻)/V, −e]],  a∓ = (F cos ωt_i − c u̇∓ − k g0)/m  (u̇⁻ = V, u̇⁺ = −eV).
struct ElasticImpactOscillator {
  double m = 1.0, k = std::pow(2.0 * std::numbers::pi, 2), zeta = 0.05, f = 0.9, amplitude = 1.0, gap = 0.01;
  double restitution = 0.8;
  double c = 2.0 * zeta * std::sqrt(k * m), omega = 2.0 * std::numbers::pi * f, wn = std::sqrt(k / m),
         wd = wn * std::sqrt(1.0 - zeta * zeta), sigma = zeta * wn, period = 1.0 / f;
  std::complex<double> u_amp = amplitude / std::complex<double>(k - m * omega * omega, omega* c);
  double t_impact = 0.0, velocity = 0.0;

  [[nodiscard]] double particular(double t) const {
    return std::real(u_amp * std::exp(std::complex<double>(0.0, omega * t)));
  }
  [[nodiscard]] double particular_velocity(double t) const {
    return std::real(std::complex<double>(0.0, omega) * u_amp * std::exp(std::complex<double>(0.0, omega * t)));
  }
  // (u, u̇) at t_i + s of the flight that leaves the stop at t_i with velocity v0.
  [[nodiscard]] Eigen::Vector2d flight(double ti, double v0, double s) const {
    const double a = gap - particular(ti), b = (v0 - particular_velocity(ti) + sigma * a) / wd;
    const double ex = std::exp(-sigma * s), cs = std::cos(wd * s), sn = std::sin(wd * s);
    return {particular(ti + s) + ex * (a * cs + b * sn),
            particular_velocity(ti + s) + ex * (-sigma * (a * cs + b * sn) + wd * (-a * sn + b * cs))};
  }
  explicit ElasticImpactOscillator(double ti_guess = 1.1, double v_guess = 0.3) {
    Eigen::Vector2d p(ti_guess, v_guess);
    auto equations = [&](const Eigen::Vector2d& q) {
      return Eigen::Vector2d(flight(q(0), -restitution * q(1), period) - Eigen::Vector2d(gap, q(1)));
    };
    for (int it = 0; it < 50 && equations(p).norm() > 1e-15; ++it) {
      Eigen::Matrix2d j;
      for (int col = 0; col < 2; ++col) {
        Eigen::Vector2d d = Eigen::Vector2d::Zero();
        d(col) = 1e-7;
        j.col(col) = (equations(p + d) - equations(p - d)) / 2e-7;
      }
      p -= j.partialPivLu().solve(equations(p));
    }
    t_impact = p(0);
    velocity = p(1);
  }
  // The largest u − g0 over the flight (negative: the orbit stays off the stop between impacts).
  [[nodiscard]] double largest_excursion() const {
    double worst = -1e300;
    for (int i = 1; i < 4000; ++i)
      worst = std::max(worst, flight(t_impact, -restitution * velocity, period * i / 4000.0)(0) - gap);
    return worst;
  }
  [[nodiscard]] Eigen::Matrix2d monodromy() const {
    const double ex = std::exp(-sigma * period), cs = std::cos(wd * period), sn = std::sin(wd * period);
    Eigen::Matrix2d phi;
    phi << cs + sigma / wd * sn, sn / wd, -(wd * wd + sigma * sigma) / wd * sn, cs - sigma / wd * sn;
    phi *= ex;
    const double load = amplitude * std::cos(omega * t_impact) - k * gap;
    const double a_minus = (load - c * velocity) / m, a_plus = (load + c * restitution * velocity) / m;
    Eigen::Matrix2d salt;
    salt << -restitution, 0.0, (a_plus + restitution * a_minus) / velocity, -restitution;
    return salt * phi;
  }
  [[nodiscard]] wbm::solvers::MechanicalSystem system() const { return one_dof_system(m, c, k); }
};

}  // namespace wbm::testing
