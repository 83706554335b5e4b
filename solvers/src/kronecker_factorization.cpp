#include "kronecker_factorization.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <unsupported/Eigen/KroneckerProduct>

#include <wbm/spectral/layout.hpp>

namespace wbm::solvers::detail {
namespace {

// C = c_M M + c_K K by least squares in the Frobenius inner product; true if it fits to
// 1e-12 relative (the rod: c_K = β).
bool rayleigh_fit(const MechanicalSystem& s, double& c_m, double& c_k) {
  const auto dot = [](const Eigen::SparseMatrix<double>& a, const Eigen::SparseMatrix<double>& b) {
    return a.cwiseProduct(b).sum();
  };
  const double mm = dot(s.mass, s.mass), kk = dot(s.stiffness, s.stiffness), mk = dot(s.mass, s.stiffness);
  const double cm = dot(s.damping, s.mass), ck = dot(s.damping, s.stiffness);
  const double det = mm * kk - mk * mk;
  const double cc = dot(s.damping, s.damping);
  if (cc == 0.0) {
    c_m = c_k = 0.0;
    return true;
  }
  if (!(std::abs(det) > 1e-14 * mm * kk)) return false;  // M ∝ K: ambiguous, use the general path
  c_m = (cm * kk - ck * mk) / det;
  c_k = (ck * mm - cm * mk) / det;
  const Eigen::SparseMatrix<double> rest = s.damping - c_m * s.mass - c_k * s.stiffness;
  return std::sqrt(dot(rest, rest)) <= 1e-12 * std::sqrt(cc);
}

// Connected components of the graph i ~ j if any of the time operators couples i and j
// (union-find); a single component is returned as an empty list.
std::vector<std::vector<Eigen::Index>> block_components(const TimeOperators& ops) {
  const Eigen::Index m = ops.mass.rows();
  std::vector<Eigen::Index> parent(static_cast<size_t>(m));
  for (Eigen::Index i = 0; i < m; ++i) parent[static_cast<size_t>(i)] = i;
  auto find = [&](Eigen::Index i) {
    while (parent[static_cast<size_t>(i)] != i) i = parent[static_cast<size_t>(i)];
    return i;
  };
  for (Eigen::Index j = 0; j < m; ++j) {
    for (Eigen::Index i = 0; i < m; ++i) {
      if (ops.mass(i, j) != 0.0 || ops.damping(i, j) != 0.0 || ops.stiffness(i, j) != 0.0) {
        parent[static_cast<size_t>(find(i))] = find(j);
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

// Distributional form with a Fourier weighting basis {1, cos 2πkτ, sin 2πkτ, …, cos πMτ}: the
// weighting functions' derivatives stay in the basis, p̈_j = −ω_j² p_j for every j and
// ṗ = D₁ p for every row but the last (cos πMτ, whose derivative sin πMτ is not in the basis), so
//   A_M = D₂ A_K,   A_C = −D₁ A_K + e_L c_Lᵀ,   c_L = last row of A_C,
// whatever the trial basis and whether A is exact or discrete (checked at set-up). A modal block
// is then f² A_M + f c_i A_C + λ_i A_K = (P_i + γ_i e_L gᵀ) A_K with
//   P_i = f² D₂ − f c_i D₁ + λ_i I (1 × 1 and 2 × 2 blocks per harmonic),  γ_i = f c_i,  gᵀ = c_Lᵀ A_K⁻¹,
// whose inverse A_K⁻¹ S_i, S_i = P_i⁻¹ − γ_i P_i⁻¹ e_L gᵀ P_i⁻¹ / (1 + γ_i gᵀ P_i⁻¹ e_L)
// (Sherman–Morrison) costs O(M²) instead of the O(M³) dense LU and inverse.
// When the last row of A_K vanishes (Haar trial functions: cos πMτ integrates to zero over every
// Haar cell), A_K is singular but the block is Q_i N with N = A_K with its last row replaced by
// c_Lᵀ and Q_i = diag(P_i without its last row and column, γ_i): then S_i = Q_i⁻¹, left factor N⁻¹.
struct FourierWeighting {
  Eigen::MatrixXd ak_inv;   // A_K⁻¹, or N⁻¹ when replaced_last_row (dense, frequency independent)
  Eigen::VectorXd g;        // A_K⁻ᵀ c_L (Sherman–Morrison form only)
  Eigen::VectorXd omega;    // ω_j = 2πk_j of weighting function j (0 for the constant)
  bool replaced_last_row = false;

  // Returns nullopt unless the identities hold to 1e-10 relative and A_K is well conditioned.
  static std::optional<FourierWeighting> detect(const TimeOperators& ops) {
    const Eigen::Index m = ops.stiffness.rows();
    if (m < 4 || m % 2 == 1) return std::nullopt;  // the M = 2^J form, with its top function
    FourierWeighting fw;
    fw.omega = Eigen::VectorXd::Zero(m);
    for (Eigen::Index j = 1; j < m - 1; ++j) fw.omega(j) = 2.0 * std::numbers::pi * static_cast<double>((j + 1) / 2);
    fw.omega(m - 1) = std::numbers::pi * static_cast<double>(m);
    const Eigen::MatrixXd d2ak = -(fw.omega.array().square().matrix().asDiagonal() * ops.stiffness);
    Eigen::MatrixXd d1ak = Eigen::MatrixXd::Zero(m, m);  // D₁ A_K: row 2k−1 (cos) ← −ω sin row, row 2k ← ω cos row
    for (Eigen::Index j = 1; j + 1 < m; j += 2) {
      d1ak.row(j) = -fw.omega(j) * ops.stiffness.row(j + 1);
      d1ak.row(j + 1) = fw.omega(j) * ops.stiffness.row(j);
    }
    const double sm = ops.mass.cwiseAbs().maxCoeff(), sc = ops.damping.cwiseAbs().maxCoeff();
    if (!((ops.mass - d2ak).cwiseAbs().maxCoeff() <= 1e-10 * sm)) return std::nullopt;
    if (!((ops.damping + d1ak).topRows(m - 1).cwiseAbs().maxCoeff() <= 1e-10 * sc)) return std::nullopt;
    const Eigen::PartialPivLU<Eigen::MatrixXd> lu(ops.stiffness);
    if (lu.rcond() > 1e-12) {
      fw.ak_inv = lu.inverse();
      fw.g = fw.ak_inv.transpose() * ops.damping.row(m - 1).transpose();
      return fw;
    }
    if (!(ops.stiffness.row(m - 1).cwiseAbs().maxCoeff() <= 1e-12 * ops.stiffness.cwiseAbs().maxCoeff())) {
      return std::nullopt;
    }
    Eigen::MatrixXd n = ops.stiffness;
    n.row(m - 1) = ops.damping.row(m - 1);
    const Eigen::PartialPivLU<Eigen::MatrixXd> nlu(n);
    if (!(nlu.rcond() > 1e-12)) return std::nullopt;
    fw.ak_inv = nlu.inverse();
    fw.replaced_last_row = true;
    return fw;
  }

  // S_i (dense M × M) for the block f² A_M + f c A_C + λ A_K.
  [[nodiscard]] Eigen::MatrixXd core(double f, double c, double lambda) const {
    const Eigen::Index m = omega.size(), last = m - 1;
    Eigen::MatrixXd pinv = Eigen::MatrixXd::Zero(m, m);  // P⁻¹
    pinv(0, 0) = 1.0 / lambda;
    for (Eigen::Index j = 1; j + 1 < m; j += 2) {
      // P on (cos, sin): [[a, b], [−b, a]] with a = λ − f² ω², b = f c ω (from −f c D₁).
      const double a = lambda - f * f * omega(j) * omega(j), b = f * c * omega(j);
      const double det = a * a + b * b;
      pinv(j, j) = a / det;
      pinv(j, j + 1) = -b / det;
      pinv(j + 1, j) = b / det;
      pinv(j + 1, j + 1) = a / det;
    }
    const double gamma = f * c;
    if (replaced_last_row) {
      pinv(last, last) = 1.0 / gamma;  // inf without damping: the block is singular (reported)
      return pinv;
    }
    const double p_last = lambda - f * f * omega(last) * omega(last);
    pinv(last, last) = 1.0 / p_last;
    const Eigen::RowVectorXd gp = g.transpose() * pinv;  // gᵀ P⁻¹
    const double denominator = 1.0 + gamma * g(last) / p_last;
    pinv.row(last) -= (gamma / (p_last * denominator)) * gp;  // − γ P⁻¹ e_L gᵀ P⁻¹ / (1 + γ gᵀ P⁻¹ e_L)
    return pinv;
  }
};

// ‖G‖₁ from the Kronecker factors t = (f² A_M, f A_C, A_K) and x = (M, C, K), G not formed.
double kronecker_norm1(const std::array<Eigen::MatrixXd, 3>& t, const std::array<const Eigen::SparseMatrix<double>*, 3>& x) {
  const auto n = x[0]->cols();
  const auto m = t[0].rows();
  double best = 0.0;
  for (Eigen::Index j = 0; j < n; ++j) {
    Eigen::VectorXd colsum = Eigen::VectorXd::Zero(m);  // over k
    // Rows i present in column j of any of M, C, K.
    std::vector<Eigen::Index> rows;
    for (const auto* xs : x) {
      for (Eigen::SparseMatrix<double>::InnerIterator it(*xs, j); it; ++it) rows.push_back(it.row());
    }
    std::sort(rows.begin(), rows.end());
    rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
    for (const Eigen::Index i : rows) {
      Eigen::MatrixXd comb = Eigen::MatrixXd::Zero(m, m);
      for (int s = 0; s < 3; ++s) {
        const double v = x[s]->coeff(i, j);
        if (v != 0.0) comb += v * t[s];
      }
      colsum += comb.cwiseAbs().colwise().sum().transpose();
    }
    best = std::max(best, colsum.maxCoeff());
  }
  return best;
}

}  // namespace

// One modal block A + λ_i B (M × M). Its sparsity graph is split into connected components
// first: Fourier:Fourier blocks fall apart into the 1 × 1 and 2 × 2 blocks of each harmonic,
// which are inverted densely (O(M) per block). A block that stays connected is factorized by
// sparse LU when it is sparse (banded circulant wavelet Galerkin operators) and by dense
// partial-pivoting LU otherwise (discrete Petrov–Galerkin).
class KroneckerFactorization::ModeBlock {
 public:
  using Components = std::vector<std::vector<Eigen::Index>>;

  /// `components`: connected components of the sparsity graph shared by every mode's block
  /// (block_components()); empty or a single one: no splitting.
  ModeBlock(const Eigen::MatrixXd& block, const Components& components) : m_(block.rows()), component_(&components) {
    if (components.size() > 1) {  // block diagonal after permutation
      ok_ = true;
      inverse_.reserve(components.size());
      for (const auto& idx : components) {
        const auto k = static_cast<Eigen::Index>(idx.size());
        Eigen::MatrixXd sub(k, k);
        for (Eigen::Index i = 0; i < k; ++i) {
          for (Eigen::Index j = 0; j < k; ++j) sub(i, j) = block(idx[i], idx[j]);
        }
        if (k <= 2) {  // closed-form inverse; singular if the determinant vanishes against the entries
          const double scale = sub.cwiseAbs().maxCoeff();
          const double det = k == 1 ? sub(0, 0) : sub(0, 0) * sub(1, 1) - sub(0, 1) * sub(1, 0);
          if (!(std::abs(det) > 1e-300 + 1e-15 * (k == 1 ? scale : scale * scale)) || !std::isfinite(det)) ok_ = false;
          Eigen::MatrixXd inv(k, k);
          if (k == 1) {
            inv(0, 0) = 1.0 / det;
          } else {
            inv << sub(1, 1) / det, -sub(0, 1) / det, -sub(1, 0) / det, sub(0, 0) / det;
          }
          inverse_.push_back(std::move(inv));
        } else {
          const Eigen::PartialPivLU<Eigen::MatrixXd> lu(sub);
          const double rc = lu.rcond();
          if (!(rc > 1e-300 && std::isfinite(rc))) ok_ = false;
          inverse_.push_back(lu.inverse());
        }
      }
      return;
    }
    const double density = static_cast<double>((block.array() != 0.0).count()) / static_cast<double>(block.size());
    sparse_ = block.rows() > 8 && density <= 0.25;
    if (sparse_) {
      sparse_lu_ = std::make_unique<SparseLu>();
      const Eigen::SparseMatrix<double> s = block.sparseView();
      sparse_lu_->analyzePattern(s);
      sparse_lu_->factorize(s);
      ok_ = sparse_lu_->info() == Eigen::Success;
    } else {
      dense_lu_.compute(block);
      const double rc = dense_lu_.rcond();
      ok_ = rc > 1e-300 && std::isfinite(rc);
    }
  }
  /// Factored block (A_K⁻¹ S)⁻¹ given S = its core and the shared left factor A_K⁻¹ (see
  /// FourierWeighting): solve and inverse apply A_K⁻¹ S.
  ModeBlock(Eigen::MatrixXd core, const Eigen::MatrixXd* left)
      : m_(core.rows()), component_(nullptr), left_(left), core_(std::move(core)) {
    ok_ = core_.allFinite();
  }
  [[nodiscard]] bool ok() const { return ok_; }
  [[nodiscard]] bool factored() const { return left_ != nullptr; }
  [[nodiscard]] const Eigen::MatrixXd& core() const { return core_; }
  [[nodiscard]] Eigen::MatrixXd solve(const Eigen::MatrixXd& r, bool transposed) const {
    if (left_ != nullptr) {
      return transposed ? Eigen::MatrixXd(core_.transpose() * (left_->transpose() * r)) : Eigen::MatrixXd(*left_ * (core_ * r));
    }
    if (!inverse_.empty()) {
      Eigen::MatrixXd out(r.rows(), r.cols());
      for (size_t c = 0; c < component_->size(); ++c) {
        const auto& idx = (*component_)[c];
        const auto k = static_cast<Eigen::Index>(idx.size());
        Eigen::MatrixXd rhs(k, r.cols());
        for (Eigen::Index i = 0; i < k; ++i) rhs.row(i) = r.row(idx[i]);
        const Eigen::MatrixXd y = transposed ? Eigen::MatrixXd(inverse_[c].transpose() * rhs) : Eigen::MatrixXd(inverse_[c] * rhs);
        for (Eigen::Index i = 0; i < k; ++i) out.row(idx[i]) = y.row(i);
      }
      return out;
    }
    if (sparse_) return transposed ? Eigen::MatrixXd(sparse_lu_->transpose().solve(r)) : Eigen::MatrixXd(sparse_lu_->solve(r));
    return transposed ? Eigen::MatrixXd(dense_lu_.transpose().solve(r)) : Eigen::MatrixXd(dense_lu_.solve(r));
  }
  /// The inverse, M × M (dense storage; only the components' entries are nonzero).
  [[nodiscard]] Eigen::MatrixXd inverse() const {
    if (left_ != nullptr) return *left_ * core_;
    if (inverse_.empty()) return solve(Eigen::MatrixXd::Identity(m_, m_), false);
    Eigen::MatrixXd out = Eigen::MatrixXd::Zero(m_, m_);
    for (size_t c = 0; c < component_->size(); ++c) {
      const auto& idx = (*component_)[c];
      for (size_t i = 0; i < idx.size(); ++i) {
        for (size_t j = 0; j < idx.size(); ++j) out(idx[i], idx[j]) = inverse_[c](static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
      }
    }
    return out;
  }

 private:
  using SparseLu = Eigen::SparseLU<Eigen::SparseMatrix<double>, Eigen::COLAMDOrdering<int>>;
  Eigen::Index m_;
  bool sparse_ = false, ok_ = false;
  const Components* component_;
  std::vector<Eigen::MatrixXd> inverse_;  // per component, when split
  const Eigen::MatrixXd* left_ = nullptr;  // factored: A_K⁻¹ (shared) ...
  Eigen::MatrixXd core_;                   // ... and S, the block's inverse being A_K⁻¹ S
  std::unique_ptr<SparseLu> sparse_lu_;  // SparseLU::transpose() is not const; held by pointer
  Eigen::PartialPivLU<Eigen::MatrixXd> dense_lu_;
};

// The frequency-independent part, shared by the factorizations at every frequency (ModeBlock
// keeps pointers into it, so it lives on the heap and never moves).
struct KroneckerFactorization::Setup {
  bool modal = false;
  double c_m = 0.0, c_k = 0.0;     // C = c_M M + c_K K (modal path)
  Eigen::MatrixXd phi;             // n × n, Φᵀ M Φ = I (modal path)
  Eigen::VectorXd lambda;
  std::vector<std::vector<Eigen::Index>> components;  // of the time operators' sparsity graph
  std::optional<FourierWeighting> fourier_weighting;  // distributional form, Fourier weighting
};

KroneckerFactorization::KroneckerFactorization(std::shared_ptr<const Setup> setup) : setup_(std::move(setup)) {}

KroneckerFactorization::KroneckerFactorization(const MechanicalSystem& system, const TimeOperators& ops,
                                               LinearSolverPath path, bool fourier_weighting) {
  auto setup = std::make_shared<Setup>();
  const bool rayleigh = rayleigh_fit(system, setup->c_m, setup->c_k);
  switch (path) {
    case LinearSolverPath::Automatic: setup->modal = rayleigh; break;
    case LinearSolverPath::SparseLU: setup->modal = false; break;
    case LinearSolverPath::Modal:
      if (!rayleigh) {
        throw std::invalid_argument("LinearSolverPath::Modal needs Rayleigh damping C = c_M M + c_K K; this C is "
                                    "not (use LinearSolverPath::SparseLU or Automatic)");
      }
      setup->modal = true;
      break;
  }
  if (setup->modal) {
    const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(Eigen::MatrixXd(system.stiffness),
                                                                        Eigen::MatrixXd(system.mass));
    if (eig.info() != Eigen::Success) {
      throw std::invalid_argument("modal solve: K Φ = M Φ Λ failed (is M symmetric positive definite?); use "
                                  "LinearSolverPath::SparseLU");
    }
    setup->phi = eig.eigenvectors();
    setup->lambda = eig.eigenvalues();
    setup->components = block_components(ops);
    if (fourier_weighting) setup->fourier_weighting = FourierWeighting::detect(ops);
  }
  setup_ = std::move(setup);
}

KroneckerFactorization KroneckerFactorization::unfactorized() const { return KroneckerFactorization(setup_); }

bool KroneckerFactorization::modal() const { return setup_->modal; }

bool KroneckerFactorization::factorize(const MechanicalSystem& system, const TimeOperators& ops, double fr) {
  const Setup& su = *setup_;
  frequency_hz_ = fr;
  norm1_ = -1.0;
  factorized_ = false;
  blocks_.clear();
  if (su.modal) {
    const Eigen::MatrixXd a = fr * fr * ops.mass + fr * su.c_m * ops.damping;
    const Eigen::MatrixXd bb = fr * su.c_k * ops.damping + ops.stiffness;
    const auto n = su.lambda.size();
    blocks_.reserve(static_cast<size_t>(n));
    factorized_ = true;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (su.fourier_weighting) {
        blocks_.push_back(std::make_shared<const ModeBlock>(
            su.fourier_weighting->core(fr, su.c_m + su.lambda(i) * su.c_k, su.lambda(i)), &su.fourier_weighting->ak_inv));
      } else {
        blocks_.push_back(std::make_shared<const ModeBlock>(a + su.lambda(i) * bb, su.components));
      }
      if (!blocks_.back()->ok()) factorized_ = false;
    }
    return factorized_;
  }
  g_ = Eigen::kroneckerProduct(Eigen::SparseMatrix<double>((fr * fr * ops.mass).sparseView()), system.mass).eval();
  g_ += Eigen::kroneckerProduct(Eigen::SparseMatrix<double>((fr * ops.damping).sparseView()), system.damping).eval();
  g_ += Eigen::kroneckerProduct(Eigen::SparseMatrix<double>(ops.stiffness.sparseView()), system.stiffness).eval();
  g_.makeCompressed();
  lu_ = std::make_shared<Eigen::SparseLU<Eigen::SparseMatrix<double>, Eigen::COLAMDOrdering<int>>>();
  lu_->analyzePattern(g_);
  lu_->factorize(g_);
  factorized_ = lu_->info() == Eigen::Success;
  return factorized_;
}

Eigen::VectorXd KroneckerFactorization::solve(const Eigen::VectorXd& v, bool transposed) const {
  if (!setup_->modal) return transposed ? Eigen::VectorXd(lu_->transpose().solve(v)) : Eigen::VectorXd(lu_->solve(v));
  const auto n = setup_->phi.rows();
  const auto m = v.size() / n;
  const Eigen::MatrixXd modal_rhs = setup_->phi.transpose() * spectral::as_coefficients(v, n);  // n × M
  Eigen::MatrixXd y(n, m);
  for (Eigen::Index i = 0; i < n; ++i) y.row(i) = blocks_[i]->solve(modal_rhs.row(i).transpose(), transposed).transpose();
  return spectral::stacked(setup_->phi * y);
}

Eigen::MatrixXd KroneckerFactorization::compliance(const std::vector<int>& contact_dofs,
                                                   const std::vector<Eigen::Index>& contact_rows) const {
  const int nc = static_cast<int>(contact_dofs.size());
  const auto m = static_cast<Eigen::Index>(contact_rows.size()) / std::max(nc, 1);
  Eigen::MatrixXd h(nc * m, nc * m);
  const Setup& su = *setup_;
  if (su.modal && su.fourier_weighting) {  // H_cd = A_K⁻¹ Σ_i φ_i(c) φ_i(d) S_i: one product per contact pair
    for (int c = 0; c < nc; ++c) {
      for (int d = 0; d < nc; ++d) {
        Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(m, m);
        for (size_t i = 0; i < blocks_.size(); ++i) {
          sum += (su.phi(contact_dofs[c], static_cast<Eigen::Index>(i)) * su.phi(contact_dofs[d], static_cast<Eigen::Index>(i))) *
                 blocks_[i]->core();
        }
        const Eigen::MatrixXd hcd = su.fourier_weighting->ak_inv * sum;
        for (Eigen::Index l = 0; l < m; ++l) {
          for (Eigen::Index k = 0; k < m; ++k) h(k * nc + c, l * nc + d) = hcd(k, l);
        }
      }
    }
    return h;
  }
  if (su.modal) {
    h.setZero();
    for (size_t i = 0; i < blocks_.size(); ++i) {
      const Eigen::MatrixXd s_i = blocks_[i]->inverse();
      for (int c = 0; c < nc; ++c) {
        for (int d = 0; d < nc; ++d) {
          const double w = su.phi(contact_dofs[c], static_cast<Eigen::Index>(i)) * su.phi(contact_dofs[d], static_cast<Eigen::Index>(i));
          for (Eigen::Index l = 0; l < m; ++l) {
            for (Eigen::Index k = 0; k < m; ++k) h(k * nc + c, l * nc + d) += w * s_i(k, l);
          }
        }
      }
    }
    return h;
  }
  Eigen::MatrixXd selection = Eigen::MatrixXd::Zero(g_.rows(), nc * m);
  for (Eigen::Index j = 0; j < nc * m; ++j) selection(contact_rows[static_cast<size_t>(j)], j) = 1.0;
  const Eigen::MatrixXd z = lu_->solve(selection);
  for (Eigen::Index i = 0; i < nc * m; ++i) h.row(i) = z.row(contact_rows[static_cast<size_t>(i)]);
  return h;
}

double KroneckerFactorization::norm1(const MechanicalSystem& system, const TimeOperators& ops) const {
  if (norm1_ >= 0.0) return norm1_;
  if (setup_->modal) {
    const double fr = frequency_hz_;
    norm1_ = kronecker_norm1({fr * fr * ops.mass, fr * ops.damping, ops.stiffness},
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
