#pragma once
/// The JSON form of each solver result, one serializer per type: what result.json
/// (diagnostics), the reproductions' meta.json and the Python dicts hold. They are nlohmann's ADL
/// serializers, so `nlohmann::json j = report;` works for every type below. They live here
/// rather than in wbm::solvers because solvers does not depend on nlohmann-json.
///
/// Every object has the solver's status word (solvers::to_string of SolveStatus, e.g.
/// "converged", "residual-not-verified") and, where a result has one, its message. Numbers that
/// are not finite are written as null (JSON has no NaN or inf). Units follow SI and are named in
/// the key where one applies (`_m`, `_N`, `_s`, `_hz`; `_gaps` for lengths over the gap).

#include <nlohmann/json.hpp>

#include <wbm/solvers/newton.hpp>
#include <wbm/solvers/nonlinear_modes.hpp>
#include <wbm/solvers/time_integration.hpp>
#include <wbm/solvers/weighted_residual.hpp>

namespace wbm::scene {

/// v as a JSON number, or null if v is NaN or ±inf.
[[nodiscard]] nlohmann::json finite_or_null(double v);

}  // namespace wbm::scene

namespace wbm::solvers {

/// {status, converged, iterations, residual_norms (one per iterate, null if not finite),
/// tolerance, jacobian_rcond (null when the linear solver estimates none),
/// levenberg_marquardt_steps, message}.
void to_json(nlohmann::json& j, const NewtonReport& r);
/// null if the contact homotopy was not tried; else {reached, sigma_reached, lambda_start,
/// points, folds, corrector_iterations, stop ("stop word: message")}.
void to_json(nlohmann::json& j, const HomotopyReport& h);
/// {status, converged, message (the verified solve's, as NewtonReport), frequency_hz, newton,
/// path, contact_homotopy, rounding_floor, relative_residual, backward_error, residual_tolerance,
/// max_penetration_m, max_contact_force_N, collocation_penetration_m, complementarity_m,
/// contact_unknowns, condition_number, dropped_harmonics_residual, linear_solver, operators,
/// wall_time_s}; the arrays (coefficients, contact force samples) are not included.
void to_json(nlohmann::json& j, const WeightedResidualSolution& s);
/// One energy level of a backbone: {energy, status, converged, residual_norm, tolerance,
/// frequency_hz, rayleigh_frequency_hz, equality_multiplier, max_penetration_gaps,
/// complementarity_gaps, normalization_error, powell_iterations, newton_iterations,
/// inequality_measure, equality_measure, message, wall_time_s}.
void to_json(nlohmann::json& j, const ModeLevel& l);
/// {status, converged, periods, steps, periodicity (the last δ, null before two periods),
/// unsettled_lcp_steps, largest_lcp_change, message, wall_time_s}.
void to_json(nlohmann::json& j, const TimeIntegrationReport& r);

}  // namespace wbm::solvers
