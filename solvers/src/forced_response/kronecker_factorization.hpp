#pragma once
// Private to wbm_solvers: the factorization of the weighted-residual operator
//   G(f) = f² A_M ⊗ M + f A_C ⊗ C + A_K ⊗ K   (size n·M, stacked layout of layout.hpp)
// along LinearSolverPath (weighted_residual.hpp): sparse LU of the assembled Kronecker sum, or
// the modal path — n independent M × M blocks A + λ_i B — with the block structures it exploits
// (components of the time operators' sparsity graph; the factored Fourier-weighting form).
// Solves with G and Gᵀ, the condensed compliance H = P G⁻¹ Pᵀ on contact rows, and ‖G‖₁.
// Off the modal path, block-diagonal time operators (Fourier:Fourier) are factorized block by
// block (kronecker_components.cpp: band LU or KLU per component) instead of assembled.
// A linear-solver policy (newton.hpp, LinearSolverPolicy) for the operator G(f): factorize(G),
// solve(rhs), rcond(). The assembled path factorizes with the SparseLu policy (KLU) when the time
// operators' joint pattern holds at most a quarter of its entries (Fourier:Fourier, Galerkin DB6),
// with SupernodalLu otherwise (dense or wide time operators fill G's factors densely).

#include <array>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <wbm/solvers/mechanical_system.hpp>
#include <wbm/solvers/newton.hpp>
#include <wbm/solvers/weighted_residual.hpp>

namespace wbm::solvers::detail {

/// ‖G‖₁ of G = Σ_s t_s ⊗ x_s, t = (f² A_M, f A_C, A_K) and x = (M, C, K), G not formed
/// (kronecker_norm.cpp): O(nnz(t)) per distinct direction of (M_ij, C_ij, K_ij) plus O(nnz(x) · M).
double kronecker_norm1(const std::array<Eigen::SparseMatrix<double>, 3>& t,
                       const std::array<const Eigen::SparseMatrix<double>*, 3>& x);

/// The nonzeros (stacked row, weight) of one row of the contact selection P.
using StackedTerms = std::vector<std::pair<Eigen::Index, double>>;

/// The operator G(f) = f² A_M ⊗ M + f A_C ⊗ C + A_K ⊗ K described by its factors, not assembled:
/// the "Jacobian" type of the KroneckerFactorization policy. It refers to `system` and `ops`,
/// which must outlive the factorization of it.
struct KroneckerOperator {
  const MechanicalSystem* system = nullptr;
  const TimeOperators* ops = nullptr;
  double frequency_hz = 0.0;
};

class KroneckerFactorization {
 public:
  /// Frequency-independent set-up: whether the modal path applies (LinearSolverPath, and C
  /// diagonal in the undamped modes: Rayleigh C = c_M M + c_K K, or any classical C, found by
  /// Caughey and O'Kelly's C M⁻¹ K = K M⁻¹ C on three probes and then Φᵀ C Φ diagonal to 1e-10,
  /// each mode then damped by (Φᵀ C Φ)_ii), the modal basis K Φ = M Φ Λ, Φᵀ M Φ = I, the
  /// components of the time operators' sparsity graph, and (if `fourier_weighting` —
  /// distributional form, Fourier weighting, wavelet trial) the factored Fourier-weighting
  /// structure when its identities hold. Nothing is factorized.
  /// `transposed`, if not null, holds A_Mᵀ, A_Cᵀ, A_Kᵀ sparse (the caller's copies of `ops`): the
  /// sparsity graph and the joint pattern's size are then read from them, O(nnz) instead of O(M²).
  /// Throws std::invalid_argument for LinearSolverPath::Modal with a C the modes do not
  /// diagonalize, or if the generalized eigenproblem fails.
  KroneckerFactorization(const MechanicalSystem& system, const TimeOperators& ops, LinearSolverPath path,
                         bool fourier_weighting,
                         const std::array<Eigen::SparseMatrix<double>, 3>* transposed = nullptr);
  /// The same set-up (shared, not recomputed), not factorized: for another frequency.
  [[nodiscard]] KroneckerFactorization unfactorized() const;

  /// Factorizes G(f) (modal blocks, or SparseLu / SupernodalLu on the assembled Kronecker sum).
  /// Returns false (and factorized() is false) if G is singular or not finite.
  bool factorize(const KroneckerOperator& g);
  [[nodiscard]] bool factorized() const { return factorized_; }
  [[nodiscard]] bool modal() const;
  /// G⁻¹ v for a stacked v of length n·M. Requires factorized().
  [[nodiscard]] Eigen::VectorXd solve(const Eigen::VectorXd& v) const;
  /// G⁻ᵀ v for a stacked v of length n·M. Requires factorized().
  [[nodiscard]] Eigen::VectorXd solve_transposed(const Eigen::VectorXd& v) const;
  /// κ₁(G) estimate ‖G‖₁ · est(‖G⁻¹‖₁), the latter by Hager–Higham from a few solves with G and
  /// Gᵀ (a lower bound, exact in most cases); +inf if not factorized.
  [[nodiscard]] double condition_estimate() const;
  /// 1 / condition_estimate(): the policy's reciprocal condition estimate (0 if not factorized).
  [[nodiscard]] std::optional<double> rcond() const;
  /// H = P G⁻¹ Pᵀ, n_c·M square in the contact ordering x(k·n_c + c): contact c has direction
  /// e_c = Σ w e_dof over directions[c] (DOF, weight), and row j = k·n_c + c of P has the
  /// nonzeros rows[j] (stacked row, weight). Also keeps,
  /// until the next factorize(), the per-pair blocks H_cd in the form compliance_product() uses:
  /// circulant (wavelet Galerkin pairs, Haar:B-spline) or A_K⁻¹ Σ_i w_i S_i with a
  /// shift-structured A_K (wavelet trial, Fourier weighting). Requires factorized().
  /// With dense = false and circulant blocks kept (circulant_compliance()), H itself is not
  /// formed and the result is 0 × 0: dense_circulant_compliance() forms it where it is read.
  [[nodiscard]] Eigen::MatrixXd compliance(const std::vector<std::vector<std::pair<int, double>>>& directions,
                                           const std::vector<StackedTerms>& rows, bool dense = true);
  /// True when the last compliance() kept circulant blocks H_cd.
  [[nodiscard]] bool circulant_compliance() const;
  /// H (n_c·M square, h(k·n_c + c, l·n_c + d) = c_cd((k − l) mod M)) from the kept circulant
  /// blocks, and its number of nonzero entries (M times those of the blocks' first columns)
  /// without forming it. Require circulant_compliance(); std::logic_error otherwise.
  [[nodiscard]] Eigen::MatrixXd dense_circulant_compliance() const;
  [[nodiscard]] Eigen::Index circulant_compliance_nonzeros() const;
  /// True when the last compliance() kept a structured form: compliance_product() then costs
  /// O(n_c · columns · M log M + n_c² · columns · M) (circulant) or O(n_c² · columns · M log M)
  /// instead of the O(n_c² M² · columns) dense product with H.
  [[nodiscard]] bool fast_compliance_product() const { return compliance_structure_ != nullptr; }
  /// H v for v with n_c·M rows (contact ordering), by the blocks kept by compliance(): circulant
  /// blocks as Σ_d ĉ_cd DFT(v_d), bin by bin, with one real DFT per contact d and one inverse per
  /// contact c; or A_K⁻¹ (Σ_d S_cd v_d) by one inverse real DFT per column.
  /// Requires fast_compliance_product().
  [[nodiscard]] Eigen::MatrixXd compliance_product(const Eigen::MatrixXd& v) const;
  /// The modal path solved mode by mode (modal(), without the Fourier-weighting form), in pieces
  /// for a solve that reads and writes a few DOFs only (issue #39: the cost of a continuation
  /// point then grows like n, not n²):
  ///  - modal_projection: Φ_Sᵀ V_S (n modes × M) for V (n DOFs × M) whose rows outside
  ///    `sources` are zero, O(n·M·|S|) instead of Φᵀ V's O(n² M);
  ///  - modal_block_solve: Y (modes × M), row i = (A + λ_i B)⁻¹ applied to row i of R;
  ///  - modal_rows: Φ_R Y (|R| × M), the DOFs `rows` of Φ Y;
  ///  - modal_damping: Φᵀ C Φ = diag(c_M + c_K λ_i) (length n), with Φᵀ M Φ = I.
  /// G⁻¹ V on the DOFs R is modal_rows(modal_block_solve(modal_projection(V, S)), R).
  /// Require factorized() and modal_blocks().
  [[nodiscard]] bool modal_blocks() const;
  [[nodiscard]] Eigen::MatrixXd modal_projection(const Eigen::MatrixXd& v, const std::vector<Eigen::Index>& sources) const;
  [[nodiscard]] Eigen::MatrixXd modal_block_solve(const Eigen::MatrixXd& r) const;
  [[nodiscard]] Eigen::MatrixXd modal_rows(const Eigen::MatrixXd& y, const std::vector<Eigen::Index>& rows) const;
  [[nodiscard]] Eigen::VectorXd modal_damping() const;
  /// ‖G(f)‖₁ of the last factorized operator: from the assembled G (sparse LU path) or from the
  /// Kronecker factors (modal path, computed on first use).
  [[nodiscard]] double norm1() const;

 private:
  [[nodiscard]] Eigen::VectorXd solve(const Eigen::VectorXd& v, bool transposed) const;
  // The component path (kronecker_components.cpp): one SparseLu of each block G_c of the time
  // operators' components, for operator_.
  bool factorize_components(const std::vector<std::vector<Eigen::Index>>& components);
  [[nodiscard]] Eigen::VectorXd solve_components(const Eigen::VectorXd& v, bool transposed,
                                                 const std::vector<std::vector<Eigen::Index>>& components) const;
  [[nodiscard]] Eigen::MatrixXd compliance_components(const std::vector<StackedTerms>& rows, int nc,
                                                      const std::vector<std::vector<Eigen::Index>>& components) const;
  struct Setup;
  struct ComponentLus;
  class ModeBlock;
  struct ComplianceStructure;
  explicit KroneckerFactorization(std::shared_ptr<const Setup> setup);
  std::shared_ptr<const Setup> setup_;
  KroneckerOperator operator_;  // the last one given to factorize()
  bool factorized_ = false;
  Eigen::SparseMatrix<double> g_;  // assembled path only
  // Assembled path only, one of the two (shared by copies: the policies are move-only).
  std::shared_ptr<SparseLu> lu_;
  std::shared_ptr<SupernodalLu> supernodal_lu_;
  std::shared_ptr<const ComponentLus> component_lus_;  // component path only
  std::vector<std::shared_ptr<const ModeBlock>> blocks_;
  mutable double norm1_ = -1.0;  // < 0: not computed yet
  std::shared_ptr<const ComplianceStructure> compliance_structure_;  // set by compliance(), reset by factorize()
};

}  // namespace wbm::solvers::detail
