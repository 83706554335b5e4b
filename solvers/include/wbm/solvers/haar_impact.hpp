#pragma once
/// The weighted residual method in the Haar basis with Newton's impact law at rigid stops: periodic
/// forced responses of structures whose contact nodes are point masses (issue #38, item 3).
/// Units: SI; u [m], impulses [N·s], times [s].
///
/// Why a law at the velocity level. The Signorini conditions on displacements of the weighted
/// residual method (weighted_residual.hpp, RigidStop) are a plastic impact at a contact node that
/// the structure presses on. A point mass has no such local compliance: the periodic Delassus
/// operator is dominated by the echo of the impulses around the period, and those solves stagnate
/// beyond M = 64 (docs/design.md, "Exact contact"). Here the activation of an impulse is decided by
/// the states before it, as in a time stepping, and the periodicity is imposed on the period's
/// first state.
///
/// The discretization. Trial and weighting functions are M boxes χ_k on the cells [k h, (k + 1) h),
/// h = T/M, T = 1/f (for M = 2^J the Haar scaling functions at level J; any M in [8, 2^22]),
/// u(t) = Σ_k u_k χ_k(t) with u_k ∈ ℝⁿ the cell values. The velocity is JL14's delta pair [JL14
/// Sec. 5.2] in the box form of BasisModes (basis_modes.hpp), u̇ = Σ_k (u_k − u_{k−1}) δ(t − k h);
/// the damping term ∫ χ_k u̇ takes half of each delta at the box's two edges (the box's mean value
/// at its jumps). Galerkin on each box, divided by h:
///   M (u_{k+1} − 2u_k + u_{k−1})/h² + C (u_{k+1} − u_{k−1})/(2h) + K u_k = f̄_k − W P_k / h,
/// f̄_k = (1/h) ∫ f_ext over cell k (exact for the harmonic loads), W = [e_1 … e_nc] the stops'
/// directions (n × n_c), P_k ≥ 0 the impulses of cell k (n_c), indices modulo M (periodicity).
/// This is the periodic central-difference scheme in time; its linear response to a load
/// harmonic of angular frequency Ω is the closed form
///   u_k = Re(F̂ e^{iΩ(k + ½)h} (K + iC sin(Ωh)/h − 4M sin²(Ωh/2)/h²)⁻¹) · sin(Ωh/2)/(Ωh/2)
/// (test_haar_impact, LinearResponseIsTheCentralDifferenceSymbol).
///
/// The impact law [Paoli & Schatzman 2002, SIAM J. Numer. Anal. 40(2) 702–733 and 734–768]: with
/// the restitution coefficient e ∈ [0, 1],
///   0 ≤ P_k ⊥ g − Wᵀ (u_{k+1} + e u_{k−1})/(1 + e) ≥ 0   (componentwise over the stops),
/// g the gaps (n_c). Where a stop's cell value u_k is on the stop, an active row reads
/// e_cᵀ(u_{k+1} − u_k)/h = −e e_cᵀ(u_k − u_{k−1})/h: Newton's law v⁺ = −e v⁻ on the discrete
/// velocities; Paoli and Schatzman prove the scheme's convergence to the motion with Moreau's
/// impact law as h → 0 (Part I: one constraint). e = 0 is the plastic impact: the mass stays on the stop while the
/// load presses it there. For e > 0 a cell value may pass the stop by O(h |u̇|) (the constraint
/// holds on the average), which `penetration` reports.
///
/// The solve. Given (u_{k−1}, u_k) and P_k, u_{k+1} follows from the box's equation; P_k solves
/// the step's LCP with the SPD Delassus operator Wᵀ (M/h² + C/(2h))⁻¹ W / (h (1 + e)), unique
/// (closed form for one stop, Siconos' Lemke for several). So the M boxes' equations are a causal
/// sweep from s = (u_{−1}, u_0), and the periodic Galerkin system is the fixed point
///   R(s) = ((u_{M−1}, u_M)(s) − s) / u_ref = 0   (2n unknowns),
/// solved by the project's Newton core (dense LU) with the sweep's exact sensitivities (the active
/// stops' rows projected). The start is the scheme's own time stepping from rest (or from
/// `guess`) over `transient_periods` periods, which a stable orbit attracts. u_ref is the larger of
/// the largest gap and the largest |u| over the last transient period. The central-difference
/// sweep is stable for h ω_max < 2 (ω_max the largest undamped natural angular frequency), which
/// is required: a model with stiff modes needs many cells, a point-mass model few. The matrices
/// are dense (n ≤ 400 DOFs; a step's sensitivities cost O(n³)).
///
/// Converged only from a verified residual: Newton's R below newton.tolerance, and then the
/// periodic Galerkin residual and the complementarity recomputed from the returned cell values
/// (independently of the sweep, with indices modulo M) within residual_tolerance:
///   max_k ‖r_k‖∞ / (‖A₊‖∞‖u_{k+1}‖∞ + ‖B₀‖∞‖u_k‖∞ + ‖A₋‖∞‖u_{k−1}‖∞ + ‖f̄_k‖∞ + ‖W P_k‖∞/h),
///   max_{k,c} |min(γ_{c,k}, d_c P_{c,k})| / u_ref with γ ≥ −tolerance·u_ref,
/// A₊ = M/h² + C/(2h), B₀ = K − 2M/h², A₋ = M/h² − C/(2h), γ the law's gap and d_c the Delassus
/// operator's diagonal.

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include <wbm/solvers/mechanical_system.hpp>
#include <wbm/solvers/newton.hpp>
#include <wbm/solvers/status.hpp>

namespace wbm::solvers {

struct HaarImpactOptions {
  int cells = 256;                  // M ∈ [8, 2^22]: Haar scaling functions (cells) per period
  double restitution = 0.0;         // Newton's coefficient e ∈ [0, 1]
  int transient_periods = 30;       // ≥ 0: periods of time stepping from the start before Newton
  double residual_tolerance = 1e-10;  // on the verified residual and complementarity (above)
  NewtonOptions newton = {};        // the fixed-point solve (tolerance on R, relative to u_ref)
  /// Throws std::invalid_argument naming the field, its value, the allowed range and a way out.
  void validate() const;
};

struct HaarImpactSolution {
  SolveStatus status = SolveStatus::MaxIterations;  // Converged only from the verified residual
  std::string message;                              // why it stopped, with its numbers
  Eigen::MatrixXd displacement;  // n × M: u_k, the cell values (the Haar coefficients as box heights) [m]
  Eigen::MatrixXd impulses;      // n_c × M: P_k per stop and cell [N·s]
  NewtonReport report;           // the fixed-point Newton solve
  double residual = 0.0;         // the verified periodic Galerkin residual (relative, above)
  double complementarity = 0.0;  // the verified complementarity (relative to u_ref)
  double penetration = 0.0;      // max_{k,c} (e_cᵀ u_k − g_c) / u_ref; > 0 only for e > 0
  double reference_displacement = 0.0;  // u_ref [m]
  int impact_cells = 0;          // cells with an impulse (any stop)
  [[nodiscard]] bool converged() const { return status == SolveStatus::Converged; }
};

/// The periodic response of M ü + C u̇ + K u = f_ext(t) with the rigid stops `stops` (each a
/// contact::RigidStop along ContactPoint::direction: one DOF, two bodies or a general direction)
/// under Newton's impact law, by the Haar weighted residual above. `guess`, when given, is the
/// start of the transient (n × 2: u_{−1}, u_0). Non-convergence is returned (status, message),
/// never thrown. Throws std::invalid_argument for invalid matrices or forcing, more than 400 DOFs
/// (reduce the model), a load harmonic that M cells do not resolve
/// (HarmonicForcing::require_resolved), an empty stop list or a stop that is not a rigid stop
/// (penalty laws: weighted_residual.hpp; friction: Moreau–Jean), a moving counter-surface, a guess
/// of the wrong shape or not finite, invalid options, and for M too small for the sweep's
/// stability (h ω_max ≥ 2: the message gives the least M).
[[nodiscard]] HaarImpactSolution solve_haar_impact(const MechanicalSystem& system, const HarmonicForcing& forcing,
                                                   const std::vector<ContactPoint>& stops,
                                                   const HaarImpactOptions& options = {},
                                                   const std::optional<Eigen::MatrixXd>& guess = std::nullopt);

}  // namespace wbm::solvers
