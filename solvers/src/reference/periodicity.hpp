#pragma once
// The period-to-period test of the time-stepping references (time_integration.hpp): with u_i the
// forced DOF's displacement at the P output samples of period i,
//   δ_i = rms(u_i − u_{i−1}) / rms(u_i)   (rms(u_i − u_{i−1}) when u_i vanishes),
// appended to the report; Converged once δ_i < tolerance [JL14 Sec. 4].
#include <cmath>
#include <sstream>
#include <string>
#include <utility>

#include <Eigen/Core>

#include <wbm/solvers/time_integration.hpp>

namespace wbm::solvers::detail {

// The checks both fixed-step schemes' options share: P ≥ 4 samples, N a positive multiple of P,
// a positive periodicity tolerance and at least 2 periods. `fail` throws with the option's text
// (prefixed by the options' type name).
template <class Fail>
void validate_fixed_step(int samples_per_period, int steps_per_period, double periodicity_tolerance, int max_periods,
                         const Fail& fail) {
  if (samples_per_period < 4) fail("samples_per_period = " + std::to_string(samples_per_period) + ": must be >= 4");
  if (steps_per_period < samples_per_period || steps_per_period % samples_per_period != 0) {
    fail("steps_per_period = " + std::to_string(steps_per_period) + ": must be a positive multiple of samples_per_period = " +
         std::to_string(samples_per_period));
  }
  if (!(periodicity_tolerance > 0.0)) fail("periodicity_tolerance: must be > 0");
  if (max_periods < 2) fail("max_periods = " + std::to_string(max_periods) + ": must be >= 2");
}

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

// The end of period `index` of a fixed-step scheme with `steps` steps a period: a non-finite
// state (q, v) ends the run NonFinite; otherwise the steps are counted and δ_i of the forced DOF's
// row of `disp` recorded (periodic above). Returns true when the run ends.
inline bool end_of_period(const Eigen::VectorXd& q, const Eigen::VectorXd& v, int index, int steps,
                          const Eigen::MatrixXd& disp, int forced_dof, Eigen::VectorXd& previous, double tolerance,
                          TimeIntegrationReport& rep) {
  rep.periods = index;
  if (!q.allFinite() || !v.allFinite()) {
    rep.status = SolveStatus::NonFinite;
    rep.message = "non-finite state in period " + std::to_string(index);
    return true;
  }
  rep.steps += steps;
  const Eigen::VectorXd tip = disp.row(forced_dof).transpose();
  return periodic(tip, previous, tolerance, rep);
}

// Moves the last period's samples into `out` and, unless a message is set, writes "periodic
// (or not periodic) after i periods of N <scheme> steps, delta = δ_i".
inline void finish_run(PeriodicResponse& out, Eigen::MatrixXd&& disp, Eigen::MatrixXd&& vel, Eigen::MatrixXd&& force,
                       int steps, const std::string& scheme) {
  out.displacement = std::move(disp);
  out.velocity = std::move(vel);
  out.contact_force = std::move(force);
  auto& rep = out.report;
  if (rep.message.empty()) {
    std::ostringstream os;
    os << (rep.converged() ? "periodic" : "not periodic") << " after " << rep.periods << " periods of " << steps << " "
       << scheme << " steps, delta = " << (rep.periodicity.empty() ? NAN : rep.periodicity.back());
    rep.message = os.str();
  }
}

}  // namespace wbm::solvers::detail
