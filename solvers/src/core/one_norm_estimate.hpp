#pragma once
// Hager's estimate of ‖A⁻¹‖₁ with Higham's refinements [Higham 1988, ACM TOMS 14(4), Alg. 4.1
// (Hager's method, at most 5 iterations, stopped when ‖z‖∞ ≤ zᵀx) and the extra test vector
// b_i = (−1)^{i+1} (1 + (i−1)/(n−1)) with estimate 2‖A⁻¹b‖₁/(3n)]. Needs only solves with A and
// Aᵀ, so it works on any factorization (modal blocks, sparse LU). The result is a lower bound
// of ‖A⁻¹‖₁, exact in most cases. Private to wbm::solvers (public Eigen API only).
#include <algorithm>
#include <cmath>

#include <Eigen/Core>

namespace wbm::solvers::detail {

// solve(v, transposed) returns A⁻¹ v (transposed = false) or A⁻ᵀ v (true); n = rows of A.
template <class Solve>
double inverse_one_norm_estimate(Eigen::Index n, const Solve& solve) {
  if (n == 0) return 0.0;
  Eigen::VectorXd x = Eigen::VectorXd::Constant(n, 1.0 / static_cast<double>(n));
  double estimate = 0.0;
  Eigen::Index last_j = -1;
  for (int k = 0; k < 5; ++k) {
    const Eigen::VectorXd y = solve(x, false);
    estimate = std::max(estimate, y.lpNorm<1>());
    const Eigen::VectorXd xi = y.unaryExpr([](double v) { return v >= 0.0 ? 1.0 : -1.0; });
    const Eigen::VectorXd z = solve(xi, true);
    Eigen::Index j = 0;
    const double z_max = z.cwiseAbs().maxCoeff(&j);
    if (k > 0 && (z_max <= z.dot(x) || j == last_j)) break;  // a local maximum of ‖A⁻¹x‖₁ on the unit ball
    x.setZero();
    x(j) = 1.0;
    last_j = j;
  }
  Eigen::VectorXd b(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    b(i) = (i % 2 == 0 ? 1.0 : -1.0) * (1.0 + (n > 1 ? static_cast<double>(i) / static_cast<double>(n - 1) : 0.0));
  }
  return std::max(estimate, 2.0 * Eigen::VectorXd(solve(b, false)).lpNorm<1>() / (3.0 * static_cast<double>(n)));
}

}  // namespace wbm::solvers::detail
