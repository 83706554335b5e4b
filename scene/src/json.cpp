// The JSON serializers of the solver results (wbm/scene/json.hpp).
#include <wbm/scene/json.hpp>

#include <cmath>
#include <string>

namespace wbm::scene {

nlohmann::json finite_or_null(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

}  // namespace wbm::scene

namespace wbm::solvers {

using scene::finite_or_null;

void to_json(nlohmann::json& j, const NewtonReport& r) {
  nlohmann::json norms = nlohmann::json::array();
  for (double v : r.residual_norms) norms.push_back(finite_or_null(v));
  j = {{"status", std::string(to_string(r.status))},
       {"converged", r.converged()},
       {"iterations", r.iterations},
       {"residual_norms", norms},
       {"tolerance", finite_or_null(r.tolerance)},
       {"jacobian_rcond", r.jacobian_rcond ? finite_or_null(*r.jacobian_rcond) : nlohmann::json(nullptr)},
       {"levenberg_marquardt_steps", r.levenberg_marquardt_steps},
       {"message", r.message}};
}

void to_json(nlohmann::json& j, const HomotopyReport& h) {
  if (!h.tried()) {
    j = nullptr;
    return;
  }
  j = {{"reached", h.reached()},
       {"sigma_reached", h.sigma_reached},
       {"lambda_start", h.lambda_start},
       {"points", h.points},
       {"folds", h.folds},
       {"corrector_iterations", h.corrector_iterations},
       {"stop", std::string(to_string(*h.stop)) + ": " + h.message}};
}

void to_json(nlohmann::json& j, const WeightedResidualSolution& s) {
  j = {{"status", std::string(to_string(s.report.status))},
       {"converged", s.converged()},
       {"message", s.report.message},
       {"frequency_hz", s.frequency_hz},
       {"newton", s.report},
       {"path", std::string(to_string(s.path))},
       {"contact_homotopy", s.homotopy},
       {"rounding_floor", finite_or_null(s.rounding_floor)},
       {"relative_residual", finite_or_null(s.relative_residual)},
       {"backward_error", finite_or_null(s.backward_error)},
       {"residual_tolerance", s.residual_tolerance},
       {"max_penetration_m", finite_or_null(s.max_penetration)},
       {"max_contact_force_N", finite_or_null(s.max_contact_force)},
       {"collocation_penetration_m", finite_or_null(s.collocation_penetration)},
       {"complementarity_m", finite_or_null(s.complementarity)},
       {"contact_unknowns", s.contact_unknowns},
       {"condition_number", finite_or_null(s.condition_number)},
       {"dropped_harmonics_residual", finite_or_null(s.dropped_harmonics_residual)},
       {"linear_solver", s.linear_solver},
       {"operators", s.operator_rule},
       {"wall_time_s", s.wall_time_s}};
}

void to_json(nlohmann::json& j, const ModeLevel& l) {
  j = {{"energy", l.energy},
       {"converged", l.converged()},
       {"status", std::string(to_string(l.status))},
       {"residual_norm", finite_or_null(l.residual_norm)},
       {"tolerance", l.tolerance},
       {"frequency_hz", finite_or_null(l.frequency_hz)},
       {"rayleigh_frequency_hz", finite_or_null(l.rayleigh_frequency_hz)},
       {"equality_multiplier", finite_or_null(l.equality_multiplier)},
       {"max_penetration_gaps", finite_or_null(l.max_penetration)},
       {"complementarity_gaps", finite_or_null(l.complementarity)},
       {"normalization_error", finite_or_null(l.normalization_error)},
       {"powell_iterations", l.powell_iterations},
       {"newton_iterations", l.newton_iterations},
       {"inequality_measure", finite_or_null(l.inequality_measure)},
       {"equality_measure", finite_or_null(l.equality_measure)},
       {"message", l.message},
       {"wall_time_s", l.wall_time_s}};
}

void to_json(nlohmann::json& j, const TimeIntegrationReport& r) {
  j = {{"status", std::string(to_string(r.status))},
       {"converged", r.converged()},
       {"periods", r.periods},
       {"steps", r.steps},
       {"periodicity", r.periodicity.empty() ? nlohmann::json(nullptr) : finite_or_null(r.periodicity.back())},
       {"unsettled_lcp_steps", r.unsettled_lcp_steps},
       {"largest_lcp_change", finite_or_null(r.largest_lcp_change)},
       {"message", r.message},
       {"wall_time_s", r.wall_time_s}};
}

}  // namespace wbm::solvers
