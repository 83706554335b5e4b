#pragma once
// A sparse matrix assembled as Eigen's setFromTriplets assembles it (column-major and
// compressed, duplicates summed in the order given, explicit zeros kept), reusing the work of an
// earlier call whose pattern was the same: then only the values are scattered, O(T) for T
// triplets, without the sort and the row-major to column-major copy of setFromTriplets.
// A Jacobian assembled at every corrector iteration keeps its pattern while its active set does
// (the KKT backbone, nonlinear_modes_kkt.cpp). The entries are equal bit for bit to those of
// setFromTriplets: each position starts at its first contribution, the later ones added in their
// order, as Eigen's collapseDuplicates does. Up to kPatterns patterns are kept (the nonsmooth
// system and a piece can differ); copies share them; safe to call from several threads.
// Private to wbm::solvers.
#include <cstddef>
#include <memory>
#include <mutex>
#include <vector>

#include <Eigen/SparseCore>

namespace wbm::solvers::detail {

class TripletPattern {
 public:
  using Triplets = std::vector<Eigen::Triplet<double>>;
  // A matrix of base's size: setFromTriplets of base's entries (column-major order, at most one
  // per position: a compressed matrix) followed by the triplets `t` (indices in range: Eigen's own
  // assertion). A base whose pattern repeats (a block-diagonal harmonic balance, filled straight
  // into compressed storage) costs a comparison of its index arrays and one scatter of its values,
  // instead of one triplet per entry. Throws std::invalid_argument for a base not compressed.
  [[nodiscard]] Eigen::SparseMatrix<double> assemble(const Eigen::SparseMatrix<double>& base, const Triplets& t) const;

 private:
  static constexpr std::size_t kPatterns = 4;
  struct Pattern {
    Eigen::Index rows = 0, cols = 0;
    std::vector<int> base_outer, base_inner;  // base's pattern
    std::vector<int> base_position;           // base entry q → its index in the compressed value array
    std::vector<int> row, col;                // the triplets' indices, in order
    std::vector<int> position;                // triplet i → its index in the compressed value array
    std::vector<char> first;                  // triplet i is the first contribution at its position
    Eigen::SparseMatrix<double> matrix;
  };
  struct Cache {
    std::mutex mutex;
    std::vector<std::shared_ptr<const Pattern>> patterns;  // most recently used last
  };
  std::shared_ptr<Cache> cache_ = std::make_shared<Cache>();
};

}  // namespace wbm::solvers::detail
