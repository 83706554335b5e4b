// Private to wbm_solvers: the factored form of a modal block when the weighting basis is Fourier
// and the formulation distributional (KroneckerFactorization::ModeBlock, "Factored"): the left factor
// A_K⁻¹ (or N⁻¹), dense or by its shift structure, and the O(M) core S_i of each block.
#pragma once

#include <cmath>
#include <complex>
#include <numbers>
#include <optional>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>

#include <wbm/solvers/weighted_residual.hpp>
#include <wbm/spectral/circulant.hpp>
#include <wbm/spectral/fourier_basis.hpp>

namespace wbm::solvers::detail {

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

}  // namespace wbm::solvers::detail
