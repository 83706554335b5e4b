#pragma once
/// An event-driven reference for the friction reproductions: the periodic steady state of a
/// 1-DOF oscillator with viscous damping and dry friction under a harmonic force,
///   m ẍ + c ẋ + k x + f = P cos ωt,
/// f either Coulomb's law (k_t = ∞: f = F0 sign ẋ in slip; ẋ = 0 while |P cos ωt − k x| ≤ F0) or a
/// Jenkins element (a spring k_t in series with a slider: f = k_t (x − s), |f| ≤ F0, the slider s
/// moving only in slip). Each phase is a linear oscillator solved in closed form:
///   slip (σ = sign ẋ):           stiffness k,        constant force −σF0,
///   Jenkins stick (slider at s): stiffness k + k_t,  constant force k_t s,
///   Coulomb stick:               x frozen,
/// x = Re(Z e^{iωt}) + F_c/K + e^{−ζω s}(A cos ω_d s + B sin ω_d s), Z = P/(K − mω² + icω), s the time
/// since the phase began. A slip ends where ẋ reaches 0 (Jenkins: stick with f = σF0; Coulomb:
/// stick if |P cos ωt − k x| ≤ F0, else slip the other way); a stick ends where |f| would exceed
/// F0. The instants are located by a scan (T/16384) and bisection to the last bit. Independent of
/// the weighted residual and of contact::jenkins_loop: it knows neither a basis nor a sample grid.
/// Units: SI; τ = t/T normalized time.
///
/// Den Hartog's closed form [Den Hartog, Phil. Mag. (7) 9 (1930) 801–817] holds for the
/// undamped Coulomb motion without stops (stick_fraction = 0); the reproduction checks this
/// reference against it there.

#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

#include <wbm/solvers/mechanical_system.hpp>

namespace wbm::reproduce {

struct CoulombOscillator {
  double mass;             // m [kg] > 0
  double damping;          // c [N s/m] ≥ 0, below critical (2√(km))
  double stiffness;        // k [N/m] > 0
  double force_amplitude;  // P [N] > 0
  double slip_force;       // F0 = μN [N] ≥ 0
  double frequency_hz;     // f = ω/2π [Hz] > 0; not the undamped resonance when c = 0
  double tangential_stiffness = std::numeric_limits<double>::infinity();  // k_t [N/m] > 0; ∞: Coulomb
  /// Throws std::invalid_argument naming the field, its value and the allowed range.
  void validate() const;
};

/// The damper of the friction reproductions: m = 1 kg, f_n = 10 Hz, P = 1 N, damping ratio ζ,
/// slip force F0 [N], forcing at r = ω/ω_n; Coulomb's law (k_t = ∞).
[[nodiscard]] CoulombOscillator friction_damper(double zeta, double slip_force, double r);

/// The oscillator's M, C, K (1 DOF) for the weighted residual.
[[nodiscard]] solvers::MechanicalSystem oscillator_system(const CoulombOscillator& oscillator);

/// The steady state over one period at the Q samples τ_q = (q + ½)/Q (the weighted residual's
/// midpoint samples).
struct CoulombSteadyState {
  Eigen::VectorXd tau;           // τ_q [-]
  Eigen::VectorXd displacement;  // x(τ_q T) [m]
  Eigen::VectorXd velocity;      // ẋ(τ_q T) [m/s]
  std::vector<bool> stuck;       // in stick at τ_q
  double amplitude = 0.0;        // max |x| over the slip ends (ẋ = 0) and the samples [m]
  double stick_fraction = 0.0;   // time in stick / T [-]
  int periods = 0;               // periods run until the state at t = nT repeated
  bool periodic = false;         // the state repeated to 1e-13 (relative) within max_periods
  std::string message;           // why not, when not periodic
};

/// Runs periods from rest at x = 0 (f = 0) until the state at the period's start repeats (|Δx|
/// and the slider's |Δs| ≤ 1e-13 P/k, |Δẋ| ≤ 1e-13 ω P/k and the same stick/slip phase), then
/// samples the last period.
/// Throws std::invalid_argument for invalid parameters or samples < 1 or max_periods < 2.
[[nodiscard]] CoulombSteadyState coulomb_steady_state(const CoulombOscillator& oscillator, int samples,
                                                      int max_periods = 20000);

/// Den Hartog's amplitude of the undamped continuous motion (c = 0, no stops) at r = ω/ω_n:
///   x0 = (P/k) √((1/(1 − r²))² − (F0 U/P)²),  U = tan(π/(2r))/r   [m];
/// NaN where the radicand is negative (no motion without stops). The formula comes from the four
/// conditions of a half period from x0 to −x0 under the constant friction force; the derivation
/// is in tests/solvers/test_friction.cpp.
[[nodiscard]] double den_hartog_amplitude(const CoulombOscillator& oscillator);

}  // namespace wbm::reproduce
