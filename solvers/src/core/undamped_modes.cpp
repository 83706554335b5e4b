// Undamped modes K Φ = M Φ Λ, Φᵀ M Φ = I (undamped_modes.hpp): Eigen's dense solver, or for
// tridiagonal K and M Sturm bisection and inverse iteration in O(n²).
#include <wbm/solvers/undamped_modes.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

#include <Eigen/Eigenvalues>

extern "C" {
// LAPACK (Fortran): LU of a general tridiagonal matrix with partial pivoting, and solves with it.
void dgttrf_(const int* n, double* dl, double* d, double* du, double* du2, int* ipiv, int* info);
void dgttrs_(const char* trans, const int* n, const int* nrhs, const double* dl, const double* d, const double* du,
             const double* du2, const int* ipiv, double* b, const int* ldb, int* info, std::size_t trans_length);
}

namespace wbm::solvers {
namespace {

// Diagonals (n) and subdiagonals (n − 1) of K and M.
struct Pencil {
  Eigen::VectorXd kd, ke, md, me;
  [[nodiscard]] Eigen::Index size() const { return kd.size(); }
  // M x, M tridiagonal.
  [[nodiscard]] Eigen::VectorXd mass_times(const Eigen::VectorXd& x) const {
    const Eigen::Index n = size();
    Eigen::VectorXd y = md.cwiseProduct(x);
    y.head(n - 1) += me.cwiseProduct(x.tail(n - 1));
    y.tail(n - 1) += me.cwiseProduct(x.head(n - 1));
    return y;
  }
};

// The diagonals if every nonzero of a lies within one of the diagonal and a is symmetric.
bool diagonals(const Eigen::SparseMatrix<double>& a, Eigen::VectorXd& d, Eigen::VectorXd& e) {
  const Eigen::Index n = a.rows();
  d = Eigen::VectorXd::Zero(n);
  e = Eigen::VectorXd::Zero(std::max<Eigen::Index>(n - 1, 0));
  Eigen::VectorXd upper = e;
  for (Eigen::Index j = 0; j < a.outerSize(); ++j) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(a, j); it; ++it) {
      const Eigen::Index i = it.row();
      if (i == j) {
        d(i) += it.value();
      } else if (i == j + 1) {
        e(j) += it.value();
      } else if (i + 1 == j) {
        upper(i) += it.value();
      } else if (it.value() != 0.0) {
        return false;
      }
    }
  }
  return e == upper;
}

// Number of eigenvalues of the pencil below σ, for kLanes values of σ at once (independent
// chains of divisions, which the processor overlaps): the negative pivots of the LDLᵀ of K − σM
// (Sylvester's law of inertia, M positive definite). A pivot smaller than `pivmin` in magnitude
// is replaced by −pivmin, as LAPACK's dstebz does [Kahan 1966; Parlett 1998, Sec. 7.2].
constexpr int kLanes = 8;
using Lanes = std::array<double, kLanes>;

std::array<Eigen::Index, kLanes> negatives(const Pencil& p, const Lanes& sigma, double pivmin) {
  const Eigen::Index n = p.size();
  std::array<Eigen::Index, kLanes> count{};
  Lanes d;
  for (int l = 0; l < kLanes; ++l) {
    d[l] = p.kd(0) - sigma[l] * p.md(0);
    if (std::abs(d[l]) < pivmin) d[l] = -pivmin;
    count[l] += d[l] < 0.0 ? 1 : 0;
  }
  for (Eigen::Index i = 1; i < n; ++i) {
    const double ke = p.ke(i - 1), me = p.me(i - 1), kd = p.kd(i), md = p.md(i);
    for (int l = 0; l < kLanes; ++l) {
      const double e = ke - sigma[l] * me;
      d[l] = (kd - sigma[l] * md) - e * e / d[l];
      if (std::abs(d[l]) < pivmin) d[l] = -pivmin;
      count[l] += d[l] < 0.0 ? 1 : 0;
    }
  }
  return count;
}

Eigen::Index negatives(const Pencil& p, double sigma, double pivmin) {
  Lanes s;
  s.fill(sigma);
  return negatives(p, s, pivmin)[0];
}

}  // namespace

std::optional<UndampedModes> tridiagonal_undamped_modes(const Eigen::SparseMatrix<double>& stiffness,
                                                        const Eigen::SparseMatrix<double>& mass) {
  const Eigen::Index n = stiffness.rows();
  if (n == 0 || stiffness.cols() != n || mass.rows() != n || mass.cols() != n) return std::nullopt;
  Pencil p;
  if (!diagonals(stiffness, p.kd, p.ke) || !diagonals(mass, p.md, p.me)) return std::nullopt;
  if (!p.kd.allFinite() || !p.ke.allFinite() || !p.md.allFinite() || !p.me.allFinite()) return std::nullopt;
  {  // M positive definite: every pivot of its LDLᵀ positive
    double d = p.md(0);
    for (Eigen::Index i = 0;; ++i) {
      if (!(d > 0.0)) return std::nullopt;
      if (i + 1 == n) break;
      d = p.md(i + 1) - p.me(i) * p.me(i) / d;
    }
  }
  const double scale = std::max({p.kd.cwiseAbs().maxCoeff(), p.ke.size() > 0 ? p.ke.cwiseAbs().maxCoeff() : 0.0,
                                 std::numeric_limits<double>::min()});
  const double pivmin = std::numeric_limits<double>::min() * std::max(1.0, scale * scale);
  // A bracket [lo, hi] of the whole spectrum, by doubling.
  double hi = 1.0, lo = -1.0;
  while (negatives(p, hi, pivmin) < n) {
    hi *= 2.0;
    if (!std::isfinite(hi)) return std::nullopt;
  }
  if (negatives(p, 0.0, pivmin) == 0) {
    lo = 0.0;
  } else {
    while (negatives(p, lo, pivmin) > 0) {
      lo *= 2.0;
      if (!std::isfinite(lo)) return std::nullopt;
    }
  }
  UndampedModes out;
  out.method = "tridiagonal";
  out.lambda.resize(n);
  const double eps = std::numeric_limits<double>::epsilon();
  // Bisection for kLanes consecutive eigenvalues at a time, each in its bracket [a_l, b_l] with
  // count(a_l) ≤ i_l < count(b_l), to the last bits of the bracket.
  double start = lo;  // count(start) ≤ the next batch's first index
  for (Eigen::Index i0 = 0; i0 < n; i0 += kLanes) {
    Lanes a, b, mid;
    a.fill(start);
    b.fill(hi);
    std::array<bool, kLanes> open{};
    for (;;) {
      bool any = false;
      for (int l = 0; l < kLanes; ++l) {
        mid[l] = 0.5 * (a[l] + b[l]);
        open[l] = i0 + l < n && b[l] - a[l] > 2.0 * eps * std::max(std::abs(a[l]), std::abs(b[l])) + pivmin &&
                  mid[l] > a[l] && mid[l] < b[l];
        any = any || open[l];
      }
      if (!any) break;
      const auto count = negatives(p, mid, pivmin);
      for (int l = 0; l < kLanes; ++l) {
        if (!open[l]) continue;
        if (count[l] > i0 + l) {
          b[l] = mid[l];
        } else {
          a[l] = mid[l];
        }
      }
    }
    for (int l = 0; l < kLanes && i0 + l < n; ++l) {
      out.lambda(i0 + l) = 0.5 * (a[l] + b[l]);
      start = a[l];
    }
  }
  // Inverse iteration, M-orthogonal to the modes within ortol of λ_i (not chained: the loss of
  // orthogonality between two computed modes is about ε ‖K‖ / |λ_i − λ_j|).
  const double lambda_max = std::max(std::abs(out.lambda(0)), std::abs(out.lambda(n - 1)));
  const double ortol = 1e-3 * lambda_max;
  out.phi.resize(n, n);
  const int size = static_cast<int>(n), one = 1;
  std::vector<double> dl(static_cast<size_t>(std::max<Eigen::Index>(n - 1, 1))), d(static_cast<size_t>(n)),
      du(dl.size()), du2(static_cast<size_t>(std::max<Eigen::Index>(n - 2, 1)));
  std::vector<int> ipiv(static_cast<size_t>(n));
  std::uint64_t state = 0x9E3779B97F4A7C15ULL;
  Eigen::Index cluster = 0;  // first j with λ_i − λ_j ≤ ortol
  for (Eigen::Index i = 0; i < n; ++i) {
    while (out.lambda(i) - out.lambda(cluster) > ortol) ++cluster;
    double shift = out.lambda(i);
    int info = 1;
    for (int attempt = 0; attempt < 4 && info != 0; ++attempt) {
      for (Eigen::Index k = 0; k < n; ++k) d[static_cast<size_t>(k)] = p.kd(k) - shift * p.md(k);
      for (Eigen::Index k = 0; k + 1 < n; ++k) {
        dl[static_cast<size_t>(k)] = du[static_cast<size_t>(k)] = p.ke(k) - shift * p.me(k);
      }
      dgttrf_(&size, dl.data(), d.data(), du.data(), du2.data(), ipiv.data(), &info);
      if (info != 0) shift += 4.0 * eps * std::max(lambda_max, pivmin) * (attempt + 1);  // an exact zero pivot
    }
    if (info != 0) return std::nullopt;
    Eigen::VectorXd x(n);
    for (Eigen::Index k = 0; k < n; ++k) {  // a fixed pseudo-random start (xorshift), in [−1, 1]
      state ^= state << 13U;
      state ^= state >> 7U;
      state ^= state << 17U;
      x(k) = static_cast<double>(state >> 11U) * 0x1.0p-52 - 1.0;
    }
    for (int step = 0; step < 3; ++step) {
      Eigen::VectorXd y = p.mass_times(x);
      int solved = 0;
      dgttrs_("N", &size, &one, dl.data(), d.data(), du.data(), du2.data(), ipiv.data(), y.data(), &size, &solved, 1);
      for (int pass = 0; pass < 2; ++pass) {
        for (Eigen::Index j = cluster; j < i; ++j) y -= out.phi.col(j).dot(p.mass_times(y)) * out.phi.col(j);
      }
      const double norm = std::sqrt(y.dot(p.mass_times(y)));
      if (!(norm > 0.0) || !std::isfinite(norm)) return std::nullopt;
      x = y / norm;
    }
    out.phi.col(i) = x;
  }
  return out;
}

UndampedModes undamped_modes(const Eigen::SparseMatrix<double>& stiffness, const Eigen::SparseMatrix<double>& mass) {
  constexpr Eigen::Index kTridiagonalFrom = 400;
  if (stiffness.rows() >= kTridiagonalFrom) {
    if (auto modes = tridiagonal_undamped_modes(stiffness, mass)) return std::move(*modes);
  }
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig{Eigen::MatrixXd(stiffness),
                                                                      Eigen::MatrixXd(mass)};
  if (eig.info() != Eigen::Success) {
    throw std::invalid_argument("undamped modes: K Φ = M Φ Λ failed (is M symmetric positive definite?)");
  }
  return {eig.eigenvalues(), eig.eigenvectors(), "dense"};
}

}  // namespace wbm::solvers
