#include "kronecker_factorization.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <iterator>
#include <numbers>
#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <unsupported/Eigen/KroneckerProduct>

#include <wbm/spectral/circulant.hpp>
#include <wbm/spectral/fourier_basis.hpp>
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

// The core S of a factored Fourier-weighting block (FourierWeighting below): block diagonal
// (1 × 1 for the constant, 2 × 2 per (cos, sin) pair) in every row but the last, whose row is
// full: S = B + e_L ℓᵀ with row L of B zero. O(M) storage and products; linear, so that the
// compliance sums Σ_i w_i S_i in the same form.
struct FourierCore {
  Eigen::VectorXd diagonal;   // B(j, j), j < L
  Eigen::VectorXd upper;      // B(j, j + 1) at the pair's first index j (cos), else 0
  Eigen::VectorXd lower;      // B(j + 1, j) likewise
  Eigen::RowVectorXd last_row;  // ℓᵀ = row L of S
  explicit FourierCore(Eigen::Index m)
      : diagonal(Eigen::VectorXd::Zero(m)), upper(Eigen::VectorXd::Zero(m)), lower(Eigen::VectorXd::Zero(m)),
        last_row(Eigen::RowVectorXd::Zero(m)) {}
  [[nodiscard]] Eigen::Index size() const { return diagonal.size(); }
  [[nodiscard]] bool finite() const {
    return diagonal.allFinite() && upper.allFinite() && lower.allFinite() && last_row.allFinite();
  }
  void add(double w, const FourierCore& o) {
    diagonal += w * o.diagonal;
    upper += w * o.upper;
    lower += w * o.lower;
    last_row += w * o.last_row;
  }
  // S r, or Sᵀ r, for each column of r (M rows); column by column (column-major storage).
  [[nodiscard]] Eigen::MatrixXd apply(const Eigen::MatrixXd& r, bool transposed) const {
    const Eigen::Index m = size(), last = m - 1;
    Eigen::MatrixXd y(m, r.cols());
    for (Eigen::Index col = 0; col < r.cols(); ++col) {
      const double* x = r.col(col).data();
      double* o = y.col(col).data();
      o[0] = diagonal(0) * x[0];
      for (Eigen::Index j = 1; j + 1 < m; j += 2) {
        const double off_up = transposed ? lower(j) : upper(j), off_low = transposed ? upper(j) : lower(j);
        o[j] = diagonal(j) * x[j] + off_up * x[j + 1];
        o[j + 1] = off_low * x[j] + diagonal(j + 1) * x[j + 1];
      }
      if (transposed) {  // row L of B is zero: Sᵀ r = Bᵀ r + ℓ r_L
        o[last] = 0.0;
        for (Eigen::Index i = 0; i < m; ++i) o[i] += last_row(i) * x[last];
      } else {
        o[last] = last_row.dot(r.col(col));
      }
    }
    return y;
  }
  // L S (M × M) for a dense left factor L: column k of S has at most three nonzeros (its pair and
  // row L), so O(M²) instead of the O(M³) dense product.
  [[nodiscard]] Eigen::MatrixXd left_multiply(const Eigen::MatrixXd& left) const {
    const Eigen::Index m = size(), last = m - 1;
    Eigen::MatrixXd out = left.col(last) * last_row;  // the full row L
    out.col(0) += diagonal(0) * left.col(0);
    for (Eigen::Index j = 1; j + 1 < m; j += 2) {
      out.col(j) += diagonal(j) * left.col(j) + lower(j) * left.col(j + 1);
      out.col(j + 1) += upper(j) * left.col(j) + diagonal(j + 1) * left.col(j + 1);
    }
    return out;
  }
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
  // Shift structure of the left factor L (A_K, or N): when trial function k is function 0 moved
  // by k/M and the samples map onto themselves under that shift (Q a multiple of M),
  //   L(0, k) = L(0, 0),   L(top, k) = (−1)^k L(top, 0),
  //   L(cos_h, k) + i L(sin_h, k) = (C_h + i S_h) e^{2πihk/M},   C_h + i S_h from column 0,
  // so (L x)_{cos_h} + i (L x)_{sin_h} = (C_h + i S_h) conj(X_h) with X the real DFT of x, and
  // L⁻¹ y costs one inverse real DFT: O(M log M) instead of O(M²), the set-up O(M² log M)
  // instead of the O(M³) LU and inverse.
  bool shift = false;
  Eigen::VectorXcd shift_coefficients;  // (C_h + i S_h), h = 0 … M/2 (h = 0: L(0, 0); h = M/2: L(top, 0))

  // L⁻¹ y for each column of y (M rows), shift structure only.
  [[nodiscard]] Eigen::MatrixXd shift_inverse(const Eigen::MatrixXd& y) const {
    const Eigen::Index m = y.rows(), half = m / 2;
    Eigen::MatrixXcd bins(half + 1, y.cols());
    bins.row(0) = y.row(0).cast<std::complex<double>>() / shift_coefficients(0);
    for (Eigen::Index h = 1; h < half; ++h) {
      const Eigen::RowVectorXcd z = (y.row(2 * h - 1).cast<std::complex<double>>() +
                                     std::complex<double>(0.0, 1.0) * y.row(2 * h).cast<std::complex<double>>()) /
                                    shift_coefficients(h);
      bins.row(h) = z.conjugate();
    }
    bins.row(half) = y.row(m - 1).cast<std::complex<double>>() / shift_coefficients(half);
    return spectral::inverse_real_dft_columns(bins, static_cast<int>(m));
  }

  // Detects the shift structure of l (to 1e-12 of its largest entry) and, if present, sets
  // shift_coefficients and ak_inv = l⁻¹ by shift_inverse. False if absent or singular.
  bool detect_shift(const Eigen::MatrixXd& l) {
    const Eigen::Index m = l.rows(), half = m / 2;
    const double tol = 1e-12 * l.cwiseAbs().maxCoeff();
    Eigen::VectorXcd coefficients(half + 1);
    coefficients(0) = l(0, 0);
    for (Eigen::Index h = 1; h < half; ++h) coefficients(h) = {l(2 * h - 1, 0), l(2 * h, 0)};
    coefficients(half) = l(m - 1, 0);
    std::vector<std::complex<double>> root(static_cast<size_t>(m));  // e^{2πij/M}
    for (Eigen::Index j = 0; j < m; ++j) root[j] = std::polar(1.0, 2.0 * std::numbers::pi * static_cast<double>(j) / m);
    for (Eigen::Index k = 0; k < m; ++k) {
      if (!(std::abs(l(0, k) - l(0, 0)) <= tol)) return false;
      if (!(std::abs(l(m - 1, k) - (k % 2 == 0 ? 1.0 : -1.0) * l(m - 1, 0)) <= tol)) return false;
      for (Eigen::Index h = 1; h < half; ++h) {
        const std::complex<double> z = coefficients(h) * root[(h * k) % m];
        if (!(std::abs(l(2 * h - 1, k) - z.real()) <= tol && std::abs(l(2 * h, k) - z.imag()) <= tol)) return false;
      }
    }
    const Eigen::VectorXd mag = coefficients.cwiseAbs();
    if (!(mag.minCoeff() > 1e-12 * mag.maxCoeff())) return false;  // singular to double precision
    shift_coefficients = coefficients;
    ak_inv = shift_inverse(Eigen::MatrixXd::Identity(m, m));
    shift = ak_inv.allFinite();
    return shift;
  }

  // Returns nullopt unless the identities hold to 1e-10 relative and A_K is well conditioned.
  static std::optional<FourierWeighting> detect(const TimeOperators& ops) {
    const Eigen::Index m = ops.stiffness.rows();
    if (m < 4 || m % 2 == 1) return std::nullopt;  // the M = 2^J form, with its top function
    FourierWeighting fw;
    fw.omega = Eigen::VectorXd::Zero(m);
    for (Eigen::Index j = 1; j < m - 1; ++j) fw.omega(j) = 2.0 * std::numbers::pi * static_cast<double>((j + 1) / 2);
    fw.omega(m - 1) = std::numbers::pi * static_cast<double>(m);
    const Eigen::MatrixXd d2ak = -(fw.omega.array().square().matrix().asDiagonal() * ops.stiffness);
    // D₁ A_K with D₁ the coefficient-space derivative (its top row is zero; checked rows only).
    const Eigen::MatrixXd d1ak = spectral::FourierBasis(static_cast<int>(m)).derivative_matrix() * ops.stiffness;
    const double sm = ops.mass.cwiseAbs().maxCoeff(), sc = ops.damping.cwiseAbs().maxCoeff();
    if (!((ops.mass - d2ak).cwiseAbs().maxCoeff() <= 1e-10 * sm)) return std::nullopt;
    if (!((ops.damping + d1ak).topRows(m - 1).cwiseAbs().maxCoeff() <= 1e-10 * sc)) return std::nullopt;
    // A vanishing last row first: Eigen's rcond() is no guide on an exactly singular matrix
    // (its estimate runs through the zero pivot; it returned 0.22 for Haar at M = 8).
    const bool last_row_vanishes =
        ops.stiffness.row(m - 1).cwiseAbs().maxCoeff() <= 1e-12 * ops.stiffness.cwiseAbs().maxCoeff();
    if (!last_row_vanishes) {
      if (fw.detect_shift(ops.stiffness)) {
        fw.g = fw.ak_inv.transpose() * ops.damping.row(m - 1).transpose();
        return fw;
      }
      const Eigen::PartialPivLU<Eigen::MatrixXd> lu(ops.stiffness);
      if (!(lu.rcond() > 1e-12)) return std::nullopt;
      fw.ak_inv = lu.inverse();
      if (!fw.ak_inv.allFinite()) return std::nullopt;
      fw.g = fw.ak_inv.transpose() * ops.damping.row(m - 1).transpose();
      return fw;
    }
    Eigen::MatrixXd n = ops.stiffness;
    n.row(m - 1) = ops.damping.row(m - 1);
    fw.replaced_last_row = true;
    if (fw.detect_shift(n)) return fw;
    const Eigen::PartialPivLU<Eigen::MatrixXd> nlu(n);
    if (!(nlu.rcond() > 1e-12)) return std::nullopt;
    fw.ak_inv = nlu.inverse();
    return fw;
  }

  // S_i for the block f² A_M + f c A_C + λ A_K (FourierCore: O(M) storage).
  [[nodiscard]] FourierCore core(double f, double c, double lambda) const {
    const Eigen::Index m = omega.size(), last = m - 1;
    FourierCore s(m);
    s.diagonal(0) = 1.0 / lambda;
    for (Eigen::Index j = 1; j + 1 < m; j += 2) {
      // P on (cos, sin): [[a, b], [−b, a]] with a = λ − f² ω², b = f c ω (from −f c D₁).
      const double a = lambda - f * f * omega(j) * omega(j), b = f * c * omega(j);
      const double det = a * a + b * b;
      s.diagonal(j) = s.diagonal(j + 1) = a / det;
      s.upper(j) = -b / det;  // S(j, j + 1)
      s.lower(j) = b / det;   // S(j + 1, j)
    }
    const double gamma = f * c;
    if (replaced_last_row) {
      s.last_row(last) = 1.0 / gamma;  // inf without damping: the block is singular (reported)
      return s;
    }
    const double p_last = lambda - f * f * omega(last) * omega(last);
    // gᵀ P⁻¹ with P⁻¹ block diagonal, P⁻¹(last, last) = 1/p_last.
    Eigen::RowVectorXd gp(m);
    gp(0) = g(0) * s.diagonal(0);
    for (Eigen::Index j = 1; j + 1 < m; j += 2) {
      gp(j) = g(j) * s.diagonal(j) + g(j + 1) * s.lower(j);
      gp(j + 1) = g(j) * s.upper(j) + g(j + 1) * s.diagonal(j + 1);
    }
    gp(last) = g(last) / p_last;
    const double denominator = 1.0 + gamma * g(last) / p_last;
    // Row `last` of P⁻¹ − γ P⁻¹ e_L gᵀ P⁻¹ / (1 + γ gᵀ P⁻¹ e_L) (P⁻¹ e_L = e_L / p_last).
    s.last_row = -(gamma / (p_last * denominator)) * gp;
    s.last_row(last) += 1.0 / p_last;
    return s;
  }
};

// ‖G‖₁ from the Kronecker factors t = (f² A_M, f A_C, A_K) and x = (M, C, K), G not formed:
// the column (j, k) of G sums |Σ_s x_s(i, j) t_s(l, k)| over (i, l) = Σ_i ‖v_ij‖ Σ_l |Σ_s u_s t_s(l, k)|
// with v_ij = (M_ij, C_ij, K_ij) = ‖v_ij‖ u. The column sums of |Σ_s u_s T_s| are computed once
// per distinct direction u (to 1e-14), a few for a FE model: O(nnz(T)) each for sparse time
// operators (Fourier:Fourier), O(M²) for dense ones, plus O(nnz(X) · M).
double kronecker_norm1(const std::array<Eigen::SparseMatrix<double>, 3>& t,
                       const std::array<const Eigen::SparseMatrix<double>*, 3>& x) {
  const auto n = x[0]->cols();
  const auto m = t[0].cols();
  // Time operators more than a quarter full (wavelet Galerkin, Petrov–Galerkin): dense sums.
  const bool dense = static_cast<double>(t[0].nonZeros() + t[1].nonZeros() + t[2].nonZeros()) >
                     0.25 * static_cast<double>(m) * static_cast<double>(m);
  std::array<Eigen::MatrixXd, 3> td;
  std::vector<std::pair<Eigen::Vector3d, Eigen::VectorXd>> directions;  // (u, column sums of Σ u_s T_s)
  if (dense) {
    for (int s = 0; s < 3; ++s) td[s] = Eigen::MatrixXd(t[s]);
  }
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
      const double v0 = x[0]->coeff(i, j), v1 = x[1]->coeff(i, j), v2 = x[2]->coeff(i, j);
      // |s·Σ u_s T_s| = |s| |Σ u_s T_s|: one column sum per direction u = v/‖v‖ (a FE model has
      // a few: the rod's interior diagonal, off-diagonal and end entries), reused to 1e-14.
      const double norm = std::sqrt(v0 * v0 + v1 * v1 + v2 * v2);
      if (norm == 0.0) continue;
      const Eigen::Vector3d u(v0 / norm, v1 / norm, v2 / norm);
      auto it = std::find_if(directions.begin(), directions.end(), [&](const auto& d) {
        return (d.first - u).template lpNorm<Eigen::Infinity>() <= 1e-14;
      });
      if (it == directions.end()) {
        Eigen::VectorXd sums;
        if (dense) {
          sums = (u(0) * td[0] + u(1) * td[1] + u(2) * td[2]).cwiseAbs().colwise().sum().transpose();
        } else {
          const Eigen::SparseMatrix<double> comb = u(0) * t[0] + u(1) * t[1] + u(2) * t[2];
          sums = Eigen::VectorXd::Zero(m);
          for (Eigen::Index k = 0; k < m; ++k) {
            for (Eigen::SparseMatrix<double>::InnerIterator c(comb, k); c; ++c) sums(k) += std::abs(c.value());
          }
        }
        directions.emplace_back(u, std::move(sums));
        it = std::prev(directions.end());
      }
      colsum += norm * it->second;
    }
    best = std::max(best, colsum.maxCoeff());
  }
  return best;
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

  /// Block a + λ bb, split along `components` (≥ 2 of them), each inverted densely. The
  /// inverses are stored flat (row-major, concatenated): a Fourier:Fourier block has M/2 of them,
  /// and continuation builds one block per mode per frequency.
  ModeBlock(const Eigen::MatrixXd& a, const Eigen::MatrixXd& bb, double lambda, const Components& components)
      : m_(a.rows()), component_(&components) {
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
  /// Circulant block with first column `column`; singular (not ok) when min |eigenvalue| ≤
  /// 1e-14 max |eigenvalue|, i.e. zero to double precision.
  explicit ModeBlock(const Eigen::VectorXd& column) : m_(column.size()), component_(nullptr) {
    const spectral::Circulant c(column);
    ok_ = c.reciprocal_condition() > 1e-14;
    if (ok_) circulant_inverse_.emplace(c.inverse());
  }
  /// Sparse or dense LU of the block.
  explicit ModeBlock(const Eigen::MatrixXd& block) : m_(block.rows()), component_(nullptr) {
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
    if (sparse_) return transposed ? Eigen::MatrixXd(sparse_lu_->transpose().solve(r)) : Eigen::MatrixXd(sparse_lu_->solve(r));
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
  using SparseLu = Eigen::SparseLU<Eigen::SparseMatrix<double>, Eigen::COLAMDOrdering<int>>;
  Eigen::Index m_;
  bool sparse_ = false, ok_ = false;
  const Components* component_;
  std::vector<double> flat_;     // component inverses, row-major, concatenated (split blocks only)
  std::vector<size_t> offset_;   // start of component c in flat_
  const Eigen::MatrixXd* left_ = nullptr;  // factored: A_K⁻¹ (shared) ...
  std::optional<FourierCore> core_;        // ... and S, the block's inverse being A_K⁻¹ S
  std::optional<spectral::Circulant> circulant_inverse_;
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
  bool circulant = false;                             // all three time operators circulant
  std::optional<FourierWeighting> fourier_weighting;  // distributional form, Fourier weighting
};

// The blocks H_cd (n_c × n_c, pair (c, d) at c·n_c + d) in a structured form, kept by
// compliance() for compliance_product(): circulant, or the core sums Σ_i w_i S_i whose product
// with the shift-structured A_K⁻¹ is H_cd.
struct KroneckerFactorization::ComplianceStructure {
  int contacts = 0;
  std::vector<spectral::Circulant> circulant;
  std::vector<FourierCore> cores;
  const FourierWeighting* fourier_weighting = nullptr;  // owned by Setup
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
    setup->circulant = setup->components.empty() && !setup->fourier_weighting &&
                       spectral::Circulant::is_circulant(ops.mass) && spectral::Circulant::is_circulant(ops.damping) &&
                       spectral::Circulant::is_circulant(ops.stiffness);
  }
  setup_ = std::move(setup);
}

KroneckerFactorization KroneckerFactorization::unfactorized() const { return KroneckerFactorization(setup_); }

bool KroneckerFactorization::modal() const { return setup_->modal; }

bool KroneckerFactorization::factorize(const MechanicalSystem& system, const TimeOperators& ops, double fr) {
  const Setup& su = *setup_;
  frequency_hz_ = fr;
  norm1_ = -1.0;
  compliance_structure_.reset();
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
      } else if (!su.components.empty()) {
        blocks_.push_back(std::make_shared<const ModeBlock>(a, bb, su.lambda(i), su.components));
      } else if (su.circulant) {
        blocks_.push_back(std::make_shared<const ModeBlock>(Eigen::VectorXd(a.col(0) + su.lambda(i) * bb.col(0))));
      } else {
        blocks_.push_back(std::make_shared<const ModeBlock>(Eigen::MatrixXd(a + su.lambda(i) * bb)));
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

Eigen::MatrixXd KroneckerFactorization::compliance(const std::vector<std::vector<std::pair<int, double>>>& directions,
                                                   const std::vector<StackedTerms>& rows) {
  const int nc = static_cast<int>(directions.size());
  const auto m = static_cast<Eigen::Index>(rows.size()) / std::max(nc, 1);
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(nc * m, nc * m);
  const Setup& su = *setup_;
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
  if (su.modal && su.circulant) {  // a sum of circulants is circulant: first columns only
    for (int c = 0; c < nc; ++c) {
      for (int d = 0; d < nc; ++d) {
        Eigen::VectorXd column = Eigen::VectorXd::Zero(m);
        for (size_t i = 0; i < blocks_.size(); ++i) column += weight(i, c, d) * blocks_[i]->circulant_inverse()->first_column();
        structure->circulant.emplace_back(column);
        scatter(c, d, structure->circulant.back().dense());
      }
    }
    compliance_structure_ = std::move(structure);
    return h;
  }
  if (su.modal && !su.components.empty()) {  // only the components' entries are nonzero
    for (size_t i = 0; i < blocks_.size(); ++i) {
      for (size_t comp = 0; comp < su.components.size(); ++comp) {
        const auto& idx = su.components[comp];
        const auto inv = blocks_[i]->component_inverse(comp);
        for (int c = 0; c < nc; ++c) {
          for (int d = 0; d < nc; ++d) {
            const double w = weight(i, c, d);
            for (size_t b = 0; b < idx.size(); ++b) {
              for (size_t a = 0; a < idx.size(); ++a) {
                h(idx[a] * nc + c, idx[b] * nc + d) += w * inv(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b));
              }
            }
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
  Eigen::MatrixXd selection = Eigen::MatrixXd::Zero(g_.rows(), nc * m);  // Pᵀ
  for (Eigen::Index j = 0; j < nc * m; ++j) {
    for (const auto& [row, w] : rows[static_cast<size_t>(j)]) selection(row, j) = w;
  }
  const Eigen::MatrixXd z = lu_->solve(selection);
  for (Eigen::Index i = 0; i < nc * m; ++i) {  // P z
    for (const auto& [row, w] : rows[static_cast<size_t>(i)]) h.row(i) += w * z.row(row);
  }
  return h;
}

Eigen::MatrixXd KroneckerFactorization::compliance_product(const Eigen::MatrixXd& v) const {
  const ComplianceStructure& cs = *compliance_structure_;
  const int nc = cs.contacts;
  const Eigen::Index m = v.rows() / std::max(nc, 1);
  // Rows of contact d (k·n_c + d), M × columns; with one contact, v itself.
  const auto rows_of = [&](int d) {
    if (nc == 1) return Eigen::MatrixXd(v);
    Eigen::MatrixXd vd(m, v.cols());
    for (Eigen::Index k = 0; k < m; ++k) vd.row(k) = v.row(k * nc + d);
    return vd;
  };
  std::vector<Eigen::MatrixXd> vd;
  for (int d = 0; d < nc; ++d) vd.push_back(rows_of(d));
  Eigen::MatrixXd out(v.rows(), v.cols());
  for (int c = 0; c < nc; ++c) {
    Eigen::MatrixXd hc = Eigen::MatrixXd::Zero(m, v.cols());
    for (int d = 0; d < nc; ++d) {
      const auto pair = static_cast<size_t>(c * nc + d);
      hc += cs.circulant.empty() ? cs.cores[pair].apply(vd[d], false) : cs.circulant[pair].apply(vd[d]);
    }
    if (cs.circulant.empty()) hc = cs.fourier_weighting->shift_inverse(hc);  // A_K⁻¹ Σ_d S_cd v_d
    if (nc == 1) return hc;
    for (Eigen::Index k = 0; k < m; ++k) out.row(k * nc + c) = hc.row(k);
  }
  return out;
}

double KroneckerFactorization::norm1(const MechanicalSystem& system, const TimeOperators& ops) const {
  if (norm1_ >= 0.0) return norm1_;
  if (setup_->modal) {
    const double fr = frequency_hz_;
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
