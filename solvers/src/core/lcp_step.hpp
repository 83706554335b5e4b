#pragma once
// The small linear complementarity problem of one step of a time-discrete impact law, solved by
// Siconos Numerics (Lemke). Private to solvers/src (core/: forced_response/ includes it).

#include <memory>

#include <Eigen/Core>

namespace wbm::solvers::detail {

/// Find z ∈ ℝᵐ with
///   w = D z + q ≥ 0,   z ≥ 0,   zᵀ w = 0,
/// D (m × m) a P-matrix (here the symmetric positive definite Delassus operator of one step, so
/// the solution is unique [Cottle, Pang & Stone 1992, Thm. 3.3.7]). m = 1 is solved in closed
/// form, z = max(0, −q/D); larger m by Siconos Numerics' linearComplementarity_driver with
/// SICONOS_LCP_LEMKE (Lemke's complementary pivoting, exact up to rounding, no iteration
/// tolerance), checked by lcp_compute_error (relative to ‖q‖, absolute when q = 0). Units are the
/// caller's (z an impulse [N·s], w a gap [m]).
class LcpStep {
 public:
  LcpStep();
  ~LcpStep();
  LcpStep(const LcpStep&) = delete;
  LcpStep& operator=(const LcpStep&) = delete;

  struct Outcome {
    int info = 0;        // Siconos's return code (0: success); 0 for m = 1
    double error = 0.0;  // lcp_compute_error of the returned z; 0 for m = 1
  };
  /// Solves the problem above; z gets the solution (resized to m). Throws std::invalid_argument
  /// for sizes that differ. D is copied (Siconos may work in place).
  Outcome solve(const Eigen::MatrixXd& d, const Eigen::VectorXd& q, Eigen::VectorXd& z);

 private:
  struct Siconos;
  std::unique_ptr<Siconos> s_;
};

}  // namespace wbm::solvers::detail
