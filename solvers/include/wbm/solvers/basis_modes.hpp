#pragma once
/// Nonlinear normal modes with exact frictionless contact in any time basis of the weighted
/// residual method: LL11's KKT formulation with the trial functions of JL14 (Fourier, B-spline,
/// Daubechies, Haar) (issue #38, item 5). Units: SI (m, kg, N/m, Hz where the name says _hz).
///
/// Unknowns: u(τ) = Σ_k Y(:, k) q_k(τ), τ = t/T, q_k the M functions of a TimeBasis (n × M
/// coefficients, column k = function k of the basis' ordering); ω²; contact forces f_s at the m
/// Signorini instants τ_s = (s + o)/m of every stop (o: BasisModeOptions::sample_offset); and σ,
/// the multiplier of the phase condition. With the basis' time operators (M × M)
///   A₀(j, k) = ∫₀¹ q_j q_k dτ,   B(j, k) = (1/4π²) ∫₀¹ q̇_j q̇_k dτ   (q̇ = dq/dτ),
/// the conditions are the Galerkin form of M ü + K u + Σ_c e_c f_c = 0 with the Signorini
/// conditions at the samples and LL11's energy normalization [LL11 Eqs. (11), (12), (24)]:
///   (A₀ ⊗ K − ω² B ⊗ M) y + (1/m) Σ_(c, s) (Θ(s, :)ᵀ ⊗ e_c) f_cs + σ (c_φ ⊗ e_p) = 0
///   min(f_cs, g_c − e_cᵀ u(τ_s)) = 0                                  (every stop c, sample s)
///   m̂(Y)/m̂_c − E = 0,  m̂(Y) = yᵀ (B ⊗ M) y = (1/4π²) ∫₀¹ u̇ᵀ M u̇ dτ
///   c_φᵀ Y(p, :)ᵀ = 0                                                  (phase condition)
/// with y the coefficients stacked k·n + dof (spectral/layout.hpp), Θ(s, k) = q_k(τ_s) (m × M),
/// p the phase DOF, m̂_c = ½ φ_cᵀ M φ_c of the linear first mode φ_c scaled to contact onset
/// (NonlinearModes::onset_mode), so E = 1 at onset for every basis, as in NonlinearModes.
/// The phase functional c_φ(k) = (1/P) Σ_p q_k(τ_p) sin 2πτ_p on P = 16 M midpoints fixes the
/// time origin at a turning point of the phase DOF (Fourier: its sin 2πτ coefficient is 0). The
/// mode is a critical point of the Rayleigh quotient on {h = 0, g ≤ 0, phase} and σ its
/// multiplier: 0 for a basis whose span is invariant under every time shift (Fourier), and of
/// the order of the discretization otherwise (a wavelet span is invariant under shifts by 1/M
/// only); reported per level (BasisModeLevel::phase_multiplier).
///
/// Velocity. B needs ∫ q̇_j q̇_k: exact for Fourier, and by connection coefficients for a
/// wavelet family with max_connection_order ≥ 2 (DB6, B-spline; TimeBasis::exact_operator).
/// Haar functions are piecewise constant: their derivative is the delta pair of [JL14 Sec. 5.2],
/// in the box form of post_processing.hpp, u̇(τ) = M (u_k − u_(k−1)) on [(k − ½)/M, (k + ½)/M)
/// (u_k = u on cell k), so ∫ u̇ᵀ M u̇ dτ = M Σ_k (u_k − u_(k−1))ᵀ M (u_k − u_(k−1)): with A₀ = I,
/// the Haar Galerkin system is the periodic central-difference scheme in time with M steps. Its
/// linear mode has f = f₁ (π/M)/sin(π/M) (tests/solvers/test_basis_modes.cpp). Other families
/// (DB4) are refused with the list of those that work.
///
/// Backbone: pseudo-arclength continuation in E (continuation.hpp) of this piecewise-smooth
/// system, the events where samples switch located and crossed, from the basis' linear mode at
/// energy_min (E < 1: Newton at fixed E from the projection of φ_c √E cos 2πτ), with the
/// Jacobian by supernodal sparse LU (linear_solver()). Residuals are scaled as NonlinearModes'
/// BackboneSystem: y = Y/g_ref, ω²/ω₀², f/f_ref with f_ref = m ω₀² m_ref g_ref, rows divided by
/// ω₀² m_ref g_ref, m_ref = 2 m̂_c/g_ref² [kg]. With TimeBasis::fourier_harmonics(N), samples m
/// and sample_offset 0 the system is that of NonlinearModes::continue_backbone, solved by an
/// independent code (the test compares them).

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <wbm/solvers/linearization.hpp>
#include <wbm/solvers/nonlinear_modes.hpp>
#include <wbm/solvers/time_basis.hpp>

namespace wbm::solvers {

struct BasisModeOptions {
  /// m Signorini instants per stop; 0: M (one per function: Haar is constant on each of its M
  /// cells, so more instants than cells repeat constraints and their multipliers are not unique).
  int samples = 0;
  /// o in τ_s = (s + o)/m, in [0, 1). Unset: ½ for Haar (its instants off its jumps at k/M), 0
  /// otherwise (LL11's τ_s = s/m: an instant at the turning point τ = 0; at midpoints two instants
  /// straddle it and enter contact almost together, docs/design.md).
  std::optional<double> sample_offset = std::nullopt;
  /// Throws std::invalid_argument naming the field, its value and the range.
  void validate() const;
};

/// One level: BasisModeLevel::level holds the frequency, the status and residual, the contact
/// forces (stop-major, m per stop) and the coefficients Y (n × M [m], the basis' ordering).
struct BasisModeLevel {
  ModeLevel level;
  double phase_multiplier = 0.0;  // σ (dimensionless, the scaled rows above)
};

/// A backbone in a time basis: the levels in branch order and the energies landed on.
struct BasisBackbone {
  std::vector<BasisModeLevel> levels, included;
  StopReason stop = StopReason::InitialPointFailed;
  SolveStatus status = SolveStatus::PathEnded;  // Converged: the range's end was reached
  int kinks = 0, rejected_steps = 0;
  std::string message;
  double wall_time_s = 0.0;
  [[nodiscard]] bool complete() const { return status == SolveStatus::Converged; }
  /// The included level at `energy` (to 1e-12 relative), or nullptr.
  [[nodiscard]] const BasisModeLevel* included_at(double energy) const;
};

/// The nonlinear modes of the problem of a NonlinearModes (structure, stops, phase DOF, onset
/// normalization; its harmonics and samples are not used) in `basis`. Throws
/// std::invalid_argument for a basis without a velocity representation (message names the basis
/// and the families that work), invalid options, M < 2, m < M (fewer instants than functions), or
/// m M > 2²⁴ (the dense instants' values Θ, 128 MiB).
class BasisModes {
 public:
  BasisModes(const NonlinearModes& problem, TimeBasis basis, BasisModeOptions options = {});

  /// The piecewise-smooth KKT system in E (PiecewiseSmoothSystem, linearization.hpp). State
  /// x = [y (n M, stacked k·n + dof, units of g_ref); ω²/ω₀²; f/f_ref (stop-major, m per
  /// stop); σ]; rows: Galerkin (n M), energy, Signorini (stops × m), phase. Sample s is active
  /// when the min picks the gap (f_s > −g_s, g_s = (e_cᵀu(τ_s) − g_c)/g_ref); events as in
  /// NonlinearModes::BackboneSystem. Exposed for tests (finite differences).
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x, double energy) const;
  [[nodiscard]] SparseLinearization linearize(const Eigen::VectorXd& x, double energy) const;
  [[nodiscard]] ActiveSet active_set(const Eigen::VectorXd& x, double energy) const;
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x, double energy, const ActiveSet& active) const;
  [[nodiscard]] SparseLinearization linearize(const Eigen::VectorXd& x, double energy, const ActiveSet& active) const;
  [[nodiscard]] Eigen::VectorXd events(const Eigen::VectorXd& x, double energy, const ActiveSet& active) const;
  /// The projection of the onset mode φ_c √E cos 2πτ on the basis (least squares on 4M
  /// midpoints), at ω²/ω₀² of its Rayleigh quotient, no contact force, σ = 0: a start, not a
  /// solution.
  [[nodiscard]] Eigen::VectorXd linear_guess(double energy) const;
  /// The level at x: Converged only if the KKT residual ‖R(x, E)‖₂ ≤ tolerance.
  [[nodiscard]] BasisModeLevel level(const Eigen::VectorXd& x, double energy, double tolerance) const;
  [[nodiscard]] Eigen::Index size() const { return size_; }
  /// The linear-solver policy of the continuation and of Newton (newton.hpp): Eigen's supernodal
  /// SparseLU. The time operators wrap around the period (dense for the B-spline) and the energy
  /// row and ω² column are full, so the factors fill in; measured on the LL11 rod it took the
  /// levels 1.2–2.5 times less time than KLU (SparseLu), the same frequencies (docs/design.md).
  [[nodiscard]] SupernodalLu linear_solver() const { return {}; }

  /// The backbone from energy_min (< 1, below contact) to energy_max, landing on `include`.
  /// Uses energy_min, energy_max, initial_step, min_step, max_step, max_energy_step, max_points,
  /// include, tolerance, max_newton_iterations and on_point. Throws std::invalid_argument for
  /// energy_min ≥ 1, a start, a penalty stiffness or a homotopy (not offered in a time basis:
  /// use NonlinearModes::continue_backbone), or options that fail validate().
  [[nodiscard]] BasisBackbone continue_backbone(const BackboneContinuationOptions& options) const;

  /// u (n × P [m]) at τ_p = p/P of a level (Haar: the cell values).
  [[nodiscard]] Eigen::MatrixXd displacement(const BasisModeLevel& level, int samples) const;
  [[nodiscard]] const TimeBasis& basis() const { return basis_; }
  [[nodiscard]] int samples() const { return samples_; }
  [[nodiscard]] double sample_offset() const { return offset_; }  // o, as used
  /// Unknowns of the KKT system: n M + 1 + stops × m + 1.
  [[nodiscard]] Eigen::Index unknowns() const { return size_; }

 private:
  struct Unpacked {
    Eigen::MatrixXd y;  // n × M, units of g_ref
    Eigen::VectorXd g, lambda;
  };
  [[nodiscard]] Unpacked unpack(const Eigen::VectorXd& x) const;
  [[nodiscard]] SparseLinearization evaluate(const Eigen::VectorXd& x, double energy, bool jacobian,
                                             const ActiveSet* active) const;
  void check(const ActiveSet& active) const;

  MechanicalSystem system_;
  std::vector<RigidStop> stops_;
  TimeBasis basis_;
  int n_ = 0, dim_ = 0, samples_ = 0, phase_dof_ = 0;
  double omega0_ = 0.0, g_ref_ = 1.0, m_ref_ = 1.0, offset_ = 0.0;
  Eigen::VectorXd onset_;
  Eigen::SparseMatrix<double> a0_, b_;             // A₀, B (M × M)
  Eigen::SparseMatrix<double> stiffness_, inertia_;  // A₀ ⊗ K̂, B ⊗ M̂ (n M × n M)
  Eigen::SparseMatrix<double> ks_, ms_;            // K̂ = K/(ω₀² m_ref), M̂ = M/m_ref
  Eigen::MatrixXd theta_;                          // Θ, m × M
  Eigen::VectorXd phase_;                          // c_φ (M)
  Eigen::Index ny_ = 0, size_ = 0;
};

}  // namespace wbm::solvers
