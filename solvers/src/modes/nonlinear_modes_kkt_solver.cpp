// NonlinearModes::BackboneSystem::KktSolver (nonlinear_modes.hpp): the KKT Jacobian of the
// exact-contact backbone solved through its block-diagonal harmonic balance and a Schur
// complement on the active contact samples; the penalty backbone's through the same blocks and a
// Schur complement on the harmonics of the stops in contact. Verified against J, backed by SparseLu.
#include <wbm/solvers/nonlinear_modes.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include <Eigen/LU>

#include <wbm/solvers/detail/rcond_bound.hpp>

namespace wbm::solvers {

namespace {
constexpr double kMinRcond = 1e-13;          // A_k or S less well conditioned: SparseLu instead
// A block whose certified lower bound of rcond (detail::rcond_lower_bound) reaches this needs no
// estimate: the estimate (from above) is then at least kMinRcond, with a margin of 1e3 for the
// rounding of the bound's two triangular solves. Else the estimate decides, as before.
constexpr double kCertifiedRcond = 1e3 * kMinRcond;
constexpr double kMaxBackwardError = 1e-11;  // normwise backward error a structured solve must reach

// 1/d where it is exact (d > 0 a power of two, d and 1/d normal), else 0. Then x · (1/d) and x / d
// are the same bits for every x: both are x 2⁻ᵉ correctly rounded. A unit direction has d = 1.
double exact_reciprocal_of(double d) {
  int e = 0;
  if (!(d > 0.0) || !std::isnormal(d) || std::frexp(d, &e) != 0.5) return 0.0;
  const double r = 1.0 / d;
  return std::isnormal(r) ? r : 0.0;
}
}  // namespace

struct NonlinearModes::BackboneSystem::KktSolver::Impl {
  // The structure of the system (fixed).
  bool exact = false;
  Eigen::Index ny = 0, size = 0, nl = 0;  // harmonic-balance unknowns, system size, multipliers
  int f = 0, ms = 0, nc = 0;              // Fourier coefficients, samples per stop, stops
  std::vector<Eigen::Index> start, length;  // block k: indices [start_k, start_k + length_k)
  std::vector<int> block_of;                // per harmonic-balance index: its block
  std::vector<Eigen::Index> local_of;       // … and its index inside the block
  std::vector<Eigen::MatrixXd> dirs;        // N_k (length_k × nc): the stop directions in block k
  std::vector<double> dir_at;               // ny × nc, row-major: dirs[block_of[i]](local_of[i], c) at i·nc + c
  Eigen::MatrixXd dir_norm2;                // nc × f: ‖N_k(:, c)‖²
  Eigen::MatrixXd dir_norm2_divisor;        // f × nc: ‖N_k(:, c)‖², 1 where it is not > 0 …
  std::vector<std::vector<int>> no_direction;  // … per stop, those k (the multiples there are 0)
  // f × nc: 1/‖N_k(:, c)‖² where exact (exact_reciprocal_of), else 0; per stop, whether every k's is
  // (a unit direction's are 1): its β and γ are then scaled by multiplications, the same bits as
  // the divisions.
  Eigen::MatrixXd dir_norm2_reciprocal;
  std::vector<int> exact_reciprocal;
  std::vector<std::vector<int>> stop_at;    // per block, per local index: the stop whose direction holds it (−1: none)
  bool disjoint_stops = true;               // no DOF in two stops' directions (the penalty path needs it)

  // The last factorization.
  bool structured = false;
  Eigen::SparseMatrix<double> j;  // J (structured path: residuals and the fallback)
  Eigen::Index rows = 0, border = -1, nd = 1;  // nd dense unknowns: ω² and, bordered, E
  std::vector<Eigen::MatrixXd> a;              // A_k
  std::vector<Eigen::PartialPivLU<Eigen::MatrixXd>> lu;
  std::vector<Eigen::MatrixXd> v, g;           // V_k = A_k⁻¹ N_k, G_k = N_kᵀ V_k
  Eigen::MatrixXd beta_t;                      // f × nl: multiplier columns β_k N_c (column l: multiplier l's β)
  Eigen::MatrixXd gamma;                       // nl × f: active rows γ_k N_cᵀ
  Eigen::VectorXd diag;                        // nl: J(f_s, f_s)
  std::vector<Eigen::Index> inactive, active;  // multiplier indices (0 … nl − 1)
  Eigen::MatrixXd beta_a, gamma_a;             // active rows of β (beta_t's columns) and γ
  Eigen::MatrixXd bd, cd, xd;                  // ny × nd: dense columns (ω², E), dense rows (normalization, border), A⁻¹ bd
  Eigen::PartialPivLU<Eigen::MatrixXd> schur;
  std::vector<Eigen::MatrixXd> chat;           // penalty: per stop, Ĉ_c (f × f, zero diagonal)
  std::vector<int> touching;                   // penalty: the stops with Ĉ_c ≠ 0, in order
  double norm_inf = 0.0;
  SparseLu sparse;
  bool sparse_ready = false;
  Counts counts;

  // A⁻¹ r, block by block (r: ny × any number of columns).
  [[nodiscard]] Eigen::MatrixXd block_solve(const Eigen::MatrixXd& r) const {
    Eigen::MatrixXd y(ny, r.cols());
    for (int k = 0; k < f; ++k) y.middleRows(start[k], length[k]) = lu[k].solve(r.middleRows(start[k], length[k]));
    return y;
  }
  std::vector<int> stop_index;              // per multiplier l: its stop, l / ms (no division per entry)
  [[nodiscard]] Eigen::Index stop_of(Eigen::Index l) const { return stop_index[static_cast<size_t>(l)]; }

  bool factorize_sparse(const Eigen::SparseMatrix<double>& jac) {
    structured = false;
    ++counts.sparse_lu;
    sparse_ready = sparse.factorize(jac);
    return sparse_ready;
  }
  bool factorize(const Eigen::SparseMatrix<double>& jac);
  bool factorize_penalty(const Eigen::SparseMatrix<double>& jac);
  // A_k = LU (rcond checked), V_k, G_k and xd = A⁻¹ bd from a[] and bd; false: not usable.
  bool factorize_blocks();
  // S singular to working precision: J singular (false); ill conditioned: SparseLu; else structured.
  bool accept_schur(const Eigen::SparseMatrix<double>& jac, Eigen::Index schur_unknowns);
  [[nodiscard]] Eigen::VectorXd core_solve(const Eigen::VectorXd& rhs) const;
  [[nodiscard]] Eigen::VectorXd core_solve_penalty(const Eigen::VectorXd& rhs) const;
  [[nodiscard]] double backward_error(const Eigen::VectorXd& rhs, const Eigen::VectorXd& x) const {
    const double denominator = norm_inf * x.lpNorm<Eigen::Infinity>() + rhs.lpNorm<Eigen::Infinity>();
    const double r = (rhs - j * x).lpNorm<Eigen::Infinity>();
    if (!std::isfinite(r)) return std::numeric_limits<double>::infinity();
    return denominator > 0.0 ? r / denominator : r;
  }
};

NonlinearModes::BackboneSystem::KktSolver::KktSolver(const BackboneSystem& system) : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  const NonlinearModes& nm = *system.nm_;
  const Eigen::Index n = nm.n_, p = nm.phase_index_;
  s.exact = system.penalty_ == 0.0;
  s.ny = system.ny_;
  s.size = system.size_;
  s.f = nm.f_;
  s.ms = nm.options_.samples;
  s.nc = static_cast<int>(nm.stops_.size());
  s.nl = static_cast<Eigen::Index>(s.nc) * s.ms;
  s.stop_index.resize(static_cast<size_t>(s.nl));
  for (Eigen::Index l = 0; l < s.nl; ++l) s.stop_index[static_cast<size_t>(l)] = static_cast<int>(l / s.ms);
  auto reduced = [p](Eigen::Index i) { return i < p ? i : i - 1; };  // full stacked index (≠ p) → state index
  s.block_of.assign(static_cast<size_t>(s.ny), 0);
  s.local_of.assign(static_cast<size_t>(s.ny), 0);
  s.dir_norm2 = Eigen::MatrixXd::Zero(s.nc, s.f);
  for (int k = 0; k < s.f; ++k) {
    const Eigen::Index first = k * n;
    const bool holds_phase = p >= first && p < first + n;
    s.start.push_back(first <= p ? first : first - 1);
    s.length.push_back(n - (holds_phase ? 1 : 0));
    for (Eigen::Index i = first; i < first + n; ++i) {
      if (i == p) continue;
      s.block_of[static_cast<size_t>(reduced(i))] = k;
      s.local_of[static_cast<size_t>(reduced(i))] = reduced(i) - s.start.back();
    }
    Eigen::MatrixXd dk = Eigen::MatrixXd::Zero(s.length.back(), s.nc);
    for (int c = 0; c < s.nc; ++c) {
      for (const auto& [d, w] : nm.stops_[static_cast<size_t>(c)].terms()) {
        if (first + d == p) continue;
        dk(reduced(first + d) - s.start.back(), c) += w;
      }
      s.dir_norm2(c, k) = dk.col(c).squaredNorm();
    }
    std::vector<int> at(static_cast<size_t>(s.length.back()), -1);
    for (int c = 0; c < s.nc; ++c) {
      for (Eigen::Index i = 0; i < dk.rows(); ++i) {
        if (dk(i, c) == 0.0) continue;
        if (at[static_cast<size_t>(i)] >= 0) s.disjoint_stops = false;
        at[static_cast<size_t>(i)] = c;
      }
    }
    s.stop_at.push_back(std::move(at));
    s.dirs.push_back(std::move(dk));
  }
  s.dir_at.assign(static_cast<size_t>(s.ny) * static_cast<size_t>(s.nc), 0.0);
  for (Eigen::Index i = 0; i < s.ny; ++i) {
    const auto& dk = s.dirs[static_cast<size_t>(s.block_of[static_cast<size_t>(i)])];
    for (int c = 0; c < s.nc; ++c) {
      s.dir_at[static_cast<size_t>(i) * static_cast<size_t>(s.nc) + static_cast<size_t>(c)] =
          dk(s.local_of[static_cast<size_t>(i)], c);
    }
  }
  s.dir_norm2_divisor = s.dir_norm2.transpose();
  s.no_direction.assign(static_cast<size_t>(s.nc), {});
  for (int c = 0; c < s.nc; ++c) {
    for (int k = 0; k < s.f; ++k) {
      if (s.dir_norm2(c, k) > 0.0) continue;
      s.dir_norm2_divisor(k, c) = 1.0;
      s.no_direction[static_cast<size_t>(c)].push_back(k);
    }
  }
  s.dir_norm2_reciprocal = s.dir_norm2_divisor.unaryExpr([](double d) { return exact_reciprocal_of(d); });
  s.exact_reciprocal.assign(static_cast<size_t>(s.nc), 1);
  for (int c = 0; c < s.nc; ++c) {
    if (!(s.dir_norm2_reciprocal.col(c).array() > 0.0).all()) s.exact_reciprocal[static_cast<size_t>(c)] = 0;
  }
}

NonlinearModes::BackboneSystem::KktSolver::~KktSolver() = default;
NonlinearModes::BackboneSystem::KktSolver::KktSolver(KktSolver&&) noexcept = default;
NonlinearModes::BackboneSystem::KktSolver& NonlinearModes::BackboneSystem::KktSolver::operator=(KktSolver&&) noexcept =
    default;

NonlinearModes::BackboneSystem::KktSolver NonlinearModes::BackboneSystem::linear_solver() const {
  return KktSolver(*this);
}

bool NonlinearModes::BackboneSystem::KktSolver::factorize(const Eigen::SparseMatrix<double>& jacobian) {
  return impl_->factorize(jacobian);
}

Eigen::VectorXd NonlinearModes::BackboneSystem::KktSolver::solve(const Eigen::VectorXd& rhs) const {
  Impl& s = *impl_;
  if (!s.structured) {
    return s.sparse_ready ? s.sparse.solve(rhs) : Eigen::VectorXd::Constant(rhs.size(), NAN);
  }
  auto core = [&s](const Eigen::VectorXd& r) { return s.exact ? s.core_solve(r) : s.core_solve_penalty(r); };
  Eigen::VectorXd x = core(rhs);
  if (s.backward_error(rhs, x) <= kMaxBackwardError) return x;
  ++s.counts.refined;  // one step of iterative refinement on J's own residual
  x += core(rhs - s.j * x);
  if (s.backward_error(rhs, x) <= kMaxBackwardError) return x;
  ++s.counts.fallback_solves;
  if (!s.sparse_ready) s.sparse_ready = s.sparse.factorize(s.j);
  return s.sparse_ready ? s.sparse.solve(rhs) : Eigen::VectorXd::Constant(rhs.size(), NAN);
}

NonlinearModes::BackboneSystem::KktSolver::Counts NonlinearModes::BackboneSystem::KktSolver::counts() const {
  return impl_->counts;
}

bool NonlinearModes::BackboneSystem::KktSolver::Impl::factorize(const Eigen::SparseMatrix<double>& jac) {
  rows = jac.rows();
  structured = false;  // until this J is factorized (a failed factorize() leaves nothing to solve with)
  sparse_ready = false;
  if (jac.cols() != rows || (rows != size && rows != size + 1)) return factorize_sparse(jac);
  if (!exact && !disjoint_stops) return factorize_sparse(jac);
  border = rows == size + 1 ? rows - 1 : -1;
  nd = border >= 0 ? 2 : 1;
  a.resize(static_cast<size_t>(f));
  for (int k = 0; k < f; ++k) a[static_cast<size_t>(k)].setZero(length[k], length[k]);
  bd.setZero(ny, nd);
  cd.setZero(ny, nd);
  if (!exact) return factorize_penalty(jac);
  beta_t.setZero(f, nl);
  gamma.setZero(nl, f);
  diag.setZero(nl);
  // Flags as int, not char: a char store may alias anything, and would make the compiler reload
  // every member below after each one.
  std::vector<int> has_hb(static_cast<size_t>(nl), 0), off_diagonal(static_cast<size_t>(nl), 0);
  std::vector<Eigen::Triplet<double>> tail;  // entries with row and column outside the harmonic balance
  Eigen::VectorXd row_sum = Eigen::VectorXd::Zero(rows);
  auto multiplier = [&](Eigen::Index i) { return i > ny && i != border; };
  // The loop's arrays through local pointers (one load each, not one per entry); dir_at[i·nc + c]
  // is dirs[block_of[i]](local_of[i], c), the same value read without two indirections.
  double* const sum = row_sum.data();
  double* const gam = gamma.data();  // gamma(l, k) at k·nl + l
  double* const bet = beta_t.data();  // beta_t(k, l) at l·f + k
  const int* const blocks = block_of.data();
  const Eigen::Index* const locals = local_of.data();
  const int* const stops = stop_index.data();
  const double* const dir = dir_at.data();
  const Eigen::Index ncs = nc, fs = f, hb_rows = ny, border_row = border;
  const int* const outer = jac.outerIndexPtr();
  const int* const inner = jac.innerIndexPtr();
  const double* const values = jac.valuePtr();
  const int* const nnz = jac.innerNonZeroPtr();  // null when compressed
  for (Eigen::Index c = 0; c < jac.outerSize(); ++c) {
    const Eigen::Index begin = outer[c], end = nnz != nullptr ? begin + nnz[c] : outer[c + 1];
    for (Eigen::Index e = begin; e < end; ++e) {
      const Eigen::Index i = inner[e];
      const double val = values[e];
      if (!std::isfinite(val)) return false;
      if (val == 0.0) continue;  // stored zeros (the border's column is stored in full)
      sum[i] += std::abs(val);
      if (c < hb_rows) {
        const int kc = blocks[c];
        const Eigen::Index lc = locals[c];
        if (i < hb_rows) {
          if (blocks[i] != kc) return factorize_sparse(jac);  // harmonics coupled
          a[static_cast<size_t>(kc)](locals[i], lc) = val;
        } else if (i == hb_rows) {
          cd(c, 0) = val;
        } else if (i == border_row) {
          cd(c, 1) = val;
        } else {
          const Eigen::Index l = i - hb_rows - 1;
          gam[kc * nl + l] += dir[c * ncs + stops[l]] * val;
          has_hb[static_cast<size_t>(l)] = 1;
        }
      } else if (i < hb_rows) {
        if (c == hb_rows) {
          bd(i, 0) = val;
        } else if (c == border_row) {
          bd(i, 1) = val;
        } else {
          const Eigen::Index l = c - hb_rows - 1;
          bet[l * fs + blocks[i]] += dir[i * ncs + stops[l]] * val;
        }
      } else {
        tail.emplace_back(i, c, val);
        if (multiplier(i)) {
          if (c == i) {
            diag(i - hb_rows - 1) = val;
          } else {
            off_diagonal[static_cast<size_t>(i - hb_rows - 1)] = 1;
          }
        }
      }
    }
  }
  norm_inf = row_sum.maxCoeff();
  // β_k, γ_k: the least-squares multiples of N_c (a column or row of another shape leaves a
  // residual that the verified solves catch).
  // In storage order, whole columns at a time (the same divisions, vectorized): β by multiplier,
  // γ by harmonic and stop (stop c's multipliers are c·m_s … (c + 1)·m_s − 1).
  for (Eigen::Index l = 0; l < nl; ++l) {
    const Eigen::Index st = stop_of(l);
    if (exact_reciprocal[static_cast<size_t>(st)] != 0) {  // the same bits, without the divisions
      beta_t.col(l).array() *= dir_norm2_reciprocal.col(st).array();
    } else {
      beta_t.col(l).array() /= dir_norm2_divisor.col(st).array();
    }
    for (const int k : no_direction[static_cast<size_t>(st)]) beta_t(k, l) = 0.0;
  }
  for (int k = 0; k < f; ++k) {
    for (int c = 0; c < nc; ++c) {
      auto samples = gamma.col(k).segment(static_cast<Eigen::Index>(c) * ms, ms);
      const double d2 = dir_norm2(c, k), reciprocal = dir_norm2_reciprocal(k, c);
      if (reciprocal > 0.0) {  // the same bits, without the divisions
        samples *= reciprocal;
      } else if (d2 > 0.0) {
        samples /= d2;
      } else {
        samples.setZero();
      }
    }
  }
  inactive.clear();
  active.clear();
  std::vector<Eigen::Index> position(static_cast<size_t>(nl), -1);  // in the Schur complement
  for (Eigen::Index l = 0; l < nl; ++l) {
    if (!has_hb[static_cast<size_t>(l)] && !off_diagonal[static_cast<size_t>(l)]) {
      if (diag(l) == 0.0) return factorize_sparse(jac);  // an empty row: let SparseLu report it
      inactive.push_back(l);
    } else {
      position[static_cast<size_t>(l)] = nd + static_cast<Eigen::Index>(active.size());
      active.push_back(l);
    }
  }
  const auto na = static_cast<Eigen::Index>(active.size());
  // Blocks, receptances at the stop directions, dense columns.
  if (!factorize_blocks()) return factorize_sparse(jac);
  // S = D − C A⁻¹ B on [ω², (E), active samples] × [normalization row, (border row), active rows].
  const Eigen::Index m = nd + na;
  Eigen::MatrixXd schur_matrix = Eigen::MatrixXd::Zero(m, m);
  auto unknown = [&](Eigen::Index c) -> Eigen::Index {
    if (c == ny) return 0;
    if (c == border) return 1;
    return position[static_cast<size_t>(c - ny - 1)];
  };
  for (const auto& t : tail) {
    const Eigen::Index e = unknown(t.row()), u = unknown(t.col());
    if (e >= 0 && u >= 0) schur_matrix(e, u) += t.value();
  }
  schur_matrix.topLeftCorner(nd, nd) -= cd.transpose() * xd;
  beta_a.resize(na, f);
  gamma_a.resize(na, f);
  for (Eigen::Index q = 0; q < na; ++q) {
    beta_a.row(q) = beta_t.col(active[static_cast<size_t>(q)]).transpose();
    gamma_a.row(q) = gamma.row(active[static_cast<size_t>(q)]);
  }
  for (int k = 0; k < f; ++k) {
    const auto kk = static_cast<size_t>(k);
    const Eigen::MatrixXd q = v[kk].transpose() * cd.middleRows(start[k], length[k]);    // nc × nd: V_kᵀ c_e
    const Eigen::MatrixXd pd = dirs[kk].transpose() * xd.middleRows(start[k], length[k]);  // nc × nd: N_kᵀ A_k⁻¹ b_u
    for (Eigen::Index r = 0; r < na; ++r) {
      const Eigen::Index st = stop_of(active[static_cast<size_t>(r)]);
      for (Eigen::Index e = 0; e < nd; ++e) {
        schur_matrix(e, nd + r) -= beta_a(r, k) * q(st, e);
        schur_matrix(nd + r, e) -= gamma_a(r, k) * pd(st, e);
      }
    }
  }
  // Active × active by stop pairs: S(c₁ rows, c₂ columns) −= Γ_c₁ diag(G_k(c₁, c₂))_k B_c₂ᵀ.
  std::vector<Eigen::Index> first(static_cast<size_t>(nc) + 1, na);
  for (Eigen::Index r = na - 1; r >= 0; --r) first[static_cast<size_t>(stop_of(active[static_cast<size_t>(r)]))] = r;
  for (int c = nc - 1; c >= 0; --c) first[static_cast<size_t>(c)] = std::min(first[static_cast<size_t>(c)], first[static_cast<size_t>(c) + 1]);
  Eigen::RowVectorXd gk(f);
  for (int c1 = 0; c1 < nc; ++c1) {
    const Eigen::Index r0 = first[static_cast<size_t>(c1)], r1 = first[static_cast<size_t>(c1) + 1];
    if (r1 == r0) continue;
    for (int c2 = 0; c2 < nc; ++c2) {
      const Eigen::Index q0 = first[static_cast<size_t>(c2)], q1 = first[static_cast<size_t>(c2) + 1];
      if (q1 == q0) continue;
      for (int k = 0; k < f; ++k) gk(k) = g[static_cast<size_t>(k)](c1, c2);
      schur_matrix.block(nd + r0, nd + q0, r1 - r0, q1 - q0).noalias() -=
          (gamma_a.middleRows(r0, r1 - r0).array().rowwise() * gk.array()).matrix() *
          beta_a.middleRows(q0, q1 - q0).transpose();
    }
  }
  schur.compute(schur_matrix);
  return accept_schur(jac, na);
}

bool NonlinearModes::BackboneSystem::KktSolver::Impl::factorize_blocks() {
  lu.resize(static_cast<size_t>(f));
  v.resize(static_cast<size_t>(f));
  g.resize(static_cast<size_t>(f));
  // Whether two matrices have the same size and the same bits (±0 told apart, unlike ==).
  auto same = [](const Eigen::MatrixXd& x, const Eigen::MatrixXd& y) {
    return x.rows() == y.rows() && x.cols() == y.cols() &&
           std::memcmp(x.data(), y.data(), static_cast<size_t>(x.size()) * sizeof(double)) == 0;
  };
  for (int k = 0; k < f; ++k) {
    const auto kk = static_cast<size_t>(k);
    // The cosine and sine blocks of a harmonic are one matrix (w_k and ν_k are equal) unless one
    // holds the phase coefficient, or a penalty's curvature differs: then the LU, V_k and G_k are
    // copied, not recomputed (the same operations on the same bits would give the same bits).
    if (k > 0 && same(a[kk], a[kk - 1]) && same(dirs[kk], dirs[kk - 1])) {
      lu[kk] = lu[kk - 1];
      v[kk] = v[kk - 1];
      g[kk] = g[kk - 1];
      continue;
    }
    lu[kk].compute(a[kk]);
    // The Hager–Higham estimate of rcond() was 17 % of the LL11 rod's backbone at N = 32 (its
    // up to 10 solves per block); the bound costs two triangular solves and decides the same.
    // ‖A_k‖₁; the block that holds the phase is empty for one DOF (the bound is then 0).
    const double a_norm = a[kk].size() > 0 ? a[kk].cwiseAbs().colwise().sum().maxCoeff() : 0.0;
    if (!(detail::rcond_lower_bound(lu[kk], a_norm) >= kCertifiedRcond) && !(lu[kk].rcond() >= kMinRcond)) {
      return false;
    }
    v[kk] = lu[kk].solve(dirs[kk]);
    g[kk] = dirs[kk].transpose() * v[kk];
  }
  xd = block_solve(bd);
  return true;
}

bool NonlinearModes::BackboneSystem::KktSolver::Impl::accept_schur(const Eigen::SparseMatrix<double>& jac,
                                                                    Eigen::Index schur_unknowns) {
  // det J = Π_k det A_k · det S · Π (inactive J_ss): with every A_k well conditioned, an S
  // singular to working precision is a singular J (e.g. more active samples on a stop than its F
  // coefficients can meet, in a corrector far from the branch); an S merely ill conditioned
  // goes to SparseLu.
  const double schur_rcond = schur.rcond();
  if (!(schur_rcond >= std::numeric_limits<double>::epsilon())) {
    ++counts.singular;
    return false;
  }
  if (!(schur_rcond >= kMinRcond)) return factorize_sparse(jac);
  j = jac;
  structured = true;
  ++counts.structured;
  counts.max_active = std::max(counts.max_active, static_cast<int>(schur_unknowns));
  return true;
}

Eigen::VectorXd NonlinearModes::BackboneSystem::KktSolver::Impl::core_solve(const Eigen::VectorXd& rhs) const {
  Eigen::VectorXd x = Eigen::VectorXd::Zero(rows);
  Eigen::VectorXd r = rhs;
  // 1. Inactive samples: their rows are f_s = rhs_s / J_ss; move their columns to the right.
  for (const Eigen::Index l : inactive) {
    const Eigen::Index col = ny + 1 + l;
    const double xv = rhs(col) / diag(l);
    x(col) = xv;
    for (Eigen::SparseMatrix<double>::InnerIterator it(j, col); it; ++it) r(it.row()) -= it.value() * xv;
  }
  // 2. Harmonic balance with the Schur unknowns at zero, then the Schur right-hand side.
  const Eigen::VectorXd y0 = block_solve(r.head(ny));
  const auto na = static_cast<Eigen::Index>(active.size());
  Eigen::VectorXd rs(nd + na);
  rs(0) = r(ny) - cd.col(0).dot(y0);
  if (border >= 0) rs(1) = r(border) - cd.col(1).dot(y0);
  Eigen::MatrixXd w(nc, f);  // N_kᵀ y0_k
  for (int k = 0; k < f; ++k) w.col(k) = dirs[static_cast<size_t>(k)].transpose() * y0.segment(start[k], length[k]);
  for (Eigen::Index q = 0; q < na; ++q) {
    const Eigen::Index l = active[static_cast<size_t>(q)];
    rs(nd + q) = r(ny + 1 + l) - gamma_a.row(q).dot(w.row(stop_of(l)));
  }
  // 3. The Schur unknowns, then the harmonic balance by back substitution.
  const Eigen::VectorXd u = schur.solve(rs);
  Eigen::VectorXd y = y0 - xd * u.head(nd);
  Eigen::MatrixXd z = Eigen::MatrixXd::Zero(nc, f);  // Σ over active samples of stop c: β_k u
  for (Eigen::Index q = 0; q < na; ++q) z.row(stop_of(active[static_cast<size_t>(q)])) += u(nd + q) * beta_a.row(q);
  for (int k = 0; k < f; ++k) y.segment(start[k], length[k]) -= v[static_cast<size_t>(k)] * z.col(k);
  x.head(ny) = y;
  x(ny) = u(0);
  if (border >= 0) x(border) = u(1);
  for (Eigen::Index q = 0; q < na; ++q) x(ny + 1 + active[static_cast<size_t>(q)]) = u(nd + q);
  return x;
}

// The penalty backbone (no multipliers: J is [Y, ω², (E)] square). Its harmonic-balance block is
// blockdiag(Ã_k) + P Ĉ Pᵀ: Ã_k = A_k plus each stop's curvature within harmonic k (read off J's
// diagonal blocks), and between two harmonics k ≠ l only the stops couple, stop c by
// C_c(k, l) N_k(:, c) N_l(:, c)ᵀ with C_c = Θᵀ diag(κ_c) Θ (NonlinearModes::contact_curvature).
// P holds the columns N_k(:, c), one per (stop, harmonic); Ĉ = blockdiag_c(Ĉ_c), Ĉ_c = C_c with
// its diagonal zeroed (it already sits in Ã_k). With z = Pᵀ y for the stops in contact, and u the
// dense unknowns (ω², E):
//   [ D − cdᵀ Ã⁻¹ bd    −cdᵀ Ã⁻¹ P Ĉ ] [u]   [r_u − cdᵀ y0]
//   [ Pᵀ Ã⁻¹ bd         I + G Ĉ      ] [z] = [Pᵀ y0       ],  y0 = Ã⁻¹ r_y,
// G = Pᵀ Ã⁻¹ P, whose (c, k), (c', l) entry is δ_kl G_k(c, c'); then y = y0 − Ã⁻¹ bd u − Ã⁻¹ P Ĉ z.
// det J = Π_k det Ã_k · det S as for exact contact. C_c(k, l) is the least-squares multiple of
// N_k(:, c) N_l(:, c)ᵀ in J's (k, l) block, exact when no DOF lies in two stops' directions (the
// constructor checks; otherwise SparseLu); an entry between two harmonics at any other DOF pair
// also goes to SparseLu.
bool NonlinearModes::BackboneSystem::KktSolver::Impl::factorize_penalty(const Eigen::SparseMatrix<double>& jac) {
  // border, nd, the zeroed blocks a and the dense columns bd, cd: set by factorize().
  std::vector<Eigen::MatrixXd> coupling(static_cast<size_t>(nc), Eigen::MatrixXd::Zero(f, f));
  Eigen::MatrixXd tail = Eigen::MatrixXd::Zero(nd, nd);
  Eigen::VectorXd row_sum = Eigen::VectorXd::Zero(rows);
  auto dense = [&](Eigen::Index i) -> Eigen::Index { return i == ny ? 0 : 1; };  // ω² or E
  for (Eigen::Index c = 0; c < jac.outerSize(); ++c) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(jac, c); it; ++it) {
      const Eigen::Index i = it.row();
      const double val = it.value();
      if (!std::isfinite(val)) return false;
      if (val == 0.0) continue;
      row_sum(i) += std::abs(val);
      if (c < ny && i < ny) {
        const int kc = block_of[static_cast<size_t>(c)], ki = block_of[static_cast<size_t>(i)];
        const Eigen::Index lc = local_of[static_cast<size_t>(c)], li = local_of[static_cast<size_t>(i)];
        if (ki == kc) {
          a[static_cast<size_t>(kc)](li, lc) = val;
          continue;
        }
        const int st = stop_at[static_cast<size_t>(ki)][static_cast<size_t>(li)];
        if (st < 0 || stop_at[static_cast<size_t>(kc)][static_cast<size_t>(lc)] != st) return factorize_sparse(jac);
        coupling[static_cast<size_t>(st)](ki, kc) +=
            dirs[static_cast<size_t>(ki)](li, st) * dirs[static_cast<size_t>(kc)](lc, st) * val;
      } else if (c < ny) {
        cd(c, dense(i)) = val;
      } else if (i < ny) {
        bd(i, dense(c)) = val;
      } else {
        tail(dense(i), dense(c)) += val;
      }
    }
  }
  norm_inf = row_sum.maxCoeff();
  chat.assign(static_cast<size_t>(nc), Eigen::MatrixXd());
  touching.clear();
  for (int st = 0; st < nc; ++st) {
    Eigen::MatrixXd& ch = coupling[static_cast<size_t>(st)];
    for (int k = 0; k < f; ++k) {
      for (int l = 0; l < f; ++l) {
        const double d2 = dir_norm2(st, k) * dir_norm2(st, l);
        ch(k, l) = k != l && d2 > 0.0 ? ch(k, l) / d2 : 0.0;
      }
    }
    if (ch.isZero(0.0)) continue;
    chat[static_cast<size_t>(st)] = std::move(ch);
    touching.push_back(st);
  }
  if (!factorize_blocks()) return factorize_sparse(jac);
  const auto nt = static_cast<Eigen::Index>(touching.size());
  const Eigen::Index m = nd + nt * f;
  Eigen::MatrixXd schur_matrix = Eigen::MatrixXd::Zero(m, m);
  schur_matrix.topLeftCorner(nd, nd) = tail - cd.transpose() * xd;
  schur_matrix.diagonal().tail(nt * f).setOnes();
  for (int k = 0; k < f; ++k) {
    const auto kk = static_cast<size_t>(k);
    const Eigen::MatrixXd q = v[kk].transpose() * cd.middleRows(start[k], length[k]);    // nc × nd: V_kᵀ c_e
    const Eigen::MatrixXd pd = dirs[kk].transpose() * xd.middleRows(start[k], length[k]);  // nc × nd: N_kᵀ A_k⁻¹ b_u
    for (Eigen::Index t = 0; t < nt; ++t) {
      const int st = touching[static_cast<size_t>(t)];
      for (Eigen::Index e = 0; e < nd; ++e) {
        schur_matrix.row(e).segment(nd + t * f, f) -= q(st, e) * chat[static_cast<size_t>(st)].row(k);
        schur_matrix(nd + t * f + k, e) += pd(st, e);
      }
    }
  }
  Eigen::VectorXd gk(f);
  for (Eigen::Index t1 = 0; t1 < nt; ++t1) {
    for (Eigen::Index t2 = 0; t2 < nt; ++t2) {
      const int c1 = touching[static_cast<size_t>(t1)], c2 = touching[static_cast<size_t>(t2)];
      for (int k = 0; k < f; ++k) gk(k) = g[static_cast<size_t>(k)](c1, c2);
      schur_matrix.block(nd + t1 * f, nd + t2 * f, f, f).noalias() += gk.asDiagonal() * chat[static_cast<size_t>(c2)];
    }
  }
  schur.compute(schur_matrix);
  return accept_schur(jac, nt * f);
}

Eigen::VectorXd NonlinearModes::BackboneSystem::KktSolver::Impl::core_solve_penalty(const Eigen::VectorXd& rhs) const {
  const Eigen::VectorXd y0 = block_solve(rhs.head(ny));
  const auto nt = static_cast<Eigen::Index>(touching.size());
  Eigen::VectorXd rs(nd + nt * f);
  rs(0) = rhs(ny) - cd.col(0).dot(y0);
  if (border >= 0) rs(1) = rhs(border) - cd.col(1).dot(y0);
  for (Eigen::Index t = 0; t < nt; ++t) {
    const int st = touching[static_cast<size_t>(t)];
    for (int k = 0; k < f; ++k) {
      rs(nd + t * f + k) = dirs[static_cast<size_t>(k)].col(st).dot(y0.segment(start[k], length[k]));
    }
  }
  const Eigen::VectorXd u = schur.solve(rs);
  Eigen::VectorXd x(rows);
  Eigen::VectorXd y = y0 - xd * u.head(nd);
  for (Eigen::Index t = 0; t < nt; ++t) {
    const int st = touching[static_cast<size_t>(t)];
    const Eigen::VectorXd cz = chat[static_cast<size_t>(st)] * u.segment(nd + t * f, f);  // (Ĉ z)_(c, k)
    for (int k = 0; k < f; ++k) y.segment(start[k], length[k]) -= v[static_cast<size_t>(k)].col(st) * cz(k);
  }
  x.head(ny) = y;
  x(ny) = u(0);
  if (border >= 0) x(border) = u(1);
  return x;
}

}  // namespace wbm::solvers
