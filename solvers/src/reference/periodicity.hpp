#pragma once
// The period-to-period test of the time-stepping references (time_integration.hpp): with u_i the
// forced DOF's displacement at the P output samples of period i,
//   δ_i = rms(u_i − u_{i−1}) / rms(u_i)   (rms(u_i − u_{i−1}) when u_i vanishes),
// appended to the report; Converged once δ_i < tolerance [JL14 Sec. 4].
#include <cmath>

#include <Eigen/Core>

#include <wbm/solvers/time_integration.hpp>

namespace wbm::solvers::detail {

// Records δ_i of `tip` against `previous` (nothing for the first period, when `previous` is
// empty), sets the report Converged when δ_i < tolerance, and keeps `tip` as the next previous.
// Returns true when converged.
inline bool periodic(const Eigen::VectorXd& tip, Eigen::VectorXd& previous, double tolerance, TimeIntegrationReport& rep) {
  if (previous.size() == tip.size()) {
    const auto count = static_cast<double>(tip.size());
    const double rms_tip = std::sqrt(tip.squaredNorm() / count);
    const double rms_diff = std::sqrt((tip - previous).squaredNorm() / count);
    const double delta = rms_tip > 0.0 ? rms_diff / rms_tip : rms_diff;
    rep.periodicity.push_back(delta);
    if (delta < tolerance) {
      rep.status = SolveStatus::Converged;
      return true;
    }
  }
  previous = tip;
  return false;
}

}  // namespace wbm::solvers::detail
