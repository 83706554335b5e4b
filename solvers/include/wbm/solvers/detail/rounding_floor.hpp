// The rounding floor of a residual at a point: how far R moves when its argument moves by its own
// rounding. Shared by WeightedResidual::rounding_floor (a single solve) and pseudo_arclength (a
// corrector that stalls at a step below minimum).
#pragma once

#include <algorithm>
#include <limits>

#include <Eigen/Core>

namespace wbm::solvers::detail {

/// v ⊙ (1 ± ε), ε = 2⁻⁵², the sign alternating from entry to entry, starting with + (pattern 0)
/// or − (pattern 1). Same length as v.
inline Eigen::VectorXd rounded(Eigen::VectorXd v, int pattern) {
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    const double sign = ((i + pattern) % 2 == 0) ? 1.0 : -1.0;
    v(i) *= 1.0 + sign * std::numeric_limits<double>::epsilon();
  }
  return v;
}

/// max over the two patterns of ‖R(rounded(v, p)) − R(v)‖₂, in R's units: a residual within a
/// few times this cannot be reduced in double precision at v. `residual`: v ↦ R(v) (any length).
/// Three evaluations of R.
template <class Residual>
double rounding_floor(const Residual& residual, const Eigen::VectorXd& v) {
  const Eigen::VectorXd r0 = residual(v);
  double floor = 0.0;
  for (int pattern = 0; pattern < 2; ++pattern) floor = std::max(floor, (residual(rounded(v, pattern)) - r0).norm());
  return floor;
}

}  // namespace wbm::solvers::detail
