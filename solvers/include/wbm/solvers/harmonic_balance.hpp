#pragma once
/// Harmonic balance (Fourier:Fourier weighted residuals in time) with alternating
/// frequency/time evaluation of the contact forces [JL14 Eqs. (14), (17); CG89].

#include <memory>
#include <vector>

#include <Eigen/Core>

#include <wbm/solvers/mechanical_system.hpp>
#include <wbm/solvers/newton.hpp>
#include <wbm/spectral/fourier_basis.hpp>

namespace wbm::solvers {

struct HarmonicBalanceOptions {
  int dimension = 64;     // M = 2^J ≥ 2 Fourier functions per DOF (M/2 harmonics)
  int time_samples = 0;   // Q ≥ M AFT samples; 0 selects max(256, 2M) (256 as in [JL14 Sec. 4.1])
  NewtonOptions newton{};
};

/// Outcome of a harmonic-balance solve. coefficients is n × M (layout.hpp).
struct HarmonicBalanceSolution {
  Eigen::MatrixXd coefficients;  // A(i, k): Fourier coefficient k of DOF i [m]
  double frequency_hz = 0.0;
  NewtonReport report;           // Newton on the contact unknowns (scaled residual, see below)
  double relative_residual = 0.0;  // ‖G a − b + n(a)‖₂ / ‖b‖₂ of the full system, recomputed
  double max_penetration = 0.0;    // max over contacts and AFT samples of u_c − g0 [m]
  double max_contact_force = 0.0;  // max over contacts and samples of f_c [N]
  int contact_unknowns = 0;        // n_c · M
  double wall_time_s = 0.0;        // set-up and solve
  [[nodiscard]] bool converged() const { return report.converged(); }
};

/// Fourier:Fourier weighted residual of M ü + C u̇ + K u = F cos(2πτ) e_f − Σ_c e_c f_c(u_c)
/// in normalized time τ = f t [JL14 Eqs. (7), (14), (17)]:
///   R(a) = G a − b + n(a) = 0,  G = f² A₂ ⊗ M + f A₁ ⊗ C + A₀ ⊗ K,
/// with A_d(j, k) = ∫₀¹ q_j q_k^{(d)} dτ (FourierBasis::galerkin_operator), b the projected
/// forcing, and n(a) = Σ_c e_c ⊗ ∫₀¹ q_j f_c(u_c(τ)) dτ by Q-point AFT. a is stacked as in
/// layout.hpp (length n·M).
///
/// Structure exploited: G is factorized once (sparse LU of the Kronecker sum), and Newton runs
/// on the n_c·M contact unknowns x = P a only (P selects the contact DOFs):
///   r(x) = (x − x_lin + H n_c(x)) / s,   H = P G⁻¹ Pᵀ,  x_lin = P G⁻¹ b,
///   ∂r/∂x = (I + H N(x)) / s,  N = blockdiag_c(∫ q_j f_c'(u_c) q_k dτ),
/// scaled by s = max_c |g0_c| (or ‖x_lin‖∞ if every gap is 0) so that the tolerance is
/// relative to the displacement scale. A Newton iteration costs O((n_c M)³), not O((nM)³); the full a is
/// recovered by one more solve with G. Immutable after construction; not thread-safe (AFT
/// buffers). Throws std::invalid_argument for invalid inputs (see validate() of each input).
class HarmonicBalance {
 public:
  HarmonicBalance(MechanicalSystem system, HarmonicForcing forcing,
                  std::vector<ContactPoint> contacts, HarmonicBalanceOptions options);
  ~HarmonicBalance();
  HarmonicBalance(HarmonicBalance&&) noexcept;
  HarmonicBalance& operator=(HarmonicBalance&&) noexcept;

  [[nodiscard]] int dofs() const;
  [[nodiscard]] int dimension() const;
  [[nodiscard]] int time_samples() const;
  [[nodiscard]] const spectral::FourierBasis& basis() const;

  /// Full residual R(a) [N], length n·M, and its Jacobian dR/da (dense n·M × n·M; for checks
  /// at small sizes, the solver never forms it).
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& a) const;
  [[nodiscard]] Eigen::MatrixXd jacobian(const Eigen::VectorXd& a) const;
  /// a_lin = G⁻¹ b: the response with every contact law removed (length n·M).
  [[nodiscard]] Eigen::VectorXd linear_response() const;

  /// The condensed system on the contact unknowns (residual/jacobian as above; satisfies
  /// NonlinearSystem). x is stacked over the contact list: x(k·n_c + c).
  [[nodiscard]] Eigen::VectorXd contact_residual(const Eigen::VectorXd& x) const;
  [[nodiscard]] Eigen::MatrixXd contact_jacobian(const Eigen::VectorXd& x) const;
  [[nodiscard]] Eigen::VectorXd contact_unknowns(const Eigen::VectorXd& a) const;  // x = P a
  /// a = G⁻¹(b − Pᵀ n_c(x)): the full coefficients for given contact unknowns.
  [[nodiscard]] Eigen::VectorXd expand(const Eigen::VectorXd& x) const;

  /// Newton on the contact unknowns from x0 (default: x_lin, the no-contact response). Without
  /// x0, if that Newton fails (stiff law, near-resonant forcing) the solve falls back on load
  /// stepping: forcing s·F, s from 0 to 1 with adaptive steps, each solved by Newton from the
  /// previous solution; report.iterations then counts all Newton iterations and report.message
  /// says so. Non-convergence is reported, never thrown.
  [[nodiscard]] HarmonicBalanceSolution solve(const Eigen::VectorXd* x0 = nullptr) const;

 private:
  struct Impl;
  struct Condensed;
  NewtonResult solve_with_load_stepping(Eigen::VectorXd x, int& steps) const;
  std::unique_ptr<Impl> impl_;
};

/// Convenience: build and solve in one call.
[[nodiscard]] HarmonicBalanceSolution solve_harmonic_balance(
    const MechanicalSystem& system, const HarmonicForcing& forcing,
    const std::vector<ContactPoint>& contacts, const HarmonicBalanceOptions& options);

/// u_i(τ_p) (or its d-th time derivative in physical time, [m/s^d]) of DOF i at the given
/// normalized times from an n × M Fourier coefficient matrix [JL14 Eqs. (11), (34)].
[[nodiscard]] Eigen::VectorXd evaluate_dof(const Eigen::MatrixXd& coefficients, int dof,
                                           const Eigen::VectorXd& tau, double frequency_hz,
                                           int derivative = 0);

}  // namespace wbm::solvers
