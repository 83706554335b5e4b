// Why a pseudo-arclength branch stopped, when the step fell below its minimum: a corrector that
// stalls at the rounding floor of its residual (Branch::stalled_residual, "raise the tolerance")
// against one that fails far from any solution (a branch that ends: no floor is claimed).
#include <cmath>
#include <string>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include <wbm/solvers/continuation.hpp>

namespace {

using namespace wbm;

// x − λ = 0, evaluated (by residual() or linearize()) with an error of δλ sgn(x − λ) (sgn 0 = +1):
// the model of a rounding floor that grows with the response, a function of the point however
// often it is evaluated. The exact root is x = λ, but a Newton step from d = x − λ ≠ 0, exact for
// that point's error, lands at d = −δλ sgn d, whose error is the opposite: |R| = 2δλ at every
// iterate after the first. On this line the predictor is exact (d = 0, |R| = δλ), so a corrector
// converges at once while δλ ≤ tolerance and never after.
// With `ends`, the branch ends at λ = 0.5 instead: beyond it (x − λ)² + 1 has no root (the
// corrector meets a singular Jacobian, ‖R‖ = 1).
struct FlooredLine {
  double delta = 0.0;
  bool ends = false;
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x, double lambda) const {
    const double d = x(0) - lambda;
    const double error = (d >= 0.0 ? delta : -delta) * lambda;
    return Eigen::VectorXd::Constant(1, (ends && lambda >= 0.5 ? d * d + 1.0 : d) + error);
  }
  [[nodiscard]] solvers::Linearization linearize(const Eigen::VectorXd& x, double lambda) const {
    const double slope = ends && lambda >= 0.5 ? 2.0 * (x(0) - lambda) : 1.0;
    return {residual(x, lambda), Eigen::MatrixXd::Constant(1, 1, slope), Eigen::VectorXd::Constant(1, -slope)};
  }
};

solvers::PseudoArclengthOptions line_options() {
  solvers::PseudoArclengthOptions o;
  o.parameter_min = 0.0;
  o.parameter_max = 1.0;
  o.initial_step = 0.05;
  o.max_step = 0.05;
  o.corrector_tolerance = 1e-10;
  return o;
}

}  // namespace

// δ = 2 × tolerance: the evaluations' error δλ reaches the tolerance at λ = 0.5. The branch stops
// there with the step below its minimum; the floor measured at the last point (R's change when x
// moves by its own rounding: 2δλ, the evaluations' error) explains the corrector's last ‖R‖, and
// the message names the tolerance, not a shorter step.
TEST(ContinuationStops, ACorrectorAtItsRoundingFloorIsReportedWithTheFloor) {
  const auto o = line_options();
  const FlooredLine line{.delta = 2.0 * o.corrector_tolerance};
  const auto b = solvers::pseudo_arclength(line, Eigen::VectorXd::Zero(1), 0.0, o);
  ASSERT_EQ(b.stop, solvers::StopReason::StepBelowMinimum) << b.message;
  const double lambda = b.points.back().parameter;
  EXPECT_NEAR(lambda, 0.5, 1e-3);
  ASSERT_TRUE(std::isfinite(b.stalled_residual)) << b.message;
  EXPECT_GT(b.stalled_residual, o.corrector_tolerance);
  EXPECT_NEAR(b.rounding_floor, 4.0 * o.corrector_tolerance * lambda, 1e-3 * o.corrector_tolerance);  // 2δλ
  EXPECT_LE(b.stalled_residual, solvers::Branch::kFloorFactor * b.rounding_floor);
  EXPECT_NE(b.message.find("rounding floor"), std::string::npos) << b.message;
}

// A branch that ends (no root beyond λ = 0.5): the step also falls below its minimum, but the
// corrector fails at ‖R‖ = 1, far above the floor at the last point (x's own rounding, 1e-16),
// so no floor is claimed (stalled_residual NaN) and the message reports the failed corrector.
TEST(ContinuationStops, ACorrectorFarFromASolutionClaimsNoFloor) {
  const auto b = solvers::pseudo_arclength(FlooredLine{.ends = true}, Eigen::VectorXd::Zero(1), 0.0, line_options());
  ASSERT_EQ(b.stop, solvers::StopReason::StepBelowMinimum) << b.message;
  EXPECT_TRUE(std::isnan(b.stalled_residual)) << b.stalled_residual;
  EXPECT_EQ(b.message.find("rounding floor"), std::string::npos) << b.message;
  EXPECT_NE(b.message.find("corrector failed"), std::string::npos) << b.message;
}
