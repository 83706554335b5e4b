// Private to wbm_solvers: WeightedResidual's implementation (its Impl), shared by the files that
// define it, one job each:
//   weighted_residual_operators.cpp  set-up: admissibility, the time operators [JL14 Eqs. (14)–(16)],
//                                    the harmonic selection, the load projection
//   weighted_residual_contact.cpp    the contact samples, forces and Jacobians (dense, low rank,
//                                    shift kernel), the compliance H = P G⁻¹ Pᵀ
//   weighted_residual_rigid.cpp      rigid stops: collocation, the Delassus operator, the Signorini
//                                    conditions and their penalty homotopy
//   weighted_residual_solve.cpp      the solution strategies (direct Newton, contact homotopy, load
//                                    stepping) and the verified solve
//   weighted_residual.cpp            the public accessors, R(a) and its full Jacobian
// The time bases sampled at the Q midpoints: sampled_basis.hpp.
#pragma once

#include <wbm/solvers/weighted_residual.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>
#include <mutex>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Sparse>

#include <wbm/contact/friction.hpp>
#include <wbm/contact/penalty.hpp>
#include <wbm/solvers/continuation.hpp>
#include <wbm/solvers/natural_parameter.hpp>
#include <wbm/spectral/aft.hpp>
#include <wbm/spectral/fourier_basis.hpp>
#include <wbm/spectral/layout.hpp>

#include "kronecker_factorization.hpp"
#include "sampled_basis.hpp"
#include "weighted_residual_collocation.hpp"

namespace wbm::solvers::detail {

// ContactQuadrature::CellAverage at one sample: the law averaged over the cell along the tangent
// of u, f̄ = (P(u + δ/2) − P(u − δ/2))/δ, and its partial derivatives in u and δ:
//   ∂f̄/∂u = (f(u + δ/2) − f(u − δ/2))/δ,   ∂f̄/∂δ = ((f(u + δ/2) + f(u − δ/2))/2 − f̄)/δ.
// Where the potential difference would lose more than four digits to cancellation
// (|ΔP| ≤ 1e-4 max|P|: a short cell deep inside one smooth piece of the law, or δ = 0), the
// midpoint value f(u) is used; it differs from f̄ by f''δ²/24 there.
void cell_average(const contact::ContactLaw& law, double u, double delta, double& f, double& dfdu, double& dfdd);

inline double elapsed(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

// The continuation of a homotopy in decades of its parameter (κ of the penalty, σ of the contact
// forces), shared by the contact homotopy (weighted_residual_solve.cpp) and the penalty homotopy
// of rigid stops (weighted_residual_rigid.cpp): λ̂ = λ (decades), the state in `state_scale`
// units, corners restarted (the (·)₊ of a penalty switches at every sample that starts touching).
PseudoArclengthOptions homotopy_continuation(double lambda_min, double lambda_max, double state_scale,
                                             const WeightedResidualOptions& w);

// The homotopy's path in its report: points, folds, iterations, stop, and the largest σ (or κ)
// reached, at most 10^lambda_cap.
void record_homotopy(const Branch& branch, double lambda_cap, HomotopyReport& report);

}  // namespace wbm::solvers::detail

namespace wbm::solvers {

struct WeightedResidual::Impl {
  using SparseRows = detail::SparseRows;
  MechanicalSystem system;
  HarmonicForcing forcing;
  std::vector<ContactPoint> contacts;
  TimeBasis trial, weighting;
  WeightedResidualOptions options;
  int n, m, q, nc;
  TimeOperators ops;
  // Transposed time operators A_Mᵀ, A_Cᵀ, A_Kᵀ for the products U Aᵀ of the residual, sparse
  // when at most 25 % full (Fourier:Fourier: diagonal and 2 × 2 blocks; banded wavelet
  // Galerkin operators at large M), so that R(a) costs O(n · nnz) instead of O(n M²).
  struct OperatorProducts {
    std::array<Eigen::SparseMatrix<double>, 3> transposed;
    bool sparse = false;
    // ⟨A_s, A_r⟩_F for s ≤ r in the order (M,M), (M,C), (M,K), (C,C), (C,K), (K,K): the time
    // factors of ‖G(f)‖_F (frobenius_norm), the same at every frequency; over the nonzeros of the
    // sparse transposes when sparse (O(nnz), not O(M²) per product).
    std::array<double, 6> time_inner{};
  };
  std::shared_ptr<const OperatorProducts> operator_products;

  // The trial basis (values and, for ContactQuadrature::CellAverage, first derivatives) and the
  // weighting basis at the Q midpoints τ_q = (q + ½)/Q (SampledBasis: FFTW for Fourier, sparse
  // for wavelets); shared with at_frequency copies (const use only).
  struct Sampling {
    Eigen::VectorXd tau;
    std::shared_ptr<const spectral::Aft> aft;  // when either basis is Fourier
    std::optional<detail::SampledBasis> trial, trial_slope, weighting;
    // Moving counter-surfaces (ContactPoint::obstacle): s_c(τ_q) (n_c × Q) and, for CellAverage,
    // its cell increments ṡ_c(τ_q)/Q; both empty when every obstacle is fixed.
    Eigen::MatrixXd obstacle, obstacle_slope;
  };
  std::shared_ptr<const Sampling> sampling;
  bool cell_average_rule = false;
  // Harmonic selection (WeightedResidualOptions::harmonics, sorted): keep(k) = 1 if function k's
  // harmonic is kept, else 0 (length M); empty without a selection.
  Eigen::RowVectorXd keep;

  // The rows of V (low_rank_contact_jacobian) of one contact: the trial functions at its samples
  // in contact (by FFTW for a Fourier trial basis, else these sparse rows), then their slopes at
  // its kink samples (CellAverage), from row `first` of V.
  struct ContactRows {
    std::vector<int> active;
    SparseRows values;           // wavelet trial: the rows at the active samples (active × M)
    Eigen::MatrixXd slope_rows;  // trial slopes at the kink samples (sloped × M)
    Eigen::Index first = 0;
  };
  // Y (n_c·M × k, rows x(k·n_c + c)) ↦ V Y (rank × k): LowRankJacobian::times_v. Holds its data.
  struct TrialRows {
    std::shared_ptr<const std::vector<ContactRows>> rows;
    std::shared_ptr<const Sampling> sampling;
    int contacts, dimension;
    Eigen::Index rank;
    Eigen::MatrixXd operator()(const Eigen::MatrixXd& y) const;
  };

  // Linear solves with G (kronecker_factorization.hpp); set up once, factorized per frequency.
  std::optional<detail::KroneckerFactorization> g;
  bool factorized = false;

  Eigen::VectorXd b, x_lin;  // x_lin = P G⁻¹ b (contact unknowns); G⁻¹ b itself: linear_coefficients()
  // H = P G⁻¹ Pᵀ (n_c·M square), and a sparse copy when at most 25 % of it is nonzero (the 1 × 1
  // and 2 × 2 harmonic blocks of Fourier:Fourier): H N and H n then cost O(nnz(H) · n_c M).
  // Otherwise the structured blocks the factorization kept (circulant, or A_K⁻¹ Σ S with a
  // shift-structured A_K: KroneckerFactorization::compliance_product) when there are any, else
  // the dense product.
  // With circulant blocks kept, H is formed on first read (dense_h(), once per set_compliance()
  // even if several threads ask; set_compliance() gives it a fresh flag): the continuation's
  // structured products never read it (issue #39).
  mutable Eigen::MatrixXd h;
  bool h_deferred = false;
  std::unique_ptr<std::once_flag> h_once = std::make_unique<std::once_flag>();
  [[nodiscard]] const Eigen::MatrixXd& dense_h() const {
    if (h_deferred) std::call_once(*h_once, [this] { h = g->dense_circulant_compliance(); });
    return h;
  }
  std::shared_ptr<const Eigen::SparseMatrix<double>> h_sparse;  // shared with the Jacobians' products
  bool h_is_sparse = false;
  // Fourier:Fourier: H's blocks commute with time shifts (ShiftKernel), detected per frequency
  // on first use (a Jacobian of low rank), once even if several threads ask.
  struct ShiftKernel {
    std::vector<Eigen::VectorXd> kappa;  // κ_cd(s), s = 0..Q−1, at index c·n_c + d
    Eigen::MatrixXd top;                 // t_cd: H's entry on the top functions cos πMτ (0 for odd M)
    Eigen::VectorXd g;                   // cos πMτ_q (the top function at the samples)
  };
  mutable std::optional<ShiftKernel> kernel;
  mutable std::once_flag kernel_once;
  // The sparse form of the contact Jacobian (sparse_contact_jacobian), formed on first use at this
  // frequency, once even if several threads ask: the assembled G(f) (null when the time
  // operators are not sparse), and H for the form's update (h_sparse, or a shared copy of h).
  struct AssembledOperator {
    std::shared_ptr<const Eigen::SparseMatrix<double>> g;   // G(f), n·M square, stacked layout
    std::shared_ptr<const Eigen::SparseMatrix<double>> p;   // P, n_c·M × n·M
    std::shared_ptr<const Eigen::MatrixXd> h;               // H when not h_is_sparse
  };
  mutable AssembledOperator assembled;
  mutable std::once_flag assembled_once;
  [[nodiscard]] const AssembledOperator& assembled_operator() const;
  [[nodiscard]] const std::optional<ShiftKernel>& shift_kernel_once() const {
    std::call_once(kernel_once, [this] { kernel = shift_kernel(); });
    return kernel;
  }
  double scale = 1.0;
  // Row j = k·n_c + c of P (contact c at instant k): its nonzeros (row in a, weight), the
  // direction e_c of ContactPoint::terms() at coefficient k.
  std::vector<detail::StackedTerms> contact_terms;
  std::vector<Eigen::Index> contact_dofs;  // the DOFs contact_terms read, ascending, once each

  // Rigid stops (every contact a RigidStop): the trial functions at τ_{k+1} (M × M, row k: the
  // instant whose gap impulse k keeps open) and the weighting functions at the impulse instants
  // τ_k = (k + ½)/M over M (M × M, row j = function, column k), frequency independent and
  // shared; per frequency the Delassus operator D = V H W, u_lin = V x_lin, and c = mean |D_ii|.
  // Exact Coulomb friction (contact::CoulombFriction, also rigid()): impulse k is paired with the
  // slip over the cell, Δ_k = u(τ_{k+1}) − u(τ_k), so its rows of V, D and u_lin are those of
  // V(τ_{k+1}) − V(τ_k) ("kinematic" rows: a gap's displacement or a slip). The instants are the
  // midpoints τ_k = (k + ½)/M unless W is singular there (Fourier of even M, B-splines), then the
  // cell ends k/M (W invertible: every impulse pattern moves the structure). In full stick the
  // slips leave the contact's position free (the slips of a constant vanish): a contact whose
  // every instant sticks has its row k = 0 replaced by the position u(τ_1) = 0 (the k_t → ∞
  // limit of the Jenkins convention): the stuck rows (stuck_*), one entry per friction contact.
  bool rigid = false;
  using Collocation = detail::Collocation;  // weighted_residual_collocation.hpp
  std::shared_ptr<const Collocation> collocation;
  Eigen::MatrixXd delassus;
  Eigen::VectorXd u_lin;
  Eigen::MatrixXd stuck_rows;     // R × n_c·M: ∂φ/∂λ of each replaced row [m/N]
  Eigen::VectorXd stuck_lin;      // R: its value at λ = 0 and load 1, negated (φ = d λ − s lin)
  std::vector<int> stuck_row_of;  // R: the row i = k·n_c + c it replaces
  std::vector<int> stuck_contact; // R: c

  double force_compliance = 1.0;
  // Friction rows: their own compliance c_f = mean |D_ii| over them (a slip is far smaller than a
  // gap's displacement), and the weight ρ = c/c_f on their φ, so that every slip row has
  // ∂φ/∂λ = c as a stop's force row: φ = ρ (c_f λ − proj_[−c_f μN, c_f μN](c_f λ + Δ)), the same
  // roots. Without stops c = c_f and ρ = 1.
  double friction_compliance = 1.0;
  [[nodiscard]] double friction_weight() const { return force_compliance / friction_compliance; }
  // The slip force of friction row i = k·n_c + c [N]: μ N, or μ λ⁺ of its normal stop's impulse k
  // (Signorini's multiplier of the same cell: the normal load; a negative iterate carries none).
  [[nodiscard]] double slip_force(const Eigen::VectorXd& lambda, Eigen::Index i) const {
    const Collocation& col = *collocation;
    const auto c = static_cast<size_t>(i % nc);
    const int normal = col.any_normal ? col.normal_of[c] : -1;
    if (normal < 0) return col.slip_forces(static_cast<Eigen::Index>(c));
    const Eigen::Index j = i - static_cast<Eigen::Index>(c) + normal;  // the stop's row k·n_c + normal
    return col.friction_coefficients(static_cast<Eigen::Index>(c)) * std::max(lambda(j), 0.0);
  }
  // A slip row whose slip force is μ λ_j⁺ of a stop's impulse j with λ_j > 0: ∂φ_i/∂λ_j = −σ μ c.
  struct CoupledSlip {
    int row;
    int normal_row;
    double sigma_mu;  // σ μ
  };
  [[nodiscard]] contact::CoulombProjection friction_row(double lambda, double slip, double slip_force) const {
    auto cp = contact::coulomb_projection(friction_compliance * lambda, slip, friction_compliance * slip_force);
    cp.value *= friction_weight();
    return cp;
  }

  Impl(MechanicalSystem s, HarmonicForcing f, std::vector<ContactPoint> c, TimeBasis tr, TimeBasis we,
       WeightedResidualOptions o);

  // The same problem at another frequency: every frequency-independent member is copied (time
  // operators, samples, b, modal basis, residual scale); only G is factorized again.
  Impl(const Impl& base, double frequency_hz);
  // g's factorization refers to this Impl's system and ops (KroneckerOperator): no plain copies.
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  // Y (M·n_c × k, rows j·n_c + c) ↦ (T ⊗ I_{n_c}) Y for an M × M time matrix T.
  [[nodiscard]] Eigen::MatrixXd per_contact(const Eigen::MatrixXd& t, const Eigen::MatrixXd& y) const {
    if (nc == 1) return t * y;
    Eigen::MatrixXd out(y.rows(), y.cols());
    for (int c = 0; c < nc; ++c) {
      const Eigen::MatrixXd yc = y(Eigen::seq(c, Eigen::last, nc), Eigen::all);
      out(Eigen::seq(c, Eigen::last, nc), Eigen::all) = t * yc;
    }
    return out;
  }

  // D = V H W and u_lin = V x_lin (rigid stops) at this frequency, and c = mean |D_ii| if asked
  // (at the base frequency only; at_frequency copies keep it, as they keep s_r).
  void set_delassus(bool set_force_compliance);
  // set_delassus's path for H commuting with shifts (commutes_with_shifts): D from its first
  // block column; v_hw0 = (V ⊗ I) H (W ⊗ I)'s first block column when there is friction.
  void set_delassus_circulant(Eigen::MatrixXd& v_hw0);

  void require_rigid(const char* what) const {
    if (!rigid) {
      throw std::logic_error(std::string("WeightedResidual::") + what +
                             ": the contacts are penalty laws, not rigid stops (use the contact_* functions)");
    }
  }
  void refuse_rigid(const char* what) const {
    if (rigid) {
      throw std::logic_error(std::string("WeightedResidual::") + what + ": the contacts are rigid stops (" +
                             contacts.front().law->describe() +
                             "), which have no force law f_c(u): use signorini_residual, signorini_jacobian, "
                             "expand_forces and residual(a, lambda)");
    }
  }

  // The kinematic rows of y (n_c·M rows, ordering k·n_c + c): V(τ_{k+1}) y_c for a stop,
  // (V(τ_{k+1}) − V(τ_k)) y_c for a friction contact.
  [[nodiscard]] Eigen::MatrixXd kinematic(const Eigen::MatrixXd& y) const;

  // φ(λ) [m] at load s, row by row: min(c λ, g0 − u(λ)) for a stop, with u(λ) = s u_lin − D λ;
  // c λ − proj_[−c μN, c μN](c λ + Δ(λ)) for friction (contact::coulomb_projection), with
  // Δ(λ) = s u_lin − D λ and μN the row's slip_force; a friction contact that sticks at every
  // instant has its row c replaced by −u(τ_1) (`pinned` lists the stuck_* entries used).
  // gap_rows: the rows on the branch that depends on D (the gap of a stop, the stick of friction,
  // pinned rows included). With a piece (stops only, no friction; require_piece), each stop row
  // takes the branch the piece names, 1 the gap g0 − u, 0 the force c λ, instead of the min's.
  // coupled: the slip rows of friction contacts on a rigid normal stop whose stop pushes (CoupledSlip).
  [[nodiscard]] Eigen::VectorXd signorini(const Eigen::VectorXd& lambda, double load, std::vector<int>* gap_rows,
                                          std::vector<int>* pinned = nullptr, const ActiveSet* piece = nullptr,
                                          std::vector<CoupledSlip>* coupled = nullptr) const;
  // Throws std::logic_error with friction contacts (their rows have three branches) and
  // std::invalid_argument unless the piece has length n_c·M; nothing for a null piece.
  void require_piece(const char* what, const ActiveSet* piece) const;
  // Multiplies the friction rows of v (length n_c·M) by ρ.
  void weigh_friction_rows(Eigen::VectorXd& v) const {
    if (!collocation->any_coulomb) return;
    for (Eigen::Index i = 0; i < v.size(); ++i) {
      if (collocation->coulomb[static_cast<size_t>(i % nc)] != 0) v(i) *= friction_weight();
    }
  }
  // ∂φ/∂λ rows of the gap rows: D_i, or stuck_rows(r) for a pinned entry r; ρ D_i on friction rows.
  [[nodiscard]] Eigen::MatrixXd constraint_rows(const std::vector<int>& rows, const std::vector<int>& pinned) const;

  // n(λ) = (W ⊗ I_{n_c}) λ, stacked like x: the weighted residual of the collocation impulses.
  [[nodiscard]] Eigen::VectorXd collocation_forces(const Eigen::VectorXd& lambda) const {
    return per_contact(collocation->weights, lambda);
  }

  void set_compliance();

  // H v for a vector or a matrix v (n_c·M rows, ordering x(k·n_c + c)).
  [[nodiscard]] Eigen::MatrixXd compliance_times(const Eigen::MatrixXd& v) const;
  [[nodiscard]] Eigen::VectorXd compliance_times(const Eigen::VectorXd& v) const {
    return compliance_times(Eigen::MatrixXd(v)).col(0);
  }

  // Fourier:Fourier, midpoint rule: when every harmonic h of H_cd couples only its own cos hτ
  // and sin hτ, as the 2 × 2 block [[a_h, b_h], [−b_h, a_h]] (the structure of the exact
  // Galerkin operators: G commutes with time shifts), the kernel of the contact Jacobian is
  //   φ(τ_r)ᵀ H_cd φ(τ_r') = κ_cd(r − r' mod Q) + t_cd cos πMτ_r cos πMτ_r',
  //   κ_cd(s) = H_cd(0, 0) + Σ_h [a_h cos(2πhs/Q) − b_h sin(2πhs/Q)],
  // with t_cd the entry on the top function cos πMτ (M even; it has no sine partner, so it is
  // not shift invariant). The structure is checked on H to 1e-12 of its largest entry; any
  // other coupling (discrete operators, another basis) gives no kernel.
  [[nodiscard]] std::optional<ShiftKernel> shift_kernel() const;
  // Fourier trial and weighting with H kept sparse: the precondition of the two checks below.
  [[nodiscard]] bool fourier_sparse_compliance() const;
  // No entry of H above tol couples two different harmonics (requires fourier_sparse_compliance).
  [[nodiscard]] bool couples_only_within_harmonics(double tol) const;
  // Fourier:Fourier: H commutes with time shifts (every harmonic's block of H_cd is the rotation
  // [[a_h, b_h], [−b_h, a_h]], the top function on its own; to 1e-12 of H's largest entry). Then
  // D = V H W is block circulant on uniform instants: D_cd(j, k) depends on j − k mod M only.
  [[nodiscard]] bool commutes_with_shifts() const;

  // WeightedResidualOptions::harmonics: validated, sorted, and the mask `keep` built.
  void select_harmonics();

  // A selection projects the weighting functions only; that is the Galerkin projection on the
  // kept span only if no time operator couples a kept function with a dropped one. True for the
  // analytic Fourier operators and for discrete ones on Q ≥ M midpoints (products of harmonics
  // up to M − 1 are integrated exactly); checked, as an invariant, in case that ever changes.
  void require_block_diagonal_operators() const;

  [[nodiscard]] std::vector<std::vector<std::pair<int, double>>> contact_directions() const {
    std::vector<std::vector<std::pair<int, double>>> d;
    for (const auto& c : contacts) d.push_back(c.terms());
    return d;
  }

  // v += s Pᵀ x: each contact unknown spread over its direction's rows.
  void scatter(Eigen::VectorXd& v, const Eigen::VectorXd& x, double s) const {
    for (size_t j = 0; j < contact_terms.size(); ++j) {
      for (const auto& [row, w] : contact_terms[j]) v(row) += s * w * x(static_cast<Eigen::Index>(j));
    }
  }

  // G⁻¹ b: the linear response's coefficients (stacked, n·M), one full solve.
  [[nodiscard]] Eigen::VectorXd linear_coefficients() const { return g->solve(b); }
  // P G⁻¹ v, or P G⁻¹ G' G⁻¹ v with G' = ∂G/∂f = 2f A_M ⊗ M + A_C ⊗ C (`frequency_derivative`),
  // through the modal blocks (KroneckerFactorization::modal_blocks) reading only the DOFs where
  // v is not zero and writing only the contact DOFs: O(n·M) per source DOF and contact DOF plus
  // the n block solves, instead of the two O(n² M) modal transforms of a full solve (issue #39,
  // item 5). In modal coordinates G' is 2f A_M ⊗ I + A_C ⊗ diag(c_M + c_K λ_i). std::nullopt when
  // G is not solved mode by mode (the caller then takes the full solve).
  [[nodiscard]] std::optional<Eigen::VectorXd> gathered_solve(const Eigen::VectorXd& v, bool frequency_derivative) const;
  // G⁻¹ v (or G⁻ᵀ v) for a stacked v of length n·M.
  [[nodiscard]] Eigen::VectorXd solve_stacked(const Eigen::VectorXd& v, bool transposed) const {
    return transposed ? g->solve_transposed(v) : g->solve(v);
  }

  /// operator_products from ops; `sparse` holds (A_M, A_C, A_K) without stored zeros when the
  /// assembly produced them sparse (exact Fourier and wavelet Galerkin rules), so that the
  /// transposes and nonzero counts are read from them instead of from M² dense entries.
  void set_operator_products(const std::array<std::optional<Eigen::SparseMatrix<double>>, 3>& sparse);
  /// ‖G(f)‖_F at this frequency from the Kronecker factors, G not formed: ‖G‖_F² = Σ_{s,r}
  /// c_s c_r ⟨A_s, A_r⟩_F ⟨X_s, X_r⟩_F, c = (f², f, 1), A = (A_M, A_C, A_K), X = (M, C, K); the
  /// time factors from operator_products, the space ones O(nnz(X)). An upper bound of ‖G‖₂
  /// (backward_error's γ).
  [[nodiscard]] double frobenius_norm() const;

  // U Aᵀ for the n × M coefficients U and operator t (0: A_M, 1: A_C, 2: A_K).
  [[nodiscard]] Eigen::MatrixXd time_product(const Eigen::MatrixXd& u, int t) const;
  // X U Aᵀ for the n × M coefficients U and operator t (0: A_M, 1: A_C, 2: A_K).
  [[nodiscard]] Eigen::MatrixXd operator_product(const Eigen::SparseMatrix<double>& x, const Eigen::MatrixXd& u,
                                                 int t) const;

  // G a − b for stacked coefficients a (n·M): (T ⊗ X) vec(U) = vec(X U Tᵀ), layout.hpp.
  [[nodiscard]] Eigen::VectorXd linear_residual(const Eigen::VectorXd& a) const {
    const auto u = spectral::as_coefficients(a, n);
    const double fr = forcing.frequency_hz;
    const Eigen::MatrixXd gu = fr * fr * operator_product(system.mass, u, 0) + fr * operator_product(system.damping, u, 1) +
                               operator_product(system.stiffness, u, 2);
    return spectral::stacked(gu) - b;
  }

  // G′ a with G′ = dG/df = 2f A_M ⊗ M + A_C ⊗ C, for n × M coefficients a, stacked.
  [[nodiscard]] Eigen::VectorXd frequency_derivative_times(const Eigen::MatrixXd& a) const {
    const double f = forcing.frequency_hz;
    return spectral::stacked(2.0 * f * operator_product(system.mass, a, 0) + operator_product(system.damping, a, 1));
  }

  // [JL14 Eqs. (14)–(16)]: exactly (connection coefficients, analytic Fourier) or by the Q-point
  // rule A = (sign/Q) Σ_q p^{(dw)}(τ_q) q^{(dt)}(τ_q)ᵀ. The discrete rule exploits the bases:
  //  - Fourier weighting, wavelet trial: A^{(0)} = (1/Q) Σ_q p(τ_q) q^{(dt)}(τ_q)ᵀ by one FFTW
  //    projection per trial function (O(M Q log Q)); the weighting's derivatives stay in the
  //    basis, row(cos ωτ)' = −ω row(sin ωτ), row(sin ωτ)' = ω row(cos ωτ), row'' = −ω² row,
  //    except the first derivative of the top function cos πMτ, summed directly;
  //  - two wavelet bases: sparse products of their sample matrices;
  //  - otherwise (Fourier trial with OperatorRule::Discrete): dense values, O(Q M²).
  void assemble_time_operators();

  // (1/Q) Σ_q p_j^{(dw)}(τ_q) v_k(τ_q) from base(j, k) = (1/Q) Σ_q p_j(τ_q) v_k(τ_q) for the
  // Fourier weighting functions p_j (FourierBasis ordering) and the samples v (Q × M).
  [[nodiscard]] Eigen::MatrixXd fourier_weighting_derivative(const Eigen::MatrixXd& base, int dw, const SparseRows& v) const;

  [[nodiscard]] Eigen::VectorXd gather(const Eigen::VectorXd& a) const {  // P a
    Eigen::VectorXd x = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(contact_terms.size()));
    for (size_t j = 0; j < contact_terms.size(); ++j) {
      for (const auto& [row, w] : contact_terms[j]) x(static_cast<Eigen::Index>(j)) += w * a(row);
    }
    return x;
  }

  // Contact displacement samples U (n_c × Q) for stacked contact unknowns x, relative to the
  // counter-surfaces (u_c(τ_q) − s_c(τ_q): what the laws see; ContactPoint::obstacle).
  [[nodiscard]] Eigen::MatrixXd contact_samples(const Eigen::VectorXd& x) const {
    if (sampling->obstacle.size() == 0) return sampling->trial->to_time(spectral::as_coefficients(x, nc));
    return sampling->trial->to_time(spectral::as_coefficients(x, nc)) - sampling->obstacle;
  }

  // block(j, k) = (1/Q) Σ_q p_j(τ_q) κ_q q_k(τ_q) over the samples with κ_q ≠ 0 (`active`): the
  // contact Jacobian of one contact. Fourier:Fourier by Aft::jacobian (O(Q log Q + M²)); one
  // Fourier basis by one FFTW projection per function of the other (O(M Q log Q)); two wavelet
  // bases by their sparse rows (O(active · support²)).
  [[nodiscard]] Eigen::MatrixXd contact_block(const Eigen::VectorXd& kc, const std::vector<int>& active) const;

  // The law's derivatives at the samples of one contact: ∂f_q/∂u_q = kc(q) (active: kc ≠ 0),
  // the CellAverage kink terms kd (sloped), and for a hysteretic law ∂f_q/∂u_r = −kc(q) at
  // r = anchor(q) (anchored: the samples with an anchor; ContactLaw::evaluate_period).
  // A friction contact under a varying normal load (ContactPoint::normal) also has
  // ∂f_q/∂u_n,r = coupled_weight(i) at q = coupled[i], r = coupled_at[i] (the normal contact n's
  // sample that sets the slip force f_q hangs on: q in slip, its anchor in stick).
  struct ContactTangent {
    Eigen::VectorXd kc, kd;
    std::vector<int> active, sloped, anchored;
    Eigen::VectorXi anchor;
    int normal = -1;
    std::vector<int> coupled, coupled_at;
    std::vector<double> coupled_weight;
    /// A Jenkins element with two tangents: (contact c', ∂f_c,q/∂u_c',r at the Q samples, Q × Q),
    /// dense, for c' = c, its second tangent and its normal contact.
    std::vector<std::pair<int, Eigen::MatrixXd>> dense;
  };

  // n_c(x) = (1/Q) Σ_q p(τ_q) f_c(u_c(τ_q)) stacked like x (f̄_q for CellAverage); optionally
  // the law's derivatives at the samples, one ContactTangent per contact.
  // With a stick/slip piece (WeightedResidual::jenkins_active_set's layout), the Jenkins elements
  // take that piece's branches.
  Eigen::VectorXd contact_forces(const Eigen::VectorXd& x, std::vector<ContactTangent>* tangents,
                                 const ActiveSet* piece = nullptr) const {
    return spectral::stacked(sampling->weighting->project(contact_force_samples(x, tangents, piece)));
  }

  // f_c(u_c(τ_q)) (f̄_q for CellAverage), n_c × Q, and optionally the tangents.
  Eigen::MatrixXd contact_force_samples(const Eigen::VectorXd& x, std::vector<ContactTangent>* tangents,
                                        const ActiveSet* piece = nullptr) const;
  // The contacts that are Jenkins elements, in contact order: the blocks of Q entries of a
  // stick/slip piece. Throws std::invalid_argument for a piece of another length than Q per element.
  [[nodiscard]] std::vector<int> jenkins_contacts() const;
  void check_jenkins_piece(const ActiveSet& piece, const char* what) const;
  // Block j of a piece (Q entries), the pattern of the j-th Jenkins element.
  [[nodiscard]] std::vector<std::uint8_t> jenkins_pattern(const ActiveSet& piece, int j) const {
    const auto begin = piece.begin() + static_cast<std::ptrdiff_t>(j) * q;
    return {begin, begin + q};
  }

  // N(x) = ∂n_c/∂x (n_c·M square, dense) from the tangents.
  [[nodiscard]] Eigen::MatrixXd contact_force_jacobian(const std::vector<ContactTangent>& tangents) const;
  // The same by M × M blocks (weighting index j by trial index k): N's entries
  // (j·n_c + row, k·n_c + column) = block(j, k); one block per contact (row = column = c, every
  // contact, zero when none of its samples is in contact), and one (c, normal) per friction
  // contact whose slip force hangs on a normal contact's gap.
  struct ForceBlock {
    int row, column;
    Eigen::MatrixXd block;
  };
  [[nodiscard]] std::vector<ForceBlock> contact_force_blocks(const std::vector<ContactTangent>& tangents) const;
  // Multiplies the law's derivatives by σ: the tangents of σ n_c(x) (the contact homotopy).
  static void scale_tangents(std::vector<ContactTangent>& tangents, double sigma);

  // N as a sparse matrix, every entry of contact_force_blocks stored (explicit zeros included).
  [[nodiscard]] Eigen::SparseMatrix<double> sparse_contact_force_jacobian(
      const std::vector<ContactTangent>& tangents) const;
  // H N (n_c·M square, dense): by sparse products where H is sparse, by compliance_product where
  // it has a kept structure, else block by block of N (contact_force_blocks), never with N dense.
  [[nodiscard]] Eigen::MatrixXd hn_product(const std::vector<ContactTangent>& tangents) const;
  // I + H N (n_c·M square, dense): s_r times the condensed Jacobian.
  [[nodiscard]] Eigen::MatrixXd identity_plus_hn(const std::vector<ContactTangent>& tangents) const;

  // The weighting functions at τ (rows = times), the dropped ones of a selection as 0.
  [[nodiscard]] Eigen::MatrixXd weighting_values(const Eigen::VectorXd& tau) const {
    Eigen::MatrixXd v = weighting.values(tau, 0);
    if (keep.size() > 0) v *= keep.asDiagonal();
    return v;
  }

  // The trial functions (d = 0) and the weighting functions, the dropped ones of a selection as
  // 0, at the samples τ_at (rows = |at|, columns = M), as trial.values(τ_at, 0) and
  // weighting_values(τ_at), entry for entry, from Sampling (SampledBasis::rows_at: the stored
  // sparse rows of a wavelet basis, a Fourier basis' table once it pays).
  [[nodiscard]] Eigen::MatrixXd trial_rows_at(const std::vector<int>& at) const;
  // Σ_i κ_i p(τ_{r_i}) q(τ_{a_i})ᵀ (M × M: weighting index j by trial index k), the sum grouped
  // by the distinct a_i: G = Sᵀ diag(κ) P_r (one row per distinct a), then Gᵀ Q_a. The stick
  // samples of a phase hang on one slip sample, so the product costs the phases, not the samples.
  [[nodiscard]] Eigen::MatrixXd anchored_product(const std::vector<int>& r, const Eigen::VectorXd& kappa,
                                                 const std::vector<int>& a) const;
  [[nodiscard]] Eigen::MatrixXd weighting_rows_at(const std::vector<int>& at) const;

  // The times τ_q and weights ∂f̄/∂δ / Q² of the CellAverage kink terms of one contact.
  [[nodiscard]] std::pair<Eigen::VectorXd, Eigen::VectorXd> sloped_samples(const ContactTangent& t) const;

  // The condensed Jacobian (I + H N)/s_r with N = W V of rank r = Σ_c (active + sloped samples):
  // column i of W (n_c·M × r) is the weighting functions at the sample times κ_q/Q (or
  // ∂f̄/∂δ/Q² for a kink term), row i of V (r × n_c·M) the trial functions (or their slopes) at
  // the same time, both on the rows x(k·n_c + c) of their contact. With U = H W and
  // C = I_r + V U, Newton's step is an r × r solve (WoodburyLu). V is applied by FFTW for a
  // Fourier trial basis (all Q samples, the active ones kept) and by the sparse rows of the
  // wavelets otherwise. When r > ¾ n_c·M the dense form (I + H N) is factorized instead: an
  // r × r LU then saves less than the two products with V cost (bench_weighted_residual).
  // Either gives way to the sparse form (sparse_contact_jacobian) when its capacitance holds
  // fewer entries than theirs (r², or (n_c·M)²).
  [[nodiscard]] LowRankJacobian low_rank_contact_jacobian(const Eigen::VectorXd& x,
                                                          const ActiveSet* piece = nullptr) const;
  // The same from the tangents (whatever law or factor gave them).
  [[nodiscard]] LowRankJacobian contact_jacobian_from(const std::vector<ContactTangent>& tangents) const;

  // The sparse form of (I + H N)/s_r (newton.hpp, LowRankJacobian): with L = G(f) assembled,
  // U = P and V′ = Pᵀ N, the capacitance K = G + Pᵀ N P is the uncondensed Jacobian ∂R/∂a, and
  // J⁻¹ y = s_r (y − P K⁻¹ Pᵀ N y): a sparse LU of n·M unknowns instead of a dense LU of the
  // r samples in contact or of the n_c·M contact unknowns. Requires sparse time operators
  // (OperatorProducts::sparse) and K's entries, bounded by Σ_t nnz(A_t) nnz(X_t) + Σ_c (M |e_c|)²
  // before anything is formed, at most `limit` (the entries of the form it would replace: r²
  // or (n_c·M)²); std::nullopt otherwise.
  [[nodiscard]] std::optional<LowRankJacobian> sparse_contact_jacobian(const std::vector<ContactTangent>& tangents,
                                                                       double limit) const;

  // The low-rank Jacobian of Fourier:Fourier through its ShiftKernel: C is gathered from κ_cd
  // and t_cd in O(r²) (no product with V), U is never formed: U Z = H W Z with W Z one FFTW
  // projection of Z's rows placed at their samples, times the sparse H. V by FFTW, as above.
  [[nodiscard]] LowRankJacobian shift_kernel_jacobian(const std::vector<ContactTangent>& tangents, LowRankJacobian jac,
                                                      Eigen::Index rank) const;

  [[nodiscard]] Eigen::VectorXd contact_residual(const Eigen::VectorXd& x, double load,
                                                 const ActiveSet* piece = nullptr) const;

  // What makes G singular, in words (model_checks.hpp), or the generic reasons.
  [[nodiscard]] std::string singular_reason() const;

  void require_factorized() const;
};

namespace detail {

// Natural-parameter continuation in the load factor s (forcing s·F) from 0 to 1, the fallback of
// both solve paths: Δs from 1/8, doubled after a success (at most max_step), quartered after a failure,
// down to 1e-6; at each s the one Newton core on make_system(s) from predict(branch, s). Returns
// the last Newton solve at s = 1 (its iterations the sum over all steps), or, if the stepping
// stalls, the last converged point (`if_none` without one) with the status of the last failure
// and a message naming the s reached. `steps` counts the Newton solves.
template <class MakeSystem, class Predict>
NewtonResult load_stepping(MakeSystem make_system, Predict predict, Eigen::VectorXd x0, const Eigen::VectorXd& if_none,
                           const NewtonOptions& newton_options, double max_step, int& steps) {
  NaturalParameterOptions o;
  o.parameter_min = 0.0;
  o.parameter_max = 1.0;
  o.initial_step = 0.125;
  o.max_step = max_step;
  o.min_step = 1e-6;
  o.shrink = 0.25;
  o.grow = [](double h, int) { return 2.0 * h; };
  NewtonResult last;  // the Newton solve of the last accepted point, for its report
  SolveStatus failed = SolveStatus::MaxIterations;  // that of the last attempt that failed
  int iterations = 0;
  steps = 0;
  auto correct = [&](double s, Eigen::VectorXd guess) {
    NewtonResult r = newton(make_system(s), std::move(guess), newton_options);
    iterations += r.report.iterations;
    ++steps;
    if (r.report.converged()) {
      last = r;
    } else {
      failed = r.report.status;
    }
    return to_correction(std::move(r));
  };
  const Branch branch = natural_parameter(correct, predict, std::move(x0), 0.0, o);
  if (branch.stop != StopReason::RangeReached) {
    NewtonResult stalled;
    stalled.x = branch.points.empty() ? if_none : branch.points.back().x;
    stalled.report.status = failed;
    stalled.report.iterations = iterations;
    stalled.report.message = "load stepping stalled at s = " +
                             format_number(branch.points.empty() ? 0.0 : branch.points.back().parameter) +
                             " of F: " + std::string(to_string(branch.stop)) + ": " + branch.message;
    return stalled;
  }
  last.report.iterations = iterations;
  return last;
}

}  // namespace detail

}  // namespace wbm::solvers
