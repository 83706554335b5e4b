// The declarations (declared_keys.hpp) of the top level, [analysis], [damping], [solver],
// [timestep] (the BDF and Moreau–Jean) and [output]; the model's sections are in
// scene_keys_model.cpp. The parser, the echo and docs/scenes.md's tables read them from here.
#include "scene_keys.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "scene_parser.hpp"

namespace wbm::scene {
namespace detail {

std::string doc_value(const nlohmann::json& v) {
  if (v.is_string()) return "\"" + v.get<std::string>() + "\"";
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  if (v.is_number_integer()) return std::to_string(v.get<long long>());
  if (v.is_array()) {
    std::string list;
    for (const auto& e : v) list += (list.empty() ? "" : ", ") + doc_value(e);
    return "[" + list + "]";
  }
  const double x = v.get<double>();
  if (std::floor(x) == x && std::abs(x) < 1e6) return std::to_string(static_cast<long long>(x));  // 100, not 1e2
  // The shortest %g form that reads back to the same double, then "e-08" → "e-8".
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

std::string key_table(const std::vector<KeyRow>& rows) {
  std::string md = "| key | type | default | allowed | meaning |\n|---|---|---|---|---|\n";
  for (const auto& r : rows) {
    md += "| `" + r.key + "` | " + r.type + " | " + r.default_value + " | " + r.allowed + " | " + r.meaning + " |\n";
  }
  return md;
}

const std::vector<std::string>& section_names() {
  static const std::vector<std::string> s = {"analysis", "structure", "damping",  "forcing", "contact",
                                             "counter_surface", "basis", "solver", "timestep", "output"};
  return s;
}

const std::vector<DeclaredKey<Scene>>& top_keys() {
  static const std::vector<DeclaredKey<Scene>> keys = [] {
    std::vector<DeclaredKey<Scene>> k = {
        text_key<Scene>("title", [](auto& s) -> auto& { return s.title; }, "free text, copied to `result.json`")
            .read_by_section()};
    for (const auto& s : section_names()) {
      const bool many = s == "contact" || s == "counter_surface";
      k.push_back(compound_key<Scene>(s.c_str(), many ? "table or array of tables" : "table", "", "",
                                      s == "contact"           ? "`[contact]` or `[[contact]]`, below"
                                      : s == "counter_surface" ? "`[[counter_surface]]`, below"
                                                               : "below"));
    }
    return k;
  }();
  return keys;
}

namespace {
Range arclength_step() {
  return {"in [1e-6, 1] (scaled arclength per step; below 1e-6 a branch takes millions of steps)",
          [](double v) { return v >= 1e-6 && v <= 1.0; }};
}
}  // namespace

const std::vector<DeclaredKey<Analysis>>& analysis_keys() {
  using A = Analysis;
  static const std::vector<DeclaredKey<A>> keys = {
      choice_key<A>("type", names(analysis_table()), [](const A& a) { return to_string(a.kind); },
                    [](A& a, const std::string& v) { a.kind = value_of(analysis_table(), v); }, "what to run (below)")
          .read_by_section(),
      compound_key<A>("functions", "list of integers", "all `0 … M−1`", "each in `[0, M)`", "the shifts k to draw",
                      [](const A& a) { return a.functions.empty() ? nlohmann::json() : nlohmann::json(a.functions); })
          .only_in({"basis-plot"}),
      integer_key<A>("derivative", [](auto& a) -> auto& { return a.derivative; }, 0, 1, "draw dφ/dτ")
          .documented_allowed("`0`, or `1` if the basis has φ'")
          .read_by_section()
          .only_in({"basis-plot"}),
      choice_key<A>("normalization", {"orthonormal", "unit-integral"},
                    [](const A& a) { return a.unit_integral ? "unit-integral" : "orthonormal"; },
                    [](A& a, const std::string& v) { a.unit_integral = v == "unit-integral"; },
                    "∫₀¹ φ_{J,k} = 1 is the paper's scaling [JL14 Sec. 3.3] (wavelets only)")
          .only_in({"basis-plot"}),
      number_key<A>("max_step", [](auto& a) -> auto& { return a.max_step; }, arclength_step(),
                    "largest step in the scaled arclength (state / largest gap, frequency / start frequency, μ / the "
                    "largest \\|μ\\| of analysis.friction_coefficient)")
          .only_in({"continuation"}),
      number_key<A>("max_frequency_step_hz", [](auto& a) -> auto& { return a.max_frequency_step_hz; },
                    non_negative("Hz"), "> 0 also caps \\|Δf\\| per step [Hz], for a dense curve (parameter = "
                    "\"frequency\")")
          .only_in({"continuation"}),
      integer_key<A>("max_points", [](auto& a) -> auto& { return a.max_points; }, 2, 1000000,
                     "the branch stops after this many points")
          .only_in({"continuation", "nnm"}),
      number_key<A>("max_state", [](auto& a) -> auto& { return a.max_state; },
                    non_negative("times s_r = max(gap, linear response); 0 = no bound"),
                    "> 0 stops the branch (reason \"state bound exceeded\", exit 1) once a contact coefficient exceeds "
                    "this many s_r, s_r = max(largest gap, ‖x_lin‖∞ at the start); 0: no bound. The default stops a "
                    "runaway branch (e.g. an undamped resonance) long before the point limit")
          .only_in({"continuation"}),
      boolean_key<A>("stability", [](auto& a) -> auto& { return a.stability; },
                     "continuation: Floquet multipliers of every point (monodromy matrix; with rigid stops that of "
                     "the exact orbit with plastic impacts near the point, by shooting, through saltation matrices; "
                     "with \"jenkins\" contacts one more state per element, its force perturbation; \"coulomb\" "
                     "refuses `true`). nnm: every level's stability through the exact orbit with elastic impacts "
                     "near it (autonomous shooting at the level's mean energy, its nontrivial multipliers through "
                     "saltation matrices; columns stable, max_multiplier, exact_frequency, orbit_distance and "
                     "impacts of backbone.csv, a level without an exact orbit near it left empty with its status; "
                     "rigid stops only: \"linear\" refuses `true`)")
          .documented_default("`true` (continuation), `false` (nnm)")
          .read_by_section()
          .only_in({"continuation", "nnm"}),
      choice_key<A>("parameter", {"frequency", "friction_coefficient"},
                    [](const A& a) {
                      return a.parameter == BranchParameter::Frequency ? "frequency" : "friction_coefficient";
                    },
                    [](A& a, const std::string& v) {
                      a.parameter =
                          v == "frequency" ? BranchParameter::Frequency : BranchParameter::FrictionCoefficient;
                    },
                    "what the branch follows: the forcing frequency over forcing.frequency_hz = [from, to], or the "
                    "friction coefficient μ of every \"jenkins\" contact over friction_coefficient = [from, to] at "
                    "one forcing frequency (G factorized once; under a constant normal_load, μ N is all that "
                    "enters, so this is also a branch in the load)")
          .only_in({"continuation"}),
      choice_key<A>("stick_slip_events", {"on-stall", "always", "never"},
                    [](const A& a) {
                      return a.stick_slip_events == StickSlipEvents::Always  ? "always"
                             : a.stick_slip_events == StickSlipEvents::Never ? "never"
                                                                             : "on-stall";
                    },
                    [](A& a, const std::string& v) {
                      a.stick_slip_events = v == "always"  ? StickSlipEvents::Always
                                            : v == "never" ? StickSlipEvents::Never
                                                           : StickSlipEvents::OnStall;
                    },
                    "\"jenkins\" contacts: how the branch crosses a sample's switch between stick and slip. "
                    "\"on-stall\": the nonsmooth corrector while it converges, and where it stalls at such a kink "
                    "the branch goes on piece by piece, each switch located and crossed as an event (and back "
                    "where the pieces cycle); \"always\": piece by piece from the start (every sample's switch an "
                    "event: slower); \"never\": the nonsmooth corrector alone")
          .only_in({"continuation"}),
      compound_key<A>("friction_coefficient", "`[from, to]`", "— (required with parameter = \"friction_coefficient\")",
                      "0 ≤ from ≠ to", "the range of μ [-], from the start `from`; the contacts' own "
                      "friction_coefficient is replaced (a warning says so where it differs)",
                      [](const A& a) {
                        return a.parameter == BranchParameter::FrictionCoefficient
                                   ? nlohmann::json({a.friction_from, a.friction_to})
                                   : nlohmann::json();
                      })
          .only_in({"continuation"}),
      compound_key<A>("energy", "`[from, to]`", "— (required)", "0 < from < to",
                      "normalized modal energy range (1 = contact onset)",
                      [](const A& a) { return nlohmann::json({a.energy_min, a.energy_max}); })
          .only_in({"nnm"}),
      integer_key<A>("harmonics", [](auto& a) -> auto& { return a.harmonics; }, 1, 256,
                     "N, harmonics of the Fourier series of one period (Sizes, below)")
          .with_hint(" (the cost grows about as N^2.2: N = 128 takes 7 s on 2 DOFs, N = 512 minutes)")
          .only_in({"nnm"}),
      integer_key<A>("samples", [](auto& a) -> auto& { return a.samples; }, 3, 1 << 16,
                     "m, instants per period where the contact conditions are imposed")
          .documented_default("`max(256, 8N)`")
          .documented_allowed("3 … 65536, > 2N")
          .read_by_section()
          .only_in({"nnm"}),
      choice_key<A>("algorithm", names(nnm_algorithm_table()), [](const A& a) { return to_string(a.algorithm); },
                    [](A& a, const std::string& v) { a.algorithm = value_of(nnm_algorithm_table(), v); },
                    "pseudo-arclength continuation in energy, or LL11 Alg. 1 / Alg. 2 (augmented Lagrangian with "
                    "Powell's updates at energy steps; rigid stops only)")
          .only_in({"nnm"}),
      number_key<A>("max_step", [](auto& a) -> auto& { return a.max_step; }, arclength_step(),
                    "largest scaled arclength step of the continuation")
          .defaulting_to(5e-2)
          .only_in({"nnm"}),
      number_key<A>("max_energy_step", [](auto& a) -> auto& { return a.max_energy_step; },
                    positive("normalized energy"),
                    "\\|ΔE\\| per step (continuation) or the largest energy step (Alg. 1/2)")
          .only_in({"nnm"}),
      compound_key<A>("levels", "list of numbers", "`[]`", "inside `energy`",
                      "energies whose mode shapes are written (landed on exactly)",
                      [](const A& a) { return nlohmann::json(a.levels); })
          .only_in({"nnm"}),
  };
  return keys;
}

const std::vector<DeclaredKey<Damping>>& damping_keys() {
  static const std::vector<DeclaredKey<Damping>> keys = {
      number_key<Damping>("alpha", [](auto& d) -> auto& { return d.alpha; }, non_negative("1/s"),
                          "mass-proportional part, C += α M [1/s]"),
      number_key<Damping>("beta", [](auto& d) -> auto& { return d.beta; }, non_negative("s"),
                          "stiffness-proportional part, C += β K [s] (the paper's C = βK)"),
      number_key<Damping>("modal_ratio", [](auto& d) -> auto& { return d.modal_ratio; }, non_negative(""),
                          "damping ratio ζ of every mode, C += M Φ diag(2ζω_i) Φᵀ M [-] (0.01: 1 % of critical)"),
  };
  return keys;
}

const std::vector<DeclaredKey<Solver>>& solver_keys() {
  static const std::vector<DeclaredKey<Solver>> keys = {
      number_key<Solver>("tolerance", [](auto& s) -> auto& { return s.newton.tolerance; }, positive(""),
                         "Newton stops when the scaled contact residual ‖r‖₂ ≤ this"),
      integer_key<Solver>("max_iterations", [](auto& s) -> auto& { return s.newton.max_iterations; }, 0, 100000,
                          "Newton iterations per solve (load stepping counts its own)"),
      boolean_key<Solver>("line_search", [](auto& s) -> auto& { return s.newton.line_search; }, "Armijo backtracking"),
      choice_key<Solver>("linear_solver", names(linear_solver_table()),
                         [](const Solver& s) { return linear_solver_name(s.linear_solver); },
                         [](Solver& s, const std::string& v) { s.linear_solver = value_of(linear_solver_table(), v); },
                         "factorization of the linear operator (modal needs a C the undamped modes diagonalize: "
                         "Rayleigh or modal_ratio)"),
      number_key<Solver>(
          "residual_tolerance", [](auto& s) -> auto& { return s.residual_tolerance; }, positive(""),
          "a solve (every point of a sweep or branch) is converged only if the normwise backward error of its full "
          "residual, ‖G a − b + n(a)‖₂ / (γ ‖a‖₂ + ‖b‖₂ + ‖n(a)‖₂) with γ = ‖G‖_F ≥ ‖G‖₂, recomputed from "
          "the solution, is at most this: the solution then solves exactly a problem whose data differ by this "
          "relative amount. Unlike ‖R‖/‖b‖ it does not grow with the conditioning that units or reduced "
          "coordinates give G, so the default holds for Craig–Bampton models. Echoed in `result.json` "
          "(`scene.solver`; per solve `backward_error` beside `relative_residual` = ‖R‖/‖b‖ in the diagnostics)"),
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

const std::vector<DeclaredKey<solvers::TimeIntegrationOptions>>& bdf_keys() {
  using T = solvers::TimeIntegrationOptions;
  static const std::vector<DeclaredKey<T>> keys = {
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

const std::vector<DeclaredKey<solvers::MoreauJeanOptions>>& moreau_jean_keys() {
  using T = solvers::MoreauJeanOptions;
  static const std::vector<DeclaredKey<T>> keys = {
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

const std::vector<DeclaredKey<solvers::CentralDifferenceOptions>>& central_difference_keys() {
  using T = solvers::CentralDifferenceOptions;
  static const std::vector<DeclaredKey<T>> keys = {
      integer_key<T>("steps_per_period", [](auto& o) -> auto& { return o.steps_per_period; }, 4, 1 << 26,
                     "fixed steps per period, a multiple of `[output] samples`; explicit: fewer than the stability "
                     "limit h ω_max < 2 (ω_max with the Jenkins elements' k_t) are refused with the smallest that "
                     "passes"),
      number_key<T>("periodicity_tolerance", [](auto& o) -> auto& { return o.periodicity_tolerance; }, positive(""),
                    kPeriodicity),
      integer_key<T>("max_periods", [](auto& o) -> auto& { return o.max_periods; }, 2, 10000000, kMaxPeriods),
  };
  return keys;
}

const std::vector<DeclaredKey<Output>>& output_keys() {
  using O = Output;
  static const std::vector<DeclaredKey<O>> keys = {
      integer_key<O>("samples", [](auto& o) -> auto& { return o.samples; }, 4, 1 << 22,
                     "P, samples per period at τ_p = p/P (also the BDF output grid)"),
      compound_key<O>("nodes", "`\"all\"` or list of locations", "forced and contact nodes (nnm: all)",
                      "see Locations", "rod only: the nodes written"),
      compound_key<O>("dofs", "`\"all\"` or list of locations", "forced and contact DOFs (nnm: all)",
                      "see Locations", "matrices only: the DOFs written"),
      compound_key<O>("formats", "list of strings", "`[\"csv\"]`",
                      "non-empty, distinct, among `\"csv\"`, `\"mat\"`",
                      "`\"csv\"`: one CSV file per table (below); `\"mat\"`: `result.mat` (MAT 5, written with matio; "
                      "MATLAB and `scipy.io.loadmat` read it) with the same tables",
                      [](const O& o) { return nlohmann::json(o.formats); }),
      compound_key<O>("observe", "list of locations", "sweep: the output DOFs; continuation: the forced DOF",
                      "sweep and continuation only",
                      "the DOFs reported per point: a sweep's `frequency_response.csv` columns, a branch's extra "
                      "`u_max_<dof>`, `u_min_<dof>`, `amplitude_<dof>` columns in `branch.csv` (after "
                      "`corrector_iterations`), and their harmonics (below); each point of a branch is expanded once "
                      "more for them (one solve with G per point)"),
      integer_key<O>("harmonics", [](auto& o) -> auto& { return o.harmonics; }, 1, 1 << 21,
                     "per point of a sweep: `sweep_harmonics.csv`, of a continuation branch: `branch_harmonics.csv` "
                     "(frequency, then `A<h>_<dof> [m]`, `phase<h>_<dof> [rad]` for h = 0 … H per observed DOF); solve "
                     "at one frequency and timestep: write `harmonics.csv`, the amplitude A_h [m] and phase φ_h [rad] "
                     "of u(t) = Σ_h A_h cos(2π h f t + φ_h), h = 0 … H, for each output DOF, from the P samples by "
                     "FFT (h = 0: the signed mean, phase 0); for comparison with tools that report harmonic amplitudes")
          .documented_default("none")
          .documented_allowed("1 … (samples − 1)/2; not nnm or basis-plot")
          .echoed_as([](const O& o) { return o.harmonics > 0 ? nlohmann::json(o.harmonics) : nlohmann::json(); })
          .read_by_section(),
  };
  return keys;
}

}  // namespace detail

std::string key_table_markdown(const std::string& section) {
  using namespace detail;
  if (section == "top") return key_table(key_rows(top_keys()));
  if (section == "analysis") return key_table(key_rows(analysis_keys()));
  if (section == "structure") {
    auto rows = key_rows(structure_keys());
    for (auto& r : key_rows(deck_keys())) rows.push_back(std::move(r));
    return key_table(rows);
  }
  if (section == "damping") return key_table(key_rows(damping_keys()));
  if (section == "forcing") return key_table(key_rows(forcing_keys()));
  if (section == "forcing.loads") return key_table(key_rows(load_keys()));
  if (section == "contact") return key_table(key_rows(contact_keys()));
  if (section == "counter_surface") return key_table(key_rows(counter_surface_keys()));
  if (section == "basis") return key_table(key_rows(basis_keys()));
  if (section == "solver") return key_table(key_rows(solver_keys()));
  if (section == "timestep") return key_table(key_rows(bdf_keys()));
  if (section == "timestep.rigid") return key_table(key_rows(moreau_jean_keys()));
  if (section == "timestep.jenkins") return key_table(key_rows(central_difference_keys()));
  if (section == "output") return key_table(key_rows(output_keys()));
  std::string known;
  for (const auto& s : declared_sections()) known += (known.empty() ? "\"" : ", \"") + s + "\"";
  throw std::invalid_argument("key_table_markdown: section = \"" + section + "\": not declared; declared: " + known);
}

std::vector<std::string> declared_sections() {
  return {"top",   "analysis", "structure", "damping",  "forcing",        "forcing.loads",
          "contact", "counter_surface", "basis",  "solver",    "timestep", "timestep.rigid", "timestep.jenkins",
          "output"};
}

}  // namespace wbm::scene
