#pragma once
// The one-step frictional contact problem of Moreau–Jean time stepping, solved by Siconos
// Numerics (fc2d). Private to solvers/src/reference.

#include <memory>

#include <Eigen/Core>

namespace wbm::solvers::detail {

/// The 2D frictional contact problem of one time step [Acary & Brogliato 2008, Sec. 10.1 and
/// 13.2]: for m contacts, find the impulses r and the local velocities u (length 2m, rows 2i the
/// normal and 2i + 1 the tangent of contact i) with
///   u = W r + q,
///   0 ≤ u_n,i ⊥ r_n,i ≥ 0                          (Signorini at the velocity level),
///   |r_t,i| ≤ μ_i r_n,i,  r_t,i = −μ_i r_n,i sign(u_t,i) where u_t,i ≠ 0   (Coulomb),
/// W the 2m × 2m Delassus matrix [1/kg] (symmetric positive definite), q [m/s], r [N·s]. Solved by
/// Siconos Numerics' fc2d_driver with SICONOS_FRICTION_2D_LEMKE: the problem is written as an LCP
/// (fc2d_tolcp) and solved by Lemke's pivoting, exact up to rounding (no iteration tolerance).
/// The solution is checked by fc2d_compute_error (its natural-map residual, relative to ‖q‖, or
/// absolute [m/s] when q = 0).
class FrictionContactStep {
 public:
  FrictionContactStep();
  ~FrictionContactStep();
  FrictionContactStep(const FrictionContactStep&) = delete;
  FrictionContactStep& operator=(const FrictionContactStep&) = delete;

  struct Outcome {
    int info = 0;       // Siconos's return code: 0 when the solver reports success
    double error = 0.0;  // fc2d_compute_error of the returned (r, u)
  };
  /// Solves the problem above for w (2m × 2m, column-major as Siconos' dense storage), q and mu
  /// (m entries, >= 0); r gets the impulses. Siconos reads w, q and mu in place and may use them
  /// as it likes: they are the caller's per-step data, not to be read afterwards (no copies here,
  /// one call a time step). Throws std::invalid_argument for sizes that differ.
  Outcome solve(Eigen::MatrixXd& w, Eigen::VectorXd& q, Eigen::VectorXd& mu, Eigen::VectorXd& r);

 private:
  struct Siconos;
  std::unique_ptr<Siconos> s_;
};

}  // namespace wbm::solvers::detail
