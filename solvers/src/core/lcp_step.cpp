#include "core/lcp_step.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

// Siconos Numerics' headers are C99: `restrict` is a keyword there, and __restrict in C++.
#define restrict __restrict
#include <siconos/numerics/LCP_Solvers.h>
#include <siconos/numerics/LinearComplementarityProblem.h>
#include <siconos/numerics/NonSmoothDrivers.h>
#include <siconos/numerics/NumericsMatrix.h>
#include <siconos/numerics/lcp_cst.h>
#undef restrict

#include "core/siconos_options.hpp"

namespace wbm::solvers::detail {

struct LcpStep::Siconos {
  SiconosOptions options{SICONOS_LCP_LEMKE, "LCP_LEMKE"};
  Eigen::MatrixXd d;  // the caller's D, copied: Siconos may pivot in place
  Eigen::VectorXd q, w;
};

LcpStep::LcpStep() : s_(std::make_unique<Siconos>()) {}

LcpStep::~LcpStep() = default;

LcpStep::Outcome LcpStep::solve(const Eigen::MatrixXd& d, const Eigen::VectorXd& q, Eigen::VectorXd& z) {
  const auto m = q.size();
  if (d.rows() != m || d.cols() != m) {
    throw std::invalid_argument("LcpStep::solve: D is " + std::to_string(d.rows()) + " x " + std::to_string(d.cols()) +
                                " for q of " + std::to_string(m) + " entries: D must be square of q's size");
  }
  z.setZero(m);
  if (m == 0) return {};
  if (m == 1) {
    z(0) = std::max(0.0, -q(0) / d(0, 0));
    return {};
  }
  s_->d = d;
  s_->q = q;
  s_->w.setZero(m);
  NumericsMatrix* matrix = NM_create_from_data(NM_DENSE, static_cast<int>(m), static_cast<int>(m), s_->d.data());
  LinearComplementarityProblem problem{static_cast<int>(m), matrix, s_->q.data()};
  Outcome out;
  out.info = linearComplementarity_driver(&problem, z.data(), s_->w.data(), s_->options.get());
  lcp_compute_error(&problem, z.data(), s_->w.data(), 1e-14, &out.error);
  // NM_create_from_data keeps our pointer as matrix0: detach it before freeing the wrapper.
  matrix->matrix0 = nullptr;
  NM_free(matrix);
  return out;
}

}  // namespace wbm::solvers::detail
