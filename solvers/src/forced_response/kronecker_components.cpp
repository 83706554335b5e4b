// KroneckerFactorization's component path (issue #39, item 5): G(f) factorized block by block
// where the time operators are block diagonal (Fourier:Fourier, whose exact operators couple a
// harmonic's cosine and sine only) and the modal path is not taken (a non-classical C, or
// LinearSolverPath::SparseLU).
//
// With the time indices split into the components c of the time operators' sparsity graph, G is
// block diagonal after a permutation, with blocks
//   G_c = f² A_M[c, c] ⊗ M + f A_C[c, c] ⊗ C + A_K[c, c] ⊗ K   (|c|·n square, |c| ≤ 2 for Fourier),
// so G⁻¹ v and the compliance H = P G⁻¹ Pᵀ need |c|·n-sized sparse solves only: O(M·n) per
// frequency for a banded FE model, with any damping matrix. For a harmonic h of the rod, G_c is
// [[K − (2πhf)² M, 2πhf C], [−2πhf C, K − (2πhf)² M]] up to the basis' scaling: the receptance
// of one harmonic. Before, the whole n·M Kronecker sum was assembled and factorized by KLU.
//
// Each block is factorized as a band matrix by LAPACK's dgbtrf (partial pivoting within the band,
// backward stable) when the structure's half-bandwidth b (in its own DOF order) is small: with the
// rows interleaved DOF by DOF (i·|c| + p), G_c has half-bandwidth |c|(b + 1) − 1, 3 for a rod of
// linear elements, so a block costs O(n) [Anderson et al., LAPACK Users' Guide, 3rd ed., 1999,
// Sec. 2.4.2]. Otherwise by KLU (SparseLu), whose threshold pivoting (KLU's default 0.001) left
// solves of the 320-element rod inaccurate enough to stall the continuation corrector at
// ‖R‖ = 2e-10.
//
// Both take one step of iterative refinement on a residual that keeps G_c's three terms apart
// and accumulates in twice the working precision (Dot2 below). Near a resonance the entries of
// G_c = f² A_M ⊗ M + f A_C ⊗ C + A_K ⊗ K cancel: on 1 280 rod elements |K_ii| is 2.4e6 times
// ω² |M_ii| at 1 173 Hz. Their rounded sum moves in steps of ε |K_ij| as f varies continuously, so
// the solution of the stored G_c is a staircase in f with steps near κ ε (1e-9 relative there):
// a continuation corrector, which moves f at every iteration, met a residual noisy at 5e-10 and
// stalled above the 1e-10 tolerance at 1 173 Hz, although any one solve is backward stable. The
// residual v − Σ_t B_t y, each term B_t = s_t A_t ⊗ X_t (s = f², f, 1) rounded on its own and
// every product exact, is that of G_c itself up to ε per term, smooth in f; the LU of the rounded
// sum is its preconditioner, and one correction leaves an error near κ ε times the first one's
// [Higham, Accuracy and Stability of Numerical Algorithms, 2nd ed., 2002, Sec. 12.1]. The modal
// path forms λ_i − ω² per mode; its circulant blocks (wavelet Galerkin pairs) cancelled in the
// transform of their first column until they were combined on the time operators' eigenvalues
// (stop 82, kronecker_factorization.cpp).
#include "kronecker_factorization.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

extern "C" {
// LAPACK (Fortran): LU of a general band matrix, and solves with its factors.
void dgbtrf_(const int* m, const int* n, const int* kl, const int* ku, double* ab, const int* ldab, int* ipiv,
             int* info);
void dgbtrs_(const char* trans, const int* n, const int* kl, const int* ku, const int* nrhs, const double* ab,
             const int* ldab, const int* ipiv, double* b, const int* ldb, int* info, std::size_t trans_length);
}

namespace wbm::solvers::detail {

namespace {

// v − Σ_t a_t x_t accumulated as if in twice the working precision, then rounded: Dot2 of Ogita,
// Rump & Oishi, SIAM J. Sci. Comput. 26(6), 2005, Alg. 5.3 (TwoProduct by fma, TwoSum).
// p = fl(a x) must be rounded, so it is its own statement: GCC contracts a product into an fma
// only across statements on a target with FMA (this build passes no -march), clang only within
// one expression.
class Dot2 {
 public:
  explicit Dot2(double v) : s_(v) {}
  void subtract(double a, double x) {
    const double p = a * x;
    const double ep = std::fma(a, x, -p);  // a x = p + ep exactly
    const double s = s_ - p;
    const double z = s - s_;
    const double es = (s_ - (s - z)) + (-p - z);  // s_ − p = s + es exactly
    s_ = s;
    c_ += es - ep;
  }
  [[nodiscard]] double value() const { return s_ + c_; }

 private:
  double s_ = 0.0, c_ = 0.0;
};

// v − Σ_t B_t y (or v − Σ_t B_tᵀ y), every column, by Dot2 per entry.
Eigen::MatrixXd residual_dot2(const std::array<Eigen::SparseMatrix<double>, 3>& terms, const Eigen::MatrixXd& v,
                              const Eigen::MatrixXd& y, bool transposed) {
  Eigen::MatrixXd r(v.rows(), v.cols());
  std::vector<Dot2> acc;
  for (Eigen::Index c = 0; c < v.cols(); ++c) {
    acc.clear();
    for (Eigen::Index i = 0; i < v.rows(); ++i) acc.emplace_back(v(i, c));
    for (const auto& b : terms) {
      for (Eigen::Index j = 0; j < b.outerSize(); ++j) {
        for (Eigen::SparseMatrix<double>::InnerIterator it(b, j); it; ++it) {
          if (transposed) {  // (Bᵀ y)_j = Σ_i B(i, j) y_i
            acc[static_cast<size_t>(j)].subtract(it.value(), y(it.row(), c));
          } else {
            acc[static_cast<size_t>(it.row())].subtract(it.value(), y(j, c));
          }
        }
      }
    }
    for (Eigen::Index i = 0; i < v.rows(); ++i) r(i, c) = acc[static_cast<size_t>(i)].value();
  }
  return r;
}

}  // namespace

// Not in an anonymous namespace: a field of ComponentLus (as KluWithTranspose in sparse_lu.cpp).
// A band LU (dgbtrf) of an N × N matrix A = Σ_t B_t with kl = ku = w off-diagonals, in LAPACK's
// band storage AB(kl + ku + i − j, j) = A(i, j) (0-based), ldab = 2 kl + ku + 1. The terms B_t are
// kept apart, B_t(i, j) at terms_[t](w + i − j, j), for the refinement's residual; factorize()
// sums them into AB's rows w … 3w.
class BandLu {
 public:
  BandLu(int size, int width) : n_(size), w_(width), ab_(Eigen::MatrixXd::Zero(3 * width + 1, size)), ipiv_(size) {
    for (auto& b : terms_) b = Eigen::MatrixXd::Zero(2 * width + 1, size);
  }
  // B_t(i, j) += v.
  void add(Eigen::Index i, Eigen::Index j, double v, size_t t) { terms_[t](w_ + i - j, j) += v; }
  bool factorize() {
    ab_.middleRows(w_, 2 * w_ + 1) = terms_[0] + terms_[1] + terms_[2];
    if (!ab_.allFinite()) return false;
    const int ldab = 3 * w_ + 1;
    int info = 0;
    dgbtrf_(&n_, &n_, &w_, &w_, ab_.data(), &ldab, ipiv_.data(), &info);
    return info == 0;
  }
  // B ← A⁻¹ B (or A⁻ᵀ B), every column, with one step of refinement on the Dot2 residual.
  void solve(Eigen::MatrixXd& b, bool transposed) const {
    const Eigen::MatrixXd v = b;
    lapack_solve(b, transposed);
    Eigen::MatrixXd r = residual(v, b, transposed);
    lapack_solve(r, transposed);
    b += r;
  }

 private:
  void lapack_solve(Eigen::MatrixXd& b, bool transposed) const {
    const int ldab = 3 * w_ + 1, nrhs = static_cast<int>(b.cols()), ldb = n_;
    const char trans = transposed ? 'T' : 'N';
    int info = 0;
    dgbtrs_(&trans, &n_, &w_, &w_, &nrhs, ab_.data(), &ldab, ipiv_.data(), b.data(), &ldb, &info, 1);
  }
  // v − Σ_t B_t y (or v − Σ_t B_tᵀ y) by Dot2, row by row over the band.
  [[nodiscard]] Eigen::MatrixXd residual(const Eigen::MatrixXd& v, const Eigen::MatrixXd& y, bool transposed) const {
    Eigen::MatrixXd r(n_, v.cols());
    for (Eigen::Index c = 0; c < v.cols(); ++c) {
      for (int i = 0; i < n_; ++i) {
        Dot2 d(v(i, c));
        for (const auto& b : terms_) {
          for (int j = std::max(0, i - w_); j <= std::min(n_ - 1, i + w_); ++j) {
            // row i of B: B(i, j) = b(w + i − j, j); row i of Bᵀ: B(j, i) = b(w + j − i, i)
            d.subtract(transposed ? b(w_ + j - i, i) : b(w_ + i - j, j), y(j, c));
          }
        }
        r(i, c) = d.value();
      }
    }
    return r;
  }
  int n_, w_;
  Eigen::MatrixXd ab_;
  std::array<Eigen::MatrixXd, 3> terms_;
  std::vector<int> ipiv_;
};

struct KroneckerFactorization::ComponentLus {
  Eigen::Index n = 0;                  // DOFs
  std::vector<size_t> component_of;    // per time index k: its component
  std::vector<Eigen::Index> position;  // per time index k: its place in the component
  int band = 0;                        // b + 1 (b: the structure's half-bandwidth) for band LUs; 0: KLU
  std::vector<BandLu> bands;           // one per component, G_c with interleaved rows (band LU)
  std::vector<SparseLu> lus;           // one per component, G_c stacked by position (KLU)
  std::vector<std::array<Eigen::SparseMatrix<double>, 3>> terms;  // KLU: G_c's terms B_t, for the refinement
  // Row of G_c for (DOF i, position p): interleaved for a band LU, stacked for KLU.
  [[nodiscard]] Eigen::Index row(Eigen::Index i, Eigen::Index p, Eigen::Index s) const {
    return band > 0 ? i * s + p : p * n + i;
  }
  // y ← G_c⁻¹ y (or G_c⁻ᵀ y) for component c, every column.
  void solve(size_t c, Eigen::MatrixXd& y, bool transposed) const {
    if (band > 0) {
      bands[c].solve(y, transposed);
      return;
    }
    const Eigen::MatrixXd rhs = y;
    y = lus[c].solve_columns(rhs, transposed);
    y += lus[c].solve_columns(residual_dot2(terms[c], rhs, y, transposed), transposed);
  }
};

namespace {

// Half-bandwidth of the joint pattern of M, C, K in their DOF order: max |i − j| over nonzeros.
Eigen::Index half_bandwidth(const std::array<const Eigen::SparseMatrix<double>*, 3>& x) {
  Eigen::Index b = 0;
  for (const auto* xs : x) {
    for (Eigen::Index j = 0; j < xs->outerSize(); ++j) {
      for (Eigen::SparseMatrix<double>::InnerIterator it(*xs, j); it; ++it) b = std::max(b, std::abs(it.row() - j));
    }
  }
  return b;
}

// The band LU is taken while G_c's half-bandwidth |c|(b + 1) − 1 is at most this: its
// factorization costs about N·w² flops, a KLU one at least its fill.
constexpr Eigen::Index kBandLimit = 32;

}  // namespace

bool KroneckerFactorization::factorize_components(const std::vector<std::vector<Eigen::Index>>& components) {
  const MechanicalSystem& system = *operator_.system;
  const TimeOperators& ops = *operator_.ops;
  const double fr = operator_.frequency_hz;
  auto lus = std::make_shared<ComponentLus>();
  const Eigen::Index n = system.mass.rows();
  lus->n = n;
  lus->component_of.resize(static_cast<size_t>(ops.mass.rows()));
  lus->position.resize(static_cast<size_t>(ops.mass.rows()));
  const std::array<double, 3> scale = {fr * fr, fr, 1.0};
  const std::array<const Eigen::MatrixXd*, 3> a = {&ops.mass, &ops.damping, &ops.stiffness};
  const std::array<const Eigen::SparseMatrix<double>*, 3> x = {&system.mass, &system.damping, &system.stiffness};
  size_t widest = 1;
  for (const auto& idx : components) widest = std::max(widest, idx.size());
  const Eigen::Index b = half_bandwidth(x);
  if (static_cast<Eigen::Index>(widest) * (b + 1) - 1 <= kBandLimit) lus->band = static_cast<int>(b + 1);
  bool ok = true;
  std::array<std::vector<Eigen::Triplet<double>>, 3> triplets;  // per term
  for (size_t c = 0; c < components.size(); ++c) {
    const auto& idx = components[c];
    const auto s = static_cast<Eigen::Index>(idx.size());
    for (Eigen::Index p = 0; p < s; ++p) {
      lus->component_of[static_cast<size_t>(idx[static_cast<size_t>(p)])] = c;
      lus->position[static_cast<size_t>(idx[static_cast<size_t>(p)])] = p;
    }
    std::optional<BandLu> band;
    if (lus->band > 0) band.emplace(static_cast<int>(s * n), static_cast<int>(s * (b + 1) - 1));
    for (auto& tt : triplets) tt.clear();
    for (size_t t = 0; t < 3; ++t) {
      for (Eigen::Index q = 0; q < s; ++q) {
        for (Eigen::Index p = 0; p < s; ++p) {
          const double v = scale[t] * (*a[t])(idx[static_cast<size_t>(p)], idx[static_cast<size_t>(q)]);
          if (v == 0.0) continue;
          for (Eigen::Index j = 0; j < x[t]->outerSize(); ++j) {
            for (Eigen::SparseMatrix<double>::InnerIterator it(*x[t], j); it; ++it) {
              if (band) {
                band->add(lus->row(it.row(), p, s), lus->row(j, q, s), v * it.value(), t);
              } else {
                triplets[t].emplace_back(lus->row(it.row(), p, s), lus->row(j, q, s), v * it.value());
              }
            }
          }
        }
      }
    }
    if (band) {
      ok = band->factorize() && ok;
      lus->bands.push_back(std::move(*band));
      continue;
    }
    std::array<Eigen::SparseMatrix<double>, 3> terms;
    for (size_t t = 0; t < 3; ++t) {
      terms[t].resize(s * n, s * n);
      terms[t].setFromTriplets(triplets[t].begin(), triplets[t].end());
    }
    const Eigen::SparseMatrix<double> gc = terms[0] + terms[1] + terms[2];
    SparseLu lu;
    ok = lu.factorize(gc) && ok;
    lus->lus.push_back(std::move(lu));
    lus->terms.push_back(std::move(terms));
  }
  component_lus_ = std::move(lus);
  return ok;
}

Eigen::VectorXd KroneckerFactorization::solve_components(
    const Eigen::VectorXd& v, bool transposed, const std::vector<std::vector<Eigen::Index>>& components) const {
  const ComponentLus& cl = *component_lus_;
  const Eigen::Index n = cl.n;
  Eigen::VectorXd out(v.size());
  for (size_t c = 0; c < components.size(); ++c) {
    const auto& idx = components[c];
    const auto s = static_cast<Eigen::Index>(idx.size());
    Eigen::MatrixXd y(s * n, 1);
    for (Eigen::Index p = 0; p < s; ++p) {
      for (Eigen::Index i = 0; i < n; ++i) y(cl.row(i, p, s), 0) = v(idx[static_cast<size_t>(p)] * n + i);
    }
    cl.solve(c, y, transposed);
    for (Eigen::Index p = 0; p < s; ++p) {
      for (Eigen::Index i = 0; i < n; ++i) out(idx[static_cast<size_t>(p)] * n + i) = y(cl.row(i, p, s), 0);
    }
  }
  return out;
}

Eigen::MatrixXd KroneckerFactorization::compliance_components(
    const std::vector<StackedTerms>& rows, int nc, const std::vector<std::vector<Eigen::Index>>& components) const {
  const ComponentLus& cl = *component_lus_;
  const Eigen::Index n = cl.n;
  const auto total = static_cast<Eigen::Index>(rows.size());
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(total, total);
  // Stacked row k·n + dof of G in its component's block; row j = k·n_c + d of P (contact d at
  // time index k) reads coefficient k only (P = I_M ⊗ E).
  const auto local = [&](Eigen::Index j, Eigen::Index stacked, Eigen::Index s) {
    const Eigen::Index k = stacked / n;
    if (k != j / nc) {
      throw std::logic_error("compliance: row " + std::to_string(j) + " of P reads time index " + std::to_string(k) +
                             ", not its own " + std::to_string(j / nc) + " (P must be I_M ⊗ E)");
    }
    return cl.row(stacked % n, cl.position[static_cast<size_t>(k)], s);
  };
  for (size_t c = 0; c < components.size(); ++c) {
    const auto& idx = components[c];
    const auto s = static_cast<Eigen::Index>(idx.size());
    Eigen::MatrixXd z = Eigen::MatrixXd::Zero(s * n, s * nc);  // the columns of Pᵀ on this block
    for (Eigen::Index p = 0; p < s; ++p) {
      for (int d = 0; d < nc; ++d) {
        const Eigen::Index j = idx[static_cast<size_t>(p)] * nc + d;
        for (const auto& [row, w] : rows[static_cast<size_t>(j)]) z(local(j, row, s), p * nc + d) += w;
      }
    }
    cl.solve(c, z, false);
    for (Eigen::Index p = 0; p < s; ++p) {  // P z on the block's rows
      for (int d = 0; d < nc; ++d) {
        const Eigen::Index i = idx[static_cast<size_t>(p)] * nc + d;
        for (const auto& [row, w] : rows[static_cast<size_t>(i)]) {
          const Eigen::Index r = local(i, row, s);
          for (Eigen::Index q = 0; q < s; ++q) {
            for (int e = 0; e < nc; ++e) h(i, idx[static_cast<size_t>(q)] * nc + e) += w * z(r, q * nc + e);
          }
        }
      }
    }
  }
  return h;
}

}  // namespace wbm::solvers::detail
