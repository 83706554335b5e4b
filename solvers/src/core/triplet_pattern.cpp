#include "core/triplet_pattern.hpp"

#include <algorithm>

namespace wbm::solvers::detail {

namespace {
bool same_indices(const std::vector<int>& row, const std::vector<int>& col, const TripletPattern::Triplets& t) {
  if (row.size() != t.size()) return false;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (row[i] != t[i].row() || col[i] != t[i].col()) return false;
  }
  return true;
}
}  // namespace

Eigen::SparseMatrix<double> TripletPattern::assemble(Eigen::Index rows, Eigen::Index cols, const Triplets& t) const {
  std::shared_ptr<const Pattern> found;
  {
    const std::lock_guard<std::mutex> lock(cache_->mutex);
    auto& list = cache_->patterns;
    for (auto it = list.begin(); it != list.end(); ++it) {
      if ((*it)->rows == rows && (*it)->cols == cols && same_indices((*it)->row, (*it)->col, t)) {
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
    for (std::size_t i = 0; i < t.size(); ++i) {
      const int p = found->position[i];
      v[p] = found->first[i] != 0 ? t[i].value() : v[p] + t[i].value();
    }
    return out;
  }
  auto pattern = std::make_shared<Pattern>();
  pattern->rows = rows;
  pattern->cols = cols;
  pattern->matrix.resize(rows, cols);
  pattern->matrix.setFromTriplets(t.begin(), t.end());
  pattern->matrix.makeCompressed();
  pattern->row.resize(t.size());
  pattern->col.resize(t.size());
  pattern->position.resize(t.size());
  pattern->first.assign(t.size(), 0);
  const Eigen::SparseMatrix<double>& m = pattern->matrix;
  std::vector<char> seen(static_cast<std::size_t>(m.nonZeros()), 0);
  for (std::size_t i = 0; i < t.size(); ++i) {
    pattern->row[i] = t[i].row();
    pattern->col[i] = t[i].col();
    const int* begin = m.innerIndexPtr() + m.outerIndexPtr()[t[i].col()];
    const int* end = m.innerIndexPtr() + m.outerIndexPtr()[t[i].col() + 1];
    const int p = static_cast<int>(std::lower_bound(begin, end, t[i].row()) - m.innerIndexPtr());
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
