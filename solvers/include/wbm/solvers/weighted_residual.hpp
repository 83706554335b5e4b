#pragma once
/// Weighted residuals in time for any trial:weighting pair of time bases, in strong, weak or
/// distributional form [JL14 Secs. 2, 4.1, Eqs. (14)–(17)], with the contact forces evaluated
/// on time samples (alternating frequency/time for any basis). Units: SI; τ = f t normalized.

#include <chrono>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include <wbm/solvers/linearization.hpp>
#include <wbm/solvers/mechanical_system.hpp>
#include <wbm/solvers/newton.hpp>
#include <wbm/solvers/time_basis.hpp>

namespace wbm::solvers {

/// Where the time derivatives of M ü + C u̇ + K u sit [JL14 Eqs. (14)–(16)]; with trial q_k and
/// weighting p_j the time operators (row j = weighting, column k = trial) are
///   Strong (14):         A_M = ∫ p q̈,    A_C = ∫ p q̇,    A_K = ∫ p q
///   Weak (15):           A_M = −∫ ṗ q̇,   A_C = ∫ p q̇,    A_K = ∫ p q
///   Distributional (16): A_M = ∫ p̈ q,    A_C = −∫ ṗ q,   A_K = ∫ p q
/// (derivatives in τ). With exact integrals of periodic functions the three coincide.
enum class Formulation { Strong, Weak, Distributional };

/// "strong", "weak", "distributional".
[[nodiscard]] std::string_view to_string(Formulation f) noexcept;
/// Inverse of to_string; throws std::invalid_argument naming the value and the three names.
[[nodiscard]] Formulation parse_formulation(const std::string& name);

/// How the linear time operators are integrated.
///  - Automatic: exactly where known — Fourier:Fourier analytically, a wavelet family with
///    itself by connection coefficients (Galerkin, as the paper does for DB6 [JL14 Sec. 4.1];
///    also the B-spline, whose coefficients wavelets:: computes) — and by discrete inner
///    products on the Q samples otherwise.
///  - Discrete: discrete inner products on the Q samples for every pair (the paper's rule for
///    all but the Daubechies Galerkin case); needs pointwise derivatives.
enum class OperatorRule { Automatic, Discrete };

/// How G is factorized (G = f² A_M ⊗ M + f A_C ⊗ C + A_K ⊗ K, size n·M).
///  - Automatic: Modal when the undamped modes diagonalize C: Rayleigh C = c_M M + c_K K (the
///    rod's β-damping is c_K = β), or any classical C such as modal damping ratios (Caughey &
///    O'Kelly 1965: C M⁻¹ K = K M⁻¹ C; then Φᵀ C Φ = diag(c_i) checked to 1e-10); SparseLU otherwise.
///  - SparseLU: any damping. Block-diagonal time operators (Fourier:Fourier: a harmonic's cosine
///    and sine) are factorized block by block, G_c = Σ_t A_t[c, c] ⊗ X_t of size |c|·n, by
///    LAPACK's band LU (dgbtrf) when the structure's half-bandwidth b gives |c|(b + 1) − 1 ≤ 32,
///    else by KLU with one step of iterative refinement: O(M·n) per frequency for a banded FE
///    model. Other time operators: the assembled Kronecker sum, by KLU (joint pattern at most ¼
///    full) or Eigen's supernodal SparseLU (slow for wavelet and dense time operators, whose
///    periodic wrap-around defeats the fill-reducing ordering).
///  - Modal: with K Φ = M Φ Λ, Φᵀ M Φ = I (undamped_modes.hpp: Eigen's dense solver, or Sturm
///    bisection and inverse iteration in O(n²) for a tridiagonal pencil of 400 DOFs or more),
///      G = (I ⊗ Φ⁻ᵀ) blockdiag_i(A + λ_i B) (I ⊗ Φ⁻¹),  A = f² A_M + f c_M A_C,  B = f c_K A_C + A_K,
///    (a classical C that is not Rayleigh: c_M = c_i = (Φᵀ C Φ)_ii per mode and c_K = 0),
///    i.e. n independent M × M blocks, each inverted in the form its time operators allow:
///    harmonic 1 × 1 and 2 × 2 components (Fourier:Fourier, O(M)), circulant by one FFT
///    (spectral::Circulant; a wavelet basis with itself, exact or on Q = multiple-of-M samples,
///    O(M log M)), the factored Fourier-weighting form A_K⁻¹ S_i with S_i in O(M) (wavelet trial,
///    Fourier weighting, distributional form; A_K⁻¹ dense, once per set-up), sparse or dense LU
///    otherwise; and H = Σ_i φ_i(c) φ_i(c') (A + λ_i B)⁻¹ in O(M²) per contact pair
///    (docs/design.md, "Speed").
///    Throws std::invalid_argument if the modes do not diagonalize C.
enum class LinearSolverPath { Automatic, SparseLU, Modal };

/// Empty if the pair (trial, weighting) can be assembled in `formulation` under `rule`; else
/// why not (the basis, the missing derivative, the term) and which formulation would work.
/// Exact operators need d_w + d_t ≤ max_connection_order of the family; discrete ones need
/// pointwise derivatives (TimeBasis::max_derivative) of the orders of the table above.
[[nodiscard]] std::string inadmissibility(const TimeBasis& trial, const TimeBasis& weighting,
                                          Formulation formulation, OperatorRule rule = OperatorRule::Automatic);

/// How the contact term (1/Q) Σ_q p(τ_q) f_c(u_c(τ_q)) samples the law on the Q cells
/// [(q, q + 1)/Q] of the period.
///  - Midpoint: f_c(u_c(τ_q)) at τ_q = (q + ½)/Q, the paper's rule [JL14 Sec. 4.1]. The
///    discrete residual is nonsmooth wherever a sample crosses the gap: each crossing changes the
///    Jacobian by k_c/Q. Against a stop much stiffer than the structure that turns a branch back
///    at a crossing, and continuation stalls or zig-zags; more samples move the stall but do not
///    remove it.
///  - CellAverage: the law integrated exactly over each cell along the tangent of u_c,
///    u_c(τ) ≈ u_q + u̇_q (τ − τ_q), with the law's potential P (ContactLaw::potential):
///      f̄_q = (P(u_q + δ_q/2) − P(u_q − δ_q/2)) / δ_q,   δ_q = u̇_c(τ_q)/Q (u̇ = du/dτ),
///    f̄_q = f_c(u_q) where the potential difference would lose four digits to cancellation
///    (|ΔP| ≤ 1e-4 max|P|: a short cell inside one smooth piece of the law). It has the midpoint
///    rule's order and is C¹ in the unknowns for a continuous law, so samples enter contact
///    smoothly. Its Jacobian adds Σ_q p_j ∂f̄/∂δ q̇_k(τ_q)/Q. Needs the trial basis' first
///    derivative: refused for Haar (std::invalid_argument naming the way out).
enum class ContactQuadrature { Midpoint, CellAverage };
/// "midpoint", "cell-average".
[[nodiscard]] std::string_view to_string(ContactQuadrature q) noexcept;

/// How solve() reached its answer, in the order it tries them (each only if the one before did
/// not converge, and the last two only when solve() chose the starting point itself).
///  - DirectNewton: Newton on the contact unknowns from the given x0 or from x_lin.
///  - ContactHomotopy: pseudo-arclength continuation (continuation.hpp) of
///      r_σ(x) = (x − x_lin + σ H n_c(x)) / s_r = 0
///    in λ = log₁₀ σ, from λ₀ = clamp(log₁₀(0.1 / ‖H N(x_lin)‖∞), −12, −1), where x ≈ x_lin
///    solves it, to σ = 1, then Newton at σ = 1. σ scales every contact force (for the penalty
///    laws, the penalty coefficient): continuation in the contact stiffness, which passes the
///    folds in the forcing amplitude that stall load stepping. Folds in σ are passed too.
///  - LoadStepping: forcing s·F, s: 0 → 1, adaptive steps, Newton at each.
///  - Linear: no contact, one solve.
enum class SolutionPath { DirectNewton, ContactHomotopy, LoadStepping, Linear, FullStepActiveSet };
/// "direct Newton", "contact homotopy", "load stepping", "linear", "full-step active set".
[[nodiscard]] std::string_view to_string(SolutionPath p) noexcept;

/// The σ path of the contact homotopy (SolutionPath::ContactHomotopy), for reports.
/// In the solvers' one vocabulary: `stop` is the σ branch's StopReason (absent when no homotopy
/// was run), `status` Converged once the path reached the problem (σ = 1, or the stiffest penalty
/// of the rigid path) and Newton converged there, else the status of that solve or PathEnded.
struct HomotopyReport {
  std::optional<StopReason> stop;
  SolveStatus status = SolveStatus::PathEnded;
  std::string message;             // the branch's message (where and why it stopped)
  [[nodiscard]] bool tried() const { return stop.has_value(); }
  [[nodiscard]] bool reached() const { return status == SolveStatus::Converged; }
  double sigma_reached = 0.0;      // largest σ on the path (1 if reached)
  double lambda_start = 0.0;       // λ₀ = log₁₀ σ₀
  int points = 0;                  // continuation points
  int folds = 0;                   // turning points in σ on the path
  long corrector_iterations = 0;
};

struct WeightedResidualOptions {
  Formulation formulation = Formulation::Distributional;  // the paper's Figs. 10–11 form
  /// Q time samples τ_q = (q + ½)/Q (midpoint rule) for the contact forces, the forcing and
  /// discrete inner products; 0 selects max(256, 2M) (256 as in [JL14 Sec. 4.1]); else Q ≥ M.
  int time_samples = 0;
  OperatorRule operators = OperatorRule::Automatic;
  ContactQuadrature contact_quadrature = ContactQuadrature::Midpoint;
  LinearSolverPath linear_solver = LinearSolverPath::Automatic;
  NewtonOptions newton{};  // on the condensed contact unknowns (scaled residual, see below)
  /// A solve is Converged only if, besides Newton on the condensed unknowns, the full residual
  /// R = G a − b + n(a), recomputed from the solution, has a normwise backward error
  /// η = ‖R‖₂ / (γ ‖a‖₂ + ‖b‖₂ + ‖n(a)‖₂) ≤ residual_tolerance (WeightedResidual::backward_error;
  /// γ ≥ ‖G‖₂): the solution solves exactly a problem whose G, b and contact forces differ from
  /// the given ones by at most this relative amount. Unlike ‖R‖/‖b‖ it does not grow with the
  /// condition of G, i.e. with the units or the scaling of the coordinates. Otherwise
  /// SolveStatus::ResidualNotVerified. Both η and ‖R‖/‖b‖ are reported (WeightedResidualSolution).
  /// Throws std::invalid_argument (at construction) unless > 0.
  double residual_tolerance = 1e-8;
  /// Contact homotopy fallback (SolutionPath::ContactHomotopy): on/off and its point limit
  /// (>= 2; std::invalid_argument at construction otherwise).
  bool contact_homotopy = true;
  int homotopy_max_points = 2000;
  /// Harmonic selection (Fourier:Fourier only; empty = every harmonic of the basis): the harmonic
  /// numbers h kept in both the trial and the weighting spaces, each with its cos 2πhτ and
  /// sin 2πhτ (h = 0: the constant; h = M/2: the top function cos πMτ of M = 2^J), e.g.
  /// {1, 3, 5, …} for odd harmonics only. The residual is the Galerkin projection on the kept
  /// functions, Π R(a) = 0 with a in the kept span: since G is block-diagonal by harmonic
  /// (checked on the time operators at construction), this is G a = Π (b − n(a)), i.e. the
  /// forcing and the contact forces projected on the kept harmonics only (Π applied to the
  /// weighting functions). Exact when the solution has no other harmonics (e.g. odd harmonics
  /// of a symmetric system: two symmetric stops, forcing in harmonic 1); otherwise an
  /// approximation whose size WeightedResidual::dropped_harmonics_residual measures (a single
  /// stop makes a contact force with a mean and even harmonics: odd harmonics alone are then
  /// wrong). The dropped unknowns are kept and solved as zeros: the selection does not reduce
  /// the cost. Throws std::invalid_argument (at construction) for a wavelet basis, a harmonic
  /// outside [0, highest harmonic] or listed twice, a load at a harmonic not kept, rigid stops
  /// (their M collocation instants need every function). (G's block-diagonal structure is
  /// checked at construction; std::logic_error if it ever fails.)
  std::vector<int> harmonics = {};
  /// The checks of the fields alone, for a basis of M functions: residual_tolerance > 0,
  /// homotopy_max_points >= 2, time_samples 0 or >= M, and newton.validate(). The harmonic
  /// selection, the contact quadrature and the formulation are checked against the problem at
  /// construction. Throws std::invalid_argument naming the field, its value, the range and a
  /// value to use.
  void validate(int dimension) const;
};

/// The three time operators (M × M, dense; row = weighting j, column = trial k), including the
/// sign of the formulation, and how each was integrated ("exact" or "discrete Q = 256").
struct TimeOperators {
  Eigen::MatrixXd mass, damping, stiffness;
  std::string rule;
};

/// Outcome of a weighted-residual solve. coefficients is n × M (layout.hpp): row = DOF, column
/// = trial function; u_i(τ) = Σ_k A(i, k) q_k(τ) [JL14 Eq. (11)].
struct WeightedResidualSolution {
  Eigen::MatrixXd coefficients;    // [m]
  double frequency_hz = 0.0;
  NewtonReport report;             // Newton on the contact unknowns (scaled residual)
  double relative_residual = 0.0;  // ‖G a − b + n(a)‖₂ / ‖b‖₂ of the full system, recomputed
  /// η of the same residual (WeightedResidual::backward_error), dimensionless; NaN if G is singular.
  double backward_error = std::numeric_limits<double>::quiet_NaN();
  double residual_tolerance = 0.0; // the bound backward_error was verified against
  double max_penetration = 0.0;    // max over normal contacts and samples of u_c − g0 [m] (NaN: none)
  double max_contact_force = 0.0;  // max over contacts and samples of f_c [N] (|f| for a friction law)
  int contact_unknowns = 0;        // n_c · M
  double condition_number = 0.0;   // 1-norm condition estimate of G (Hager–Higham), inf if G is singular
  std::string linear_solver;       // "sparse-lu" or "modal"
  std::string operator_rule;       // TimeOperators::rule
  SolutionPath path = SolutionPath::DirectNewton;  // the route that gave `report`
  HomotopyReport homotopy;         // the σ path, when it was tried
  /// Only for a solve whose full residual was not verified (SolveStatus::ResidualNotVerified):
  /// the rounding floor of the relative residual at this solution, measured as the largest
  /// change of ‖G a − b + n(a)‖/‖b‖ when the contact unknowns x, or all the coefficients a,
  /// move by their own rounding (x ⊙ (1 ± ε), a ⊙ (1 ± ε), two sign patterns each, ε = 2⁻⁵²);
  /// NaN otherwise. A residual within 10× of it cannot be reduced in double precision (a
  /// penalty too stiff for the arithmetic: x; an ill-conditioned G: a).
  double rounding_floor = std::numeric_limits<double>::quiet_NaN();
  static constexpr double kRoundingFloorFactor = 10.0;
  /// Not verified, but as small as double precision allows: relative_residual ≤ 10 × rounding_floor.
  [[nodiscard]] bool at_rounding_floor() const {
    return report.status == SolveStatus::ResidualNotVerified && relative_residual <= kRoundingFloorFactor * rounding_floor;
  }
  double wall_time_s = 0.0;        // set-up and solve
  /// With a harmonic selection (WeightedResidualOptions::harmonics), the part of the full
  /// residual in the harmonics left out, ‖(I − Π) R(a)‖₂ / ‖b‖₂ (WeightedResidual::
  /// dropped_harmonics_residual); NaN without a selection.
  double dropped_harmonics_residual = std::numeric_limits<double>::quiet_NaN();
  /// Exact contacts only (WeightedResidual::rigid(): rigid stops, Coulomb friction), else empty / NaN:
  ///  - contact_force_samples: λ, n_c × M [N], row = contact, column k = impulse instant τ_k
  ///    (collocation_times); λ_k/M is the impulse (N·period), λ_k the mean force over one cell;
  ///  - collocation_times: τ_k (length M), (k + ½)/M, or k/M for friction with a weighting
  ///    basis that does not see every impulse pattern at the midpoints (WeightedResidual);
  ///  - collocation_penetration: max over the stops and k of u_c(τ_{k+1}) − g0 [m], recomputed
  ///    from `coefficients` (the plateau's flatness where the conditions are imposed;
  ///    max_penetration is over the Q samples, between the instants as well); NaN without a stop;
  ///  - complementarity: max over contacts and k of |φ| [m], the stops' min(c λ_k, g0 − u_c(τ_{k+1}))
  ///    and friction's c λ_k − proj(c λ_k + Δ_k), recomputed from `coefficients`, c the force
  ///    compliance (WeightedResidual::force_compliance).
  Eigen::MatrixXd contact_force_samples;
  Eigen::VectorXd collocation_times;
  double collocation_penetration = std::numeric_limits<double>::quiet_NaN();
  double complementarity = std::numeric_limits<double>::quiet_NaN();
  [[nodiscard]] bool converged() const { return report.converged(); }
  /// One line: the status, the verified full residual against its tolerance, and Newton's brief().
  [[nodiscard]] std::string brief() const {
    return std::string(to_string(report.status)) + ": ‖G a − b + n(a)‖/‖b‖ = " + format_number(relative_residual) +
           ", backward error " + format_number(backward_error) + " (tolerance " + format_number(residual_tolerance) +
           "); Newton " + report.brief();
  }
};

/// Weighted residual of M ü + C u̇ + K u = F cos(2πτ) e_f − Σ_c e_c f_c(u_c) in τ = f t with
/// trial functions q_k and weighting functions p_j of one dimension M [JL14 Eqs. (7), (11)–(17)]:
///   R(a) = G a − b + n(a) = 0,   G = f² A_M ⊗ M + f A_C ⊗ C + A_K ⊗ K,
///   b = F e_f ⊗ (1/Q) Σ_q p(τ_q) cos 2πτ_q,
///   n(a) = Σ_c e_c ⊗ (1/Q) Σ_q p(τ_q) f_c(u_c(τ_q)),   u_c(τ_q) = Σ_k a_{c,k} q_k(τ_q),
/// a stacked as in layout.hpp (length n·M), e_c = e_dof − e_other for a contact between two
/// DOFs (ContactPoint::other; e_dof against a fixed obstacle). The Q-point midpoint rule never samples a Haar
/// breakpoint k/M and is second order on piecewise-smooth integrands with breakpoints on the
/// grid, spectral on smooth periodic ones.
///
/// Structure exploited (as the harmonic balance of the foundation): G is factorized once
/// (LinearSolverPath), and Newton runs on the n_c·M contact unknowns x = P a only:
///   r(x) = (x − x_lin + H n_c(x)) / s,   H = P G⁻¹ Pᵀ,   x_lin = P G⁻¹ b,
///   ∂r/∂x = (I + H N(x)) / s,   N = blockdiag_c((1/Q) Σ_{q: f_c' ≠ 0} p(τ_q) f_c'(u_c(τ_q)) q(τ_q)ᵀ),
/// scaled by s_r = max(max_c |g0_c|, ‖x_lin‖∞) (1 m if both vanish; metres, so that a 1 nm gap
/// does not ask Newton for 1e-19 m). N sums over the samples in contact only, and over the
/// basis functions nonzero there (compact support).
///
/// Rigid stops (contact::RigidStop, ContactLaw::rigid()): when every contact is rigid, the
/// contact force of contact c is M impulses per period, λ_{c,k}/M at the instants
/// τ_k = (k + ½)/M (λ_k: the mean force over one cell, N), and the Signorini conditions pair
/// impulse k with the gap one instant later [JL14 Sec. 6, the exact contact the paper proposes]:
///   n(λ) = Σ_c e_c ⊗ (1/M) Σ_k p(τ_k) λ_{c,k},
///   g_{c,k} = g0_c − u_c(τ_{k+1}) ≥ 0,   λ_{c,k} ≥ 0,   g_{c,k} λ_{c,k} = 0   (k + 1 mod M).
/// This is the periodic analogue of the Moreau–Jean scheme (the impulse of a step keeps the
/// gap open at its end) and, like it with a position-level condition, a plastic impact law
/// (e = 0): the solutions converge to the Moreau–Jean steady state with e = 0 as M grows
/// (tests/solvers/test_rigid_contact.cpp). Pairing an impulse with the gap at its own instant
/// is ill-posed: the displacement there does not depend on it (a kink, not a jump), and the
/// active-set iteration cycles (docs/design.md).
/// Condensed onto the n_c·M impulses λ (ordering λ(k·n_c + c), like x):
///   u(λ) = u_lin − D λ,   D = V H W   (the Delassus operator),
/// V = trial functions at τ_{k+1}, W = weighting functions at τ_k / M, u_lin = V x_lin; the
/// equations φ(λ) = min(c λ, g0 − u(λ)) / s_r = 0 (contact::signorini_min, c = the mean |D_ii|
/// [m/N]) are solved by the one Newton core with their generalized Jacobian, i.e. the primal–
/// dual active-set method: on the r instants where the gap branch is active the step solves
/// D_AA (an r × r LU, WoodburyLu), elsewhere λ = 0. Cost: D once per frequency
/// (O((n_c M)² M)), then r × r per Newton step. With a Fourier trial basis of even M the top
/// function cos πMτ vanishes at every instant: the conditions do not see it. A point mass at
/// the stop (a 1-DOF oscillator) has no local compliance: its D is dominated by the periodic
/// echo of the impulses and the iteration may stagnate (reported, not hidden). Mixing rigid and
/// penalty contacts, and ContactQuadrature::CellAverage with rigid stops, are refused.
///
/// Exact Coulomb friction (contact::CoulombFriction, also rigid(); it may be mixed with rigid
/// stops): the friction force of contact c is the same M impulses, each paired with the slip
/// of the cell it opens, Δ_{c,k} = u_c(τ_{k+1}) − u_c(τ_k), through the discrete Coulomb law
/// Δ ∈ N_[−μN, μN](λ) (the implicit, Moreau-type discretization of f ∈ μN Sign(u̇)), written
///   φ_{c,k} = c λ_{c,k} − proj_[−c μN, c μN](c λ_{c,k} + Δ_{c,k}) = 0
/// (contact::coulomb_projection); its rows of D and u_lin use V(τ_{k+1}) − V(τ_k), and the same
/// active-set Newton applies (stick rows: D_i/c; slip rows: λ = ±μN). At convergence this is the
/// fixed point the DLFT iterates on [NPT03], with c in the role of the DLFT's
/// inverse penalty; here it is solved in time, on the impulses, by Newton. Contrary to the
/// frequency-domain DLFT it holds for any admissible pair. The friction force switches at an
/// instant: the response converges at first order in 1/M (tests/solvers/test_friction.cpp).
/// A friction contact whose ContactPoint::normal names a rigid stop is a 2D contact (Signorini and
/// Coulomb on one point): its slip force at impulse k is μ λ⁺_{n,k}, the stop's multiplier of the
/// same cell (the normal load the stop transmits; zero where it is open, so that the tangential
/// impulse vanishes there), μN replaced by it in φ; a slip row then also has ∂φ/∂λ_{n,k} = −σμc
/// (σ the slip direction), one more row in the Jacobian's low-rank part. This is the pairing of
/// the Moreau–Jean step with fc2d (integrate_moreau_jean_to_periodic), the reference it converges
/// to (tests/solvers/test_friction_rigid_normal.cpp).
/// In full stick the slips leave the position free: a contact that sticks at every instant is
/// pinned at u(τ_1) = 0 (the Jenkins convention, f = k_t w, as k_t → ∞). The instants are the
/// midpoints unless W is singular there (Fourier of even M, whose top function vanishes at
/// them; the B-splines, against (−1)^k): then τ_k = k/M, where W is invertible (else
/// std::invalid_argument at construction). Exact friction has no penalty homotopy (its
/// regularization, the Jenkins element, has a state): when the active-set Newton from zero
/// impulses fails, the load is stepped, s: 0 → 1 (SolutionPath::LoadStepping; natural-parameter
/// continuation from λ = 0, where every contact sticks or stays open, adaptive steps from 1/8,
/// the active-set Newton at each from the secant prediction). When that fails too, the
/// active-set iteration runs from zero impulses with full steps, without the line search on ‖φ‖
/// (SolutionPath::FullStepActiveSet; the primal–dual active-set method of [HIK02], whose steps
/// are not descent directions of ‖φ‖ where an instant changes branch: the backtracking then stalls
/// where the full steps settle the branches; a cycle of the residual norms stops it). Measured on
/// a point pressed on a plane and rubbing on it (a 2D contact, test_friction_rigid_normal.cpp):
/// with the line search it failed for DB6 at M = 64 and 256, without it converged there; in
/// reproduce/friction_rigid_normal 28 of 30 solves converge, Haar:B-spline failing at two M.
///
/// A moving counter-surface (ContactPoint::obstacle, s_c(τ) along e_c): every law sees the
/// relative displacement u_c − s_c, i.e. f_c(u_c(τ_q) − s_c(τ_q)) at the Q samples (CellAverage:
/// the slope δ_q less ṡ_c(τ_q)/Q), the gap g0 + s_c(τ_{k+1}) − u_c(τ_{k+1}) of a rigid stop, and the
/// slip Δ_{c,k} − (s_c(τ_{k+1}) − s_c(τ_k)) of exact friction (a drift d included: τ_M = τ_0 + 1),
/// whose full stick pins u_c(τ_1) = s_c(τ_1). s is a given function of τ, so the Jacobians and
/// ∂r/∂f are unchanged, and it is not scaled by the load (∂r/∂s as without it). Its harmonics must
/// satisfy 2h < M, like the loads'; s_r also covers its excursion (ObstacleMotion::amplitude_bound).
///
/// Throws std::invalid_argument for invalid inputs, for a load at a harmonic h with 2h ≥ M
/// (HarmonicForcing::require_resolved: M functions would alias it), for M differing between trial and weighting,
/// and for a pair/formulation that needs a derivative a basis lacks; the message names the
/// basis, the order, the term of the equation and the formulation that works (e.g. Haar trial:
/// Formulation::Distributional), and for a counter-surface moving at a harmonic 2h ≥ M.
/// Immutable after construction.
class WeightedResidual {
 public:
  WeightedResidual(MechanicalSystem system, HarmonicForcing forcing, std::vector<ContactPoint> contacts,
                   TimeBasis trial, TimeBasis weighting, WeightedResidualOptions options = {});
  ~WeightedResidual();
  WeightedResidual(WeightedResidual&&) noexcept;
  WeightedResidual& operator=(WeightedResidual&&) noexcept;

  [[nodiscard]] int dofs() const;
  [[nodiscard]] int dimension() const;
  [[nodiscard]] int time_samples() const;
  [[nodiscard]] const MechanicalSystem& system() const;
  [[nodiscard]] const HarmonicForcing& forcing() const;
  [[nodiscard]] const std::vector<ContactPoint>& contacts() const;
  [[nodiscard]] const TimeBasis& trial() const;
  [[nodiscard]] const TimeBasis& weighting() const;
  [[nodiscard]] Formulation formulation() const;
  [[nodiscard]] const TimeOperators& time_operators() const;
  /// "Fourier:Fourier, distributional" etc.
  [[nodiscard]] std::string describe() const;

  /// Full residual R(a) [N], length n·M, and its Jacobian dR/da (dense n·M × n·M; for checks at
  /// small sizes only, the solver never forms it).
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& a) const;
  [[nodiscard]] Eigen::MatrixXd jacobian(const Eigen::VectorXd& a) const;
  /// a_lin = G⁻¹ b: the response with every contact law removed (length n·M).
  [[nodiscard]] Eigen::VectorXd linear_response() const;
  /// 1-norm condition estimate κ₁(G) = ‖G‖₁ ‖G⁻¹‖₁: ‖G‖₁ exact from the Kronecker factors,
  /// ‖G⁻¹‖₁ by Hager's method with Higham's refinements [Higham 1988, Alg. 4.1] (a lower bound,
  /// a few solves with G and Gᵀ; solvers/src/core/one_norm_estimate.hpp); inf if G is singular.
  [[nodiscard]] double condition_number() const;
  /// Normwise backward error of coefficients a (length n·M) whose full residual is r (length n·M,
  /// from residual(a), or residual(a, λ) for exact contact) [Rigal & Gaches 1967; Higham,
  /// Accuracy and Stability of Numerical Algorithms, 2nd ed. 2002, Thm. 7.1]:
  ///   η = ‖r‖₂ / (γ ‖a‖₂ + ‖b‖₂ + ‖n‖₂),   n = r − (G a − b) the contact forces' term [N],
  ///   γ = ‖G‖_F ≥ ‖G‖₂, exact from the Kronecker factors (G = Σ_s c_s A_s ⊗ X_s, so
  ///   ‖G‖_F² = Σ_{s,s'} c_s c_s' ⟨A_s, A_s'⟩_F ⟨X_s, X_s'⟩_F: O(M²) + O(nnz(X)), G not formed).
  /// η is the smallest ε for which a solves (G + ΔG) a − (b + Δb) + (n + Δn) = 0 exactly with
  /// ‖ΔG‖₂ ≤ ε γ, ‖Δb‖₂ ≤ ε ‖b‖₂, ‖Δn‖₂ ≤ ε ‖n‖₂: relative changes of the data, dimensionless.
  /// Rounding alone leaves ‖r‖ ≈ ε_mach ‖G‖ ‖a‖ ≤ ε_mach κ(G) ‖b‖, so the relative residual
  /// ‖r‖/‖b‖ of an exact solve grows with the condition of G (mixed units, Craig–Bampton
  /// coordinates), while η stays at the order of ε_mach. This is the quantity
  /// WeightedResidualOptions::residual_tolerance bounds. 0 when r = 0. Throws
  /// std::invalid_argument if a or r has not n·M entries, std::logic_error if G is singular.
  [[nodiscard]] double backward_error(const Eigen::VectorXd& a, const Eigen::VectorXd& r) const;
  /// "sparse-lu" or "modal".
  [[nodiscard]] std::string linear_solver() const;

  /// The condensed system on the contact unknowns (satisfies NonlinearSystem); x(k·n_c + c).
  /// `load` scales the forcing (s·F): r = (x − s·x_lin + H n_c(x)) / s_r, so ∂r/∂s = −x_lin/s_r.
  /// With a stick/slip `piece` (jenkins_active_set's layout) the Jenkins elements take that
  /// piece's branches (contact::jenkins_loop with a pattern): the smooth residual of the piece,
  /// for the piecewise-smooth continuation (JenkinsResponseFamily); std::invalid_argument for a
  /// piece of another length. contact_jacobian_low_rank, contact_residual_frequency_derivative
  /// and contact_residual_friction_derivative take the same piece.
  [[nodiscard]] Eigen::VectorXd contact_residual(const Eigen::VectorXd& x, double load = 1.0,
                                                 const ActiveSet* piece = nullptr) const;
  /// ∂r/∂x = (I + H N(x)) / s_r (n_c·M square, dense), N = ∂n_c/∂x.
  [[nodiscard]] Eigen::MatrixXd contact_jacobian(const Eigen::VectorXd& x) const;
  /// The same Jacobian in the form Newton uses (newton.hpp, WoodburyLu): N = W V has the rank
  /// r of the contact samples where the law's derivative is nonzero (plus the kink samples of
  /// ContactQuadrature::CellAverage), so ∂r/∂x = (I + U V)/s_r with U = H W (n_c·M × r) and
  /// the capacitance C = I_r + V U; V is applied by FFTW (Fourier trial basis) or by the
  /// wavelets' sparse rows. Fourier:Fourier (midpoint rule, H commuting with time shifts):
  /// C gathered from the shift kernel of H in O(r²) and U given by its product (times_u).
  /// Dense form (C = I + H N) when r > ¾ n_c·M or a hysteretic or coupled friction law makes N
  /// not diagonal in the samples. Either gives way to the sparse form (newton.hpp) with the
  /// assembled G(f) as L, U = P and V′ = Pᵀ N, its capacitance G + Pᵀ N P the uncondensed
  /// Jacobian, when the time operators are sparse and a bound on that capacitance's entries is
  /// at most those of the form it replaces (r², or (n_c·M)²): many contacts on a sparse FE model
  /// (a chain of n_c = 64 at M = 16 factorizes 1 024 sparse unknowns instead of a dense r × r
  /// with r up to 768). dense() equals contact_jacobian(x) to rounding. The products hold their
  /// own data (shared), not a reference to this object.
  /// Throws std::runtime_error if G is singular.
  [[nodiscard]] LowRankJacobian contact_jacobian_low_rank(const Eigen::VectorXd& x,
                                                          const ActiveSet* piece = nullptr) const;
  /// Jenkins elements (contact::JenkinsLaw): the stick/slip piece the return map picks at x, 1
  /// where sample q of an element slips (|f*_q| > F_s,q), 0 where it sticks; Q entries per
  /// element, the elements in contact order (element j's sample q at j·Q + q). Empty without a
  /// Jenkins element. Throws std::logic_error for rigid stops.
  [[nodiscard]] ActiveSet jenkins_active_set(const Eigen::VectorXd& x) const;
  /// The event functions of a stick/slip piece at x (same layout and length):
  ///   e_q = (F_s,q − |f*_q|) / (k_t s_r) on a stick entry,  −(F_s,q − |f*_q|) / (k_t s_r) on a slip one,
  /// f*_q the elastic predictor of the piece's loop and k_t the element's tangential stiffness:
  /// the slider's margin in metres, scaled like the residual. All ≥ 0 exactly where the return
  /// map picks the piece's branches, so a branch leaves the piece where one changes sign
  /// (contact::jenkins_loop, "A stick/slip pattern"). Throws as contact_residual with a piece.
  [[nodiscard]] Eigen::VectorXd jenkins_events(const Eigen::VectorXd& x, const ActiveSet& piece) const;
  [[nodiscard]] Eigen::VectorXd contact_unknowns(const Eigen::VectorXd& a) const;  // x = P a
  /// Harmonic selection (WeightedResidualOptions::harmonics): ‖(I − Π) R(a(x))‖₂ / ‖s b‖₂ at the
  /// contact unknowns x and load s (a(x) = G⁻¹Π(s b − Pᵀ n(x))): the weighted residual of the
  /// contact forces in the harmonics left out (G a and b have none there), relative to the
  /// forcing (‖s b‖₂ replaced by 1 N when it vanishes); 0 when the contact forces have no
  /// dropped harmonic (a symmetric system in odd harmonics). NaN without a selection. Throws
  /// std::invalid_argument for x of another length than n_c·M, like contact_residual otherwise.
  [[nodiscard]] double dropped_harmonics_residual(const Eigen::VectorXd& x, double load = 1.0) const;
  /// The kept harmonic numbers, ascending (empty: every harmonic).
  [[nodiscard]] const std::vector<int>& harmonics() const;

  /// True when every contact is a rigid stop (the Signorini path above; the penalty-law
  /// functions contact_residual, contact_jacobian, contact_jacobian_low_rank, expand and the
  /// homotopy then throw std::logic_error naming the rigid ones).
  [[nodiscard]] bool rigid() const;
  /// The contact quadrature in use (WeightedResidualOptions::contact_quadrature).
  [[nodiscard]] ContactQuadrature contact_quadrature() const;
  /// Exact contacts: the impulse instants τ_k (length M), (k + ½)/M or, for friction with a
  /// weighting basis singular at the midpoints, k/M; impulse k is paired with the gap at τ_{k+1}
  /// (a stop) or the slip from τ_k to τ_{k+1} (friction).
  [[nodiscard]] Eigen::VectorXd collocation_times() const;
  /// Rigid stops: D = V H W (n_c·M square [m/N], rows and columns k·n_c + c): the contact
  /// displacements at τ_{k+1} are u(λ) = u_lin − D λ.
  [[nodiscard]] const Eigen::MatrixXd& delassus() const;
  /// Rigid stops: c = mean |D_ii| [m/N], the scale of c λ in the complementarity function (of
  /// the frequency the object was built at: at_frequency keeps it, as it keeps s_r).
  [[nodiscard]] double force_compliance() const;
  /// Rigid stops: φ(λ) = min(c λ, g0 − u(λ)) / s_r (length n_c·M) at load s (x_lin → s x_lin),
  /// and its generalized Jacobian (gap rows: D_i/s_r; force rows: c e_i/s_r) as identity plus
  /// the gap rows, (c/s_r)(I + P_A (D/c − I)_A), with capacitance D_AA/c (dense when
  /// r > ¾ n_c·M); A also holds the slip rows of 2D contacts whose stop pushes (their row
  /// e_i − σμ e_j, j the stop's impulse). λ in N, ordering k·n_c + c. Throw std::logic_error unless rigid().
  /// With a piece (rigid stops without friction; an ActiveSet of length n_c·M, ordering
  /// k·n_c + c, 1 = the gap row g0 − u(λ), 0 = the force row c λ): the smooth residual of that
  /// piece, each row on the branch the piece names instead of the min's, and its Jacobian and
  /// derivatives; the pieces of the piecewise-smooth continuation (SignoriniResponseFamily).
  /// Throws std::logic_error for a piece with friction contacts (a friction row has three
  /// branches) and std::invalid_argument for a piece of another length.
  [[nodiscard]] Eigen::VectorXd signorini_residual(const Eigen::VectorXd& lambda, double load = 1.0,
                                                   const ActiveSet* piece = nullptr) const;
  /// (The Jacobian's branches are those at load s, or the piece's.)
  [[nodiscard]] LowRankJacobian signorini_jacobian(const Eigen::VectorXd& lambda, double load = 1.0,
                                                   const ActiveSet* piece = nullptr) const;
  /// Rigid stops: ∂φ/∂f of signorini_residual at λ and load s [1/Hz]: on the gap rows
  /// (V P G⁻¹ G′(f) a(λ)) / s_r with a(λ) = G⁻¹(s b − Pᵀ n(λ)), G′ = 2f A_M ⊗ M + A_C ⊗ C; 0 on
  /// the force rows. And ∂φ/∂s (the load): −u_lin/s_r on the gap rows, 0 elsewhere. (Gap rows:
  /// the min's at λ, or the piece's.)
  [[nodiscard]] Eigen::VectorXd signorini_frequency_derivative(const Eigen::VectorXd& lambda, double load = 1.0,
                                                               const ActiveSet* piece = nullptr) const;
  [[nodiscard]] Eigen::VectorXd signorini_load_derivative(const Eigen::VectorXd& lambda, double load = 1.0,
                                                          const ActiveSet* piece = nullptr) const;
  /// Rigid stops without friction: the piece the min picks at λ and load s, 1 where
  /// g0 − u(λ) ≤ c λ (contact::signorini_min's tie rule). Throws std::logic_error with friction.
  [[nodiscard]] ActiveSet signorini_active_set(const Eigen::VectorXd& lambda, double load = 1.0) const;
  /// Rigid stops without friction: the event functions of a piece (length n_c·M), the row it
  /// does not hold: c λ / s_r on a gap row (the impulse stays ≥ 0 while the sample touches),
  /// (g0 − u(λ)) / s_r on a force row (the gap stays ≥ 0 while the sample is free); all ≥ 0
  /// exactly where the piece's solution satisfies the Signorini conditions. Throws as the
  /// pieces above.
  [[nodiscard]] Eigen::VectorXd signorini_events(const Eigen::VectorXd& lambda, double load, const ActiveSet& piece) const;
  /// Rigid stops: a = G⁻¹(s b − Pᵀ n(λ)), the full coefficients (length n·M) for given forces.
  [[nodiscard]] Eigen::VectorXd expand_forces(const Eigen::VectorXd& lambda, double load = 1.0) const;
  /// Rigid stops: R(a, λ) = G a − b + Pᵀ n(λ) [N] (length n·M), the full residual with the
  /// collocation impulses.
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& a, const Eigen::VectorXd& lambda) const;
  /// a = G⁻¹(b − Pᵀ n_c(x)): the full coefficients for given contact unknowns.
  [[nodiscard]] Eigen::VectorXd expand(const Eigen::VectorXd& x) const;

  /// The same problem at another forcing frequency f [Hz]: time operators, samples, forcing
  /// vector, modal basis and the residual scale s_r (and for rigid stops the force compliance c)
  /// are reused, only G(f) is factorized again (so contact residuals at different f are
  /// comparable, as continuation needs).
  /// Throws std::invalid_argument unless f > 0 and finite.
  [[nodiscard]] WeightedResidual at_frequency(double frequency_hz) const;
  [[nodiscard]] double frequency_hz() const;
  /// s_r, the scale of contact_residual [m].
  [[nodiscard]] double residual_scale() const;
  /// ∂r/∂f of contact_residual at x and load s [1/Hz]: with a(x) = G⁻¹(s b − Pᵀ n_c(x)),
  ///   ∂r/∂f = P G⁻¹ G′(f) a(x) / s_r,   G′(f) = 2f A_M ⊗ M + A_C ⊗ C,
  /// since b does not depend on f in normalized time τ = f t. Two solves with the factorized G.
  [[nodiscard]] Eigen::VectorXd contact_residual_frequency_derivative(const Eigen::VectorXd& x, double load = 1.0,
                                                                      const ActiveSet* piece = nullptr) const;

  /// Sets the friction coefficient μ [-] of every Jenkins element (contact::JenkinsLaw) to `mu`,
  /// keeping its k_t and preload (with_friction_coefficient, mechanical_system.hpp). Everything
  /// else is kept as it is, G's factorization included: a Jenkins law enters only the contact
  /// forces n_c(x) (a tangential law has no gap, so s_r does not move). Continuation in μ
  /// (ContinuationParameter::FrictionCoefficient) sets it on its own copy. Throws
  /// std::invalid_argument for a μ that is not finite and >= 0, for a problem without a Jenkins
  /// element, or with exact Coulomb friction (common_friction_coefficient).
  void set_friction_coefficient(double mu);
  /// ∂r/∂μ of contact_residual at x, with μ the friction coefficient every Jenkins element shares
  /// (common_friction_coefficient) [m per unit μ, scaled by 1/s_r like r]:
  ///   ∂r/∂μ = H ∂n_c/∂μ / s_r,   ∂f_q/∂μ = σ_r (N + n_r),
  /// on the element's loop at x (contact::JenkinsLoop): r = q in slip, r the anchor (its last
  /// slip) in stick, σ_r = ±1 the slip direction there, N the preload and n_r the normal law's
  /// force at sample r under a varying normal load (0 otherwise); 0 in full stick. Exact on
  /// each stick/slip pattern, where the force is affine in μ; at μ = 0 every sample slips with
  /// σ = sign(w_q − w_(q−1)), the direction the first slip of a small μ takes. Shape n_c·M,
  /// ordering of x. Throws as set_friction_coefficient for the contacts, std::logic_error for
  /// rigid stops.
  [[nodiscard]] Eigen::VectorXd contact_residual_friction_derivative(const Eigen::VectorXd& x,
                                                                     const ActiveSet* piece = nullptr) const;

  /// The contact homotopy of SolutionPath::ContactHomotopy as a ParametrizedSystem
  /// (linearization.hpp) in λ = log₁₀ σ, on the contact unknowns x (length n_c·M):
  ///   r(x, λ) = (x − x_lin + σ H n_c(x)) / s_r,   ∂r/∂x = (I + σ H N(x)) / s_r,
  ///   ∂r/∂λ = ln 10 · σ H n_c(x) / s_r,   σ = 10^λ.
  /// r(x, 0) = contact_residual(x). The Jacobian in the form contact_jacobian_low_rank gives
  /// (with σ N for N), so that the corrector's bordered solves use its structure. Refers to this
  /// object, which must outlive it.
  struct ContactHomotopy {
    const WeightedResidual* problem;
    [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x, double lambda) const;
    [[nodiscard]] LowRankLinearization linearize(const Eigen::VectorXd& x, double lambda) const;
  };
  [[nodiscard]] ContactHomotopy contact_homotopy() const { return {this}; }

  /// Rigid stops (rigid()): the primal–dual active-set Newton on the Signorini conditions from
  /// the impulses x0 (length n_c·M, default 0); without x0, if it fails (the active set cycles:
  /// D is not a P-matrix), SolutionPath::ContactHomotopy: pseudo-arclength continuation of the
  /// conditions regularized by a penalty at the same instants, c λ = κ (u − g0)₊, in log₁₀ κ
  /// from 10⁻² to 10⁸, then the active-set Newton from there (`homotopy` reports κ reached as
  /// sigma_reached). SolveStatus::Converged only if the conditions recomputed from the
  /// coefficients meet newton.tolerance and the full residual R(a, λ) meets residual_tolerance.
  /// Penalty laws:
  /// Newton on the contact unknowns from x0 (default x_lin); without x0 a failed Newton falls
  /// back on the contact homotopy, then on load stepping (SolutionPath; `path` says which gave
  /// the answer). Non-convergence is reported in the solution's report, never thrown: a
  /// homotopy that ends before σ = 1 (and load stepping that stalls after it) gives
  /// SolveStatus::PathEnded with the σ reached and the branch's stop reason.
  [[nodiscard]] WeightedResidualSolution solve(const Eigen::VectorXd* x0 = nullptr) const;

 private:
  struct Impl;
  struct Condensed;
  explicit WeightedResidual(std::unique_ptr<Impl> impl);
  NewtonResult solve_with_load_stepping(Eigen::VectorXd x, int& steps) const;
  NewtonResult solve_with_contact_homotopy(HomotopyReport& report) const;
  struct Signorini;
  struct SignoriniPenalty;
  NewtonResult solve_rigid_with_penalty_homotopy(HomotopyReport& report) const;
  NewtonResult solve_exact_with_load_stepping(int& steps) const;
  WeightedResidualSolution solve_rigid(const Eigen::VectorXd* lambda0, WeightedResidualSolution s,
                                       std::chrono::steady_clock::time_point start) const;
  double rounding_floor(const Eigen::VectorXd& a, const Eigen::VectorXd& x) const;
  std::unique_ptr<Impl> impl_;
};

/// Build and solve in one call; wall_time_s covers both.
[[nodiscard]] WeightedResidualSolution solve_weighted_residual(
    const MechanicalSystem& system, const HarmonicForcing& forcing, const std::vector<ContactPoint>& contacts,
    const TimeBasis& trial, const TimeBasis& weighting, const WeightedResidualOptions& options = {});

}  // namespace wbm::solvers
