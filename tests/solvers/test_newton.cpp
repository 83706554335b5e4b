#include <wbm/solvers/newton.hpp>

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

using namespace wbm::solvers;

namespace {
// x³ − 8 = 0 component-wise: root 2, quadratic convergence from x0 = 3.
struct Cubic {
  Eigen::VectorXd residual(const Eigen::VectorXd& x) const { return x.array().cube() - 8.0; }
  Eigen::MatrixXd jacobian(const Eigen::VectorXd& x) const {
    return (3.0 * x.array().square()).matrix().asDiagonal();
  }
};
// arctan(x) = 0: undamped Newton diverges from |x0| > 1.39; the line search must rescue it.
struct Arctan {
  Eigen::VectorXd residual(const Eigen::VectorXd& x) const { return x.array().atan(); }
  Eigen::MatrixXd jacobian(const Eigen::VectorXd& x) const {
    return (1.0 / (1.0 + x.array().square())).matrix().asDiagonal();
  }
};
// x² + 1 = 0 has no real root: Newton cannot converge.
struct NoRoot {
  Eigen::VectorXd residual(const Eigen::VectorXd& x) const { return x.array().square() + 1.0; }
  Eigen::MatrixXd jacobian(const Eigen::VectorXd& x) const { return (2.0 * x).asDiagonal(); }
};
struct Nan {
  Eigen::VectorXd residual(const Eigen::VectorXd& x) const {
    return Eigen::VectorXd::Constant(x.size(), std::numeric_limits<double>::quiet_NaN());
  }
  Eigen::MatrixXd jacobian(const Eigen::VectorXd& x) const { return Eigen::MatrixXd::Identity(x.size(), x.size()); }
};
}  // namespace

// Quadratic convergence: e_{k+1} ≈ e_k² f''/(2f') = e_k²/2 at the root 2 of x³ − 8.
TEST(Newton, ConvergesQuadraticallyOnASmoothRoot) {
  const auto r = newton(Cubic{}, Eigen::VectorXd::Constant(2, 3.0), {.tolerance = 1e-13});
  ASSERT_TRUE(r.report.converged()) << r.report.message;
  EXPECT_NEAR(r.x(0), 2.0, 1e-14);
  const auto& n = r.report.residual_norms;
  ASSERT_GE(n.size(), 4u);
  EXPECT_LT(n[n.size() - 2], 1e-3 * n[n.size() - 3]);  // super-linear near the root
}

TEST(Newton, LineSearchGlobalizesArctan) {
  const auto damped = newton(Arctan{}, Eigen::VectorXd::Constant(1, 10.0));
  ASSERT_TRUE(damped.report.converged()) << damped.report.message;
  EXPECT_NEAR(damped.x(0), 0.0, 1e-10);
  const auto plain = newton(Arctan{}, Eigen::VectorXd::Constant(1, 10.0), {.max_iterations = 10, .line_search = false});
  EXPECT_FALSE(plain.report.converged());
}

TEST(Newton, ReportsFailureWithoutThrowing) {
  const auto r = newton(NoRoot{}, Eigen::VectorXd::Constant(1, 0.5), {.max_iterations = 20});
  EXPECT_FALSE(r.report.converged());
  EXPECT_NE(r.report.message.find("last ||R||"), std::string::npos);
  const auto bad = newton(Nan{}, Eigen::VectorXd::Zero(3));
  EXPECT_EQ(bad.report.status, SolveStatus::NonFinite);
}
