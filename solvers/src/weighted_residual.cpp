#include <wbm/solvers/weighted_residual.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/SparseLU>
#include <unsupported/Eigen/KroneckerProduct>

#include <wbm/spectral/aft.hpp>
#include <wbm/spectral/layout.hpp>
#include <wbm/wavelets/connection_coefficients.hpp>

#include "one_norm_estimate.hpp"

namespace wbm::solvers {
namespace {

// One term of [JL14 Eqs. (14)–(16)]: sign · ∫ p^{(weighting)} q^{(trial)} dτ.
struct Term {
  int weighting, trial;
  double sign;
  const char* text;  // the integral as written in the paper
};

// Mass, damping, stiffness terms of each formulation.
std::array<Term, 3> terms(Formulation f) {
  switch (f) {
    case Formulation::Strong:
      return {{{0, 2, 1.0, "∫ p M q̈ (Eq. 14)"}, {0, 1, 1.0, "∫ p C q̇ (Eq. 14)"}, {0, 0, 1.0, "∫ p K q"}}};
    case Formulation::Weak:
      return {{{1, 1, -1.0, "−∫ ṗ M q̇ (Eq. 15)"}, {0, 1, 1.0, "∫ p C q̇ (Eq. 15)"}, {0, 0, 1.0, "∫ p K q"}}};
    case Formulation::Distributional:
      return {{{2, 0, 1.0, "∫ p̈ M q (Eq. 16)"}, {1, 0, -1.0, "−∫ ṗ C q (Eq. 16)"}, {0, 0, 1.0, "∫ p K q"}}};
  }
  throw std::logic_error("unknown formulation");
}

bool exact_rule(const TimeBasis& trial, const TimeBasis& weighting, OperatorRule rule) {
  return rule == OperatorRule::Automatic && trial.same_family(weighting);
}

int connection_limit(const TimeBasis& b) {
  return b.is_fourier() ? 2 : wavelets::max_connection_order(b.wavelet_basis()->family());
}

std::string why_term(const TimeBasis& trial, const TimeBasis& weighting, Formulation f, OperatorRule rule,
                     const Term& t) {
  std::ostringstream os;
  if (exact_rule(trial, weighting, rule)) {
    const int limit = connection_limit(trial);
    if (t.weighting + t.trial > limit) {
      os << trial.name() << ":" << weighting.name() << " (Galerkin, connection coefficients), "
         << to_string(f) << " form: the term " << t.text << " needs ∫ φ^(" << t.weighting << ") φ^(" << t.trial
         << "), order " << t.weighting + t.trial << ", but " << trial.name()
         << " admits connection coefficients up to order " << limit;
    }
    return os.str();
  }
  if (t.trial > trial.max_derivative()) {
    os << trial.name() << ":" << weighting.name() << ", " << to_string(f) << " form: the trial basis "
       << trial.name() << " has no pointwise derivative of order " << t.trial << " (largest: "
       << trial.max_derivative() << "), needed by the term " << t.text;
  } else if (t.weighting > weighting.max_derivative()) {
    os << trial.name() << ":" << weighting.name() << ", " << to_string(f) << " form: the weighting basis "
       << weighting.name() << " has no pointwise derivative of order " << t.weighting << " (largest: "
       << weighting.max_derivative() << "), needed by the term " << t.text;
  }
  return os.str();
}

std::string why_not(const TimeBasis& trial, const TimeBasis& weighting, Formulation f, OperatorRule rule) {
  for (const Term& t : terms(f)) {
    std::string w = why_term(trial, weighting, f, rule, t);
    if (!w.empty()) return w;
  }
  return {};
}

double elapsed(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

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

}  // namespace

std::string_view to_string(Formulation f) noexcept {
  switch (f) {
    case Formulation::Strong: return "strong";
    case Formulation::Weak: return "weak";
    case Formulation::Distributional: return "distributional";
  }
  return "unknown";
}

Formulation parse_formulation(const std::string& name) {
  for (Formulation f : {Formulation::Strong, Formulation::Weak, Formulation::Distributional}) {
    if (name == to_string(f)) return f;
  }
  throw std::invalid_argument("formulation '" + name + "' is unknown; use strong (JL14 Eq. 14), weak (Eq. 15) "
                              "or distributional (Eq. 16)");
}

std::string inadmissibility(const TimeBasis& trial, const TimeBasis& weighting, Formulation formulation,
                            OperatorRule rule) {
  std::string why = why_not(trial, weighting, formulation, rule);
  if (why.empty()) return why;
  std::string alternatives;
  for (Formulation f : {Formulation::Strong, Formulation::Weak, Formulation::Distributional}) {
    if (f != formulation && why_not(trial, weighting, f, rule).empty()) {
      alternatives += std::string(alternatives.empty() ? "" : " or ") + "the " + std::string(to_string(f)) + " form";
    }
  }
  why += alternatives.empty()
             ? "; no formulation admits this pair: pair the basis with a smooth one (e.g. Haar:Fourier or "
               "Haar:B-spline in the distributional form)"
             : "; use " + alternatives + " instead";
  return why;
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

// One modal block A + λ_i B (M × M). Its sparsity graph is split into connected components
// first: Fourier:Fourier blocks fall apart into the 1 × 1 and 2 × 2 blocks of each harmonic,
// which are inverted densely (O(M) per block). A block that stays connected is factorized by
// sparse LU when it is sparse (banded circulant wavelet Galerkin operators) and by dense
// partial-pivoting LU otherwise (discrete Petrov–Galerkin).
class ModeBlock {
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
    if (m < 4) return std::nullopt;
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

struct WeightedResidual::Impl {
  MechanicalSystem system;
  HarmonicForcing forcing;
  std::vector<ContactPoint> contacts;
  TimeBasis trial, weighting;
  WeightedResidualOptions options;
  int n, m, q, nc;
  TimeOperators ops;

  // Samples τ_q = (q + ½)/Q: theta(q, k) = q_k(τ_q) (trial), wq(q, j) = p_j(τ_q) / Q (weighting).
  Eigen::MatrixXd theta, wq;
  std::vector<std::vector<int>> theta_nz, wq_nz;  // nonzero columns of each row
  bool sparse_rows = false;                       // rows have compact support (N by loops)
  // FFTW on the same midpoint samples, when the trial or the weighting basis is Fourier: u_c(τ_q)
  // (Fourier trial), the projection of the sampled forces (Fourier weighting) and, for
  // Fourier:Fourier, the contact Jacobian blocks (Aft::jacobian) in O(Q log Q) instead of O(QM)
  // and O(QM²). Shared with at_frequency copies (const use only).
  std::shared_ptr<const spectral::Aft> aft;

  // Linear solve with G.
  bool modal = false;
  bool factorized = false;
  Eigen::SparseMatrix<double> g;  // SparseLU path only
  // mutable: Eigen 3.4 SparseLU::transpose() is not const (it only stores a pointer).
  mutable Eigen::SparseLU<Eigen::SparseMatrix<double>, Eigen::COLAMDOrdering<int>> lu;
  Eigen::MatrixXd phi;            // modal path: n × n, Φᵀ M Φ = I
  Eigen::VectorXd lambda;
  std::vector<ModeBlock> blocks;
  std::vector<std::vector<Eigen::Index>> components;  // of the time operators' sparsity graph
  std::optional<FourierWeighting> fourier_weighting;  // distributional form, Fourier weighting
  mutable double g_norm1 = 0.0;  // < 0: not computed yet

  Eigen::VectorXd b, a_lin, x_lin;
  Eigen::MatrixXd h;
  double scale = 1.0;
  std::vector<Eigen::Index> contact_rows;  // row in a of contact unknown x(k·n_c + c)

  Impl(MechanicalSystem s, HarmonicForcing f, std::vector<ContactPoint> c, TimeBasis tr, TimeBasis we,
       WeightedResidualOptions o)
      : system(std::move(s)), forcing(f), contacts(std::move(c)), trial(std::move(tr)), weighting(std::move(we)),
        options(o) {
    system.validate();
    forcing.validate(system.dofs());
    ContactPoint::validate(contacts, system.dofs());
    n = system.dofs();
    m = trial.dimension();
    nc = static_cast<int>(contacts.size());
    if (weighting.dimension() != m) {
      throw std::invalid_argument("weighted residual: trial " + trial.name() + " has M = " + std::to_string(m) +
                                  " functions but weighting " + weighting.name() + " has " +
                                  std::to_string(weighting.dimension()) + "; use one dimension M for both");
    }
    if (!(options.residual_tolerance > 0.0)) {
      throw std::invalid_argument("WeightedResidualOptions.residual_tolerance = " +
                                  format_number(options.residual_tolerance) +
                                  ": must be > 0 (a relative bound on the full residual, e.g. 1e-8)");
    }
    if (options.time_samples < 0 || (options.time_samples > 0 && options.time_samples < m)) {
      throw std::invalid_argument("WeightedResidualOptions.time_samples Q = " + std::to_string(options.time_samples) +
                                  ": must be 0 (automatic, max(256, 2M)) or >= M = " + std::to_string(m));
    }
    q = options.time_samples > 0 ? options.time_samples : std::max(256, 2 * m);
    const std::string why = inadmissibility(trial, weighting, options.formulation, options.operators);
    if (!why.empty()) throw std::invalid_argument(why);

    Eigen::VectorXd tau(q);
    for (int k = 0; k < q; ++k) tau(k) = (k + 0.5) / q;
    theta = trial.values(tau, 0);
    wq = weighting.values(tau, 0) / static_cast<double>(q);
    assemble_time_operators(tau);
    sample_structure();
    if (trial.is_fourier() || weighting.is_fourier()) aft = std::make_shared<const spectral::Aft>(m, q, 0.5);
    components = block_components(ops);
    if (weighting.is_fourier() && !trial.is_fourier() && options.formulation == Formulation::Distributional) {
      fourier_weighting = FourierWeighting::detect(ops);
    }

    Eigen::VectorXd cosine(q);
    for (int k = 0; k < q; ++k) cosine(k) = std::cos(2.0 * std::numbers::pi * tau(k));
    Eigen::MatrixXd bm = Eigen::MatrixXd::Zero(n, m);
    bm.row(forcing.dof) = forcing.amplitude * (wq.transpose() * cosine).transpose();
    b = spectral::stacked(bm);

    contact_rows.resize(static_cast<size_t>(nc) * m);
    for (int k = 0; k < m; ++k) {
      for (int c = 0; c < nc; ++c) {
        contact_rows[static_cast<size_t>(k) * nc + c] = spectral::stacked_index(k, contacts[c].dof, n);
      }
    }

    factorize();
    if (!factorized) return;
    a_lin = solve_stacked(b, false);
    x_lin = gather(a_lin);
    if (nc > 0) {
      compliance();
      double gmax = 0.0;
      for (const auto& ct : contacts) gmax = std::max(gmax, std::abs(ct.law->gap()));
      scale = gmax > 0.0 ? gmax : x_lin.lpNorm<Eigen::Infinity>();
      if (!(scale > 0.0) || !std::isfinite(scale)) scale = 1.0;
    }
  }

  // The same problem at another frequency: every frequency-independent member is copied (time
  // operators, samples, b, modal basis, residual scale); only G is factorized again.
  Impl(const Impl& base, double frequency_hz)
      : system(base.system), forcing(base.forcing), contacts(base.contacts), trial(base.trial),
        weighting(base.weighting), options(base.options), n(base.n), m(base.m), q(base.q), nc(base.nc),
        ops(base.ops), theta(base.theta), wq(base.wq), theta_nz(base.theta_nz), wq_nz(base.wq_nz),
        sparse_rows(base.sparse_rows), aft(base.aft), phi(base.phi), lambda(base.lambda), components(base.components),
        fourier_weighting(base.fourier_weighting), b(base.b),
        scale(base.scale),
        contact_rows(base.contact_rows) {
    forcing.frequency_hz = frequency_hz;
    forcing.validate(n);
    factorize();
    if (!factorized) return;
    a_lin = solve_stacked(b, false);
    x_lin = gather(a_lin);
    if (nc > 0) compliance();
  }

  void assemble_time_operators(const Eigen::VectorXd& tau) {
    const auto ts = terms(options.formulation);
    const bool exact = exact_rule(trial, weighting, options.operators);
    std::array<Eigen::MatrixXd, 3> a;
    std::array<Eigen::MatrixXd, 3> pw, qt;  // values by derivative order, computed once
    for (int t = 0; t < 3; ++t) {
      const Term& term = ts[t];
      if (exact) {
        a[t] = term.sign * Eigen::MatrixXd(trial.exact_operator(term.weighting, term.trial));
      } else {
        if (pw[term.weighting].size() == 0) pw[term.weighting] = weighting.values(tau, term.weighting);
        if (qt[term.trial].size() == 0) qt[term.trial] = trial.values(tau, term.trial);
        a[t] = (term.sign / q) * (pw[term.weighting].transpose() * qt[term.trial]);
      }
    }
    ops.mass = std::move(a[0]);
    ops.damping = std::move(a[1]);
    ops.stiffness = std::move(a[2]);
    ops.rule = exact ? (trial.is_fourier() ? "exact (analytic)" : "exact (connection coefficients)")
                     : "discrete, Q = " + std::to_string(q) + " midpoints";
  }

  void sample_structure() {
    theta_nz.assign(q, {});
    wq_nz.assign(q, {});
    long nnz = 0;
    for (int r = 0; r < q; ++r) {
      for (int k = 0; k < m; ++k) {
        if (theta(r, k) != 0.0) theta_nz[r].push_back(k);
        if (wq(r, k) != 0.0) wq_nz[r].push_back(k);
      }
      nnz += static_cast<long>(theta_nz[r].size() * wq_nz[r].size());
    }
    sparse_rows = nnz < static_cast<long>(q) * m * m / 8;
  }

  // ‖G‖₁ from the Kronecker factors (G itself is not formed on the modal path).
  [[nodiscard]] double kronecker_norm1(const std::array<Eigen::MatrixXd, 3>& t,
                                       const std::array<const Eigen::SparseMatrix<double>*, 3>& x) const {
    double best = 0.0;
    for (int j = 0; j < n; ++j) {
      Eigen::VectorXd colsum = Eigen::VectorXd::Zero(m);  // over k
      // Rows i present in column j of any of M, C, K.
      std::vector<int> rows;
      for (const auto* xs : x) {
        for (Eigen::SparseMatrix<double>::InnerIterator it(*xs, j); it; ++it) rows.push_back(static_cast<int>(it.row()));
      }
      std::sort(rows.begin(), rows.end());
      rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
      for (int i : rows) {
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

  void factorize() {
    const double fr = forcing.frequency_hz;
    const std::array<Eigen::MatrixXd, 3> t = {fr * fr * ops.mass, fr * ops.damping, ops.stiffness};
    double c_m = 0.0, c_k = 0.0;
    const bool rayleigh = rayleigh_fit(system, c_m, c_k);
    switch (options.linear_solver) {
      case LinearSolverPath::Automatic: modal = rayleigh; break;
      case LinearSolverPath::SparseLU: modal = false; break;
      case LinearSolverPath::Modal:
        if (!rayleigh) {
          throw std::invalid_argument("LinearSolverPath::Modal needs Rayleigh damping C = c_M M + c_K K; this C is "
                                      "not (use LinearSolverPath::SparseLU or Automatic)");
        }
        modal = true;
        break;
    }
    if (modal && phi.size() == 0) {  // the modal basis does not depend on f: computed once
      const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(Eigen::MatrixXd(system.stiffness),
                                                                          Eigen::MatrixXd(system.mass));
      if (eig.info() != Eigen::Success) {
        throw std::invalid_argument("modal solve: K Φ = M Φ Λ failed (is M symmetric positive definite?); use "
                                    "LinearSolverPath::SparseLU");
      }
      phi = eig.eigenvectors();
      lambda = eig.eigenvalues();
    }
    if (modal) {
      const Eigen::MatrixXd a = t[0] + fr * c_m * ops.damping;
      const Eigen::MatrixXd bb = fr * c_k * ops.damping + t[2];
      blocks.clear();
      factorized = true;
      blocks.reserve(static_cast<size_t>(n));
      for (int i = 0; i < n; ++i) {
        if (fourier_weighting) {
          blocks.emplace_back(fourier_weighting->core(fr, c_m + lambda(i) * c_k, lambda(i)), &fourier_weighting->ak_inv);
        } else {
          blocks.emplace_back(a + lambda(i) * bb, components);
        }
        if (!blocks.back().ok()) factorized = false;
      }
      g_norm1 = -1.0;  // ‖G‖₁ from the Kronecker factors on demand (condition_number), not per frequency
    } else {
      g = Eigen::kroneckerProduct(Eigen::SparseMatrix<double>(t[0].sparseView()), system.mass).eval();
      g += Eigen::kroneckerProduct(Eigen::SparseMatrix<double>(t[1].sparseView()), system.damping).eval();
      g += Eigen::kroneckerProduct(Eigen::SparseMatrix<double>(t[2].sparseView()), system.stiffness).eval();
      g.makeCompressed();
      lu.analyzePattern(g);
      lu.factorize(g);
      factorized = lu.info() == Eigen::Success;
      g_norm1 = 0.0;
      for (int k = 0; k < g.outerSize(); ++k) {
        double s = 0.0;
        for (Eigen::SparseMatrix<double>::InnerIterator it(g, k); it; ++it) s += std::abs(it.value());
        g_norm1 = std::max(g_norm1, s);
      }
    }
  }

  // G⁻¹ v (or G⁻ᵀ v) for a stacked v of length n·M.
  [[nodiscard]] Eigen::VectorXd solve_stacked(const Eigen::VectorXd& v, bool transposed) const {
    if (!modal) return transposed ? Eigen::VectorXd(lu.transpose().solve(v)) : Eigen::VectorXd(lu.solve(v));
    const Eigen::MatrixXd modal_rhs = phi.transpose() * spectral::as_coefficients(v, n);  // n × M
    Eigen::MatrixXd y(n, m);
    for (int i = 0; i < n; ++i) y.row(i) = blocks[i].solve(modal_rhs.row(i).transpose(), transposed).transpose();
    return spectral::stacked(phi * y);
  }

  // H = P G⁻¹ Pᵀ (n_c·M square, x ordering).
  void compliance() {
    h.resize(nc * m, nc * m);
    if (modal && fourier_weighting) {  // H_cd = A_K⁻¹ Σ_i φ_i(c) φ_i(d) S_i: one product per contact pair
      for (int c = 0; c < nc; ++c) {
        for (int d = 0; d < nc; ++d) {
          Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(m, m);
          for (int i = 0; i < n; ++i) sum += (phi(contacts[c].dof, i) * phi(contacts[d].dof, i)) * blocks[i].core();
          const Eigen::MatrixXd hcd = fourier_weighting->ak_inv * sum;
          for (int l = 0; l < m; ++l) {
            for (int k = 0; k < m; ++k) h(k * nc + c, l * nc + d) = hcd(k, l);
          }
        }
      }
      return;
    }
    if (modal) {
      h.setZero();
      for (int i = 0; i < n; ++i) {
        const Eigen::MatrixXd s_i = blocks[i].inverse();
        for (int c = 0; c < nc; ++c) {
          for (int d = 0; d < nc; ++d) {
            const double w = phi(contacts[c].dof, i) * phi(contacts[d].dof, i);
            for (int l = 0; l < m; ++l) {
              for (int k = 0; k < m; ++k) h(k * nc + c, l * nc + d) += w * s_i(k, l);
            }
          }
        }
      }
      return;
    }
    Eigen::MatrixXd selection = Eigen::MatrixXd::Zero(n * m, nc * m);
    for (int j = 0; j < nc * m; ++j) selection(contact_rows[j], j) = 1.0;
    const Eigen::MatrixXd z = lu.solve(selection);
    for (int i = 0; i < nc * m; ++i) h.row(i) = z.row(contact_rows[i]);
  }

  [[nodiscard]] Eigen::VectorXd gather(const Eigen::VectorXd& a) const {
    Eigen::VectorXd x(contact_rows.size());
    for (size_t j = 0; j < contact_rows.size(); ++j) x(static_cast<Eigen::Index>(j)) = a(contact_rows[j]);
    return x;
  }

  // Contact displacement samples U (n_c × Q) for stacked contact unknowns x.
  [[nodiscard]] Eigen::MatrixXd contact_samples(const Eigen::VectorXd& x) const {
    if (trial.is_fourier()) return aft->to_time(spectral::as_coefficients(x, nc));
    return spectral::as_coefficients(x, nc) * theta.transpose();
  }

  // n_c(x) = (1/Q) Σ_q p(τ_q) f_c(u_c(τ_q)) stacked like x; optionally N(x) (n_c·M square).
  Eigen::VectorXd contact_forces(const Eigen::VectorXd& x, Eigen::MatrixXd* jac) const {
    const Eigen::MatrixXd u = contact_samples(x);
    Eigen::MatrixXd force(nc, q);
    if (jac != nullptr) jac->setZero(nc * m, nc * m);
    Eigen::VectorXd fc(q), kc(q);
    for (int c = 0; c < nc; ++c) {
      contacts[c].law->evaluate(u.row(c).transpose(), fc, kc);
      force.row(c) = fc.transpose();
      if (jac == nullptr) continue;
      std::vector<int> active;
      for (int r = 0; r < q; ++r) {
        if (kc(r) != 0.0) active.push_back(r);
      }
      Eigen::MatrixXd block = Eigen::MatrixXd::Zero(m, m);  // block(j, k) = Σ_q w_j f' q_k
      if (active.empty()) {
        // no sample in contact: N_c = 0
      } else if (trial.is_fourier() && weighting.is_fourier()) {
        block = aft->jacobian(kc);
      } else if (sparse_rows) {
        for (int r : active) {
          for (int j : wq_nz[r]) {
            const double wj = wq(r, j) * kc(r);
            for (int k : theta_nz[r]) block(j, k) += wj * theta(r, k);
          }
        }
      } else {
        Eigen::MatrixXd wa(active.size(), m), ta(active.size(), m);
        for (size_t i = 0; i < active.size(); ++i) {
          wa.row(static_cast<Eigen::Index>(i)) = wq.row(active[i]) * kc(active[i]);
          ta.row(static_cast<Eigen::Index>(i)) = theta.row(active[i]);
        }
        block.noalias() = wa.transpose() * ta;
      }
      for (int k = 0; k < m; ++k) {
        for (int j = 0; j < m; ++j) (*jac)(j * nc + c, k * nc + c) = block(j, k);
      }
    }
    return spectral::stacked(weighting.is_fourier() ? aft->project(force) : Eigen::MatrixXd(force * wq));
  }

  [[nodiscard]] Eigen::VectorXd contact_residual(const Eigen::VectorXd& x, double load) const {
    require_factorized();
    return (x - load * x_lin + h * contact_forces(x, nullptr)) / scale;
  }

  void require_factorized() const {
    if (!factorized) {
      std::ostringstream os;
      os << "weighted residual " << trial.name() << ":" << weighting.name() << ": the linear operator G is singular at f = "
         << forcing.frequency_hz << " Hz (forcing at an undamped natural frequency?); add damping or move the frequency";
      throw std::runtime_error(os.str());
    }
  }
};

WeightedResidual::WeightedResidual(MechanicalSystem system, HarmonicForcing forcing,
                                   std::vector<ContactPoint> contacts, TimeBasis trial, TimeBasis weighting,
                                   WeightedResidualOptions options)
    : impl_(std::make_unique<Impl>(std::move(system), forcing, std::move(contacts), std::move(trial),
                                   std::move(weighting), options)) {}
WeightedResidual::~WeightedResidual() = default;
WeightedResidual::WeightedResidual(WeightedResidual&&) noexcept = default;
WeightedResidual& WeightedResidual::operator=(WeightedResidual&&) noexcept = default;

int WeightedResidual::dofs() const { return impl_->n; }
int WeightedResidual::dimension() const { return impl_->m; }
int WeightedResidual::time_samples() const { return impl_->q; }
const MechanicalSystem& WeightedResidual::system() const { return impl_->system; }
const HarmonicForcing& WeightedResidual::forcing() const { return impl_->forcing; }
const std::vector<ContactPoint>& WeightedResidual::contacts() const { return impl_->contacts; }
const TimeBasis& WeightedResidual::trial() const { return impl_->trial; }
const TimeBasis& WeightedResidual::weighting() const { return impl_->weighting; }
Formulation WeightedResidual::formulation() const { return impl_->options.formulation; }
const TimeOperators& WeightedResidual::time_operators() const { return impl_->ops; }
std::string WeightedResidual::linear_solver() const { return impl_->modal ? "modal" : "sparse-lu"; }

std::string WeightedResidual::describe() const {
  return impl_->trial.name() + ":" + impl_->weighting.name() + ", " + std::string(to_string(formulation()));
}

double WeightedResidual::condition_number() const {
  const auto& p = *impl_;
  if (!p.factorized) return std::numeric_limits<double>::infinity();
  if (p.g_norm1 < 0.0) {
    const double fr = p.forcing.frequency_hz;
    p.g_norm1 = p.kronecker_norm1({fr * fr * p.ops.mass, fr * p.ops.damping, p.ops.stiffness},
                                  {&p.system.mass, &p.system.damping, &p.system.stiffness});
  }
  // ‖G⁻¹‖₁ by Hager–Higham (a few solves with G and Gᵀ through the factorization in use).
  const double inverse_norm = detail::inverse_one_norm_estimate(
      static_cast<Eigen::Index>(p.n) * p.m,
      [&](const Eigen::VectorXd& v, bool transposed) { return p.solve_stacked(v, transposed); });
  return p.g_norm1 * inverse_norm;
}

Eigen::VectorXd WeightedResidual::residual(const Eigen::VectorXd& a) const {
  const auto& p = *impl_;
  const auto u = spectral::as_coefficients(a, p.n);
  const double fr = p.forcing.frequency_hz;
  // (T ⊗ X) vec(U) = vec(X U Tᵀ), layout.hpp.
  const Eigen::MatrixXd gu = fr * fr * (p.system.mass * u * p.ops.mass.transpose()) +
                             fr * (p.system.damping * u * p.ops.damping.transpose()) +
                             p.system.stiffness * u * p.ops.stiffness.transpose();
  Eigen::VectorXd r = spectral::stacked(gu) - p.b;
  if (p.nc > 0) {
    const Eigen::VectorXd nx = p.contact_forces(p.gather(a), nullptr);
    for (size_t j = 0; j < p.contact_rows.size(); ++j) r(p.contact_rows[j]) += nx(static_cast<Eigen::Index>(j));
  }
  return r;
}

Eigen::MatrixXd WeightedResidual::jacobian(const Eigen::VectorXd& a) const {
  const auto& p = *impl_;
  const double fr = p.forcing.frequency_hz;
  Eigen::MatrixXd jac = Eigen::kroneckerProduct(fr * fr * p.ops.mass, Eigen::MatrixXd(p.system.mass)) +
                        Eigen::kroneckerProduct(fr * p.ops.damping, Eigen::MatrixXd(p.system.damping)) +
                        Eigen::kroneckerProduct(p.ops.stiffness, Eigen::MatrixXd(p.system.stiffness));
  if (p.nc > 0) {
    Eigen::MatrixXd nj;
    (void)p.contact_forces(p.gather(a), &nj);
    for (size_t i = 0; i < p.contact_rows.size(); ++i) {
      for (size_t j = 0; j < p.contact_rows.size(); ++j) {
        jac(p.contact_rows[i], p.contact_rows[j]) += nj(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
      }
    }
  }
  return jac;
}

Eigen::VectorXd WeightedResidual::linear_response() const {
  impl_->require_factorized();
  return impl_->a_lin;
}

Eigen::VectorXd WeightedResidual::contact_unknowns(const Eigen::VectorXd& a) const { return impl_->gather(a); }

Eigen::VectorXd WeightedResidual::contact_residual(const Eigen::VectorXd& x, double load) const {
  return impl_->contact_residual(x, load);
}

WeightedResidual::WeightedResidual(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

WeightedResidual WeightedResidual::at_frequency(double frequency_hz) const {
  if (!(frequency_hz > 0.0) || !std::isfinite(frequency_hz)) {
    throw std::invalid_argument("WeightedResidual::at_frequency: f = " + format_number(frequency_hz) +
                                " Hz; must be > 0 and finite");
  }
  return WeightedResidual(std::make_unique<Impl>(*impl_, frequency_hz));
}

double WeightedResidual::frequency_hz() const { return impl_->forcing.frequency_hz; }
double WeightedResidual::residual_scale() const { return impl_->scale; }

Eigen::VectorXd WeightedResidual::contact_residual_frequency_derivative(const Eigen::VectorXd& x, double load) const {
  const auto& p = *impl_;
  p.require_factorized();
  Eigen::VectorXd rhs = load * p.b;
  if (p.nc > 0) {
    const Eigen::VectorXd nx = p.contact_forces(x, nullptr);
    for (size_t j = 0; j < p.contact_rows.size(); ++j) rhs(p.contact_rows[j]) -= nx(static_cast<Eigen::Index>(j));
  }
  const Eigen::MatrixXd a = spectral::as_coefficients(p.solve_stacked(rhs, false), p.n);  // n × M
  // G′ a with G′ = 2f A_M ⊗ M + A_C ⊗ C: (T ⊗ S) a ↔ S A Tᵀ on the n × M coefficients.
  const double f = p.forcing.frequency_hz;
  const Eigen::MatrixXd ga = 2.0 * f * (p.system.mass * a * p.ops.mass.transpose()) +
                             p.system.damping * a * p.ops.damping.transpose();
  return p.gather(p.solve_stacked(spectral::stacked(ga), false)) / p.scale;
}

Eigen::MatrixXd WeightedResidual::contact_jacobian(const Eigen::VectorXd& x) const {
  const auto& p = *impl_;
  p.require_factorized();
  Eigen::MatrixXd nj;
  (void)p.contact_forces(x, &nj);
  Eigen::MatrixXd jac = p.h * nj;
  jac.diagonal().array() += 1.0;
  return jac / p.scale;
}

Eigen::VectorXd WeightedResidual::expand(const Eigen::VectorXd& x) const {
  const auto& p = *impl_;
  p.require_factorized();
  Eigen::VectorXd rhs = p.b;
  if (p.nc > 0) {
    const Eigen::VectorXd nx = p.contact_forces(x, nullptr);
    for (size_t j = 0; j < p.contact_rows.size(); ++j) rhs(p.contact_rows[j]) -= nx(static_cast<Eigen::Index>(j));
  }
  return p.solve_stacked(rhs, false);
}

// The condensed system at load factor s (forcing s·F) as a NonlinearSystem.
struct WeightedResidual::Condensed {
  const WeightedResidual* wr;
  double load;
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x) const {
    return wr->impl_->contact_residual(x, load);
  }
  [[nodiscard]] Eigen::MatrixXd jacobian(const Eigen::VectorXd& x) const { return wr->contact_jacobian(x); }
};

NewtonResult WeightedResidual::solve_with_load_stepping(Eigen::VectorXd x, int& steps) const {
  // Forcing s·F for s from 0 to 1; ds doubles after a success (at most ½) and is quartered after
  // a failure; predictor x + ds·x_lin (the linear part of the response).
  const auto& p = *impl_;
  double s = 0.0, ds = 0.125;
  NewtonResult last{std::move(x), {}};
  int iterations = 0;
  steps = 0;
  while (s < 1.0) {
    const double target = std::min(1.0, s + ds);
    Eigen::VectorXd guess = last.x + (target - s) * p.x_lin;
    NewtonResult trial = newton(Condensed{this, target}, std::move(guess), p.options.newton);
    iterations += trial.report.iterations;
    ++steps;
    if (trial.report.converged()) {
      s = target;
      last = std::move(trial);
      ds = std::min(0.5, 2.0 * ds);
    } else {
      ds *= 0.25;
      if (ds < 1e-6) {
        trial.report.iterations = iterations;
        trial.report.message = "load stepping stalled at s = " + std::to_string(s) + " of F: " + trial.report.message;
        return trial;
      }
    }
  }
  last.report.iterations = iterations;
  return last;
}

WeightedResidualSolution WeightedResidual::solve(const Eigen::VectorXd* x0) const {
  const auto start = std::chrono::steady_clock::now();
  const auto& p = *impl_;
  WeightedResidualSolution s;
  s.frequency_hz = p.forcing.frequency_hz;
  s.contact_unknowns = p.nc * p.m;
  s.linear_solver = linear_solver();
  s.operator_rule = p.ops.rule;
  s.condition_number = condition_number();
  if (!p.factorized) {
    s.report.status = SolveStatus::SingularJacobian;
    s.report.message = "linear operator G is singular (forcing at an undamped natural frequency?)";
    s.coefficients = Eigen::MatrixXd::Zero(p.n, p.m);
    s.relative_residual = std::numeric_limits<double>::infinity();
    return s;
  }
  Eigen::VectorXd x;
  if (p.nc > 0) {
    Eigen::VectorXd start_x = x0 != nullptr ? *x0 : p.x_lin;
    if (start_x.size() != p.nc * p.m) {
      throw std::invalid_argument("WeightedResidual::solve: initial guess has length " +
                                  std::to_string(start_x.size()) + ", expected n_c*M = " + std::to_string(p.nc * p.m));
    }
    NewtonResult result = newton(Condensed{this, 1.0}, start_x, p.options.newton);
    if (!result.report.converged() && x0 == nullptr) {
      int steps = 0;
      NewtonResult stepped = solve_with_load_stepping(Eigen::VectorXd::Zero(start_x.size()), steps);
      const std::string first = result.report.message;
      stepped.report.iterations += result.report.iterations;
      stepped.report.message = "direct Newton: " + first + "; load stepping (" + std::to_string(steps) +
                               " steps): " + stepped.report.message;
      result = std::move(stepped);
    }
    x = std::move(result.x);
    s.report = std::move(result.report);
  } else {
    s.report.status = SolveStatus::Converged;
    s.report.message = "linear problem (no contact): one solve";
    s.report.residual_norms = {0.0};
  }
  const Eigen::VectorXd a = p.nc > 0 ? expand(x) : p.a_lin;
  s.coefficients = spectral::as_coefficients(a, p.n);
  const double bnorm = p.b.norm();
  s.relative_residual = residual(a).norm() / (bnorm > 0.0 ? bnorm : 1.0);
  if (p.nc > 0) {
    const Eigen::MatrixXd u = p.contact_samples(x);
    s.max_penetration = -std::numeric_limits<double>::infinity();
    for (int c = 0; c < p.nc; ++c) {
      for (int k = 0; k < p.q; ++k) {
        s.max_penetration = std::max(s.max_penetration, u(c, k) - p.contacts[c].law->gap());
        s.max_contact_force = std::max(s.max_contact_force, p.contacts[c].law->force(u(c, k)));
      }
    }
  }
  s.residual_tolerance = p.options.residual_tolerance;
  if (s.report.converged() && (!std::isfinite(s.relative_residual) || !s.coefficients.allFinite())) {
    s.report.status = SolveStatus::NonFinite;
    s.report.message = "non-finite full residual after convergence of the condensed system";
  } else if (s.report.converged() && !(s.relative_residual <= p.options.residual_tolerance)) {
    s.report.status = SolveStatus::ResidualNotVerified;
    s.report.message = "the condensed system converged (" + s.report.message + "), but the full residual " +
                       format_number(s.relative_residual) + " ‖b‖ exceeds residual_tolerance = " +
                       format_number(p.options.residual_tolerance) +
                       " (ill-conditioned G? condition estimate " + format_number(s.condition_number) + ")";
  }
  s.wall_time_s = elapsed(start);
  return s;
}

WeightedResidualSolution solve_weighted_residual(const MechanicalSystem& system, const HarmonicForcing& forcing,
                                                 const std::vector<ContactPoint>& contacts, const TimeBasis& trial,
                                                 const TimeBasis& weighting, const WeightedResidualOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const WeightedResidual wr(system, forcing, contacts, trial, weighting, options);
  WeightedResidualSolution s = wr.solve();
  s.wall_time_s = elapsed(start);
  return s;
}

}  // namespace wbm::solvers
