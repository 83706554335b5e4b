#include "kronecker_factorization.hpp"
#include "kronecker_compliance.hpp"
#include "fourier_weighting_factor.hpp"
#include "modal_damping_structure.hpp"
#include "core/one_norm_estimate.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <iterator>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <unsupported/Eigen/KroneckerProduct>

#include <wbm/solvers/undamped_modes.hpp>
#include <wbm/spectral/circulant.hpp>
#include <wbm/spectral/fourier_basis.hpp>
#include <wbm/spectral/layout.hpp>

namespace wbm::solvers::detail {
namespace {

// Connected components of the graph i ~ j if any of the time operators couples i and j
// (union-find); a single component is returned as an empty list. The couplings are read from
// the operators' sparse transposes when the caller has them (the undirected graph is the same),
// O(nnz), else from the M² dense entries.
std::vector<std::vector<Eigen::Index>> block_components(const TimeOperators& ops,
                                                        const std::array<Eigen::SparseMatrix<double>, 3>* transposed) {
  const Eigen::Index m = ops.mass.rows();
  std::vector<Eigen::Index> parent(static_cast<size_t>(m));
  for (Eigen::Index i = 0; i < m; ++i) parent[static_cast<size_t>(i)] = i;
  auto find = [&](Eigen::Index i) {
    while (parent[static_cast<size_t>(i)] != i) i = parent[static_cast<size_t>(i)];
    return i;
  };
  if (transposed != nullptr) {
    for (const auto& t : *transposed) {
      for (Eigen::Index j = 0; j < t.outerSize(); ++j) {
        for (Eigen::SparseMatrix<double>::InnerIterator it(t, j); it; ++it) {
          if (it.value() != 0.0) parent[static_cast<size_t>(find(it.row()))] = find(j);
        }
      }
    }
  } else {
    for (Eigen::Index j = 0; j < m; ++j) {
      for (Eigen::Index i = 0; i < m; ++i) {
        if (ops.mass(i, j) != 0.0 || ops.damping(i, j) != 0.0 || ops.stiffness(i, j) != 0.0) {
          parent[static_cast<size_t>(find(i))] = find(j);
        }
      }
    }
  }
  std::vector<std::vector<Eigen::Index>> groups(static_cast<size_t>(m));
  for (Eigen::Index i = 0; i < m; ++i) groups[static_cast<size_t>(find(i))].push_back(i);
  std::vector<std::vector<Eigen::Index>> out;
  for (auto& g : groups) {
    if (!g.empty()) out.push_back(std::move(g));
  }
  if (out.size() == 1) out.clear();
  return out;
}

// Entries of the joint pattern of (A_M, A_C, A_K), from the sparse transposes when given.
Eigen::Index joint_nonzeros(const TimeOperators& ops, const std::array<Eigen::SparseMatrix<double>, 3>* transposed) {
  if (transposed == nullptr) {
    return (ops.mass.array() != 0.0 || ops.damping.array() != 0.0 || ops.stiffness.array() != 0.0).count();
  }
  const auto& t = *transposed;
  Eigen::SparseMatrix<double> joint = t[0].cwiseAbs() + t[1].cwiseAbs() + t[2].cwiseAbs();
  joint.prune([](Eigen::Index, Eigen::Index, double v) { return v != 0.0; });
  return joint.nonZeros();
}

}  // namespace

// One modal block A + λ_i B (M × M) and its inverse, in the form the time operators allow:
//  - Components: the sparsity graph splits into connected components (Fourier:Fourier: the
//    1 × 1 and 2 × 2 blocks of each harmonic), each inverted densely: O(M) per mode.
//  - Circulant: the three time operators are circulant (a wavelet basis with itself, exact or
//    on Q = multiple-of-M midpoints): the block's inverse is circulant, from one FFT of its first
//    column (spectral::Circulant): O(M log M) per mode.
//  - Factored: Fourier weighting, distributional form: inverse A_K⁻¹ S_i with the shared dense
//    left factor and the O(M) core S_i (FourierWeighting, FourierCore).
//  - Sparse / dense LU otherwise (sparse when ≤ 25 % filled).
class KroneckerFactorization::ModeBlock {
 public:
  using Components = std::vector<std::vector<Eigen::Index>>;

  /// Block a + λ bb with a = f² A_M + f c_M A_C and bb = f c_K A_C + A_K (the time operators
  /// `ops` at frequency f; the mode's damping c_M + c_K λ, Setup), split along `components` (≥ 2 of
  /// them), each inverted densely; only the components' entries are read. The inverses are
  /// stored flat (row-major, concatenated): a Fourier:Fourier block has M/2 of them, and
  /// continuation builds one block per mode per frequency.
  ModeBlock(const TimeOperators& ops, double f, double c_m, double c_k, double lambda, const Components& components)
      : m_(ops.mass.rows()), component_(&components) {
    const double f2 = f * f, fcm = f * c_m, fck = f * c_k;
    const auto a = [&](Eigen::Index i, Eigen::Index j) { return f2 * ops.mass(i, j) + fcm * ops.damping(i, j); };
    const auto bb = [&](Eigen::Index i, Eigen::Index j) { return fck * ops.damping(i, j) + ops.stiffness(i, j); };
    ok_ = true;
    offset_.reserve(components.size() + 1);
    size_t total = 0;
    for (const auto& idx : components) {
      offset_.push_back(total);
      total += idx.size() * idx.size();
    }
    offset_.push_back(total);
    flat_.resize(total);
    for (size_t comp = 0; comp < components.size(); ++comp) {
      const auto& idx = components[comp];
      const auto k = static_cast<Eigen::Index>(idx.size());
      double* inv = flat_.data() + offset_[comp];
      const auto entry = [&](Eigen::Index i, Eigen::Index j) { return a(idx[i], idx[j]) + lambda * bb(idx[i], idx[j]); };
      if (k <= 2) {  // closed-form inverse; singular if the determinant vanishes against the entries
        if (k == 1) {
          const double d = entry(0, 0);
          if (!(std::abs(d) > 1e-300) || !std::isfinite(d)) ok_ = false;
          inv[0] = 1.0 / d;
        } else {
          const double e00 = entry(0, 0), e01 = entry(0, 1), e10 = entry(1, 0), e11 = entry(1, 1);
          const double scale = std::max({std::abs(e00), std::abs(e01), std::abs(e10), std::abs(e11)});
          const double det = e00 * e11 - e01 * e10;
          if (!(std::abs(det) > 1e-300 + 1e-15 * scale * scale) || !std::isfinite(det)) ok_ = false;
          inv[0] = e11 / det;
          inv[1] = -e01 / det;
          inv[2] = -e10 / det;
          inv[3] = e00 / det;
        }
      } else {
        Eigen::MatrixXd sub(k, k);
        for (Eigen::Index i = 0; i < k; ++i) {
          for (Eigen::Index j = 0; j < k; ++j) sub(i, j) = entry(i, j);
        }
        const Eigen::PartialPivLU<Eigen::MatrixXd> lu(sub);
        const Eigen::MatrixXd sub_inverse = lu.inverse();
        const double rc = lu.rcond();
        if (!(rc > 1e-300 && std::isfinite(rc)) || !sub_inverse.allFinite()) ok_ = false;
        RowMajorMap(inv, k, k) = sub_inverse;
      }
    }
  }
  /// Circulant block of eigenvalues `bins` (ĉ_m, m = 0 … ⌊M/2⌋); singular (not ok) when one is not
  /// finite or min |ĉ_m| ≤ 1e-14 max |ĉ_m|, i.e. zero to double precision. Its inverse has 1/ĉ_m.
  ModeBlock(const Eigen::VectorXcd& bins, Eigen::Index m) : m_(m), component_(nullptr) {
    const Eigen::VectorXd magnitude = bins.cwiseAbs();
    ok_ = bins.allFinite() && magnitude.minCoeff() > 1e-14 * magnitude.maxCoeff();
    if (ok_) {
      circulant_inverse_.emplace(spectral::Circulant::from_eigenvalues(bins.cwiseInverse(), static_cast<int>(m)));
    }
  }
  /// Sparse or dense LU of the block.
  explicit ModeBlock(const Eigen::MatrixXd& block) : m_(block.rows()), component_(nullptr) {
    const double density = static_cast<double>((block.array() != 0.0).count()) / static_cast<double>(block.size());
    sparse_ = block.rows() > 8 && density <= 0.25;
    if (sparse_) {
      sparse_lu_ = std::make_unique<SparseLu>();
      ok_ = sparse_lu_->factorize(Eigen::SparseMatrix<double>(block.sparseView()));
    } else {
      dense_lu_.compute(block);
      const double rc = dense_lu_.rcond();
      ok_ = rc > 1e-300 && std::isfinite(rc);
    }
  }
  /// Factored block (A_K⁻¹ S)⁻¹ given S = its core and the shared left factor A_K⁻¹ (see
  /// FourierWeighting): solve and inverse apply A_K⁻¹ S.
  ModeBlock(FourierCore core, const Eigen::MatrixXd* left)
      : m_(core.size()), component_(nullptr), left_(left), core_(std::move(core)) {
    ok_ = core_->finite();
  }
  [[nodiscard]] bool ok() const { return ok_; }
  [[nodiscard]] const FourierCore* core() const { return core_ ? &*core_ : nullptr; }
  [[nodiscard]] const spectral::Circulant* circulant_inverse() const {
    return circulant_inverse_ ? &*circulant_inverse_ : nullptr;
  }
  using RowMajorMap = Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>;
  using ConstRowMajorMap = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>;
  /// Inverse of component c (|c| × |c|), when the block is split.
  [[nodiscard]] ConstRowMajorMap component_inverse(size_t c) const {
    const auto k = static_cast<Eigen::Index>((*component_)[c].size());
    return {flat_.data() + offset_[c], k, k};
  }
  /// The block's inverse applied to r (M × k), or its transpose.
  [[nodiscard]] Eigen::MatrixXd solve(const Eigen::MatrixXd& r, bool transposed) const {
    if (core_) {
      return transposed ? core_->apply(left_->transpose() * r, true) : Eigen::MatrixXd(*left_ * core_->apply(r, false));
    }
    if (circulant_inverse_) return circulant_inverse_->apply(r, transposed);
    if (!flat_.empty()) {
      Eigen::MatrixXd out = Eigen::MatrixXd::Zero(r.rows(), r.cols());
      for (size_t c = 0; c < component_->size(); ++c) {  // no temporaries: most components are 1 × 1 or 2 × 2
        const auto& idx = (*component_)[c];
        const double* inv = flat_.data() + offset_[c];
        const auto k = static_cast<Eigen::Index>(idx.size());
        for (Eigen::Index col = 0; col < r.cols(); ++col) {
          for (Eigen::Index i = 0; i < k; ++i) {
            double sum = 0.0;
            for (Eigen::Index j = 0; j < k; ++j) sum += (transposed ? inv[j * k + i] : inv[i * k + j]) * r(idx[j], col);
            out(idx[i], col) = sum;
          }
        }
      }
      return out;
    }
    if (sparse_) return sparse_lu_->solve_columns(r, transposed);
    return transposed ? Eigen::MatrixXd(dense_lu_.transpose().solve(r)) : Eigen::MatrixXd(dense_lu_.solve(r));
  }
  /// The inverse, M × M (dense).
  [[nodiscard]] Eigen::MatrixXd inverse() const {
    if (core_) return core_->left_multiply(*left_);
    if (circulant_inverse_) return circulant_inverse_->dense();
    if (flat_.empty()) return solve(Eigen::MatrixXd::Identity(m_, m_), false);
    Eigen::MatrixXd out = Eigen::MatrixXd::Zero(m_, m_);
    for (size_t c = 0; c < component_->size(); ++c) {
      const auto& idx = (*component_)[c];
      for (size_t i = 0; i < idx.size(); ++i) {
        for (size_t j = 0; j < idx.size(); ++j) out(idx[i], idx[j]) = flat_[offset_[c] + i * idx.size() + j];
      }
    }
    return out;
  }

 private:
  Eigen::Index m_;
  bool sparse_ = false, ok_ = false;
  const Components* component_;
  std::vector<double> flat_;     // component inverses, row-major, concatenated (split blocks only)
  std::vector<size_t> offset_;   // start of component c in flat_
  const Eigen::MatrixXd* left_ = nullptr;  // factored: A_K⁻¹ (shared) ...
  std::optional<FourierCore> core_;        // ... and S, the block's inverse being A_K⁻¹ S
  std::optional<spectral::Circulant> circulant_inverse_;
  std::unique_ptr<SparseLu> sparse_lu_;  // the SparseLu policy (KLU) of newton.hpp
  Eigen::PartialPivLU<Eigen::MatrixXd> dense_lu_;
};

// The frequency-independent part, shared by the factorizations at every frequency (ModeBlock
// keeps pointers into it, so it lives on the heap and never moves).
struct KroneckerFactorization::Setup {
  bool modal = false;
  double c_m = 0.0, c_k = 0.0;     // C = c_M M + c_K K (modal path, Rayleigh)
  Eigen::VectorXd mode_damping;    // Φᵀ C Φ's diagonal (modal path, classical C that is not Rayleigh); else empty
  // Mode i's damping as c_M,i + c_K,i λ_i: (c_M, c_K) for Rayleigh, (Φᵀ C Φ)_ii and 0 otherwise.
  [[nodiscard]] double mass_part(Eigen::Index i) const { return mode_damping.size() > 0 ? mode_damping(i) : c_m; }
  [[nodiscard]] double stiffness_part() const { return mode_damping.size() > 0 ? 0.0 : c_k; }
  Eigen::MatrixXd phi;             // n × n, Φᵀ M Φ = I (modal path)
  Eigen::VectorXd lambda;
  std::vector<std::vector<Eigen::Index>> components;  // of the time operators' sparsity graph
  bool circulant = false;                             // all three time operators circulant
  // Circulant: the eigenvalues of A_M, A_C and A_K (bins 0 … ⌊M/2⌋), transformed once; each block
  // is combined on them bin by bin, so a near-resonant bin carries only its own terms' rounding
  // (docs/design.md, "Circulant blocks combined on their eigenvalues").
  Eigen::VectorXcd mass_bins, damping_bins, stiffness_bins;
  bool supernodal = false;  // assembled path: the time operators' joint pattern is over ¼ full
  bool by_components = false;  // not modal: G factorized per component (kronecker_components.cpp)
  std::optional<FourierWeighting> fourier_weighting;  // distributional form, Fourier weighting
};

KroneckerFactorization::KroneckerFactorization(std::shared_ptr<const Setup> setup) : setup_(std::move(setup)) {}

KroneckerFactorization::KroneckerFactorization(const MechanicalSystem& system, const TimeOperators& ops,
                                               LinearSolverPath path, bool fourier_weighting,
                                               const std::array<Eigen::SparseMatrix<double>, 3>* transposed) {
  auto setup = std::make_shared<Setup>();
  const bool rayleigh = rayleigh_fit(system, setup->c_m, setup->c_k);
  // A classical C that is not Rayleigh (modal damping ratios, Caughey series) is diagonal in the
  // modes too: mode i is damped by (Φᵀ C Φ)_ii. Checked on Φᵀ C Φ itself once the modes exist.
  const bool classical = !rayleigh && path != LinearSolverPath::SparseLU && classical_damping_probe(system);
  if (path == LinearSolverPath::Modal && !rayleigh && !classical) {
    throw std::invalid_argument("LinearSolverPath::Modal needs a damping matrix that the undamped modes diagonalize "
                                "(Rayleigh C = c_M M + c_K K, or modal damping); this C is not (C M⁻¹ K ≠ K M⁻¹ C): "
                                "use LinearSolverPath::SparseLU or Automatic");
  }
  // Block-diagonal time operators (Fourier:Fourier) off the modal path: G's blocks G_c are sparse
  // and |c|·n square, so G is factorized block by block (kronecker_components.cpp) instead of
  // assembled whole.
  auto components = block_components(ops, transposed);
  const bool by_components = !components.empty() && (path == LinearSolverPath::SparseLU ||
                                                     (path == LinearSolverPath::Automatic && !(rayleigh || classical)));
  setup->modal = path != LinearSolverPath::SparseLU && (rayleigh || classical);
  if (by_components) {
    setup->by_components = true;
    setup->components = std::move(components);
  }
  if (setup->modal) {
    // Dense below 400 DOFs; O(n²) for a larger tridiagonal pencil (undamped_modes.hpp).
    UndampedModes modes;
    try {
      modes = undamped_modes(system.stiffness, system.mass);
    } catch (const std::invalid_argument&) {
      throw std::invalid_argument("modal solve: K Φ = M Φ Λ failed (is M symmetric positive definite?); use "
                                  "LinearSolverPath::SparseLU");
    }
    setup->phi = std::move(modes.phi);
    setup->lambda = std::move(modes.lambda);
    if (classical) {
      auto d = modal_damping_of(system, setup->phi);
      if (d) {
        setup->mode_damping = std::move(*d);
      } else if (path == LinearSolverPath::Modal) {
        throw std::invalid_argument("LinearSolverPath::Modal: the modes K Φ = M Φ Λ do not diagonalize C (Φᵀ C Φ has "
                                    "off-diagonal entries above 1e-10 of it, e.g. at a repeated frequency): use "
                                    "LinearSolverPath::SparseLU or Automatic");
      } else {
        setup->modal = false;  // the sparse LU of the assembled G, as for any other C
      }
    }
  }
  if (setup->modal) {
    setup->components = std::move(components);
    if (fourier_weighting) setup->fourier_weighting = FourierWeighting::detect(ops);
    setup->circulant = setup->components.empty() && !setup->fourier_weighting &&
                       spectral::Circulant::is_circulant(ops.mass) && spectral::Circulant::is_circulant(ops.damping) &&
                       spectral::Circulant::is_circulant(ops.stiffness);
    if (setup->circulant) {
      setup->mass_bins = spectral::real_dft_columns(ops.mass.col(0)).col(0);
      setup->damping_bins = spectral::real_dft_columns(ops.damping.col(0)).col(0);
      setup->stiffness_bins = spectral::real_dft_columns(ops.stiffness.col(0)).col(0);
    }
  }
  // Nonzeros of the joint pattern of (A_M, A_C, A_K) against M²: above ¼, G's factors fill in
  // densely and the supernodal LU is faster (bench_weighted_residual, newton.hpp SupernodalLu).
  setup->supernodal = 4 * joint_nonzeros(ops, transposed) > ops.mass.size();
  setup_ = std::move(setup);
}

KroneckerFactorization KroneckerFactorization::unfactorized() const { return KroneckerFactorization(setup_); }

bool KroneckerFactorization::modal() const { return setup_->modal; }

static_assert(wbm::solvers::LinearSolverPolicy<KroneckerFactorization, KroneckerOperator>);

bool KroneckerFactorization::factorize(const KroneckerOperator& g) {
  const MechanicalSystem& system = *g.system;
  const TimeOperators& ops = *g.ops;
  const double fr = g.frequency_hz;
  const Setup& su = *setup_;
  operator_ = g;
  norm1_ = -1.0;
  compliance_structure_.reset();
  factorized_ = false;
  blocks_.clear();
  if (su.modal) {
    // Mode i's block is a + λ_i bb with a = f² A_M + f c_M A_C and bb = f c_K A_C + A_K (c_M,
    // c_K: Setup::mass_part, stiffness_part), formed only where read: densely for a dense block,
    // on the eigenvalues for a circulant one (Setup::mass_bins), on the components' entries for a
    // block-diagonal one (ModeBlock), not at all for the Fourier-weighting form. c_K is the same
    // for every mode, so bb is formed once; a too with Rayleigh damping, per mode for a classical C.
    const bool dense_blocks = !su.fourier_weighting && su.components.empty() && !su.circulant;
    const bool per_mode = su.mode_damping.size() > 0;
    const double ck = su.stiffness_part();
    Eigen::MatrixXd a, bb;
    Eigen::VectorXcd a_bins, bb_bins;
    if (dense_blocks) {
      bb = fr * ck * ops.damping + ops.stiffness;
    } else if (su.circulant) {
      bb_bins = fr * ck * su.damping_bins + su.stiffness_bins;
    }
    const auto form_a = [&](double cm) {
      if (dense_blocks) {
        a = fr * fr * ops.mass + fr * cm * ops.damping;
      } else if (su.circulant) {
        a_bins = fr * fr * su.mass_bins + fr * cm * su.damping_bins;
      }
    };
    if (!per_mode) form_a(su.c_m);
    const auto n = su.lambda.size();
    blocks_.reserve(static_cast<size_t>(n));
    factorized_ = true;
    for (Eigen::Index i = 0; i < n; ++i) {
      const double cm = su.mass_part(i);
      if (per_mode) form_a(cm);
      if (su.fourier_weighting) {
        blocks_.push_back(std::make_shared<const ModeBlock>(
            su.fourier_weighting->core(fr, cm + su.lambda(i) * ck, su.lambda(i)), &su.fourier_weighting->ak_inv));
      } else if (!su.components.empty()) {
        blocks_.push_back(std::make_shared<const ModeBlock>(ops, fr, cm, ck, su.lambda(i), su.components));
      } else if (su.circulant) {
        blocks_.push_back(
            std::make_shared<const ModeBlock>(Eigen::VectorXcd(a_bins + su.lambda(i) * bb_bins), ops.mass.rows()));
      } else {
        blocks_.push_back(std::make_shared<const ModeBlock>(Eigen::MatrixXd(a + su.lambda(i) * bb)));
      }
      if (!blocks_.back()->ok()) factorized_ = false;
    }
    return factorized_;
  }
  component_lus_.reset();
  if (su.by_components) {
    factorized_ = factorize_components(su.components);
    return factorized_;
  }
  g_ = Eigen::kroneckerProduct(Eigen::SparseMatrix<double>((fr * fr * ops.mass).sparseView()), system.mass).eval();
  g_ += Eigen::kroneckerProduct(Eigen::SparseMatrix<double>((fr * ops.damping).sparseView()), system.damping).eval();
  g_ += Eigen::kroneckerProduct(Eigen::SparseMatrix<double>(ops.stiffness.sparseView()), system.stiffness).eval();
  g_.makeCompressed();
  lu_.reset();
  supernodal_lu_.reset();
  if (su.supernodal) {
    supernodal_lu_ = std::make_shared<SupernodalLu>();
    factorized_ = supernodal_lu_->factorize(g_);
  } else {
    lu_ = std::make_shared<SparseLu>();
    factorized_ = lu_->factorize(g_);
  }
  return factorized_;
}

Eigen::VectorXd KroneckerFactorization::solve(const Eigen::VectorXd& v) const { return solve(v, false); }

Eigen::VectorXd KroneckerFactorization::solve_transposed(const Eigen::VectorXd& v) const { return solve(v, true); }

double KroneckerFactorization::condition_estimate() const {
  if (!factorized_) return std::numeric_limits<double>::infinity();
  const double inverse_norm = inverse_one_norm_estimate(
      static_cast<Eigen::Index>(operator_.system->mass.rows()) * operator_.ops->mass.rows(),
      [&](const Eigen::VectorXd& v, bool transposed) { return solve(v, transposed); });
  return norm1() * inverse_norm;
}

std::optional<double> KroneckerFactorization::rcond() const { return 1.0 / condition_estimate(); }

Eigen::VectorXd KroneckerFactorization::solve(const Eigen::VectorXd& v, bool transposed) const {
  if (!setup_->modal) {
    if (setup_->by_components) return solve_components(v, transposed, setup_->components);
    if (supernodal_lu_) return transposed ? supernodal_lu_->solve_transposed(v) : supernodal_lu_->solve(v);
    return transposed ? lu_->solve_transposed(v) : lu_->solve(v);
  }
  const auto n = setup_->phi.rows();
  const auto m = v.size() / n;
  const Eigen::MatrixXd modal_rhs = setup_->phi.transpose() * spectral::as_coefficients(v, n);  // n × M
  Eigen::MatrixXd y(n, m);
  if (setup_->fourier_weighting) {
    // One product with the shared left factor for every mode: A_K⁻¹ [S_1 r_1 … S_n r_n], or
    // [S_1ᵀ z_1 …] with Z = A_K⁻ᵀ R.
    const Eigen::MatrixXd& left = setup_->fourier_weighting->ak_inv;
    if (transposed) {
      const Eigen::MatrixXd z = left.transpose() * modal_rhs.transpose();  // M × n
      for (Eigen::Index i = 0; i < n; ++i) y.row(i) = blocks_[i]->core()->apply(z.col(i), true).transpose();
    } else {
      Eigen::MatrixXd z(m, n);
      for (Eigen::Index i = 0; i < n; ++i) z.col(i) = blocks_[i]->core()->apply(modal_rhs.row(i).transpose(), false);
      y = (left * z).transpose();
    }
    return spectral::stacked(setup_->phi * y);
  }
  for (Eigen::Index i = 0; i < n; ++i) y.row(i) = blocks_[i]->solve(modal_rhs.row(i).transpose(), transposed).transpose();
  return spectral::stacked(setup_->phi * y);
}

bool KroneckerFactorization::modal_blocks() const { return setup_->modal && !setup_->fourier_weighting; }

Eigen::MatrixXd KroneckerFactorization::modal_projection(const Eigen::MatrixXd& v,
                                                         const std::vector<Eigen::Index>& sources) const {
  const Eigen::MatrixXd& phi = setup_->phi;
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(phi.cols(), v.cols());
  for (const Eigen::Index dof : sources) out += phi.row(dof).transpose() * v.row(dof);
  return out;
}

Eigen::MatrixXd KroneckerFactorization::modal_block_solve(const Eigen::MatrixXd& r) const {
  Eigen::MatrixXd y(r.rows(), r.cols());
  for (Eigen::Index i = 0; i < r.rows(); ++i) {
    y.row(i) = blocks_[static_cast<size_t>(i)]->solve(r.row(i).transpose(), false).transpose();
  }
  return y;
}

Eigen::MatrixXd KroneckerFactorization::modal_rows(const Eigen::MatrixXd& y, const std::vector<Eigen::Index>& rows) const {
  Eigen::MatrixXd out(static_cast<Eigen::Index>(rows.size()), y.cols());
  for (size_t r = 0; r < rows.size(); ++r) out.row(static_cast<Eigen::Index>(r)) = setup_->phi.row(rows[r]) * y;
  return out;
}

Eigen::VectorXd KroneckerFactorization::modal_damping() const {
  if (setup_->mode_damping.size() > 0) return setup_->mode_damping;
  return (setup_->c_m + setup_->c_k * setup_->lambda.array()).matrix();
}

Eigen::MatrixXd KroneckerFactorization::compliance(const std::vector<std::vector<std::pair<int, double>>>& directions,
                                                   const std::vector<StackedTerms>& rows, bool dense) {
  const int nc = static_cast<int>(directions.size());
  const auto m = static_cast<Eigen::Index>(rows.size()) / std::max(nc, 1);
  const Setup& su = *setup_;
  const bool circulant_path = su.modal && su.circulant && !su.fourier_weighting;
  Eigen::MatrixXd h;
  if (!circulant_path) h.setZero(nc * m, nc * m);
  // H_cd = Σ_i φ_i(c) φ_i(d) (A + λ_i B)⁻¹ (M × M) scattered into h(k·n_c + c, l·n_c + d).
  const auto scatter = [&](int c, int d, const Eigen::MatrixXd& hcd) {
    for (Eigen::Index l = 0; l < m; ++l) {
      for (Eigen::Index k = 0; k < m; ++k) h(k * nc + c, l * nc + d) = hcd(k, l);
    }
  };
  // ψ_c(i) = e_cᵀ φ_i: mode i along contact c's direction.
  const auto shape = [&](int c, Eigen::Index mode) {
    double v = 0.0;
    for (const auto& [dof, w] : directions[static_cast<size_t>(c)]) v += w * su.phi(dof, mode);
    return v;
  };
  const auto weight = [&](size_t i, int c, int d) {
    const auto mode = static_cast<Eigen::Index>(i);
    return shape(c, mode) * shape(d, mode);
  };
  auto structure = std::make_shared<ComplianceStructure>();
  structure->contacts = nc;
  if (su.modal && su.fourier_weighting) {  // A_K⁻¹ (Σ_i w_i S_i): the sum in O(nM), the product in O(M²)
    for (int c = 0; c < nc; ++c) {
      for (int d = 0; d < nc; ++d) {
        FourierCore sum(m);
        for (size_t i = 0; i < blocks_.size(); ++i) sum.add(weight(i, c, d), *blocks_[i]->core());
        scatter(c, d, sum.left_multiply(su.fourier_weighting->ak_inv));
        structure->cores.push_back(std::move(sum));
      }
    }
    if (su.fourier_weighting->shift) {
      structure->fourier_weighting = &*su.fourier_weighting;
      compliance_structure_ = std::move(structure);
    }
    return h;
  }
  if (su.modal && su.circulant) {  // a sum of circulants is circulant: summed bin by bin
    // ψ_c(i) once per contact and mode (weight() would form them for every pair), the same products.
    Eigen::MatrixXd psi(nc, static_cast<Eigen::Index>(blocks_.size()));
    for (int c = 0; c < nc; ++c) {
      for (Eigen::Index i = 0; i < psi.cols(); ++i) psi(c, i) = shape(c, i);
    }
    // The modes' bins gathered once (column i), each pair's sum in the modes' order as before.
    const Eigen::Index nb = m / 2 + 1;
    Eigen::MatrixXcd eig(nb, psi.cols());
    for (Eigen::Index i = 0; i < psi.cols(); ++i) {
      eig.col(i) = blocks_[static_cast<size_t>(i)]->circulant_inverse()->eigenvalues();
    }
    for (int c = 0; c < nc; ++c) {
      for (int d = 0; d < nc; ++d) {
        Eigen::VectorXcd bins = Eigen::VectorXcd::Zero(nb);
        for (Eigen::Index i = 0; i < psi.cols(); ++i) bins += (psi(c, i) * psi(d, i)) * eig.col(i);
        structure->circulant.push_back(spectral::Circulant::from_eigenvalues(bins, static_cast<int>(m)));
      }
    }
    compliance_structure_ = std::move(structure);
    return dense && nc > 0 ? dense_circulant_compliance() : Eigen::MatrixXd(nc * m, nc * m);
  }
  // Ψ (n_c × modes), Ψ(c, i) = ψ_c(i): H_cd(k, l) = Σ_i Ψ(c, i) s_i(k, l) Ψ(d, i), so for each entry (k, l)
  // of the blocks the n_c × n_c matrix Ψ diag(s_·(k, l)) Ψᵀ is one matrix product instead of a scalar
  // sum over (i, c, d) (issue #39: the blade's 24 rigid stops at H = 6, where this loop was 66 % of the
  // continuation, went from 30.9 s to 9.7 s).
  const auto modes = static_cast<Eigen::Index>(blocks_.size());
  Eigen::MatrixXd psi(nc, modes);
  if (su.modal) {
    for (int c = 0; c < nc; ++c) {
      for (Eigen::Index i = 0; i < modes; ++i) psi(c, i) = shape(c, i);
    }
  }
  if (su.modal && !su.components.empty()) {  // only the components' entries are nonzero
    Eigen::VectorXd s(modes);
    for (size_t comp = 0; comp < su.components.size(); ++comp) {
      const auto& idx = su.components[comp];
      for (size_t b = 0; b < idx.size(); ++b) {
        for (size_t a = 0; a < idx.size(); ++a) {
          for (Eigen::Index i = 0; i < modes; ++i) {
            s(i) = blocks_[static_cast<size_t>(i)]->component_inverse(comp)(static_cast<Eigen::Index>(a),
                                                                            static_cast<Eigen::Index>(b));
          }
          const Eigen::MatrixXd hab = psi * s.asDiagonal() * psi.transpose();
          for (int d = 0; d < nc; ++d) {
            for (int c = 0; c < nc; ++c) h(idx[a] * nc + c, idx[b] * nc + d) += hab(c, d);
          }
        }
      }
    }
    return h;
  }
  if (su.modal) {
    for (size_t i = 0; i < blocks_.size(); ++i) {
      const Eigen::MatrixXd s_i = blocks_[i]->inverse();
      for (int c = 0; c < nc; ++c) {
        for (int d = 0; d < nc; ++d) {
          const double w = weight(i, c, d);
          for (Eigen::Index l = 0; l < m; ++l) {
            for (Eigen::Index k = 0; k < m; ++k) h(k * nc + c, l * nc + d) += w * s_i(k, l);
          }
        }
      }
    }
    return h;
  }
  if (su.by_components) return compliance_components(rows, nc, su.components);
  Eigen::MatrixXd selection = Eigen::MatrixXd::Zero(g_.rows(), nc * m);  // Pᵀ
  for (Eigen::Index j = 0; j < nc * m; ++j) {
    for (const auto& [row, w] : rows[static_cast<size_t>(j)]) selection(row, j) = w;
  }
  const Eigen::MatrixXd z =
      supernodal_lu_ ? supernodal_lu_->solve_columns(selection, false) : lu_->solve_columns(selection, false);
  for (Eigen::Index i = 0; i < nc * m; ++i) {  // P z
    for (const auto& [row, w] : rows[static_cast<size_t>(i)]) h.row(i) += w * z.row(row);
  }
  return h;
}

double KroneckerFactorization::norm1() const {
  if (norm1_ >= 0.0) return norm1_;
  if (setup_->modal || setup_->by_components) {
    const MechanicalSystem& system = *operator_.system;
    const TimeOperators& ops = *operator_.ops;
    const double fr = operator_.frequency_hz;
    norm1_ = kronecker_norm1({Eigen::SparseMatrix<double>((fr * fr * ops.mass).sparseView()),
                              Eigen::SparseMatrix<double>((fr * ops.damping).sparseView()),
                              Eigen::SparseMatrix<double>(ops.stiffness.sparseView())},
                             {&system.mass, &system.damping, &system.stiffness});
    return norm1_;
  }
  norm1_ = 0.0;
  for (int k = 0; k < g_.outerSize(); ++k) {
    double s = 0.0;
    for (Eigen::SparseMatrix<double>::InnerIterator it(g_, k); it; ++it) s += std::abs(it.value());
    norm1_ = std::max(norm1_, s);
  }
  return norm1_;
}

}  // namespace wbm::solvers::detail
