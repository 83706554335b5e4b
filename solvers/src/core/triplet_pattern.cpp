#include "core/triplet_pattern.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>

namespace wbm::solvers::detail {

namespace {
bool same_indices(const std::vector<int>& row, const std::vector<int>& col, const TripletPattern::Triplets& t) {
  if (row.size() != t.size()) return false;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (row[i] != t[i].row() || col[i] != t[i].col()) return false;
  }
  return true;
}

bool same_array(const std::vector<int>& a, const int* b, Eigen::Index n) {
  return static_cast<Eigen::Index>(a.size()) == n &&
         (n == 0 || std::memcmp(a.data(), b, static_cast<std::size_t>(n) * sizeof(int)) == 0);
}

// Index of entry (row, col) in the compressed matrix m (present by construction).
int position_of(const Eigen::SparseMatrix<double>& m, int row, int col) {
  const int* begin = m.innerIndexPtr() + m.outerIndexPtr()[col];
  const int* end = m.innerIndexPtr() + m.outerIndexPtr()[col + 1];
  return static_cast<int>(std::lower_bound(begin, end, row) - m.innerIndexPtr());
}
}  // namespace

Eigen::SparseMatrix<double> TripletPattern::assemble(const Eigen::SparseMatrix<double>& base, const Triplets& t) const {
  if (!base.isCompressed()) throw std::invalid_argument("TripletPattern::assemble: the base matrix is not compressed");
  const Eigen::Index rows = base.rows(), cols = base.cols(), nb = base.nonZeros();
  const int* outer = base.outerIndexPtr();
  const int* inner = base.innerIndexPtr();
  const double* base_value = base.valuePtr();
  std::shared_ptr<const Pattern> found;
  {
    const std::lock_guard<std::mutex> lock(cache_->mutex);
    auto& list = cache_->patterns;
    for (auto it = list.begin(); it != list.end(); ++it) {
      const Pattern& p = **it;
      if (p.rows == rows && p.cols == cols && same_array(p.base_outer, outer, cols + 1) &&
          same_array(p.base_inner, inner, nb) && same_indices(p.row, p.col, t)) {
        found = *it;
        list.erase(it);
        list.push_back(found);
        break;
      }
    }
  }
  if (found) {
    Eigen::SparseMatrix<double> out = found->matrix;
    double* v = out.valuePtr();
    for (Eigen::Index q = 0; q < nb; ++q) v[found->base_position[static_cast<std::size_t>(q)]] = base_value[q];
    for (std::size_t i = 0; i < t.size(); ++i) {
      const int p = found->position[i];
      v[p] = found->first[i] != 0 ? t[i].value() : v[p] + t[i].value();
    }
    return out;
  }
  auto pattern = std::make_shared<Pattern>();
  pattern->rows = rows;
  pattern->cols = cols;
  pattern->base_outer.assign(outer, outer + cols + 1);
  pattern->base_inner.assign(inner, inner + nb);
  Triplets all;
  all.reserve(static_cast<std::size_t>(nb) + t.size());
  for (Eigen::Index c = 0; c < cols; ++c) {
    for (int q = outer[c]; q < outer[c + 1]; ++q) all.emplace_back(inner[q], static_cast<int>(c), base_value[q]);
  }
  all.insert(all.end(), t.begin(), t.end());
  pattern->matrix.resize(rows, cols);
  pattern->matrix.setFromTriplets(all.begin(), all.end());
  pattern->matrix.makeCompressed();
  const Eigen::SparseMatrix<double>& m = pattern->matrix;
  std::vector<char> seen(static_cast<std::size_t>(m.nonZeros()), 0);
  pattern->base_position.resize(static_cast<std::size_t>(nb));
  for (Eigen::Index c = 0; c < cols; ++c) {
    for (int q = outer[c]; q < outer[c + 1]; ++q) {
      const int p = position_of(m, inner[q], static_cast<int>(c));
      pattern->base_position[static_cast<std::size_t>(q)] = p;
      seen[static_cast<std::size_t>(p)] = 1;
    }
  }
  pattern->row.resize(t.size());
  pattern->col.resize(t.size());
  pattern->position.resize(t.size());
  pattern->first.assign(t.size(), 0);
  for (std::size_t i = 0; i < t.size(); ++i) {
    pattern->row[i] = t[i].row();
    pattern->col[i] = t[i].col();
    const int p = position_of(m, t[i].row(), t[i].col());
    pattern->position[i] = p;
    pattern->first[i] = seen[static_cast<std::size_t>(p)] == 0 ? 1 : 0;
    seen[static_cast<std::size_t>(p)] = 1;
  }
  Eigen::SparseMatrix<double> out = pattern->matrix;
  const std::lock_guard<std::mutex> lock(cache_->mutex);
  if (cache_->patterns.size() == kPatterns) cache_->patterns.erase(cache_->patterns.begin());
  cache_->patterns.push_back(std::move(pattern));
  return out;
}

}  // namespace wbm::solvers::detail
