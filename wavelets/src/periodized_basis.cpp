// Periodized scaling-function basis [JL14 Eq. (25)].
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <wbm/wavelets/periodized_basis.hpp>

namespace wbm::wavelets {

int PeriodizedBasisOptions::grid_level_at(int level) const { return grid_level < 0 ? std::max(level, 12) : grid_level; }

void PeriodizedBasisOptions::validate(int level) const {
  if (normalization != Normalization::Orthonormal && normalization != Normalization::UnitIntegral) {
    throw std::invalid_argument("PeriodizedBasisOptions.normalization = " +
                                std::to_string(static_cast<int>(normalization)) +
                                ": must be Orthonormal or UnitIntegral");
  }
  const int grid = grid_level_at(level);
  if (grid_level < -1 || grid < level || grid - level > 20) {
    throw std::invalid_argument("PeriodizedBasisOptions.grid_level = " + std::to_string(grid_level) +
                                ": must be -1 (max(J, 12)) or in [J, J + 20] = [" + std::to_string(level) + ", " +
                                std::to_string(level + 20) + "]");
  }
}

PeriodizedBasis::PeriodizedBasis(const Family& family, int level, PeriodizedBasisOptions options)
    : level_(level), dimension_(0), normalization_(options.normalization), scale_(1.0) {
  if (level < 0 || level > 20) {
    throw std::invalid_argument("PeriodizedBasis: level J = " + std::to_string(level) +
                                " must be in [0, 20] (M = 2^J basis functions)");
  }
  options.validate(level);
  const int grid = options.grid_level_at(level);
  dimension_ = 1 << level;
  if (normalization_ == Normalization::UnitIntegral) scale_ = std::sqrt(std::ldexp(1.0, level));  // 2^{J/2}
  function_ = std::make_shared<const ScalingFunction>(family, grid - level);
}

double PeriodizedBasis::value(int k, double tau, int derivative) const {
  if (k < 0 || k >= dimension_) {
    throw std::out_of_range("PeriodizedBasis::value: k = " + std::to_string(k) + " outside [0, " +
                            std::to_string(dimension_) + ")");
  }
  const double m = dimension_;
  const double x0 = std::ldexp(tau, level_) - k;  // exact for dyadic τ
  // φ_{J,k}(τ) = 2^{J/2} Σ_ℓ φ(2^J(τ − ℓ) − k): the ℓ with begin ≤ x0 − ℓM ≤ end.
  const auto lo = static_cast<long>(std::ceil((x0 - function_->support_end()) / m));
  const auto hi = static_cast<long>(std::floor((x0 - function_->support_begin()) / m));
  double s = 0.0;
  for (long l = lo; l <= hi; ++l) s += function_->value(x0 - static_cast<double>(l) * m, derivative);
  return scale_ * std::sqrt(m) * std::ldexp(1.0, level_ * derivative) * s;
}

Eigen::MatrixXd PeriodizedBasis::values(const Eigen::VectorXd& tau, int derivative) const {
  return Eigen::MatrixXd(sparse_values(tau, derivative));
}

Eigen::SparseMatrix<double, Eigen::RowMajor> PeriodizedBasis::sparse_values(const Eigen::VectorXd& tau,
                                                                             int derivative) const {
  // Only the functions whose (wrapped) support covers τ_p are non-zero: visit the integer shifts
  // j = k + ℓM with begin ≤ 2^J τ_p − j ≤ end, so the cost is O(Q · support), not O(Q · M).
  // Wrapped shifts that land on the same k (support longer than the period) are summed.
  const double factor = scale_ * std::sqrt(static_cast<double>(dimension_)) * std::ldexp(1.0, level_ * derivative);
  std::vector<Eigen::Triplet<double>> entries;
  const double width = function_->support_end() - function_->support_begin() + 1.0;
  entries.reserve(static_cast<size_t>(tau.size()) * static_cast<size_t>(std::min<double>(width, dimension_)));
  for (Eigen::Index p = 0; p < tau.size(); ++p) {
    if (!std::isfinite(tau(p))) {
      throw std::invalid_argument("PeriodizedBasis::values: tau[" + std::to_string(p) + "] is not finite; give "
                                  "normalized times, finite (the functions are 1-periodic)");
    }
    // The functions are 1-periodic: τ − ⌊τ⌋ ∈ [0, 1) keeps the shifts below in range for any finite τ.
    const double x = std::ldexp(tau(p) - std::floor(tau(p)), level_);
    const auto lo = static_cast<long>(std::ceil(x - function_->support_end()));
    const auto hi = static_cast<long>(std::floor(x - function_->support_begin()));
    for (long j = lo; j <= hi; ++j) {
      const long k = ((j % dimension_) + dimension_) % dimension_;
      const double v = function_->value(x - static_cast<double>(j), derivative);
      if (v != 0.0) entries.emplace_back(static_cast<int>(p), static_cast<int>(k), factor * v);
    }
  }
  Eigen::SparseMatrix<double, Eigen::RowMajor> out(tau.size(), dimension_);
  out.setFromTriplets(entries.begin(), entries.end());  // duplicates (wrapped shifts) are summed
  return out;
}

Eigen::MatrixXd PeriodizedBasis::sampled(int samples, int derivative) const {
  if (samples < 1) throw std::invalid_argument("PeriodizedBasis::sampled: samples Q = " + std::to_string(samples) + " must be >= 1");
  const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(samples, 0.0, 1.0 - 1.0 / samples);
  return values(tau, derivative);
}

Eigen::SparseMatrix<double> PeriodizedBasis::connection_matrix(int d1, int d2) const {
  return scale_ * scale_ * periodized_connection_matrix(connection_coefficients(family(), d1, d2), level_);
}

Eigen::MatrixXd PeriodizedBasis::discrete_inner_products(int d1, int d2, int samples) const {
  const Eigen::MatrixXd a = sampled(samples, d1);
  const Eigen::MatrixXd b = d2 == d1 ? a : sampled(samples, d2);
  return a.transpose() * b / static_cast<double>(samples);
}

}  // namespace wbm::wavelets
