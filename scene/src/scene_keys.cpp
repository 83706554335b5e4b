// The declarations of the scalar sections (scalar_keys.hpp): [solver], [timestep] for the BDF and
// for Moreau–Jean. The parser, the echo and docs/scenes.md's tables read them from here.
#include "scene_keys.hpp"

#include <cstdio>
#include <stdexcept>

#include "scene_parser.hpp"

namespace wbm::scene {
namespace detail {

std::string doc_value(const nlohmann::json& v) {
  if (v.is_string()) return "\"" + v.get<std::string>() + "\"";
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  if (v.is_number_integer()) return std::to_string(v.get<long long>());
  // The shortest %g form that reads back to the same double, then "e-08" → "e-8".
  const double x = v.get<double>();
  char buffer[32];
  for (int digits = 1; digits <= 17; ++digits) {
    std::snprintf(buffer, sizeof buffer, "%.*g", digits, x);
    if (std::stod(buffer) == x) break;
  }
  std::string text(buffer);
  if (const auto e = text.find('e'); e != std::string::npos) {
    size_t digit = e + 1;
    if (digit < text.size() && (text[digit] == '-' || text[digit] == '+')) {
      if (text[digit] == '+') text.erase(digit, 1); else ++digit;
    }
    while (digit + 1 < text.size() && text[digit] == '0') text.erase(digit, 1);
  }
  return text;
}

const std::vector<ScalarKey<Solver>>& solver_keys() {
  static const std::vector<ScalarKey<Solver>> keys = {
      number_key<Solver>("tolerance", [](auto& s) -> auto& { return s.newton.tolerance; }, positive(""),
                         "Newton stops when the scaled contact residual ‖r‖₂ ≤ this"),
      integer_key<Solver>("max_iterations", [](auto& s) -> auto& { return s.newton.max_iterations; }, 0, 100000,
                          "Newton iterations per solve (load stepping counts its own)"),
      boolean_key<Solver>("line_search", [](auto& s) -> auto& { return s.newton.line_search; }, "Armijo backtracking"),
      {"linear_solver", ScalarKey<Solver>::Type::Choice, {}, 0, 0, names(linear_solver_table()),
       "factorization of the linear operator (modal needs Rayleigh damping)",
       [](const Solver& s) { return nlohmann::json(linear_solver_name(s.linear_solver)); },
       [](Solver& s, const nlohmann::json& v) { s.linear_solver = value_of(linear_solver_table(), v.get<std::string>()); }},
      number_key<Solver>(
          "residual_tolerance", [](auto& s) -> auto& { return s.residual_tolerance; }, positive(""),
          "a solve (every point of a sweep or branch) is converged only if the full residual ‖G a − b + n(a)‖₂ ≤ "
          "this · ‖b‖₂, recomputed from the solution; echoed in `result.json` (`scene.solver`, and per solve in the "
          "diagnostics). Raise it (e.g. 1e-7) only for an ill-conditioned G whose solve is reported \"not verified\" "
          "at its rounding floor (Craig–Bampton models)"),
  };
  return keys;
}

namespace {
Range open_unit() { return {"in (0, 1)", [](double v) { return v > 0.0 && v < 1.0; }}; }
Range closed_unit() { return {"in [0, 1]", [](double v) { return v >= 0.0 && v <= 1.0; }}; }
constexpr const char* kPeriodicity =
    "stop when rms(u_i − u_{i−1})/rms(u_i) of the forced DOF is below this";
constexpr const char* kMaxPeriods = "give up (reported, exit 1) after this many periods";
}  // namespace

const std::vector<ScalarKey<solvers::TimeIntegrationOptions>>& bdf_keys() {
  using T = solvers::TimeIntegrationOptions;
  static const std::vector<ScalarKey<T>> keys = {
      number_key<T>("relative_tolerance", [](auto& o) -> auto& { return o.relative_tolerance; }, open_unit(),
                    "GSL local error control"),
      number_key<T>("absolute_tolerance", [](auto& o) -> auto& { return o.absolute_tolerance; }, positive("m"),
                    "on u and du/dτ"),
      number_key<T>("periodicity_tolerance", [](auto& o) -> auto& { return o.periodicity_tolerance; }, positive(""),
                    kPeriodicity),
      integer_key<T>("max_periods", [](auto& o) -> auto& { return o.max_periods; }, 2, 10000000, kMaxPeriods),
  };
  return keys;
}

const std::vector<ScalarKey<solvers::MoreauJeanOptions>>& moreau_jean_keys() {
  using T = solvers::MoreauJeanOptions;
  static const std::vector<ScalarKey<T>> keys = {
      integer_key<T>("steps_per_period", [](auto& o) -> auto& { return o.steps_per_period; }, 4, 1 << 26,
                     "fixed steps per period (first order through impacts); a multiple of `[output] samples`"),
      number_key<T>("restitution", [](auto& o) -> auto& { return o.restitution; }, closed_unit(),
                    "Newton's coefficient e at the stops"),
      number_key<T>("periodicity_tolerance", [](auto& o) -> auto& { return o.periodicity_tolerance; }, positive(""),
                    kPeriodicity),
      integer_key<T>("max_periods", [](auto& o) -> auto& { return o.max_periods; }, 2, 10000000, kMaxPeriods),
  };
  return keys;
}

}  // namespace detail

std::string key_table_markdown(const std::string& section) {
  if (section == "solver") return detail::key_table(detail::solver_keys());
  if (section == "timestep") return detail::key_table(detail::bdf_keys());
  if (section == "timestep.rigid") return detail::key_table(detail::moreau_jean_keys());
  throw std::invalid_argument("key_table_markdown: section = \"" + section +
                              "\": not declared; declared: \"solver\", \"timestep\", \"timestep.rigid\"");
}

}  // namespace wbm::scene
