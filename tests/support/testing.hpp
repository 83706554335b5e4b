#pragma once
/// Shared test helpers: convergence orders and finite-difference Jacobian checks.

#include <cmath>
#include <functional>
#include <numbers>
#include <vector>

#include <Eigen/Core>
#include <gtest/gtest.h>

namespace wbm::testing {

/// π, for the test files that take it unqualified (`using wbm::testing::kPi;`: one definition,
/// so that test files can share a unity-build unit, tests/CMakeLists.txt).
inline constexpr double kPi = std::numbers::pi;

/// Least-squares slope of log(error) against log(h): the observed convergence order.
inline double observed_order(const std::vector<double>& h, const std::vector<double>& errors) {
  const auto n = static_cast<double>(h.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (size_t i = 0; i < h.size(); ++i) {
    const double x = std::log(h[i]), y = std::log(errors[i]);
    sx += x; sy += y; sxx += x * x; sxy += x * y;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

/// Central-difference Jacobian of `residual` at x, step h_j = step·max(|x_j|, scale).
inline Eigen::MatrixXd fd_jacobian(const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& residual,
                                   const Eigen::VectorXd& x, double step, double scale) {
  const Eigen::VectorXd r0 = residual(x);
  Eigen::MatrixXd j(r0.size(), x.size());
  for (Eigen::Index k = 0; k < x.size(); ++k) {
    const double h = step * std::max(std::abs(x(k)), scale);
    Eigen::VectorXd xp = x, xm = x;
    xp(k) += h;
    xm(k) -= h;
    j.col(k) = (residual(xp) - residual(xm)) / (2.0 * h);
  }
  return j;
}

/// Expects ‖J_analytic − J_fd‖_F ≤ rel_tol · ‖J_fd‖_F for any system with residual/jacobian.
template <class System>
void expect_jacobian_matches_fd(const System& system, const Eigen::VectorXd& x, double rel_tol,
                                double step = 1e-6, double scale = 1e-12) {
  const Eigen::MatrixXd analytic = system.jacobian(x);
  const Eigen::MatrixXd fd = fd_jacobian([&](const Eigen::VectorXd& y) { return Eigen::VectorXd(system.residual(y)); },
                                         x, step, scale);
  ASSERT_EQ(analytic.rows(), fd.rows());
  ASSERT_EQ(analytic.cols(), fd.cols());
  EXPECT_LE((analytic - fd).norm(), rel_tol * fd.norm())
      << "analytic and central-difference Jacobians differ; max |diff| = "
      << (analytic - fd).cwiseAbs().maxCoeff();
}

/// Expects `f()` to throw E with a message containing every fragment.
template <class E, class F>
void expect_throw_with(F&& f, const std::vector<std::string>& fragments) {
  try {
    f();
    ADD_FAILURE() << "expected an exception";
  } catch (const E& e) {
    const std::string what = e.what();
    for (const auto& frag : fragments) {
      EXPECT_NE(what.find(frag), std::string::npos) << "message \"" << what << "\" lacks \"" << frag << "\"";
    }
  }
}

}  // namespace wbm::testing
