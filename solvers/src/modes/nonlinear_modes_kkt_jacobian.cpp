// The Jacobian of NonlinearModes::BackboneSystem (nonlinear_modes.hpp): exact contact straight
// into compressed storage, penalty stops through TripletPattern (the contact curvature adds onto
// the harmonic-balance blocks). Both give the entries, explicit zeros and summation order of
// Eigen's setFromTriplets over the blocks followed by the triplets of the layout below.
//
// Layout (reduced indices: the phase row and column removed; ny harmonic-balance unknowns):
//   rows and columns 0 … ny − 1: w_k (K̂ − ν_k² s M̂) per coefficient k (block diagonal);
//   column ny (s = ω²/ω₀²): −w_k ν_k² (M̂ Y_k)_i in every harmonic-balance row;
//   row ny (the normalization m̂/m̂_c − E): 2 w_k ν_k² (M̂ Y_k)_i m_ref/m̂_c in every such column;
//   exact contact, sample s of stop c (column and row ny + 1 + c m + s): w θ_sk in row (k, d) for
//   every term (d, w) of the stop's direction; its row is 1 on the diagonal where the min picks
//   f_s, else −w θ_sk in column (k, d) (the min picks −g_s).
#include <wbm/solvers/nonlinear_modes.hpp>

#include <algorithm>
#include <utility>
#include <vector>

#include "core/triplet_pattern.hpp"

namespace wbm::solvers {

namespace {

// Full stacked index → reduced (state) index, −1 for the phase coefficient p (removed).
Eigen::Index reduced_index(Eigen::Index i, Eigen::Index p) { return i < p ? i : (i == p ? Eigen::Index{-1} : i - 1); }

// The entries of column `col` of w (K̂ − ν² s M̂) = w K̂ + mass_factor M̂, rows in ascending order,
// as fl(w k) + fl(mass_factor m) where both patterns hold the row: emit(row, value).
template <class Emit>
void block_column(const Eigen::SparseMatrix<double>& ks, const Eigen::SparseMatrix<double>& ms, Eigen::Index col,
                  double w, double mass_factor, Emit&& emit) {
  Eigen::SparseMatrix<double>::InnerIterator ik(ks, col), im(ms, col);
  while (ik || im) {
    if (ik && (!im || ik.row() < im.row())) {
      emit(ik.row(), w * ik.value());
      ++ik;
    } else if (!ik || im.row() < ik.row()) {
      emit(im.row(), mass_factor * im.value());
      ++im;
    } else {
      emit(ik.row(), w * ik.value() + mass_factor * im.value());
      ++ik;
      ++im;
    }
  }
}

}  // namespace

struct NonlinearModes::BackboneSystem::ExactLayout {
  Eigen::MatrixXd theta_t;  // Θᵀ (F × m): a multiplier's column of J reads a column of it
  // Per stop: its direction as (DOF, weight) in ascending DOF order (the order of J's rows); its
  // DOFs are distinct (NonlinearModes' validation refuses a DOF given twice), so no entry sums
  // two terms.
  std::vector<std::vector<std::pair<int, double>>> dirs;
  // Per DOF: the stops whose direction holds it (ascending), each with the DOF's weight there.
  std::vector<std::vector<std::pair<int, double>>> stops_at;
  Eigen::Index terms = 0;  // the most terms of a direction
};

std::shared_ptr<const NonlinearModes::BackboneSystem::ExactLayout> NonlinearModes::BackboneSystem::make_exact_layout()
    const {
  const auto& nm = *nm_;
  auto out = std::make_shared<ExactLayout>();
  out->theta_t = nm.theta_.transpose();
  out->stops_at.resize(static_cast<size_t>(nm.n_));
  for (size_t c = 0; c < nm.stops_.size(); ++c) {
    auto d = nm.stops_[c].terms();
    std::sort(d.begin(), d.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    for (const auto& [dof, w] : d) out->stops_at[static_cast<size_t>(dof)].emplace_back(static_cast<int>(c), w);
    out->terms = std::max(out->terms, static_cast<Eigen::Index>(d.size()));
    out->dirs.push_back(std::move(d));
  }
  return out;
}

Eigen::SparseMatrix<double> NonlinearModes::BackboneSystem::exact_jacobian(const Eigen::MatrixXd& my, double s,
                                                                           const ActiveSet& gap_rows) const {
  const auto& nm = *nm_;
  const ExactLayout& layout = *exact_layout_;
  const int n = nm.n_, f = nm.f_, ms = nm.options_.samples;
  const Eigen::Index p = nm.phase_index_;
  auto reduced = [p](Eigen::Index i) { return reduced_index(i, p); };
  const auto n_stops = static_cast<int>(nm.stops_.size());
  Eigen::Index gap_count = 0;
  for (const auto a : gap_rows) gap_count += a != 0 ? 1 : 0;
  const Eigen::Index nl = static_cast<Eigen::Index>(n_stops) * ms;
  const Eigen::Index ft = static_cast<Eigen::Index>(f) * layout.terms;
  const Eigen::Index bound = static_cast<Eigen::Index>(f) * (nm.ks_.nonZeros() + nm.ms_.nonZeros()) + 2 * ny_ +
                             nl * (ft + 1) + gap_count * ft;

  Eigen::SparseMatrix<double> j(size_, size_);
  j.resizeNonZeros(bound);
  int* outer = j.outerIndexPtr();
  int* inner = j.innerIndexPtr();
  double* value = j.valuePtr();
  int q = 0;
  Eigen::Index column = 0;
  auto put = [&](Eigen::Index row, double v) {
    inner[q] = static_cast<int>(row);
    value[q++] = v;
  };
  // Harmonic-balance columns (k, d): the block, the normalization row, the active Signorini rows.
  for (int k = 0; k < f; ++k) {
    const double w = nm.weight_(k), nu2 = nm.nu_(k) * nm.nu_(k);
    const double mass_factor = -w * nu2 * s;
    const Eigen::Index first = static_cast<Eigen::Index>(k) * n;
    for (Eigen::Index d = 0; d < n; ++d) {
      if (first + d == p) continue;
      outer[column++] = q;
      block_column(nm.ks_, nm.ms_, d, w, mass_factor, [&](Eigen::Index row, double v) {
        const Eigen::Index r = reduced(first + row);
        if (r >= 0) put(r, v);
      });
      put(ny_, 2.0 * w * nu2 * my(d, k) * nm.m_ref_ / nm.m_c_);  // ∂(m̂/m̂_c)/∂Y
      for (const auto& [c, weight] : layout.stops_at[static_cast<size_t>(d)]) {
        for (int smp = 0; smp < ms; ++smp) {
          const Eigen::Index i = static_cast<Eigen::Index>(c) * ms + smp;
          // The min picks −g_s = −Σ_d w θ_s Y_d + g_c.
          if (gap_rows[static_cast<size_t>(i)] != 0) put(ny_ + 1 + i, -weight * nm.theta_(smp, k));
        }
      }
    }
  }
  // Column ny: ∂/∂s of every harmonic-balance row.
  outer[column++] = q;
  for (int k = 0; k < f; ++k) {
    const double w = nm.weight_(k), nu2 = nm.nu_(k) * nm.nu_(k);
    for (int i = 0; i < n; ++i) {
      const Eigen::Index r = reduced(static_cast<Eigen::Index>(k) * n + i);
      if (r >= 0) put(r, -w * nu2 * my(i, k));
    }
  }
  // Multiplier columns: w θ_sk in the rows of the stop's direction (∂HB/∂λ), 1 where the min picks f_s.
  for (int c = 0; c < n_stops; ++c) {
    const auto& dir = layout.dirs[static_cast<size_t>(c)];
    for (int smp = 0; smp < ms; ++smp) {
      const Eigen::Index i = static_cast<Eigen::Index>(c) * ms + smp, col = ny_ + 1 + i;
      outer[column++] = q;
      const double* theta = layout.theta_t.col(smp).data();  // θ_sk, k = 0 … F − 1
      for (int k = 0; k < f; ++k) {
        for (const auto& [d, weight] : dir) {
          const Eigen::Index r = reduced(static_cast<Eigen::Index>(k) * n + d);
          if (r >= 0) put(r, weight * theta[k]);
        }
      }
      if (gap_rows[static_cast<size_t>(i)] == 0) put(col, 1.0);
    }
  }
  while (column <= size_) outer[column++] = q;
  j.resizeNonZeros(q);
  return j;
}

Eigen::SparseMatrix<double> NonlinearModes::BackboneSystem::penalty_jacobian(const Eigen::MatrixXd& my, double s,
                                                                             const Eigen::VectorXd& curvature) const {
  const auto& nm = *nm_;
  const int n = nm.n_, f = nm.f_;
  const Eigen::Index p = nm.phase_index_;
  auto reduced = [p](Eigen::Index i) { return reduced_index(i, p); };
  // The harmonic-balance blocks, straight into compressed storage (column-major, the phase row
  // and column left out). TripletPattern puts them first at their positions, before the triplets.
  Eigen::SparseMatrix<double> blocks(size_, size_);
  blocks.resizeNonZeros(static_cast<Eigen::Index>(f) * (nm.ks_.nonZeros() + nm.ms_.nonZeros()));
  {
    int* outer = blocks.outerIndexPtr();
    int* inner = blocks.innerIndexPtr();
    double* value = blocks.valuePtr();
    int q = 0;
    Eigen::Index column = 0;
    for (int k = 0; k < f; ++k) {
      const double w = nm.weight_(k), nu2 = nm.nu_(k) * nm.nu_(k);
      const Eigen::Index first = static_cast<Eigen::Index>(k) * n;
      for (Eigen::Index col = 0; col < n; ++col) {
        if (first + col == p) continue;
        outer[column++] = q;
        block_column(nm.ks_, nm.ms_, col, w, -w * nu2 * s, [&](Eigen::Index row, double v) {
          const Eigen::Index r = reduced(first + row);
          if (r < 0) return;
          inner[q] = static_cast<int>(r);
          value[q++] = v;
        });
      }
    }
    while (column <= size_) outer[column++] = q;
    blocks.resizeNonZeros(q);
  }
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<size_t>(f) * 2 * n);
  for (int k = 0; k < f; ++k) {
    const double w = nm.weight_(k), nu2 = nm.nu_(k) * nm.nu_(k);
    for (int i = 0; i < n; ++i) {
      const Eigen::Index r = reduced(static_cast<Eigen::Index>(k) * n + i);
      if (r < 0) continue;
      t.emplace_back(r, ny_, -w * nu2 * my(i, k));                                   // ∂/∂s
      t.emplace_back(ny_, r, 2.0 * w * nu2 * my(i, k) * nm.m_ref_ / nm.m_c_);        // ∂(m̂/m̂_c)/∂Y
    }
  }
  // ∂HB(k, i)/∂Y(l, j) = w_i w_j Σ_s θ_sk f′(g_s) θ_sl, f′ = κ [g_s > 0]
  for (const auto& e : nm.contact_curvature(curvature)) {
    const Eigen::Index r = reduced(e.row()), c = reduced(e.col());
    if (r >= 0 && c >= 0) t.emplace_back(r, c, e.value());
  }
  return pattern_->assemble(blocks, t);
}

}  // namespace wbm::solvers
