#pragma once
/// The one Newton core of the project: damped Newton–Raphson for R(x) = 0 with a backtracking
/// (Armijo) line search, an optional Levenberg–Marquardt fallback, and a linear-solver policy
/// (dense LU; sparse LU (KLU) that keeps its symbolic analysis while the sparsity pattern is
/// unchanged; Woodbury for identity plus low rank, the condensed contact systems; or a
/// system's own, e.g. NonlinearModes::BackboneSystem::KktSolver for the KKT backbone). The
/// forced response (weighted residuals), the continuation corrector, the nonlinear-mode
/// stationarity solves and the fixed-energy KKT solves all run through newton().

#include <algorithm>
#include <cmath>
#include <concepts>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>
#include <Eigen/SparseCore>

#include <wbm/solvers/status.hpp>

namespace wbm::solvers {

/// The Jacobian of a system condensed onto the unknowns of a nonlinearity (the contact
/// unknowns of the weighted residual method): identity plus a rank-r update,
///   J = (I_n + U V) / s,   U: n × r,   V: r × n,
/// with V given by its product Y ↦ V Y, U by the dense matrix `u` or by its product `times_u`
/// (then `u` is empty), and the capacitance matrix C = I_r + V U (r × r) formed by the system,
/// which knows fast products (an FFT, or the few nonzeros of compactly supported wavelets).
/// Sherman–Morrison–Woodbury [Hager 1989, SIAM Review 31(2) 221–239]:
/// J⁻¹ y = s (y − U C⁻¹ V y), so a step costs an r × r LU instead of an n × n one;
/// det J = det C / sⁿ. An empty `times_v` is the dense case: V = I_n, r = n, and J = C / s
/// (U unused).
///
/// The sparse form (sparse_form(): `sparse_capacitance` not empty) is for an update whose rank
/// is not small but whose factors are sparse through a sparse regular L (q × q):
///   J = (I_n + U L⁻¹ V′) / s,   U: n × q (`sparse_u`),   V′: q × n (`sparse_v`),
/// with the capacitance K = L + V′ U (q × q, sparse, `sparse_capacitance`): the generalized
/// Woodbury identity (I + U L⁻¹ V′)⁻¹ = I − U K⁻¹ V′ [Hager 1989] makes a step one sparse LU
/// of K. `times_update` gives Y ↦ U L⁻¹ V′ Y (n × k), for apply() and dense() only; `u`,
/// `capacitance`, `times_v` and `times_u` are empty. The condensed contact Jacobian takes it
/// with L the assembled operator G(f), U = P and V′ = Pᵀ N: K = G + Pᵀ N P is the uncondensed
/// Jacobian, sparse where the structure is (weighted_residual.hpp, contact_jacobian_low_rank).
/// det J = det K / (det L · sⁿ).
struct LowRankJacobian {
  double scale = 1.0;            // s > 0
  Eigen::Index rows = 0;         // n
  Eigen::MatrixXd u;             // U, n × r, or empty when times_u is given (and in the dense case)
  Eigen::MatrixXd capacitance;   // C = I_r + V U, r × r (dense case: C = s J, n × n)
  std::function<Eigen::MatrixXd(const Eigen::MatrixXd&)> times_v;  // Y (n × k) ↦ V Y (r × k)
  std::function<Eigen::MatrixXd(const Eigen::MatrixXd&)> times_u;  // Z (r × k) ↦ U Z (n × k), optional
  Eigen::SparseMatrix<double> sparse_capacitance;  // sparse form: K = L + V′ U (q × q)
  Eigen::SparseMatrix<double> sparse_u;            // sparse form: U (n × q)
  Eigen::SparseMatrix<double> sparse_v;            // sparse form: V′ (q × n)
  std::function<Eigen::MatrixXd(const Eigen::MatrixXd&)> times_update;  // sparse form: Y ↦ U L⁻¹ V′ Y

  [[nodiscard]] bool dense_form() const { return !times_v && !sparse_form(); }
  [[nodiscard]] bool sparse_form() const { return sparse_capacitance.rows() > 0; }
  [[nodiscard]] Eigen::Index size() const { return dense_form() ? capacitance.rows() : rows; }
  /// r (q in the sparse form).
  [[nodiscard]] Eigen::Index rank() const { return sparse_form() ? sparse_capacitance.rows() : capacitance.rows(); }
  /// Every stored entry finite (capacitance, U, and the sparse form's three factors).
  [[nodiscard]] bool all_finite() const;
  /// U Z (n × k) for Z (r × k); not in the sparse form.
  [[nodiscard]] Eigen::MatrixXd u_times(const Eigen::MatrixXd& z) const;
  /// J y (length n).
  [[nodiscard]] Eigen::VectorXd apply(const Eigen::VectorXd& y) const;
  /// J as an n × n matrix: O(n² r) (the Levenberg–Marquardt fallback and tests).
  [[nodiscard]] Eigen::MatrixXd dense() const;
};

/// The bordered matrix of a continuation corrector (continuation.hpp) for J = (I + U V)/s:
///   B = [[α J, b], [cᵀ, d]]   ((n + 1) × (n + 1), the border last),
/// itself identity plus low rank, so that its solves cost an (r + 2) × (r + 2) LU instead of an
/// (n + 1) × (n + 1) one: with a = α/s,
///   B = a (I + Û V̂),   Û = [[U, b/a, 0], [0, 0, 1/a]]   ((n + 1) × (r + 2)),
///                      V̂ = [[V, 0], [0, 1], [cᵀ, d − a]]  ((r + 2) × (n + 1)),
/// and the capacitance I + V̂ Û = [[C, V b/a, 0], [0, 1, 1/a], [cᵀ U, cᵀ b/a, d/a]] with
/// C = I + V U, J's own: a bordered Woodbury [Govaerts 2000, Numerical Methods for Bifurcations
/// of Dynamical Equilibria, Sec. 3.6, on bordered systems; Hager 1989]. det B = aⁿ⁺¹ det(I + V̂ Û),
/// so the capacitance is singular exactly where B is: at a fold, where J is singular and B is
/// not, it is regular. Returned with scale 1/a. When J is in the dense form (C = s J, n × n), B
/// is returned dense (capacitance = B, scale 1), its block α J formed as (C/s) α, as the dense
/// corrector forms it. cᵀ U needs U: J.u, else U = times_u(I_r) is formed (r products).
/// In the sparse form the same bordering multiplied through by L̂ = diag(L, 1, 1) stays sparse:
///   K̂ = [[K, V′ b/a, 0], [0, 1, 1/a], [cᵀ U, cᵀ b/a, d/a]],   V̂′ = [[V′, 0], [0, 1], [cᵀ, d − a]],
/// Û as above (sparse, its column b/a dense); the entries of V′ b and cᵀ U are stored on the rows
/// of V′ and the columns of U that hold any entry, so that the pattern of K̂ depends on the
/// patterns only (a sparse LU keeps its symbolic analysis).
/// Throws std::invalid_argument if α is not finite and > 0, or if b or c does not have J's size.
[[nodiscard]] LowRankJacobian bordered_low_rank(const LowRankJacobian& j, double alpha, const Eigen::VectorXd& b,
                                                const Eigen::VectorXd& c, double d);

/// A symmetric Jacobian that is sparse plus a dense update of low rank, the Hessian of a
/// function whose terms are local but for a few global scalars (the augmented Lagrangian of
/// nonlinear modes [LL11 Eq. (18)]: the Rayleigh quotient and the energy normalization couple
/// every unknown through rank-one terms, the rest is block diagonal in the harmonics plus the
/// contact samples):
///   H = S + U C Uᵀ,   S: n × n sparse symmetric,   U: n × p dense,   C: p × p symmetric,
/// with p small. S alone may be singular (a harmonic block K − ν²ω²M at a resonance of the
/// linear mode) and so may C; BorderedSparseLu never inverts either.
struct SparseLowRankHessian {
  Eigen::SparseMatrix<double> sparse;  // S (n × n)
  Eigen::MatrixXd u;                   // U (n × p)
  Eigen::MatrixXd core;                // C (p × p)
  [[nodiscard]] Eigen::Index size() const { return sparse.rows(); }
  /// H y (length n): O(nnz(S) + n p).
  [[nodiscard]] Eigen::VectorXd apply(const Eigen::VectorXd& y) const;
  /// H as an n × n matrix: O(n² p) (the slow reference path and the fallback).
  [[nodiscard]] Eigen::MatrixXd dense() const;
};

/// A square nonlinear system: residual(x) (length n) and its Jacobian dR/dx (n × n), either
/// dense (Eigen::MatrixXd), sparse (Eigen::SparseMatrix<double>), identity plus low rank
/// (LowRankJacobian) or sparse plus symmetric low rank (SparseLowRankHessian); the Jacobian's
/// type picks the default linear solver (DenseLu, SparseLu, WoodburyLu or BorderedSparseLu).
template <class S>
concept NonlinearSystem = requires(const S& s, const Eigen::VectorXd& x) {
  { s.residual(x) } -> std::convertible_to<Eigen::VectorXd>;
  requires std::convertible_to<decltype(s.jacobian(x)), Eigen::MatrixXd> ||
               std::convertible_to<decltype(s.jacobian(x)), Eigen::SparseMatrix<double>> ||
               std::same_as<std::decay_t<decltype(s.jacobian(x))>, LowRankJacobian> ||
               std::same_as<std::decay_t<decltype(s.jacobian(x))>, SparseLowRankHessian>;
};

/// The norm in which the convergence test ‖R(x)‖ ≤ tolerance is made (and residual_norms are
/// reported). The line search always decreases the Euclidean norm.
enum class ResidualNorm { Euclidean, Max };

struct NewtonOptions {
  double tolerance = 1e-10;   // converged when ‖R(x)‖ ≤ tolerance (R as scaled by the system)
  int max_iterations = 50;    // Newton steps, >= 0
  bool line_search = true;    // Armijo backtracking on ‖R‖₂ (halving, at most max_backtracks)
  int max_backtracks = 30;
  double min_rcond = 1e-15;   // dense Jacobians with a smaller reciprocal condition estimate are singular
  /// When the line search finds no decrease: Levenberg–Marquardt steps
  /// (JᵀJ + μ² I) d = −Jᵀ R, μ from 10⁻⁶ ‖J‖∞, ×0.3 after a decrease of ‖R‖₂ and ×4 after a
  /// failure (at most max_lm_trials per iteration). Each iteration tries the Newton step first:
  /// the fallback is taken only at the iterations whose line search fails, and μ is kept between
  /// them. (Kept for the rest of the solve instead, LM's damped steps converge linearly where
  /// Newton converges quadratically: LL11 Alg. 1 on the Fig. 3 rod at N = 12, m = 256 then
  /// spent over 120 s on the level E = 1.3, against 2 s.) Each step is the policy's own when it
  /// has one (LevenbergMarquardtPolicy: BorderedSparseLu's shifted sparse LU), else a dense
  /// Householder QR of [J; μI] (detail::levenberg_marquardt_step), for small systems only.
  bool levenberg_marquardt = false;
  int max_lm_trials = 20;
  ResidualNorm norm = ResidualNorm::Euclidean;
  /// Stop (Stagnated) once the residual norms repeat with period p = 2 or 3: ‖R_k‖ and ‖R_(k−1)‖
  /// both equal ‖R_(k−p)‖ and ‖R_(k−1−p)‖ to a relative cycle_tolerance. Without line search a
  /// semismooth Newton whose steps alternate between active sets (a continuation corrector whose
  /// hyperplane misses the branch beyond a corner of a complementarity branch) repeats its
  /// iterates and never leaves the cycle; so does smooth Newton on x³ − 2x + 2 from x = 0
  /// (0 → 1 → 0). With the check a corrector gives up after 3–4 iterations instead of
  /// max_iterations. Off by default.
  bool stop_on_cycle = false;
  double cycle_tolerance = 1e-3;

  /// Throws std::invalid_argument naming the field, its value, the allowed range and a way out:
  /// tolerance > 0 and finite; max_iterations, max_backtracks >= 0; min_rcond in [0, 1);
  /// max_lm_trials >= 1 (with levenberg_marquardt); cycle_tolerance > 0 (with stop_on_cycle).
  /// newton() calls it first.
  void validate() const;
};

struct NewtonReport {
  SolveStatus status = SolveStatus::MaxIterations;
  int iterations = 0;
  std::vector<double> residual_norms;  // ‖R(x_k)‖ for k = 0..iterations (NewtonOptions::norm)
  double tolerance = 0.0;              // the tolerance the convergence test used
  /// Reciprocal condition estimate of the last dense LU; absent for sparse LU (not estimated).
  std::optional<double> jacobian_rcond;
  int levenberg_marquardt_steps = 0;   // steps taken by the fallback
  std::string message;                 // why it stopped, with the last residual
  [[nodiscard]] bool converged() const { return status == SolveStatus::Converged; }
  /// One line, like Ceres' BriefReport: "converged in 4 iterations, ‖R‖ 3.2e-04 → 1.1e-12
  /// (tolerance 1e-10)".
  [[nodiscard]] std::string brief() const {
    std::string s = std::string(to_string(status)) + " in " + std::to_string(iterations) + " iterations";
    if (!residual_norms.empty()) {
      s += ", ‖R‖ " + format_number(residual_norms.front()) + " → " + format_number(residual_norms.back());
    }
    s += " (tolerance " + format_number(tolerance) + ")";
    if (levenberg_marquardt_steps > 0) s += ", " + std::to_string(levenberg_marquardt_steps) + " Levenberg–Marquardt steps";
    return s;
  }
};

struct NewtonResult {
  Eigen::VectorXd x;  // last iterate; meaningful as a solution only if report.converged()
  NewtonReport report;
};

/// Linear-solver policy for dense Jacobians: Eigen::PartialPivLU with its rcond() estimate.
class DenseLu {
 public:
  /// Factorizes J (partial pivoting); false if the factors are not finite (a NaN or inf in J,
  /// or an overflow). A singular J gives finite factors: newton() tells it by rcond().
  bool factorize(const Eigen::MatrixXd& jacobian);
  [[nodiscard]] Eigen::VectorXd solve(const Eigen::VectorXd& rhs) const;
  [[nodiscard]] std::optional<double> rcond() const;

 private:
  Eigen::PartialPivLU<Eigen::MatrixXd> lu_;
};

/// Linear-solver policy for sparse Jacobians: KLU [Davis & Palamadai Natarajan 2010, ACM TOMS
/// 37(3) 36] from SuiteSparse, through Eigen::KLU: block triangular form, AMD ordering of each
/// block, left-looking LU with partial pivoting. On the nonlinear-mode KKT Jacobians (a sparse
/// harmonic-balance block bordered by dense contact rows) it factorizes 3.5 times faster than
/// Eigen::SparseLU (bench_nonlinear_modes, docs/design.md). The symbolic analysis (ordering,
/// blocks) is kept and reused while the sparsity pattern of J is unchanged, across Newton
/// iterations and, when the same object is passed again, across solves (e.g. the steps of a
/// continuation). A pattern that changes (an active-set change in a semismooth Newton)
/// triggers a new analysis. symbolic_analyses() counts them. factorize() returns false for a
/// numerically singular J (KLU's zero pivot) or a non-finite one. The same factors solve with
/// Jᵀ (klu_tsolve) and several right-hand sides at once. It is also the factorization of the
/// assembled weighted-residual operator G (LinearSolverPath::SparseLU; Eigen's SparseLU before
/// issue #41). Implemented in solvers/src/core/sparse_lu.cpp, so that KLU stays a private
/// dependency of wbm::solvers.
class SparseLu {
 public:
  SparseLu();
  ~SparseLu();
  SparseLu(SparseLu&&) noexcept;
  SparseLu& operator=(SparseLu&&) noexcept;
  bool factorize(const Eigen::SparseMatrix<double>& jacobian);
  /// J⁻¹ rhs; NaN everywhere if the last factorize() failed.
  [[nodiscard]] Eigen::VectorXd solve(const Eigen::VectorXd& rhs) const;
  /// J⁻ᵀ rhs from the same factors; NaN everywhere if the last factorize() failed.
  [[nodiscard]] Eigen::VectorXd solve_transposed(const Eigen::VectorXd& rhs) const;
  /// J⁻¹ B (or J⁻ᵀ B) for the columns of B (rows = J's size) in one KLU call.
  [[nodiscard]] Eigen::MatrixXd solve_columns(const Eigen::MatrixXd& rhs, bool transposed) const;
  [[nodiscard]] static std::optional<double> rcond() { return std::nullopt; }
  [[nodiscard]] int symbolic_analyses() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Linear-solver policy for sparse matrices whose factors fill in densely: Eigen's SparseLU
/// (COLAMD column ordering, supernodal panels factorized with dense kernels, after SuperLU
/// [Demmel et al. 1999, SIAM J. Matrix Anal. Appl. 20(3) 720–755]). Where the L and U factors
/// are nearly dense blocks its panels beat KLU's column-by-column left-looking LU: on the
/// assembled weighted-residual operator of Case 1 (25 DOFs) with dense time operators (Haar,
/// DB6 or B-spline trial against Fourier or B-spline weighting) at M = 256 it factorizes and
/// solves H in 1.2–1.6 s where KLU takes 2.2–2.8 s, while KLU wins where the time operators
/// are sparse (Fourier:Fourier 18.7 against 40.4 ms, DB6:DB6 0.62 against 1.36 s;
/// bench_weighted_residual, BM_WeightedResidual_AssemblySparseLu). The same interface as
/// SparseLu, and like it the symbolic analysis (COLAMD's ordering, the elimination tree: the
/// pattern's alone) is kept and reused while the stored pattern is unchanged (COLAMD was 18 % of
/// the wavelet-basis backbones of reproduce/ll11_wavelet_modes; the factors are the same bit for
/// bit). factorize() returns false for a singular or non-finite matrix. Implemented in
/// solvers/src/core/sparse_lu.cpp.
class SupernodalLu {
 public:
  SupernodalLu();
  ~SupernodalLu();
  SupernodalLu(SupernodalLu&&) noexcept;
  SupernodalLu& operator=(SupernodalLu&&) noexcept;
  bool factorize(const Eigen::SparseMatrix<double>& matrix);
  /// A⁻¹ rhs; NaN everywhere if the last factorize() failed.
  [[nodiscard]] Eigen::VectorXd solve(const Eigen::VectorXd& rhs) const;
  /// A⁻ᵀ rhs from the same factors; NaN everywhere if the last factorize() failed.
  [[nodiscard]] Eigen::VectorXd solve_transposed(const Eigen::VectorXd& rhs) const;
  /// A⁻¹ B (or A⁻ᵀ B) for the columns of B (rows = A's size).
  [[nodiscard]] Eigen::MatrixXd solve_columns(const Eigen::MatrixXd& rhs, bool transposed) const;
  [[nodiscard]] static std::optional<double> rcond() { return std::nullopt; }
  [[nodiscard]] int symbolic_analyses() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Linear-solver policy for LowRankJacobian: partial-pivoting LU of the capacitance matrix C
/// (r × r), then d = s (y − U C⁻¹ V y) and one step of iterative refinement on the residual
/// y − J d (which makes the Woodbury formula as accurate as a backward-stable solve when C is
/// well conditioned [Yip 1986, SIAM J. Sci. Stat. Comput. 7(2) 507–513]). rcond() is C's
/// reciprocal condition estimate (s J has the eigenvalues of C and the eigenvalue 1 with
/// multiplicity n − r); in the dense form it is that of s J itself. In the sparse form K is
/// factorized by SparseLu (KLU, its symbolic analysis kept while K's pattern is unchanged),
/// d = s (y − U K⁻¹ V′ y), refined alike; rcond() is then not estimated (std::nullopt), and a
/// singular K fails factorize().
class WoodburyLu {
 public:
  bool factorize(const LowRankJacobian& jacobian);
  [[nodiscard]] Eigen::VectorXd solve(const Eigen::VectorXd& rhs) const;
  [[nodiscard]] std::optional<double> rcond() const;

 private:
  [[nodiscard]] Eigen::VectorXd woodbury(const Eigen::VectorXd& y) const;
  LowRankJacobian j_;
  Eigen::PartialPivLU<Eigen::MatrixXd> lu_;
  // The sparse form's LU; shared by copies until one of them factorizes (then it takes its own).
  std::shared_ptr<SparseLu> sparse_lu_;
};

/// Linear-solver policy for SparseLowRankHessian, H = S + U C Uᵀ: the bordered system
///   [[S, U C D], [D⁻¹ Uᵀ, −I]] [x; z] = [b; 0]
/// ((n + p) × (n + p), sparse but for the p dense border rows and columns; D = diag(‖U(:, q)‖∞)),
/// whose Schur complement on x is H, is factorized by SparseLu (KLU, partial pivoting; the
/// symbolic analysis kept while the pattern is unchanged) [Govaerts 2000, Numerical Methods for
/// Bifurcations of Dynamical Equilibria, Sec. 3.6, on bordered systems]. Its determinant is
/// ± det H, so it is singular exactly where H is, whether or not S or C is; the cost is that of
/// the sparse LU of S (block diagonal in the harmonics for nonlinear modes) instead of a dense LU
/// of n. Every solve is refined once on H's residual and verified: a normwise backward error
/// ‖b − H x‖∞ / (‖H‖∞ ‖x‖∞ + ‖b‖∞) above 1e-11 sends it to a dense LU of H (fallback_solves()).
/// rcond() is 1/(‖H‖₁ est ‖H⁻¹‖₁) with Hager–Higham's estimate from solves (H is symmetric).
/// factorize() returns false for a singular (KLU's zero pivot) or non-finite H, or mismatched
/// sizes. The Levenberg–Marquardt step of newton() uses the symmetry: (H² + μ²I) d = −H r is
/// d = −Re[(H − iμI)⁻¹ r], one real sparse LU of the bordered 2(n + p) system with the blocks
/// [[S, μI], [−μI, S]] and the same borders on both copies, instead of a dense QR of [H; μI]
/// (levenberg_marquardt_step). Implemented in solvers/src/core/bordered_sparse_lu.cpp.
class BorderedSparseLu {
 public:
  BorderedSparseLu();
  ~BorderedSparseLu();
  BorderedSparseLu(BorderedSparseLu&&) noexcept;
  BorderedSparseLu& operator=(BorderedSparseLu&&) noexcept;
  bool factorize(const SparseLowRankHessian& hessian);
  /// H⁻¹ rhs; NaN everywhere if the last factorize() failed.
  [[nodiscard]] Eigen::VectorXd solve(const Eigen::VectorXd& rhs) const;
  [[nodiscard]] std::optional<double> rcond() const;
  /// ‖H‖∞ (= ‖H‖₁), for the initial Levenberg–Marquardt damping.
  [[nodiscard]] double jacobian_infinity_norm(const SparseLowRankHessian& hessian) const;
  /// argmin ‖H d + r‖₂² + μ²‖d‖₂² (μ > 0) through the shifted bordered system above; the same d
  /// as detail::levenberg_marquardt_step(H.dense(), r, μ) up to rounding. Non-finite entries for
  /// μ ≤ 0, mismatched sizes, or a shifted system KLU cannot factorize (it is regular for μ > 0).
  [[nodiscard]] Eigen::VectorXd levenberg_marquardt_step(const SparseLowRankHessian& hessian, const Eigen::VectorXd& r,
                                                         double mu);
  /// Solves that missed the backward error and were redone by the dense LU.
  [[nodiscard]] int fallback_solves() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// A linear-solver policy P that computes newton()'s Levenberg–Marquardt step for its Jacobian
/// type J itself (BorderedSparseLu); other policies get the dense QR of [J; μI].
template <class P, class J>
concept LevenbergMarquardtPolicy = requires(P& p, const P& cp, const J& j, const Eigen::VectorXd& r, double mu) {
  { cp.jacobian_infinity_norm(j) } -> std::convertible_to<double>;
  { p.levenberg_marquardt_step(j, r, mu) } -> std::convertible_to<Eigen::VectorXd>;
};

/// What a linear-solver policy provides for Jacobians (or operators) of type J: factorize(j) →
/// false if it cannot be factorized, solve(rhs) → J⁻¹ rhs, rcond() → a reciprocal condition
/// estimate when the policy has one. DenseLu, SparseLu, SupernodalLu, WoodburyLu and
/// BorderedSparseLu are policies for their Jacobian types; the weighted-residual operator's
/// factorization is one for G(f)
/// (solvers/src/forced_response/kronecker_factorization.hpp).
template <class P, class J>
concept LinearSolverPolicy = requires(P& p, const P& cp, const J& j, const Eigen::VectorXd& v) {
  { p.factorize(j) } -> std::convertible_to<bool>;
  { cp.solve(v) } -> std::convertible_to<Eigen::VectorXd>;
  { cp.rcond() } -> std::convertible_to<std::optional<double>>;
};
static_assert(LinearSolverPolicy<DenseLu, Eigen::MatrixXd>);
static_assert(LinearSolverPolicy<SparseLu, Eigen::SparseMatrix<double>>);
static_assert(LinearSolverPolicy<SupernodalLu, Eigen::SparseMatrix<double>>);
static_assert(LinearSolverPolicy<WoodburyLu, LowRankJacobian>);
static_assert(LinearSolverPolicy<BorderedSparseLu, SparseLowRankHessian>);

namespace detail {
template <class S>
using SystemJacobian = std::decay_t<decltype(std::declval<const S&>().jacobian(std::declval<const Eigen::VectorXd&>()))>;
template <class S>
inline constexpr bool sparse_jacobian_v = std::is_base_of_v<Eigen::SparseMatrixBase<SystemJacobian<S>>, SystemJacobian<S>>;

inline double residual_norm(const Eigen::VectorXd& r, ResidualNorm norm) {
  return norm == ResidualNorm::Max ? r.lpNorm<Eigen::Infinity>() : r.norm();
}
// The period p (2 or 3) with which the last norms repeat: r_k ≈ r_(k−p) and r_(k−1) ≈ r_(k−1−p)
// to a relative `tolerance`; 0 if none.
inline int residual_cycle(const std::vector<double>& r, double tolerance) {
  const auto k = r.size();
  auto same = [&](size_t a, size_t b) { return std::abs(r[a] - r[b]) <= tolerance * std::max(r[a], r[b]); };
  for (size_t p : {2u, 3u}) {
    if (k >= p + 2 && same(k - 1, k - 1 - p) && same(k - 2, k - 2 - p)) return static_cast<int>(p);
  }
  return 0;
}
template <class J>
Eigen::MatrixXd as_dense(const J& j) {
  return Eigen::MatrixXd(j);
}
inline Eigen::MatrixXd as_dense(const LowRankJacobian& j) { return j.dense(); }
inline Eigen::MatrixXd as_dense(const SparseLowRankHessian& j) { return j.dense(); }

/// The Levenberg–Marquardt step d = argmin ‖J d + r‖₂² + μ²‖d‖₂², i.e. (JᵀJ + μ²I) d = −Jᵀr,
/// computed as the least-squares solution of the stacked system [J; μI] d = [−r; 0] by
/// Householder QR [Moré 1978, Lecture Notes in Math. 630, 105–116; Nocedal & Wright 2006,
/// Sec. 10.3], never by the normal equations, whose matrix has the square of J's condition
/// number (κ(J) = 1e7 loses every digit of the step along J's small singular vectors).
/// J: m × n (m ≥ 1), r: length m, μ > 0 (then [J; μI] has full column rank). O((m + n) n²).
/// Returns d (length n); non-finite entries if J or r has NaN or inf.
Eigen::VectorXd levenberg_marquardt_step(const Eigen::MatrixXd& jacobian, const Eigen::VectorXd& r, double mu);
}  // namespace detail

/// The linear solver newton() uses by default for a system: SparseLu for a sparse Jacobian,
/// WoodburyLu for a LowRankJacobian, BorderedSparseLu for a SparseLowRankHessian, DenseLu
/// otherwise.
template <class S>
using DefaultLinearSolver = std::conditional_t<
    detail::sparse_jacobian_v<S>, SparseLu,
    std::conditional_t<std::is_same_v<detail::SystemJacobian<S>, LowRankJacobian>, WoodburyLu,
                       std::conditional_t<std::is_same_v<detail::SystemJacobian<S>, SparseLowRankHessian>,
                                          BorderedSparseLu, DenseLu>>>;

/// Newton–Raphson from x: J(x_k) Δ = −R(x_k), x_{k+1} = x_k + t Δ with t = 1, ½, ¼, … the
/// first step length that reduces ‖R‖₂ by the factor (1 − 10⁻⁴ t) (Armijo), or t = 1 without
/// line search; with levenberg_marquardt, a failed line search switches to LM steps.
/// `solver` is the linear-solver policy (DenseLu, SparseLu, WoodburyLu or any type with
/// factorize(J) → bool, solve(rhs) and rcond() → optional<double>: LinearSolverPolicy); pass the same object to
/// successive calls to keep what it caches (SparseLu's symbolic analysis).
/// Stops with Converged (‖R‖ ≤ tolerance, verified on the returned x), MaxIterations,
/// Stagnated (no acceptable step), SingularJacobian (factorization failed, e.g. DenseLu's factors
/// of a J with NaN or inf, or rcond < min_rcond) or NonFinite (NaN/inf in R or the step); the
/// returned x is then the last finite iterate.
/// With levenberg_marquardt a singular Jacobian or a failed line search switches to LM steps.
/// Never throws for non-convergence; throws std::invalid_argument for invalid options
/// (NewtonOptions::validate).
template <NonlinearSystem S, class Solver>
NewtonResult newton(const S& system, Eigen::VectorXd x, const NewtonOptions& options, Solver& solver) {
  options.validate();
  NewtonReport report;
  report.tolerance = options.tolerance;
  auto finish = [&](SolveStatus status, const std::string& why) {
    report.status = status;
    report.message = why + " after " + std::to_string(report.iterations) + " iterations, last ||R|| = " +
                     format_number(report.residual_norms.empty() ? NAN : report.residual_norms.back()) +
                     " (tolerance " + format_number(options.tolerance) + ")";
    return NewtonResult{std::move(x), std::move(report)};
  };
  Eigen::VectorXd r = system.residual(x);
  double norm = detail::residual_norm(r, options.norm);
  report.residual_norms.push_back(norm);
  if (!std::isfinite(norm)) return finish(SolveStatus::NonFinite, "non-finite residual at the initial guess");
  double mu = 0.0;  // Levenberg–Marquardt damping; 0 until the first fallback, then kept
  for (;;) {
    if (norm <= options.tolerance) return finish(SolveStatus::Converged, "converged");
    if (report.iterations >= options.max_iterations) return finish(SolveStatus::MaxIterations, "iteration limit reached");
    const auto jac = system.jacobian(x);
    bool accepted = false;
    Eigen::VectorXd x_new, r_new;
    bool finite_trial = true;
    const double norm2 = r.norm();
    {
      // A singular or non-finite Newton step ends the solve, unless the LM fallback takes over.
      SolveStatus failure = SolveStatus::Converged;
      std::string why;
      Eigen::VectorXd step;
      if (!solver.factorize(jac)) {
        failure = SolveStatus::SingularJacobian;
        why = "the linear solver could not factorize the Jacobian";
      } else if (report.jacobian_rcond = solver.rcond(); report.jacobian_rcond && !(*report.jacobian_rcond >= options.min_rcond)) {
        failure = SolveStatus::SingularJacobian;
        why = "singular Jacobian (rcond " + format_number(*report.jacobian_rcond) + ")";
      } else if (step = -solver.solve(r); !step.allFinite()) {
        failure = SolveStatus::NonFinite;
        why = "non-finite Newton step (Jacobian singular or non-finite)";
      }
      if (failure != SolveStatus::Converged && !options.levenberg_marquardt) return finish(failure, why);
      double t = 1.0;
      for (int b = 0; failure == SolveStatus::Converged && b <= options.max_backtracks; ++b, t *= 0.5) {
        x_new = x + t * step;
        r_new = system.residual(x_new);
        const double trial = r_new.norm();
        finite_trial = std::isfinite(trial);
        if (!options.line_search) {
          accepted = finite_trial;
          break;
        }
        if (finite_trial && trial <= (1.0 - 1e-4 * t) * norm2) {
          accepted = true;
          break;
        }
      }
    }
    if (!accepted && options.levenberg_marquardt) {  // Levenberg–Marquardt on ½‖R‖₂²: the policy's, or by QR
      constexpr bool own_step = LevenbergMarquardtPolicy<Solver, std::decay_t<decltype(jac)>>;
      Eigen::MatrixXd dense;
      if constexpr (!own_step) dense = detail::as_dense(jac);
      if (mu == 0.0) {
        if constexpr (own_step) {
          mu = 1e-6 * solver.jacobian_infinity_norm(jac);
        } else {
          mu = 1e-6 * dense.cwiseAbs().rowwise().sum().maxCoeff();
        }
      }
      for (int b = 0; b < options.max_lm_trials; ++b) {
        Eigen::VectorXd d;
        if constexpr (own_step) {
          d = solver.levenberg_marquardt_step(jac, r, mu);
        } else {
          d = detail::levenberg_marquardt_step(dense, r, mu);
        }
        if (d.allFinite()) {
          x_new = x + d;
          r_new = system.residual(x_new);
          finite_trial = r_new.allFinite();
          if (finite_trial && r_new.norm() < norm2) {
            accepted = true;
            mu *= 0.3;
            ++report.levenberg_marquardt_steps;
            break;
          }
        }
        mu *= 4.0;
      }
    }
    if (!accepted) {
      return finish(finite_trial ? SolveStatus::Stagnated : SolveStatus::NonFinite,
                    finite_trial ? "no step decreased ||R||" : "non-finite residual along the Newton step");
    }
    x = std::move(x_new);
    r = std::move(r_new);
    norm = detail::residual_norm(r, options.norm);
    ++report.iterations;
    report.residual_norms.push_back(norm);
    if (options.stop_on_cycle && norm > options.tolerance) {
      if (const int p = detail::residual_cycle(report.residual_norms, options.cycle_tolerance); p > 0) {
        return finish(SolveStatus::Stagnated, "cycling (the residual norms repeat with period " + std::to_string(p) + ")");
      }
    }
  }
}

/// newton() with a fresh DefaultLinearSolver<S>.
template <NonlinearSystem S>
NewtonResult newton(const S& system, Eigen::VectorXd x, const NewtonOptions& options = {}) {
  DefaultLinearSolver<S> solver;
  return newton(system, std::move(x), options, solver);
}

}  // namespace wbm::solvers
