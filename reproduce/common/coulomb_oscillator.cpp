#include "coulomb_oscillator.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>

#include <wbm/solvers/status.hpp>

namespace wbm::reproduce {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr int kScan = 16384;       // scan steps per period for the phase ends
constexpr double kRepeat = 1e-13;  // periodicity, relative to P/k and ω P/k

struct State {
  double x = 0.0, v = 0.0;
  bool stuck = true;
  double sigma = 0.0;   // slip direction (±1) when not stuck
  double slider = 0.0;  // the slider's position s in stick (finite k_t)
};

// The linear motion m ẍ + c ẋ + K x = P cos ωt + F_c from (t0, x0, v0): the forced response
// Re(Z e^{iωt}) + F_c/K, Z = P/(K − mω² + icω), plus the free one e^{−ζω s}(A cos ω_d s + B sin ω_d s).
class LinearPhase {
 public:
  LinearPhase(const CoulombOscillator& o, double stiffness, double constant_force, double t0, double x0, double v0)
      : omega_(2.0 * kPi * o.frequency_hz), decay_(o.damping / (2.0 * o.mass)), t0_(t0),
        offset_(constant_force / stiffness) {
    omega_d_ = std::sqrt(stiffness / o.mass - decay_ * decay_);
    z_ = o.force_amplitude / std::complex<double>(stiffness - o.mass * omega_ * omega_, o.damping * omega_);
    a_ = x0 - particular(t0);
    b_ = (v0 - particular_velocity(t0) + decay_ * a_) / omega_d_;
  }
  [[nodiscard]] double displacement(double t) const {
    const double u = t - t0_, e = std::exp(-decay_ * u);
    return particular(t) + e * (a_ * std::cos(omega_d_ * u) + b_ * std::sin(omega_d_ * u));
  }
  [[nodiscard]] double velocity(double t) const {
    const double u = t - t0_, e = std::exp(-decay_ * u), c = std::cos(omega_d_ * u), s = std::sin(omega_d_ * u);
    return particular_velocity(t) + e * ((-decay_ * a_ + omega_d_ * b_) * c - (decay_ * b_ + omega_d_ * a_) * s);
  }

 private:
  [[nodiscard]] double particular(double t) const {
    return z_.real() * std::cos(omega_ * t) - z_.imag() * std::sin(omega_ * t) + offset_;
  }
  [[nodiscard]] double particular_velocity(double t) const {
    return -omega_ * (z_.real() * std::sin(omega_ * t) + z_.imag() * std::cos(omega_ * t));
  }
  double omega_, decay_, t0_, offset_, omega_d_ = 0.0, a_ = 0.0, b_ = 0.0;
  std::complex<double> z_;
};

// The phases of one period t ∈ [0, T] (the forcing is T-periodic, so each period restarts at 0).
class Integrator {
 public:
  explicit Integrator(const CoulombOscillator& o) : o_(o), period_(1.0 / o.frequency_hz) {}
  [[nodiscard]] double period() const { return period_; }
  [[nodiscard]] bool coulomb() const { return std::isinf(o_.tangential_stiffness); }
  // P cos ωt − k x: the force the friction must hold in a Coulomb stick.
  [[nodiscard]] double unbalanced(double t, double x) const {
    return o_.force_amplitude * std::cos(2.0 * kPi * o_.frequency_hz * t) - o_.stiffness * x;
  }

  // The state at t_end ≥ t; adds the time spent in stick to stick_time and the |x| at each
  // velocity zero that ends a slip to extreme.
  State advance(State s, double t, double t_end) {
    while (t < t_end) {
      if (s.stuck && coulomb()) {
        auto slips = [&](double tt) { return std::abs(unbalanced(tt, s.x)) > o_.slip_force; };
        double lo = t, hi = t;
        if (!slips(t)) {
          hi = first_where(t, t_end, slips, lo);
          if (hi < 0.0) {  // holds to the end
            stick_time += t_end - t;
            return s;
          }
        }
        stick_time += hi - t;
        t = hi;
        s = {s.x, 0.0, false, unbalanced(t, s.x) > 0.0 ? 1.0 : -1.0, 0.0};
      } else if (s.stuck) {  // the spring k_t holds the slider: stiffness k + k_t, force k_t s
        const double kt = o_.tangential_stiffness;
        const LinearPhase phase(o_, o_.stiffness + kt, kt * s.slider, t, s.x, s.v);
        auto slips = [&](double tt) { return std::abs(kt * (phase.displacement(tt) - s.slider)) > o_.slip_force; };
        double lo = t;
        const double hi = first_where(t, t_end, slips, lo);
        if (hi < 0.0) {
          stick_time += t_end - t;
          return {phase.displacement(t_end), phase.velocity(t_end), true, 0.0, s.slider};
        }
        stick_time += hi - t;
        t = hi;
        const double x = phase.displacement(t);
        s = {x, phase.velocity(t), false, x > s.slider ? 1.0 : -1.0, 0.0};
      } else {  // slip: stiffness k, friction force −σF0
        const LinearPhase phase(o_, o_.stiffness, -s.sigma * o_.slip_force, t, s.x, s.v);
        auto stops = [&](double tt) { return s.sigma * phase.velocity(tt) <= 0.0; };
        double lo = t;
        const double hi = first_where(t, t_end, stops, lo);
        if (hi < 0.0) return {phase.displacement(t_end), phase.velocity(t_end), false, s.sigma, 0.0};
        t = hi;
        const double x = phase.displacement(t);
        extreme = std::max(extreme, std::abs(x));
        if (!coulomb()) {  // the slider stops where the spring holds σF0
          s = {x, 0.0, true, 0.0, x - s.sigma * o_.slip_force / o_.tangential_stiffness};
        } else {
          const double f = unbalanced(t, x);
          s = std::abs(f) <= o_.slip_force ? State{x, 0.0, true, 0.0, 0.0}
                                           : State{x, 0.0, false, f > 0.0 ? 1.0 : -1.0, 0.0};
        }
      }
    }
    return s;
  }

  double stick_time = 0.0, extreme = 0.0;

 private:
  // The first instant in (t, t_end] where `event` holds, by a scan of step T/kScan and bisection
  // to adjacent doubles (the returned instant satisfies it); −1 if it never does. `lo` is left at
  // the last instant where it did not.
  template <class Event>
  double first_where(double t, double t_end, const Event& event, double& lo) const {
    const double h = period_ / kScan;
    lo = t;
    for (double hi = std::min(t + h, t_end);; hi = std::min(hi + h, t_end)) {
      if (event(hi)) {
        while (true) {
          const double mid = 0.5 * (lo + hi);
          if (mid <= lo || mid >= hi) return hi;
          (event(mid) ? hi : lo) = mid;
        }
      }
      lo = hi;
      if (hi >= t_end) return -1.0;
    }
  }

  CoulombOscillator o_;
  double period_;
};

}  // namespace

void CoulombOscillator::validate() const {
  auto require = [](bool ok, const char* field, double value, const char* range) {
    if (!ok) {
      throw std::invalid_argument(std::string("CoulombOscillator: ") + field + " = " + solvers::format("%g", value) +
                                  " is out of range; allowed: " + range);
    }
  };
  require(std::isfinite(mass) && mass > 0.0, "mass", mass, "finite and > 0 [kg]");
  require(std::isfinite(stiffness) && stiffness > 0.0, "stiffness", stiffness, "finite and > 0 [N/m]");
  require(std::isfinite(damping) && damping >= 0.0 && damping < 2.0 * std::sqrt(stiffness * mass), "damping", damping,
          "finite, >= 0 and below critical 2 sqrt(k m) [N s/m]");
  require(std::isfinite(force_amplitude) && force_amplitude > 0.0, "force_amplitude", force_amplitude, "finite and > 0 [N]");
  require(std::isfinite(slip_force) && slip_force >= 0.0, "slip_force", slip_force, "finite and >= 0 [N]");
  require(std::isfinite(frequency_hz) && frequency_hz > 0.0, "frequency_hz", frequency_hz, "finite and > 0 [Hz]");
  require(tangential_stiffness > 0.0, "tangential_stiffness", tangential_stiffness,
          "> 0 [N/m], or infinity for Coulomb's law (a rigid stick)");
  const double omega = 2.0 * kPi * frequency_hz;
  require(damping > 0.0 || std::abs(stiffness - mass * omega * omega) > 1e-9 * stiffness, "frequency_hz", frequency_hz,
          "away from the undamped resonance sqrt(k/m)/2pi when damping = 0 (add damping or move the frequency)");
}

CoulombSteadyState coulomb_steady_state(const CoulombOscillator& o, int samples, int max_periods) {
  o.validate();
  if (samples < 1) throw std::invalid_argument("coulomb_steady_state: samples = " + std::to_string(samples) + "; allowed: >= 1");
  if (max_periods < 2) {
    throw std::invalid_argument("coulomb_steady_state: max_periods = " + std::to_string(max_periods) + "; allowed: >= 2");
  }
  Integrator in(o);
  const double scale = o.force_amplitude / o.stiffness, vscale = 2.0 * kPi * o.frequency_hz * scale;
  auto repeats = [&](const State& a, const State& b) {
    return std::abs(a.x - b.x) <= kRepeat * scale && std::abs(a.v - b.v) <= kRepeat * vscale && a.stuck == b.stuck &&
           a.sigma == b.sigma && std::abs(a.slider - b.slider) <= kRepeat * scale;
  };
  CoulombSteadyState out;
  State s;  // rest at x = 0
  for (out.periods = 1; out.periods <= max_periods; ++out.periods) {
    const State next = in.advance(s, 0.0, in.period());
    const bool same = repeats(next, s);
    s = next;
    if (same) {
      out.periodic = true;
      break;
    }
  }
  if (!out.periodic) {
    out.periods = max_periods;
    out.message = "the state at the period's start did not repeat to " + solvers::format("%g", kRepeat) + " within " +
                  std::to_string(max_periods) + " periods (raise max_periods)";
  }
  // The last period, sampled.
  in.stick_time = 0.0;
  in.extreme = 0.0;
  out.tau.resize(samples);
  out.displacement.resize(samples);
  out.velocity.resize(samples);
  out.stuck.assign(static_cast<size_t>(samples), false);
  double t = 0.0;
  for (int q = 0; q < samples; ++q) {
    out.tau(q) = (q + 0.5) / samples;
    const double tq = out.tau(q) * in.period();
    s = in.advance(s, t, tq);
    t = tq;
    out.displacement(q) = s.x;
    out.velocity(q) = s.v;
    out.stuck[static_cast<size_t>(q)] = s.stuck;
  }
  s = in.advance(s, t, in.period());
  out.amplitude = std::max(in.extreme, out.displacement.cwiseAbs().maxCoeff());
  out.stick_fraction = in.stick_time / in.period();
  return out;
}

double den_hartog_amplitude(const CoulombOscillator& o) {
  const double k = o.stiffness, r = 2.0 * kPi * o.frequency_hz / std::sqrt(k / o.mass);
  const double u = std::tan(kPi / (2.0 * r)) / r;
  const double radicand = std::pow(1.0 / (1.0 - r * r), 2) - std::pow(o.slip_force * u / o.force_amplitude, 2);
  return radicand < 0.0 ? NAN : o.force_amplitude / k * std::sqrt(radicand);
}

CoulombOscillator friction_damper(double zeta, double slip_force, double r) {
  constexpr double kMass = 1.0, kNaturalHz = 10.0, kForce = 1.0;
  const double k = std::pow(2.0 * kPi * kNaturalHz, 2);
  return {kMass, 2.0 * zeta * std::sqrt(k * kMass), k, kForce, slip_force, r * kNaturalHz};
}

solvers::MechanicalSystem oscillator_system(const CoulombOscillator& o) {
  solvers::MechanicalSystem s;
  s.mass.resize(1, 1);
  s.mass.insert(0, 0) = o.mass;
  s.stiffness.resize(1, 1);
  s.stiffness.insert(0, 0) = o.stiffness;
  s.damping.resize(1, 1);
  if (o.damping > 0.0) s.damping.insert(0, 0) = o.damping;
  return s;
}

}  // namespace wbm::reproduce
