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
// ‖R‖ = 2e-10: its solves take one step of iterative refinement on G_c.
#include "kronecker_factorization.hpp"

#include <algorithm>
#include <array>
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

// Not in an anonymous namespace: a field of ComponentLus (as KluWithTranspose in sparse_lu.cpp).
// A band LU (dgbtrf) of an N × N matrix with kl = ku = w off-diagonals, in LAPACK's band storage
// AB(kl + ku + i − j, j) = A(i, j) (0-based), ldab = 2 kl + ku + 1.
class BandLu {
 public:
  BandLu(int size, int width) : n_(size), w_(width), ab_(Eigen::MatrixXd::Zero(3 * width + 1, size)), ipiv_(size) {}
  void add(Eigen::Index i, Eigen::Index j, double v) { ab_(2 * w_ + i - j, j) += v; }
  bool factorize() {
    if (!ab_.allFinite()) return false;
    const int ldab = 3 * w_ + 1;
    int info = 0;
    dgbtrf_(&n_, &n_, &w_, &w_, ab_.data(), &ldab, ipiv_.data(), &info);
    return info == 0;
  }
  // B ← A⁻¹ B (or A⁻ᵀ B), every column.
  void solve(Eigen::MatrixXd& b, bool transposed) const {
    const int ldab = 3 * w_ + 1, nrhs = static_cast<int>(b.cols()), ldb = n_;
    const char trans = transposed ? 'T' : 'N';
    int info = 0;
    dgbtrs_(&trans, &n_, &w_, &w_, &nrhs, ab_.data(), &ldab, ipiv_.data(), b.data(), &ldb, &info, 1);
  }

 private:
  int n_, w_;
  Eigen::MatrixXd ab_;
  std::vector<int> ipiv_;
};

struct KroneckerFactorization::ComponentLus {
  Eigen::Index n = 0;                  // DOFs
  std::vector<size_t> component_of;    // per time index k: its component
  std::vector<Eigen::Index> position;  // per time index k: its place in the component
  int band = 0;                        // b + 1 (b: the structure's half-bandwidth) for band LUs; 0: KLU
  std::vector<BandLu> bands;           // one per component, G_c with interleaved rows (band LU)
  std::vector<SparseLu> lus;           // one per component, G_c stacked by position (KLU)
  std::vector<Eigen::SparseMatrix<double>> blocks;  // G_c, for KLU's step of iterative refinement
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
    const Eigen::MatrixXd r = transposed ? Eigen::MatrixXd(rhs - blocks[c].transpose() * y)
                                         : Eigen::MatrixXd(rhs - blocks[c] * y);
    y += lus[c].solve_columns(r, transposed);
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
  std::vector<Eigen::Triplet<double>> triplets;
  for (size_t c = 0; c < components.size(); ++c) {
    const auto& idx = components[c];
    const auto s = static_cast<Eigen::Index>(idx.size());
    for (Eigen::Index p = 0; p < s; ++p) {
      lus->component_of[static_cast<size_t>(idx[static_cast<size_t>(p)])] = c;
      lus->position[static_cast<size_t>(idx[static_cast<size_t>(p)])] = p;
    }
    std::optional<BandLu> band;
    if (lus->band > 0) band.emplace(static_cast<int>(s * n), static_cast<int>(s * (b + 1) - 1));
    triplets.clear();
    for (size_t t = 0; t < 3; ++t) {
      for (Eigen::Index q = 0; q < s; ++q) {
        for (Eigen::Index p = 0; p < s; ++p) {
          const double v = scale[t] * (*a[t])(idx[static_cast<size_t>(p)], idx[static_cast<size_t>(q)]);
          if (v == 0.0) continue;
          for (Eigen::Index j = 0; j < x[t]->outerSize(); ++j) {
            for (Eigen::SparseMatrix<double>::InnerIterator it(*x[t], j); it; ++it) {
              if (band) {
                band->add(lus->row(it.row(), p, s), lus->row(j, q, s), v * it.value());
              } else {
                triplets.emplace_back(lus->row(it.row(), p, s), lus->row(j, q, s), v * it.value());
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
    Eigen::SparseMatrix<double> gc(s * n, s * n);
    gc.setFromTriplets(triplets.begin(), triplets.end());
    SparseLu lu;
    ok = lu.factorize(gc) && ok;
    lus->lus.push_back(std::move(lu));
    lus->blocks.push_back(std::move(gc));
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
