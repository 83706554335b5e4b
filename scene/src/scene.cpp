#include <wbm/scene/scene.hpp>
#include <wbm/solvers/condensation.hpp>

#include "scene_keys.hpp"
#include "scene_parser.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <fstream>
#include <limits>
#include <numbers>
#include <regex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <utility>

#include <Eigen/SparseCholesky>
#include <wbm/contact/friction.hpp>
#include <wbm/contact/jenkins_disc.hpp>
#include <wbm/contact/signorini.hpp>
#include <wbm/fem/calculix.hpp>
#include <wbm/fem/matrix_market.hpp>
#include <wbm/scene/reduce.hpp>
#include <wbm/scene/resources.hpp>
#include <wbm/solvers/model_checks.hpp>
#include <toml++/toml.h>

#include "reader.hpp"

namespace wbm::scene {

using namespace detail;

namespace {


Scene parse_table(const toml::table& root, const std::filesystem::path& file) {
  Reader r(file.string());
  Parser parser(r, file.has_parent_path() ? file.parent_path() : std::filesystem::current_path());
  Scene s = parser.parse(root);
  r.finish();
  s.name = file.stem().string();
  s.path = file.string();
  s.warnings = r.warnings();
  return s;
}

// JSON → TOML, member by member (null dropped), so JSON scenes go through the same checks.
toml::array to_toml_array(const nlohmann::json& j);
void insert(toml::table& t, const std::string& key, const nlohmann::json& v);

toml::table to_toml_table(const nlohmann::json& j) {
  toml::table t;
  for (const auto& [key, value] : j.items()) insert(t, key, value);
  return t;
}

template <class Add>
void convert(const nlohmann::json& v, Add&& add) {
  if (v.is_object()) {
    add(to_toml_table(v));
  } else if (v.is_array()) {
    add(to_toml_array(v));
  } else if (v.is_boolean()) {
    add(v.get<bool>());
  } else if (v.is_number_integer()) {
    add(v.get<int64_t>());
  } else if (v.is_number()) {
    add(v.get<double>());
  } else if (v.is_string()) {
    add(v.get<std::string>());
  }
}

void insert(toml::table& t, const std::string& key, const nlohmann::json& v) {
  convert(v, [&](auto&& x) { t.insert(key, std::forward<decltype(x)>(x)); });
}

toml::array to_toml_array(const nlohmann::json& j) {
  toml::array a;
  for (const auto& v : j) convert(v, [&](auto&& x) { a.push_back(std::forward<decltype(x)>(x)); });
  return a;
}

nlohmann::json matrix_json(const Eigen::SparseMatrix<double>& a, const std::string& file) {
  if (!file.empty()) return file;
  const Eigen::MatrixXd d(a);
  nlohmann::json rows = nlohmann::json::array();
  for (Eigen::Index i = 0; i < d.rows(); ++i) {
    nlohmann::json row = nlohmann::json::array();
    for (Eigen::Index j = 0; j < d.cols(); ++j) row.push_back(d(i, j));
    rows.push_back(row);
  }
  return rows;
}

}  // namespace

std::string_view to_string(AnalysisKind kind) noexcept { return name_of(analysis_table(), kind); }
std::string_view to_string(ContactLawKind law) noexcept { return name_of(law_table(), law); }
std::string_view to_string(NnmAlgorithm algorithm) noexcept { return name_of(nnm_algorithm_table(), algorithm); }

int Structure::dofs() const {
  if (kind == StructureKind::Rod) return rod.elements;
  return deck ? static_cast<int>(dof_names.size()) : static_cast<int>(mass.rows());
}

std::string Structure::dof_name(int dof) const {
  if (dof < 0 || dof >= dofs()) throw std::out_of_range("Structure::dof_name: DOF " + std::to_string(dof) + " outside [0, " + std::to_string(dofs()) + ")");
  return dof_names[static_cast<size_t>(dof)];
}

std::vector<double> Forcing::frequencies_hz() const {
  if (!range) return {frequency_hz};
  if (!range->list_hz.empty()) return range->list_hz;
  std::vector<double> f(static_cast<size_t>(range->points));
  for (int i = 0; i < range->points; ++i) {
    f[static_cast<size_t>(i)] = range->from_hz + (range->to_hz - range->from_hz) * i / (range->points - 1);
  }
  return f;
}

solvers::MechanicalSystem Scene::system() const {
  if (!structure) throw std::logic_error("Scene::system: scene \"" + name + "\" has no [structure]");
  if (structure->awaiting_reduction()) {
    throw std::logic_error("Scene::system: the [structure] deck of scene \"" + name + "\" is not reduced yet; call "
                           "reduce_structure first (run_analysis does)");
  }
  solvers::MechanicalSystem sys;
  if (condensation) {  // C = C_mm + αM_mm + βK̃ (+ modal damping) of the condensed model
    sys = condensation->system;
    sys.damping += damping.beta * sys.stiffness + damping.alpha * sys.mass;
    if (damping.modal_ratio > 0.0) sys.damping += solvers::modal_damping(sys, damping.modal_ratio);
    sys.validate();
    return sys;
  }
  if (structure->kind == StructureKind::Rod) {
    sys = solvers::beta_damped(fem::Rod(structure->rod), damping.beta);  // C = βK [JL14 Eq. (7)]
  } else {
    sys.mass = structure->mass;
    sys.stiffness = structure->stiffness;
    sys.damping = damping.beta * structure->stiffness;
    if (structure->damping.size() > 0) sys.damping += structure->damping;
  }
  if (damping.alpha != 0.0) sys.damping += damping.alpha * sys.mass;
  if (damping.modal_ratio > 0.0) sys.damping += solvers::modal_damping(sys, damping.modal_ratio);
  sys.validate();
  return sys;
}

solvers::HarmonicForcing Scene::harmonic_forcing(std::optional<double> frequency_hz) const {
  if (!forcing) throw std::logic_error("Scene::harmonic_forcing: scene \"" + name + "\" has no [forcing]");
  if (!frequency_hz && forcing->range) {
    throw std::logic_error("Scene::harmonic_forcing: scene \"" + name + "\" sweeps a range; pass the frequency");
  }
  solvers::HarmonicForcing h{solver_dof(forcing->dof), forcing->amplitude, frequency_hz.value_or(forcing->frequency_hz)};
  for (auto l : forcing->loads) {
    l.dof = solver_dof(l.dof);
    h.more.push_back(l);
  }
  return h;
}

int Scene::solver_dof(int dof) const { return condensation ? condensation->retained_index(dof) : dof; }

Eigen::MatrixXd Scene::expand_displacement(const Eigen::MatrixXd& u) const {
  return condensation ? condensation->expand_displacement(u) : u;
}

Eigen::MatrixXd Scene::expand_velocity(const Eigen::MatrixXd& u, const Eigen::MatrixXd& v) const {
  return condensation ? condensation->expand_velocity(u, v) : v;
}

std::vector<solvers::ContactPoint> Scene::contact_points() const {
  if (condensation) return condensation->contacts;
  std::vector<solvers::ContactPoint> points;
  for (const auto& c : contacts) {
    std::shared_ptr<const contact::ContactLaw> law;
    if (c.law == ContactLawKind::Rigid) {
      law = std::make_shared<contact::RigidStop>(c.gap);
    } else if (c.law == ContactLawKind::Exponential) {
      law = std::make_shared<contact::ExponentialPenalty>(
          contact::ExponentialPenaltyParameters{c.coefficient, c.exponent, c.gap});
    } else if (c.law == ContactLawKind::Jenkins && c.second_tangent >= 0 &&
               c.second_tangent < static_cast<int>(points.size())) {
      law = points[static_cast<size_t>(c.second_tangent)].law;  // the element's first tangent made it
    } else if (c.law == ContactLawKind::Jenkins && c.second_tangent >= 0) {
      law = std::make_shared<contact::JenkinsDiscLaw>(
          contact::JenkinsParameters{c.tangential_stiffness, c.friction_coefficient, c.normal_load});
    } else if (c.law == ContactLawKind::Jenkins) {
      law = std::make_shared<contact::JenkinsLaw>(
          contact::JenkinsParameters{c.tangential_stiffness, c.friction_coefficient, c.normal_load});
    } else if (c.law == ContactLawKind::Coulomb) {
      law = std::make_shared<contact::CoulombFriction>(contact::CoulombParameters{c.friction_coefficient, c.normal_load});
    } else {
      law = std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{c.stiffness, c.gap});
    }
    points.push_back({c.dof, law, c.against, c.along, c.normal_index});
    points.back().second_tangent = c.second_tangent;
    if (c.counter_surface >= 0) {
      const bool friction = c.law == ContactLawKind::Jenkins || c.law == ContactLawKind::Coulomb;
      points.back().obstacle = counter_surfaces.at(static_cast<size_t>(c.counter_surface)).motion(friction);
    }
  }
  return points;
}

solvers::ObstacleMotion CounterSurface::motion(bool friction) const {
  if (type == "oval_casing") {
    if (friction) return {.drift = -2.0 * std::numbers::pi * radius / lobes};
    const double phase = phase_deg * std::numbers::pi / 180.0;
    return {.cosine = {ovalization * std::cos(phase)}, .sine = {-ovalization * std::sin(phase)}};
  }
  return {.cosine = cosine, .sine = sine, .drift = drift};
}

solvers::TimeBasis Scene::trial() const { return solvers::TimeBasis::from_name(basis.trial, basis.dimension); }
solvers::TimeBasis Scene::weighting() const { return solvers::TimeBasis::from_name(basis.weighting, basis.dimension); }

solvers::WeightedResidualOptions Scene::weighted_residual_options() const {
  return {.formulation = basis.formulation,
          .time_samples = basis.time_samples,
          .operators = basis.operators,
          .contact_quadrature = basis.contact_quadrature,
          .linear_solver = solver.linear_solver,
          .newton = solver.newton,
          .residual_tolerance = solver.residual_tolerance,
          .harmonics = basis.selected_harmonics};
}

std::vector<int> Scene::output_dofs() const {
  std::vector<int> dofs;
  if (!structure) return dofs;
  if (output.all_dofs) {
    for (int i = 0; i < structure->dofs(); ++i) dofs.push_back(i);
    return dofs;
  }
  dofs = output.dofs;
  if (dofs.empty()) {
    if (forcing) {
      dofs.push_back(forcing->dof);
      for (const auto& l : forcing->loads) dofs.push_back(l.dof);
    }
    for (const auto& c : contacts) dofs.push_back(c.dof);
  }
  std::sort(dofs.begin(), dofs.end());
  dofs.erase(std::unique(dofs.begin(), dofs.end()), dofs.end());
  return dofs;
}

Scene parse_scene(std::string_view toml_text, const std::filesystem::path& file) {
  toml::table root;
  try {
    root = toml::parse(toml_text, file.string());
  } catch (const toml::parse_error& e) {
    std::ostringstream os;
    os << file.string() << ":" << e.source().begin.line << ": TOML syntax: " << e.description();
    throw std::invalid_argument(os.str());
  }
  return parse_table(root, file);
}

Scene scene_from_json(const nlohmann::json& json, const std::filesystem::path& file) {
  const nlohmann::json& body = json.contains("scene") ? json.at("scene") : json;
  if (!body.is_object()) {
    throw std::invalid_argument(file.string() + ": expected a JSON object holding a scene (or a result.json with "
                                "a \"scene\" member)");
  }
  return parse_table(to_toml_table(body), file);
}

Scene load_scene(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw std::invalid_argument("scene " + path.string() + ": is a directory, not a scene file (give the path of a "
                                ".toml scene, or of a result.json to re-run it)");
  }
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw std::invalid_argument("scene " + path.string() + ": no such file (give the path of a .toml scene, or of a "
                                "result.json to re-run it)");
  }
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  if (!in) throw std::invalid_argument("scene " + path.string() + ": cannot read the file (permissions?)");
  if (path.extension() == ".json") {
    nlohmann::json j;
    try {
      j = nlohmann::json::parse(text.str());
    } catch (const nlohmann::json::parse_error& e) {
      throw std::invalid_argument(path.string() + ": JSON syntax: " + e.what());
    }
    return scene_from_json(j, path);
  }
  return parse_scene(text.str(), path);
}

nlohmann::json to_json(const Scene& s) {
  nlohmann::json j;
  j["title"] = s.title;
  j["analysis"] = echo_keys(analysis_keys(), s.analysis, std::string(to_string(s.analysis.kind)));
  const bool rod = s.structure && s.structure->kind == StructureKind::Rod;
  auto where = [&](nlohmann::json& o, int dof) {
    if (rod) {
      o["node"] = dof + 1;
    } else {
      o["dof"] = s.structure->dof_name(dof);
    }
  };
  if (s.structure) {
    const Structure& st = *s.structure;
    if (rod) {
      j["structure"] = echo_keys(structure_keys(), st, "rod");  // type, E, ρ, S, L, elements
    } else if (st.deck) {  // the deck again (read and predicted again when read back), not the reduced matrices
      j["structure"] = echo_keys(deck_keys(), *st.deck);
      j["structure"]["type"] = "deck";
    } else {
      j["structure"] = {{"type", "matrices"},
                        {"mass", matrix_json(st.mass, st.mass_file)},
                        {"stiffness", matrix_json(st.stiffness, st.stiffness_file)},
                        {"dofs", st.dof_names}};
      if (st.damping.size() > 0) j["structure"]["damping"] = matrix_json(st.damping, st.damping_file);
    }
    if (s.analysis.kind != AnalysisKind::NonlinearModes) j["damping"] = echo_keys(damping_keys(), s.damping);
  }
  if (s.forcing) {
    nlohmann::json f = {{"amplitude", s.forcing->amplitude}};
    where(f, s.forcing->dof);
    if (!s.forcing->loads.empty()) {  // a vector file is written as its loads
      nlohmann::json loads = nlohmann::json::array();
      for (const auto& l : s.forcing->loads) {
        nlohmann::json one = {{"amplitude", l.amplitude}, {"phase_rad", l.phase_rad}, {"harmonic", l.harmonic}};
        where(one, l.dof);
        loads.push_back(one);
      }
      f["loads"] = loads;
    }
    if (s.forcing->range && !s.forcing->range->list_hz.empty()) {
      f["frequencies_hz"] = s.forcing->range->list_hz;
    } else if (s.forcing->range) {
      f["frequency_hz"] = {s.forcing->range->from_hz, s.forcing->range->to_hz};
      if (s.analysis.kind != AnalysisKind::Continuation) f["points"] = s.forcing->range->points;
    } else {
      f["frequency_hz"] = s.forcing->frequency_hz;
    }
    j["forcing"] = f;
  }
  if (!s.contacts.empty()) {
    nlohmann::json list = nlohmann::json::array();
    for (const auto& c : s.contacts) {
      nlohmann::json o = {{"law", std::string(to_string(c.law))}};
      if (c.law != ContactLawKind::Jenkins && c.law != ContactLawKind::Coulomb) o["gap"] = c.gap;
      if (c.law == ContactLawKind::Jenkins || c.law == ContactLawKind::Coulomb) {
        if (c.law == ContactLawKind::Jenkins) o["tangential_stiffness"] = c.tangential_stiffness;
        o["friction_coefficient"] = c.friction_coefficient;
        o["normal_load"] = c.normal_load;
        if (c.normal_contact >= 0) o["normal_contact"] = c.normal_contact;
        if (c.second_tangent >= 0) o["second_tangent_contact"] = c.second_tangent;  // its index in this list
      } else if (c.law == ContactLawKind::Exponential) {
        o["coefficient"] = c.coefficient;
        o["exponent"] = c.exponent;
      } else if (c.law == ContactLawKind::Linear) {
        o["stiffness"] = c.stiffness;
      }
      where(o, c.dof);
      if (c.against >= 0) {
        nlohmann::json a;
        where(a, c.against);
        o["against"] = rod ? a["node"] : a["dof"];
      }
      if (c.along.size() == 1 && c.along.front() == std::pair<int, double>{c.dof, -1.0}) {
        o["direction"] = -1;
      } else if (!c.along.empty()) {
        nlohmann::json d = nlohmann::json::object();
        for (const auto& [j, w] : c.along) d[s.structure->dof_name(j)] = w;
        o["direction"] = d;
      }
      if (c.counter_surface >= 0) {
        o["counter_surface"] = s.counter_surfaces.at(static_cast<size_t>(c.counter_surface)).name;
      }
      list.push_back(o);
    }
    j["contact"] = list;
    if (!s.counter_surfaces.empty()) {
      nlohmann::json surfaces = nlohmann::json::array();
      for (const auto& cs : s.counter_surfaces) surfaces.push_back(echo_keys(counter_surface_keys(), cs, cs.type));
      j["counter_surface"] = surfaces;
    }
  }
  if (s.analysis.kind != AnalysisKind::Timestep && s.analysis.kind != AnalysisKind::NonlinearModes) {
    nlohmann::json b = {{"trial", s.basis.trial}};
    if (s.basis.harmonics > 0) {
      b["harmonics"] = s.basis.harmonics;
    } else {
      b["dimension"] = s.basis.dimension;
    }
    if (s.analysis.kind != AnalysisKind::BasisPlot) {
      b["weighting"] = s.basis.weighting;
      b["formulation"] = std::string(solvers::to_string(s.basis.formulation));
      b["time_samples"] = s.basis.time_samples;
      b["operators"] = s.basis.operators == solvers::OperatorRule::Discrete ? "discrete" : "automatic";
      b["contact_quadrature"] = std::string(solvers::to_string(s.basis.contact_quadrature));
      if (!s.basis.selected_harmonics.empty()) {  // as given: "odd", or the list
        b["harmonic_selection"] = s.basis.harmonic_selection == "odd" ? nlohmann::json("odd")
                                                                       : nlohmann::json(s.basis.selected_harmonics);
      }
    }
    j["basis"] = b;
  }
  if (s.analysis.kind == AnalysisKind::Solve || s.analysis.kind == AnalysisKind::Continuation) {
    j["solver"] = echo_keys(solver_keys(), s.solver);
  }
  if (s.analysis.kind == AnalysisKind::Timestep) {
    j["timestep"] = s.rigid()     ? echo_keys(moreau_jean_keys(), s.moreau_jean)
                    : s.jenkins() ? echo_keys(central_difference_keys(), s.central_difference)
                                  : echo_keys(bdf_keys(), s.timestep);
  }
  nlohmann::json out = echo_keys(output_keys(), s.output);  // samples, formats, harmonics
  if (!s.output.observe.empty() && s.structure) {
    nlohmann::json list = nlohmann::json::array();
    for (int dof : s.output.observe) list.push_back(rod ? nlohmann::json(dof + 1) : nlohmann::json(s.structure->dof_name(dof)));
    out["observe"] = list;
  }
  if (s.structure) {
    nlohmann::json list = nlohmann::json::array();
    for (int dof : s.output_dofs()) list.push_back(rod ? nlohmann::json(dof + 1) : nlohmann::json(s.structure->dof_name(dof)));
    out[rod ? "nodes" : "dofs"] = list;
  }
  j["output"] = out;
  return j;
}

}  // namespace wbm::scene
