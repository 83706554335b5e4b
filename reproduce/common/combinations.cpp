#include "combinations.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace wbm::reproduce {

std::string Combination::label() const {
  return solvers::TimeBasis::from_name(trial, 2).name() + ":" + solvers::TimeBasis::from_name(weighting, 2).name();
}

std::string Combination::key() const { return trial + "_" + weighting; }

const std::vector<Combination>& table2_combinations() {
  static const std::vector<Combination> c = {{"fourier", "fourier"}, {"bspline", "bspline"}, {"db6", "db6"},
                                             {"haar", "fourier"},    {"db6", "fourier"},     {"haar", "bspline"}};
  return c;
}

std::string format(const char* spec, double value) {
  char b[64];
  std::snprintf(b, sizeof b, spec, value);
  return b;
}

Reference solve_reference(Run& run, const std::string& scene_name, double relative_tolerance) {
  Reference r;
  r.scene = load_scene(scene_name);
  if (r.scene.contacts.empty()) {
    throw std::invalid_argument(r.scene.path + ": [contact] is required for the weighted-residual figures; add a "
                                "[contact] table");
  }
  r.system = r.scene.system();
  r.forcing = r.scene.harmonic_forcing();
  r.contacts = r.scene.contact_points();
  r.response = solvers::integrate_to_periodic(
      r.system, r.forcing, r.contacts,
      {.samples_per_period = run.quick() ? 256 : 1024, .relative_tolerance = relative_tolerance});
  if (!r.response.report.converged()) run.fail(r.scene.name + ": BDF reference: " + r.response.report.message);
  const int tip = r.forcing.dof;
  r.tip_displacement = r.response.displacement.row(tip).transpose();
  r.tip_velocity = r.response.velocity.row(tip).transpose();
  r.contact_force = solvers::contact_force(r.contacts, r.response.displacement);
  r.energy = solvers::system_energy(r.system, r.contacts, r.response.displacement, r.response.velocity);
  return r;
}

CombinationResult solve_combination(const Reference& ref, const Combination& c, int dimension, int repeats) {
  CombinationResult out;
  out.combination = c;
  out.dimension = dimension;
  const auto trial = solvers::TimeBasis::from_name(c.trial, dimension);
  const auto weighting = solvers::TimeBasis::from_name(c.weighting, dimension);
  std::vector<double> times;
  for (int k = 0; k < std::max(1, repeats); ++k) {
    const auto start = std::chrono::steady_clock::now();
    out.solution = solvers::solve_weighted_residual(ref.system, ref.forcing, ref.contacts, trial, weighting,
                                                    {.formulation = kFigureFormulation});
    times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  std::nth_element(times.begin(), times.begin() + static_cast<long>(times.size() / 2), times.end());
  out.median_time_s = times[times.size() / 2];
  if (!out.converged()) return out;
  const auto fields = solvers::evaluate_fields(trial, out.solution.coefficients, ref.tau(), ref.forcing.frequency_hz);
  out.tip_displacement = fields.displacement.row(ref.forcing.dof).transpose();
  out.tip_velocity = fields.velocity.row(ref.forcing.dof).transpose();
  out.contact_force = solvers::contact_force(ref.contacts, fields.displacement);
  out.energy = solvers::system_energy(ref.system, ref.contacts, fields.displacement, fields.velocity);
  out.tip_error = solvers::rms_relative_error(out.tip_displacement, ref.tip_displacement);
  out.energy_norm = solvers::rms(out.energy) / solvers::rms(ref.energy);
  return out;
}

namespace {
// JSON null for a value that does not exist (NaN, inf): never 0 or −1.
nlohmann::json finite_or_null(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }
}  // namespace

nlohmann::json to_json(const CombinationResult& r) {
  const auto& s = r.solution;
  return {{"combination", r.combination.label()},
          {"dimension", r.dimension},
          {"formulation", std::string(solvers::to_string(kFigureFormulation))},
          {"status", std::string(solvers::to_string(s.report.status))},
          {"message", s.report.message},
          {"newton_iterations", s.report.iterations},
          {"relative_residual", finite_or_null(s.relative_residual)},
          {"condition_number", finite_or_null(s.condition_number)},
          {"linear_solver", s.linear_solver},
          {"operators", s.operator_rule},
          {"median_solve_time_s", r.median_time_s},
          {"tip_error", r.converged() ? finite_or_null(r.tip_error) : nlohmann::json(nullptr)},
          {"energy_norm", r.converged() ? finite_or_null(r.energy_norm) : nlohmann::json(nullptr)},
          {"max_penetration_m", r.converged() ? finite_or_null(s.max_penetration) : nlohmann::json(nullptr)}};
}

nlohmann::json to_json(const Reference& r) {
  const auto& s = r.scene;
  const auto& rep = r.response.report;
  return {{"scene", {{"name", s.name}, {"file", s.path}, {"title", s.title}, {"E_Pa", s.structure->rod.young_modulus},
                     {"rho_kg_m3", s.structure->rod.density}, {"S_m2", s.structure->rod.area}, {"L_m", s.structure->rod.length},
                     {"elements", s.structure->rod.elements}, {"beta_s", s.damping.beta}, {"F_N", s.forcing->amplitude},
                     {"frequency_hz", s.forcing->frequency_hz}, {"contact", r.contacts.front().law->describe()},
                     {"gap_m", s.contacts.front().gap}}},
          {"reference", {{"method", "GSL msbdf"},
                         {"status", std::string(solvers::to_string(rep.status))},
                         {"periods", rep.periods},
                         {"steps", rep.steps},
                         {"periodicity", rep.periodicity.empty() ? nlohmann::json(nullptr)
                                                                 : finite_or_null(rep.periodicity.back())},
                         {"wall_time_s", rep.wall_time_s},
                         {"samples", r.response.tau.size()}}}};
}

void write_sweep(Run& run, const std::string& file, const std::vector<CombinationResult>& results) {
  const auto n = static_cast<Eigen::Index>(results.size());
  Eigen::VectorXd index(n), m(n), err(n), energy(n), time(n), iterations(n), cond(n);
  std::vector<std::string> status(static_cast<size_t>(n));
  const auto& combos = table2_combinations();
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto& r = results[static_cast<size_t>(i)];
    const auto it = std::find_if(combos.begin(), combos.end(), [&](const Combination& c) {
      return c.key() == r.combination.key();
    });
    index(i) = static_cast<double>(it - combos.begin());
    m(i) = r.dimension;
    // Missing values (empty cells, the status says why): errors of an iterate that is not a
    // solution, an infinite condition estimate.
    status[static_cast<size_t>(i)] = std::string(solvers::to_string(r.solution.report.status));
    err(i) = r.converged() && std::isfinite(r.tip_error) ? r.tip_error : NAN;
    energy(i) = r.converged() && std::isfinite(r.energy_norm) ? r.energy_norm : NAN;
    time(i) = r.median_time_s;
    iterations(i) = r.solution.report.iterations;
    cond(i) = std::isfinite(r.solution.condition_number) ? r.solution.condition_number : NAN;
  }
  run.table(file,
            {"combination [-]", "M [-]", "tip_error [-]", "energy_norm [-]", "solve_time [s]", "newton_iterations [-]",
             "condition_number [-]"},
            {index, m, err, energy, time, iterations, cond}, status);
}

namespace {

const Eigen::VectorXd& pick(const Reference& r, const std::string& q) {
  return q == "displacement" ? r.tip_displacement : q == "velocity" ? r.tip_velocity : r.contact_force;
}
const Eigen::VectorXd& pick(const CombinationResult& r, const std::string& q) {
  return q == "displacement" ? r.tip_displacement : q == "velocity" ? r.tip_velocity : r.contact_force;
}

}  // namespace

void history_figure(Run& run, const std::string& scene_name, const std::string& figure, const std::string& quantity,
                    const std::string& paper_note) {
  if (quantity != "displacement" && quantity != "velocity" && quantity != "force") {
    throw std::invalid_argument("history_figure: quantity '" + quantity + "' must be displacement, velocity or force");
  }
  const Reference ref = solve_reference(run, scene_name);
  const int m = run.quick() ? 16 : 64;
  const double scale = quantity == "force" ? 1.0 / ref.scene.forcing->amplitude : 1.0;
  const std::string unit = quantity == "displacement" ? "[m]" : quantity == "velocity" ? "[m/s]" : "[-]";
  const std::string prefix = quantity == "displacement" ? "u_tip_" : quantity == "velocity" ? "v_tip_" : "f_contact_";

  std::vector<std::string> header = {"tau [-]", prefix + "bdf " + unit};
  std::vector<Eigen::VectorXd> columns = {ref.tau(), scale * pick(ref, quantity)};
  nlohmann::json solves = nlohmann::json::array();
  std::ostringstream rows;
  for (const auto& c : table2_combinations()) {
    const auto r = solve_combination(ref, c, m);
    solves.push_back(to_json(r));
    rows << "| " << c.label() << " | " << solvers::to_string(r.solution.report.status) << " | "
         << r.solution.report.iterations << " | ";
    if (!r.converged()) {
      rows << "— | — | " << r.solution.report.message << " |\n";
      continue;
    }
    const Eigen::VectorXd v = scale * pick(r, quantity);
    const Eigen::VectorXd v_ref = scale * pick(ref, quantity);
    header.push_back(prefix + c.key() + " " + unit);
    columns.push_back(v);
    rows << format("%.3e", solvers::rms_relative_error(v, v_ref)) << " | "
         << format("%.3e", (v - v_ref).cwiseAbs().maxCoeff()) << " | |\n";
  }
  const std::string file = quantity == "displacement" ? "tip_displacement.csv"
                           : quantity == "velocity"   ? "tip_velocity.csv"
                                                      : "contact_force.csv";
  run.table(file, header, columns);
  nlohmann::json meta = to_json(ref);
  meta["quantity"] = quantity;
  meta["figure"] = figure;
  meta["figure_dimension"] = m;
  meta["gap_m"] = ref.scene.contacts.front().gap;
  meta["combinations"] = solves;
  run.meta(meta);

  const auto& rep = ref.response.report;
  std::ostringstream md;
  md << "## " << figure << ": tip " << quantity << (quantity == "force" ? " / F" : "") << ", " << ref.scene.title
     << "\n\n"
     << "Files: `out/" << run.id() << "/" << file.substr(0, file.size() - 4) << ".{csv,png,pdf}`, `meta.json`. Scene: `"
     << "reproduce/scenes/" << ref.scene.name << ".toml`. All six combinations of Table 2 with M = " << m
     << ", distributional form, contact forces on Q = 256 midpoints.\n\n"
     << "Paper: " << paper_note << "\n\n"
     << "BDF reference (GSL msbdf, rtol 1e-10): periodic after " << rep.periods << " periods, " << rep.steps
     << " steps, " << format("%.2f", rep.wall_time_s) << " s.\n\n"
     << "| combination | status | Newton iterations | rms relative difference to BDF | max abs difference "
     << unit << " | note |\n|---|---|---|---|---|---|\n"
     << rows.str() << "\n";
  run.report(md.str());
}

}  // namespace wbm::reproduce

namespace wbm::reproduce {

namespace {

// The paper's statements on Fig. 11 [JL14 Sec. 5.5], checked against our sweep.
std::string paper_checks(const std::vector<CombinationResult>& results, const std::vector<int>& dims) {
  const auto at = [&](const std::string& key, int m) -> const CombinationResult* {
    for (const auto& r : results) {
      if (r.combination.key() == key && r.dimension == m && r.converged()) return &r;
    }
    return nullptr;
  };
  std::ostringstream md;
  md << "Against the paper's text:\n\n";
  std::vector<std::pair<double, std::string>> at8;
  for (const auto& c : table2_combinations()) {
    if (const auto* r = at(c.key(), dims.front())) at8.emplace_back(r->tip_error, c.label());
  }
  std::sort(at8.begin(), at8.end());
  if (at8.size() >= 2) {
    md << "- Lowest error at M = " << dims.front() << " (paper: HBM and Galerkin B-spline): ours " << at8[0].second
       << " (" << format("%.2e", at8[0].first) << ") and " << at8[1].second << " (" << format("%.2e", at8[1].first)
       << ").\n";
  }
  const auto* db16 = at("db6_db6", 16);
  const auto* db8 = at("db6_db6", 8);
  const auto* db64 = at("db6_db6", 64);
  const auto* hb64 = at("fourier_fourier", 64);
  if (db16 && db8 && db64 && hb64) {
    md << "- Galerkin DB6 poor at M = 16, then comparable to HBM (paper): ours " << format("%.2e", db16->tip_error)
       << " at 16 against " << format("%.2e", db8->tip_error) << " at 8; at 64 " << format("%.2e", db64->tip_error)
       << " against HBM " << format("%.2e", hb64->tip_error) << ".\n";
  }
  const auto* bs = at("bspline_bspline", dims.back());
  const auto* hb = at("fourier_fourier", dims.back());
  if (bs && hb) {
    md << "- Galerkin B-spline behind HBM at large M (paper): at M = " << dims.back() << " "
       << format("%.2e", bs->tip_error) << " against " << format("%.2e", hb->tip_error) << ".\n";
  }
  double haar = std::numeric_limits<double>::infinity(), other = 0.0;  // smallest Haar, largest other
  for (const auto& r : results) {
    if (r.dimension != 128 || !r.converged()) continue;
    if (r.combination.trial == "haar") {
      haar = std::min(haar, r.tip_error);
    } else {
      other = std::max(other, r.tip_error);
    }
  }
  if (std::isfinite(haar)) {
    md << "- Haar trial functions have the highest error (paper): at M = 128 the smallest Haar error "
       << format("%.2e", haar) << " against the largest other " << format("%.2e", other) << ": "
       << (haar > other ? "agrees" : "disagrees") << " (Haar converges at first order in M).\n\n";
  }
  return md.str();
}

}  // namespace

void convergence_figure(Run& run, const std::string& figure, const std::string& metric, const std::string& paper_note) {
  if (metric != "energy_norm" && metric != "tip_error") {
    throw std::invalid_argument("convergence_figure: metric '" + metric + "' must be energy_norm or tip_error");
  }
  const std::vector<int> dims = run.quick() ? std::vector<int>{8, 16} : std::vector<int>{8, 16, 32, 64, 128, 256};
  std::ostringstream md;
  md << "## " << figure << ": " << (metric == "energy_norm" ? "energy norm rms(E)/rms(E_BDF)" : "rms relative tip error")
     << " against M, distributional form\n\n"
     << "Files: `out/" << run.id() << "/sweep_case{1,2}.csv` (long format: combination index in the order of "
     << "Table 2, M, converged, tip error, energy norm, solve time, Newton iterations, condition estimate), "
     << "`" << metric << ".{png,pdf}`, `meta.json`.\n\nPaper: " << paper_note << "\n\n";
  nlohmann::json meta = nlohmann::json::object();
  meta["combinations"] = nlohmann::json::array();
  for (const auto& c : table2_combinations()) meta["combinations"].push_back(c.label());
  meta["metric"] = metric;
  meta["figure"] = figure;
  for (int case_id : {1, 2}) {
    const std::string name = "jl14_case" + std::to_string(case_id);
    const Reference ref = solve_reference(run, name);
    std::vector<CombinationResult> results;
    nlohmann::json solves = nlohmann::json::array();
    md << "### " << ref.scene.title << "\n\n| combination |";
    for (int m : dims) md << " M = " << m << " |";
    md << "\n|---|";
    for (size_t i = 0; i < dims.size(); ++i) md << "---|";
    md << "\n";
    for (const auto& c : table2_combinations()) {
      md << "| " << c.label() << " |";
      for (int m : dims) {
        results.push_back(solve_combination(ref, c, m));
        const auto& r = results.back();
        solves.push_back(to_json(r));
        md << " " << (r.converged() ? format("%.3e", metric == "energy_norm" ? r.energy_norm : r.tip_error)
                                    : std::string("not converged (") +
                                          std::string(solvers::to_string(r.solution.report.status)) + ")")
           << " |";
      }
      md << "\n";
    }
    md << "\n";
    if (metric == "tip_error" && !run.quick()) md << paper_checks(results, dims);
    write_sweep(run, "sweep_case" + std::to_string(case_id) + ".csv", results);
    meta["case" + std::to_string(case_id)] = to_json(ref);
    meta["case" + std::to_string(case_id)]["solves"] = solves;
  }
  run.meta(meta);
  run.report(md.str());
}

}  // namespace wbm::reproduce
