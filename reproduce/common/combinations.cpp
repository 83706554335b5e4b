#include "combinations.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>

#include <wbm/contact/signorini.hpp>
#include <wbm/scene/json.hpp>

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
  return std::isnan(value) ? "—" : solvers::format(spec, value);  // a missing value, never printed as a number
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
  r.method = "GSL msbdf";
  return r;
}

Reference solve_rigid_reference(Run& run, const std::string& scene_name, int steps, double restitution, int max_periods) {
  Reference r;
  r.scene = load_scene(scene_name);
  if (r.scene.contacts.empty()) {
    throw std::invalid_argument(r.scene.path + ": [contact] is required for the rigid-stop figures; add a [contact] table");
  }
  r.system = r.scene.system();
  r.forcing = r.scene.harmonic_forcing();
  for (const auto& c : r.scene.contact_points()) r.contacts.push_back({c.dof, std::make_shared<contact::RigidStop>(c.law->gap())});
  solvers::MoreauJeanOptions o;
  o.samples_per_period = run.quick() ? 256 : 1024;
  o.steps_per_period = steps;
  o.restitution = restitution;
  o.max_periods = max_periods;
  r.response = solvers::integrate_moreau_jean_to_periodic(r.system, r.forcing, r.contacts, o);
  const int tip = r.forcing.dof;
  r.tip_displacement = r.response.displacement.row(tip).transpose();
  r.tip_velocity = r.response.velocity.row(tip).transpose();
  r.contact_force = r.response.contact_force.row(0).transpose();
  r.energy = solvers::system_energy(r.system, r.contacts, r.response.displacement, r.response.velocity);
  r.method = "Moreau–Jean (theta = " + format("%g", o.theta) + ", restitution " + format("%g", restitution) + ", " +
             std::to_string(steps) + " steps per period)";
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
  if (!ref.contacts.front().law->rigid()) out.contact_force = solvers::contact_force(ref.contacts, fields.displacement);
  out.energy = solvers::system_energy(ref.system, ref.contacts, fields.displacement, fields.velocity);
  out.tip_error = solvers::rms_relative_error(out.tip_displacement, ref.tip_displacement);
  out.energy_norm = solvers::rms(out.energy) / solvers::rms(ref.energy);
  return out;
}

nlohmann::json to_json(const CombinationResult& r) {
  using scene::finite_or_null;
  // The solve as the solver's own serializer writes it (wbm/scene/json.hpp), and what this
  // study adds: the combination, the figure's formulation, the median time and the errors
  // against the reference (null when the solve did not converge: never 0 or −1).
  return {{"combination", r.combination.label()},
          {"dimension", r.dimension},
          {"formulation", std::string(solvers::to_string(kFigureFormulation))},
          {"status", std::string(solvers::to_string(r.solution.report.status))},
          {"solution", r.solution},
          {"median_solve_time_s", r.median_time_s},
          {"tip_error", r.converged() ? finite_or_null(r.tip_error) : nlohmann::json(nullptr)},
          {"energy_norm", r.converged() ? finite_or_null(r.energy_norm) : nlohmann::json(nullptr)}};
}

nlohmann::json to_json(const Reference& r) {
  const auto& s = r.scene;
  nlohmann::json reference = r.response.report;  // the integrator's report (wbm/scene/json.hpp)
  reference["method"] = r.method;
  reference["samples"] = r.response.tau.size();
  return {{"scene", {{"name", s.name}, {"file", s.path}, {"title", s.title}, {"E_Pa", s.structure->rod.young_modulus},
                     {"rho_kg_m3", s.structure->rod.density}, {"S_m2", s.structure->rod.area}, {"L_m", s.structure->rod.length},
                     {"elements", s.structure->rod.elements}, {"beta_s", s.damping.beta}, {"F_N", s.forcing->amplitude},
                     {"frequency_hz", s.forcing->frequency_hz}, {"contact", r.contacts.front().law->describe()},
                     {"gap_m", s.contacts.front().gap}}},
          {"reference", reference}};
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

const CombinationResult* find_converged(const std::vector<CombinationResult>& results, const std::string& key,
                                        int dimension) {
  for (const auto& r : results) {
    if (r.combination.key() == key && (dimension == 0 || r.dimension == dimension) && r.converged()) return &r;
  }
  return nullptr;
}

namespace {
void check_quantity(const std::string& q) {
  if (q != "displacement" && q != "velocity" && q != "force") {
    throw std::invalid_argument("history: quantity '" + q + "' must be displacement, velocity or force");
  }
}
double history_scale(const Reference& r, const std::string& q) {
  return q == "force" ? 1.0 / r.scene.forcing->amplitude : 1.0;
}
}  // namespace

Eigen::VectorXd history(const Reference& r, const std::string& q) {
  check_quantity(q);
  const Eigen::VectorXd& v = q == "displacement" ? r.tip_displacement : q == "velocity" ? r.tip_velocity : r.contact_force;
  return history_scale(r, q) * v;
}

Eigen::VectorXd history(const Reference& ref, const CombinationResult& r, const std::string& q) {
  check_quantity(q);
  const Eigen::VectorXd& v = q == "displacement" ? r.tip_displacement : q == "velocity" ? r.tip_velocity : r.contact_force;
  return history_scale(ref, q) * v;
}

double fraction_above(const Eigen::VectorXd& u, double threshold) {
  return u.size() == 0 ? NAN : static_cast<double>((u.array() > threshold).count()) / static_cast<double>(u.size());
}

double total_variation(const Eigen::VectorXd& v) {
  double tv = 0.0;
  for (Eigen::Index q = 0; q < v.size(); ++q) tv += std::abs(v((q + 1) % v.size()) - v(q));
  return tv;
}

double rms_relative_error_on(const Eigen::VectorXd& v, const Eigen::VectorXd& reference, const std::vector<bool>& mask) {
  double num = 0.0, den = 0.0;
  long count = 0;
  for (Eigen::Index q = 0; q < v.size(); ++q) {
    if (!mask[static_cast<size_t>(q)]) continue;
    num += (v(q) - reference(q)) * (v(q) - reference(q));
    den += reference(q) * reference(q);
    ++count;
  }
  return count == 0 || den == 0.0 ? NAN : std::sqrt(num / den);
}

double loglog_slope(const std::vector<double>& x, const std::vector<double>& y) {
  if (x.size() != y.size()) {
    throw std::invalid_argument("loglog_slope: x has " + std::to_string(x.size()) + " values, y " +
                                std::to_string(y.size()) + "; give one y per x");
  }
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (size_t i = 0; i < x.size(); ++i) {
    if (!(x[i] > 0.0) || !(y[i] > 0.0) || !std::isfinite(x[i]) || !std::isfinite(y[i])) continue;
    const double lx = std::log(x[i]), ly = std::log(y[i]);
    sx += lx, sy += ly, sxx += lx * lx, sxy += lx * ly, ++n;
  }
  const double d = n * sxx - sx * sx;
  return n >= 2 && d > 0.0 ? (n * sxy - sx * sy) / d : NAN;
}

std::string dimension_table_header(const std::vector<int>& dimensions, const std::string& last) {
  std::string head = "| pair |", rule = "|---|";
  for (int m : dimensions) head += " M = " + std::to_string(m) + " |", rule += "---|";
  if (!last.empty()) head += " " + last + " |", rule += "---|";
  return head + "\n" + rule + "\n";
}

std::string claims_markdown(const std::vector<Claim>& claims) {
  std::ostringstream md;
  int agree = 0, disagree = 0, unchecked = 0;
  md << "Against the paper's text:\n\n";
  for (const auto& c : claims) {
    md << "- \"" << c.statement << "\": " << c.numbers << ": ";
    if (!c.agrees.has_value()) {
      md << "not checked.\n";
      ++unchecked;
    } else {
      md << (*c.agrees ? "agrees" : "disagrees") << ".\n";
      ++(*c.agrees ? agree : disagree);
    }
  }
  md << "\n" << agree << " agree, " << disagree << " disagree, " << unchecked << " not checked.\n\n";
  return md.str();
}

HistoryFigure history_figure(Run& run, const std::string& scene_name, const std::string& figure,
                             const std::string& quantity, const std::string& paper_note) {
  check_quantity(quantity);
  HistoryFigure out{solve_reference(run, scene_name), {}, run.quick() ? 16 : 64};
  const Reference& ref = out.reference;
  const int m = out.dimension;
  const std::string unit = quantity == "displacement" ? "[m]" : quantity == "velocity" ? "[m/s]" : "[-]";
  const std::string prefix = quantity == "displacement" ? "u_tip_" : quantity == "velocity" ? "v_tip_" : "f_contact_";

  std::vector<std::string> header = {"tau [-]", prefix + "bdf " + unit};
  const Eigen::VectorXd v_ref = history(ref, quantity);
  std::vector<Eigen::VectorXd> columns = {ref.tau(), v_ref};
  nlohmann::json solves = nlohmann::json::array();
  std::ostringstream rows;
  for (const auto& c : table2_combinations()) {
    out.results.push_back(solve_combination(ref, c, m));
    const auto& r = out.results.back();
    solves.push_back(to_json(r));
    rows << "| " << c.label() << " | " << solvers::to_string(r.solution.report.status) << " | "
         << r.solution.report.iterations << " | ";
    if (!r.converged()) {
      rows << "— | — | " << r.solution.report.message << " |\n";
      continue;
    }
    const Eigen::VectorXd v = history(ref, r, quantity);
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
  return out;
}

}  // namespace wbm::reproduce

namespace wbm::reproduce {

std::string ConvergenceFigure::frequency_label(int c) const {
  return format("%g", frequencies_hz[static_cast<size_t>(c)]) + " Hz";
}

ConvergenceFigure convergence_figure(Run& run, const std::string& figure, const std::string& metric,
                                     const std::string& paper_note) {
  if (metric != "energy_norm" && metric != "tip_error") {
    throw std::invalid_argument("convergence_figure: metric '" + metric + "' must be energy_norm or tip_error");
  }
  ConvergenceFigure out;
  out.dimensions = run.quick() ? std::vector<int>{8, 16} : std::vector<int>{8, 16, 32, 64, 128, 256};
  const std::vector<int>& dims = out.dimensions;
  std::ostringstream md;
  md << "## " << figure << ": " << (metric == "energy_norm" ? "energy norm rms(E)/rms(E_BDF)" : "rms relative tip error")
     << " against M, distributional form\n\n"
     << "Files: `out/" << run.id() << "/sweep_case{1,2}.csv` (long format: combination index in the order of "
     << "Table 2, M, tip error, energy norm, solve time, Newton iterations, condition estimate, status; a value that does not exist is an empty cell), "
     << "`" << metric << ".{png,pdf}`, `meta.json`.\n\nPaper: " << paper_note << "\n\n";
  nlohmann::json meta = nlohmann::json::object();
  meta["combinations"] = nlohmann::json::array();
  for (const auto& c : table2_combinations()) meta["combinations"].push_back(c.label());
  meta["metric"] = metric;
  meta["figure"] = figure;
  for (int case_id : {1, 2}) {
    const std::string name = "jl14_case" + std::to_string(case_id);
    const Reference ref = solve_reference(run, name);
    out.frequencies_hz[static_cast<size_t>(case_id - 1)] = ref.scene.forcing->frequency_hz;
    std::vector<CombinationResult>& results = out.cases[static_cast<size_t>(case_id - 1)];
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
    write_sweep(run, "sweep_case" + std::to_string(case_id) + ".csv", results);
    meta["case" + std::to_string(case_id)] = to_json(ref);
    meta["case" + std::to_string(case_id)]["solves"] = solves;
  }
  run.meta(meta);
  run.report(md.str());
  return out;
}

}  // namespace wbm::reproduce
