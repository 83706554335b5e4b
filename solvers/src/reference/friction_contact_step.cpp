#include "reference/friction_contact_step.hpp"

#include <stdexcept>
#include <string>

// Siconos Numerics' headers are C99: `restrict` is a keyword there, and __restrict in C++.
#define restrict __restrict
#include <siconos/numerics/FrictionContactProblem.h>
#include <siconos/numerics/Friction_cst.h>
#include <siconos/numerics/NonSmoothDrivers.h>
#include <siconos/numerics/NumericsMatrix.h>
#include <siconos/numerics/SolverOptions.h>
#include <siconos/numerics/fc2d_compute_error.h>
#undef restrict

#include "core/siconos_options.hpp"

namespace wbm::solvers::detail {

struct FrictionContactStep::Siconos {
  SiconosOptions options{SICONOS_FRICTION_2D_LEMKE, "FRICTION_2D_LEMKE"};
  Eigen::VectorXd u;  // the local velocities of the last solve
};

FrictionContactStep::FrictionContactStep() : s_(std::make_unique<Siconos>()) {}

FrictionContactStep::~FrictionContactStep() = default;

FrictionContactStep::Outcome FrictionContactStep::solve(Eigen::MatrixXd& w, Eigen::VectorXd& q, Eigen::VectorXd& mu,
                                                        Eigen::VectorXd& r) {
  const auto m = mu.size();
  if (w.rows() != 2 * m || w.cols() != 2 * m || q.size() != 2 * m) {
    throw std::invalid_argument("FrictionContactStep::solve: W is " + std::to_string(w.rows()) + " x " +
                                std::to_string(w.cols()) + " and q has " + std::to_string(q.size()) +
                                " entries for " + std::to_string(m) + " contacts: both must have 2m rows");
  }
  r = Eigen::VectorXd::Zero(2 * m);
  s_->u = Eigen::VectorXd::Zero(2 * m);
  if (m == 0) return {};
  const double norm = q.norm() > 0.0 ? q.norm() : 1.0;  // relative to ‖q‖ [m/s]
  NumericsMatrix* matrix = NM_create_from_data(NM_DENSE, static_cast<int>(2 * m), static_cast<int>(2 * m), w.data());
  FrictionContactProblem problem{2, static_cast<int>(m), matrix, q.data(), mu.data()};
  Outcome out;
  out.info = fc2d_driver(&problem, r.data(), s_->u.data(), s_->options.get());
  fc2d_compute_error(&problem, r.data(), s_->u.data(), 1e-14, norm, &out.error);
  // NM_create_from_data keeps our pointer as matrix0: detach it before freeing the wrapper.
  matrix->matrix0 = nullptr;
  NM_free(matrix);
  return out;
}

}  // namespace wbm::solvers::detail
