#pragma once
/// Exact conservative periodic orbits with elastic impacts, the reference of nonlinear normal modes
/// with rigid stops, and their stability through saltation matrices (issue #38, item 4).
/// Units: SI; times in s, frequencies in Hz, states x = (u [m], u̇ [m/s]), energies in J.
///
/// The free, undamped structure M ü + K u = −Σ_c e_c λ_c with rigid stops e_cᵀ u ≤ g_c is linear
/// between impacts; each impact obeys Newton's law with e = 1, e_cᵀ u̇⁺ = −e_cᵀ u̇⁻ (ImpactFlow,
/// impact_shooting.hpp). That is the only law under which a free orbit whose contact node carries
/// mass can be periodic: an impact with e < 1 takes ½ (1 − e²) W⁻¹ (e_cᵀ u̇⁻)² of the energy
/// (W = e_cᵀ M⁻¹ e_c), and LL11's "work of the contact forces is zero" [LL11 Sec. 3.2] then fails.
/// The Hamiltonian H(x) = ½ u̇ᵀ M u̇ + ½ uᵀ K u is conserved through flights and impacts.
///
/// Autonomous shooting. Unknowns: x₀ with its phase velocity u̇_p(0) = 0 removed (the phase
/// condition: the orbit starts where the phase DOF turns, a time of free flight for a stop's own
/// DOF), and the period T. Equations, in the scaled coordinates x̂ = D x, D = diag(I/s, I/(ω s))
/// (s the largest of |u| and |u̇|/ω of the guess, ω = 2π/T_guess):
///   D (x(T) − x₀) = 0   without its row i,
///   (H(x₀) − H*)/H* = 0   (OrbitLevel::Energy)  or  (T − T*)/T* = 0   (OrbitLevel::Period).
/// Because H(x(T)) = H(x₀) for every x₀ and T, the periodicity rows are dependent to first order
/// with the coefficients ∇H; row i, the one with the largest |∂Ĥ/∂x̂_i| at the guess, is dropped
/// (it then holds to second order), so the system is square [Seydel 2010, Practical Bifurcation
/// and Stability Analysis, Sec. 7.6; Peeters et al. 2009, Mech. Syst. Signal Process. 23, 195].
/// Jacobian: the saltation monodromy Φ for x₀, f(x(T)) = (u̇, −M⁻¹ K u) for T, ∇H = (K u₀, M u̇₀).
/// Solved by the project's Newton core (dense LU); converged from a verified residual: after it
/// the whole ‖D (x(T) − x₀)‖₂, the dropped row included, is checked against the tolerance.
///
/// Stability. Φ has the trivial pair at +1: Φ f(x₀) = f(x₀) (a time shift) and, along the family,
/// a Jordan block, which a dense eigensolver splits by about √(ε‖Φ‖), far above the rounding of
/// the others. So the verdict is taken on the nontrivial multipliers: the map that Φ induces on
/// the energy surface's tangent space {∇Ĥᵀ δ = 0} modulo the flow direction f̂, i.e. R = Bᵀ Φ̂ B
/// with B an orthonormal basis (2n × (2n − 2)) of {δ : ∇Ĥᵀ δ = 0, f̂ᵀ δ = 0} (Φ̂ maps the tangent
/// space into itself, and f̂ spans what the orthogonal projection removes). The orbit is
/// unstable when max |μ_R| > 1 + stability_tolerance; otherwise it is linearly stable (every
/// nontrivial multiplier on the unit circle: the monodromy of a conservative impacting system is
/// symplectic, ΦᵀΩΦ = Ω with Ω = [[0, M], [−M, 0]], so its multipliers come in pairs μ, 1/μ, μ̄).

#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

#include <wbm/solvers/impact_shooting.hpp>
#include <wbm/solvers/mechanical_system.hpp>
#include <wbm/solvers/newton.hpp>

namespace wbm::solvers {

/// Which quantity fixes an orbit on its one-parameter family: the Hamiltonian H [J] or the
/// period T [s]. Near a turning point of H along a backbone, fix T (and the reverse).
enum class OrbitLevel { Energy, Period };

struct ConservativeOrbitOptions {
  /// The shooting: tolerance on ‖residual‖₂ in the scaled coordinates (dimensionless).
  NewtonOptions newton = {.tolerance = 1e-10, .max_iterations = 30};
  int steps_per_period = 512;         // ImpactFlowOptions::steps_per_period (event brackets, ≥ 8)
  int max_events = 1000;              // ImpactFlowOptions::max_events (impacts per period)
  /// Unstable when the largest nontrivial |μ| exceeds 1 + this (≥ 0; on the LL11 rod's linear mode,
  /// whose multipliers lie on the unit circle, every computed |μ| is 1 within 1e-8:
  /// test_impact_modes).
  double stability_tolerance = 1e-6;
  /// Throws std::invalid_argument naming the field, its value and the range.
  void validate() const;
};

/// One exact conservative periodic orbit.
struct ConservativeOrbit {
  Eigen::VectorXd state;              // x₀ = (u₀, u̇₀) at t = 0 (2n), with u̇_p(0) = 0
  double period_s = 0.0;              // T [s]
  double frequency_hz = 0.0;          // 1/T [Hz]
  double hamiltonian = 0.0;           // H(x₀) [J]
  /// (1/T) ∫₀ᵀ u̇ᵀ M u̇ dt / ω² [kg m²], ω = 2π/T: LL11's m̂ [LL11 Eq. (11)] of this orbit (twice
  /// the mean kinetic energy over ω²), by the trapezoidal rule on `samples` instants (the kinetic
  /// energy is continuous at an elastic impact, so the rule is second order); NaN if not asked.
  double mean_square_rate = std::numeric_limits<double>::quiet_NaN();
  ImpactFlowResult period;            // the flow over one period from `state` (events, Φ)
  Eigen::VectorXcd multipliers;       // the 2n eigenvalues of Φ, by decreasing modulus
  Eigen::VectorXcd nontrivial_multipliers;  // the 2n − 2 of R (above), by decreasing modulus
  double max_modulus = std::numeric_limits<double>::quiet_NaN();  // max |μ_R| (1 for n = 1)
  bool stable = false;                // max_modulus ≤ 1 + stability_tolerance (converged orbits only)
  /// ‖Φ̂ᵀ Ω̂ Φ̂ − Ω̂‖_F / ‖Ω̂‖_F in the scaled coordinates: 0 up to rounding for an exact monodromy.
  double symplectic_defect = std::numeric_limits<double>::quiet_NaN();
  double periodicity_residual = std::numeric_limits<double>::quiet_NaN();  // ‖D (x(T) − x₀)‖₂, every row
  NewtonReport report;                // converged only if periodicity_residual ≤ the tolerance too and
                                      // the multipliers are finite (NonFinite otherwise)
  [[nodiscard]] bool converged() const { return report.converged(); }
};

/// Shoots the conservative orbit near (x_guess, period_guess_s) of the undamped structure (the
/// system's damping is ignored) with rigid stops and elastic impacts, fixed by `level` = `value`
/// (H [J] or T [s]). `phase_dof` names the DOF whose velocity vanishes at t = 0 (x_guess's value
/// there is replaced by 0). `samples` > 0 also fills mean_square_rate. Never throws for
/// non-convergence: a flow that fails on an iterate (a graze, chatter: std::domain_error) gives
/// a non-finite residual, the line search backs away, and at the guess itself the report says
/// NonFinite with the flow's message. Throws std::invalid_argument for a guess of the wrong size,
/// non-finite or zero, period_guess_s or value not finite and > 0, a phase_dof outside [0, n),
/// contacts that are not rigid stops (ImpactFlow), invalid options, samples < 0.
[[nodiscard]] ConservativeOrbit shoot_conservative_orbit(const MechanicalSystem& system,
                                                         const std::vector<ContactPoint>& stops,
                                                         const Eigen::VectorXd& x_guess, double period_guess_s,
                                                         int phase_dof, OrbitLevel level, double value,
                                                         const ConservativeOrbitOptions& options = {},
                                                         int samples = 0);

/// H(x) = ½ u̇ᵀ M u̇ + ½ uᵀ K u [J] for x = (u, u̇) (2n). Throws std::invalid_argument for a wrong size.
[[nodiscard]] double hamiltonian(const MechanicalSystem& system, const Eigen::VectorXd& x);

}  // namespace wbm::solvers
