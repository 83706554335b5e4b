#include <wbm/scene/scene.hpp>
#include <wbm/solvers/condensation.hpp>

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
#include <wbm/contact/signorini.hpp>
#include <wbm/fem/calculix.hpp>
#include <wbm/fem/matrix_market.hpp>
#include <wbm/scene/reduce.hpp>
#include <wbm/scene/resources.hpp>
#include <wbm/solvers/model_checks.hpp>
#include <toml++/toml.h>

#include "reader.hpp"

namespace wbm::scene {
namespace {

using detail::Range;
using detail::Reader;

// One table per enumerated scene value: the parser's list of choices, the value it stands for,
// and the name the JSON echo and messages print are read from the same entry.
template <class E>
using NameTable = std::vector<std::pair<E, std::string_view>>;

const NameTable<AnalysisKind>& analysis_table() {
  static const NameTable<AnalysisKind> t = {{AnalysisKind::Solve, "solve"},
                                            {AnalysisKind::Timestep, "timestep"},
                                            {AnalysisKind::BasisPlot, "basis-plot"},
                                            {AnalysisKind::Continuation, "continuation"},
                                            {AnalysisKind::NonlinearModes, "nnm"}};
  return t;
}
const NameTable<ContactLawKind>& law_table() {
  static const NameTable<ContactLawKind> t = {
      {ContactLawKind::Exponential, "exponential"}, {ContactLawKind::Linear, "linear"}, {ContactLawKind::Rigid, "rigid"}};
  return t;
}
const NameTable<NnmAlgorithm>& nnm_algorithm_table() {
  static const NameTable<NnmAlgorithm> t = {{NnmAlgorithm::Continuation, "continuation"},
                                            {NnmAlgorithm::Simultaneous, "simultaneous"},
                                            {NnmAlgorithm::Sequential, "sequential"}};
  return t;
}
const NameTable<solvers::LinearSolverPath>& linear_solver_table() {
  static const NameTable<solvers::LinearSolverPath> t = {{solvers::LinearSolverPath::Automatic, "automatic"},
                                                         {solvers::LinearSolverPath::SparseLU, "sparse-lu"},
                                                         {solvers::LinearSolverPath::Modal, "modal"}};
  return t;
}

template <class E>
std::vector<std::string> names(const NameTable<E>& t) {
  std::vector<std::string> out;
  for (const auto& [value, name] : t) out.emplace_back(name);
  return out;
}
// The name of a value; the table lists every enumerator.
template <class E>
std::string_view name_of(const NameTable<E>& t, E value) {
  for (const auto& [v, name] : t) {
    if (v == value) return name;
  }
  return t.front().second;
}
// The value of a name already checked by Reader::choice against names(t).
template <class E>
E value_of(const NameTable<E>& t, const std::string& name) {
  for (const auto& [v, n] : t) {
    if (n == name) return v;
  }
  return t.front().first;
}

const std::vector<std::string>& analysis_names() {
  static const std::vector<std::string> n = names(analysis_table());
  return n;
}

std::string linear_solver_name(solvers::LinearSolverPath p) { return std::string(name_of(linear_solver_table(), p)); }

// Every [analysis] key, once: the analysis types that read it (empty: every type) and its value
// in the JSON echo (null: not echoed as such). The parser's list of known keys, its "only used
// by type = …" errors and to_json() all read this table.
struct AnalysisKey {
  const char* key;
  std::vector<AnalysisKind> kinds;
  std::function<nlohmann::json(const Analysis&)> echo;
};

const std::vector<AnalysisKey>& analysis_keys() {
  using K = AnalysisKind;
  static const std::vector<AnalysisKey> keys = {
      {"type", {}, nullptr},
      {"functions", {K::BasisPlot},
       [](const Analysis& a) { return a.functions.empty() ? nlohmann::json() : nlohmann::json(a.functions); }},
      {"derivative", {K::BasisPlot}, [](const Analysis& a) { return nlohmann::json(a.derivative); }},
      {"normalization", {K::BasisPlot},
       [](const Analysis& a) { return nlohmann::json(a.unit_integral ? "unit-integral" : "orthonormal"); }},
      {"max_step", {K::Continuation, K::NonlinearModes}, [](const Analysis& a) { return nlohmann::json(a.max_step); }},
      {"max_frequency_step_hz", {K::Continuation},
       [](const Analysis& a) { return nlohmann::json(a.max_frequency_step_hz); }},
      {"max_points", {K::Continuation, K::NonlinearModes}, [](const Analysis& a) { return nlohmann::json(a.max_points); }},
      {"max_state", {K::Continuation}, [](const Analysis& a) { return nlohmann::json(a.max_state); }},
      {"stability", {K::Continuation}, [](const Analysis& a) { return nlohmann::json(a.stability); }},
      {"energy", {K::NonlinearModes}, [](const Analysis& a) { return nlohmann::json({a.energy_min, a.energy_max}); }},
      {"harmonics", {K::NonlinearModes}, [](const Analysis& a) { return nlohmann::json(a.harmonics); }},
      {"samples", {K::NonlinearModes}, [](const Analysis& a) { return nlohmann::json(a.samples); }},
      {"algorithm", {K::NonlinearModes}, [](const Analysis& a) { return nlohmann::json(std::string(to_string(a.algorithm))); }},
      {"max_energy_step", {K::NonlinearModes}, [](const Analysis& a) { return nlohmann::json(a.max_energy_step); }},
      {"levels", {K::NonlinearModes}, [](const Analysis& a) { return nlohmann::json(a.levels); }},
  };
  return keys;
}

bool reads(const AnalysisKey& k, AnalysisKind kind) {
  return k.kinds.empty() || std::find(k.kinds.begin(), k.kinds.end(), kind) != k.kinds.end();
}

bool is_power_of_two(long long m) { return m >= 1 && (m & (m - 1)) == 0; }

// Reads one scene table into a Scene, reporting into a Reader.
class Parser {
 public:
  Parser(Reader& reader, std::filesystem::path base) : r_(reader), base_(std::move(base)) {}

  Scene parse(const toml::table& root) {
    r_.only(root, "", {"title", "structure", "damping", "forcing", "contact", "basis", "solver", "timestep",
                       "analysis", "output"});
    if (const toml::node* t = root.get("title")) {
      if (t->is_string()) {
        s_.title = t->as_string()->get();
      } else {
        r_.error(t->source(), "title", "expected a string, got " + Reader::type_name(*t));
      }
    }
    // An unknown analysis type decides nothing: the other sections' messages would be guesses.
    if (!analysis(root)) return std::move(s_);
    const bool plot = s_.analysis.kind == AnalysisKind::BasisPlot;
    if (plot) {
      for (const char* unused : {"structure", "damping", "forcing", "contact", "solver", "timestep"}) {
        if (const toml::node* n = root.get(unused)) {
          r_.warn(n->source(), std::string("[") + unused + "] is not used by analysis \"basis-plot\" (no structure is "
                               "built); ignored");
        }
      }
    } else if (s_.analysis.kind == AnalysisKind::NonlinearModes) {
      // Modes of the conservative system against its stops: no forcing, damping, basis, solver
      // or time stepping.
      for (const char* unused : {"forcing", "damping", "basis", "solver", "timestep"}) {
        if (const toml::node* n = root.get(unused)) {
          r_.warn(n->source(), std::string("[") + unused + "] is not used by analysis \"nnm\" (modes of the "
                               "undamped, unforced structure); ignored");
        }
      }
      structure(root);
      contacts(root);
      if (s_.structure && s_.structure->kind == StructureKind::Matrices && !solvers::massless_dofs(s_.structure->mass).empty()) {
        r_.error(Reader::source_of(*root.get_as<toml::table>("structure"), "mass"), "structure.mass",
                 "has massless DOFs (rows of zeros): analysis \"nnm\" does not condense them; give every DOF a mass "
                 "(massless DOFs are condensed for solve, timestep and continuation)");
      }
      const bool penalty = std::any_of(s_.contacts.begin(), s_.contacts.end(),
                                       [](const Contact& c) { return c.law == ContactLawKind::Linear; });
      if (penalty && s_.analysis.algorithm != NnmAlgorithm::Continuation) {
        r_.error(root.source(), "analysis.algorithm",
                 "\"" + std::string(to_string(s_.analysis.algorithm)) + "\" (augmented Lagrangian, LL11 Alg. 1/2) imposes exact contact: use "
                 "law = \"rigid\", or algorithm = \"continuation\" for penalty stops");
      }
      stiffness_definiteness(root);
      if (root.get("contact") == nullptr) {
        r_.error(root.source(), "[contact]", "missing: analysis \"nnm\" needs at least one stop (law = \"rigid\" "
                                             "for exact contact, or \"linear\" for a penalty spring), with a gap > 0");
      }
    } else {
      structure(root);
      damping(root);
      forcing(root);
      contacts(root);
      solver(root);
      timestep(root);
      stiffness_definiteness(root);
      condense(root);
    }
    if (s_.analysis.kind != AnalysisKind::NonlinearModes) basis(root);
    if (plot) basis_plot(root);
    output(root);
    load_harmonics(root);
    if (r_.error_count() == 0) resources(root);
    if (s_.analysis.kind == AnalysisKind::Timestep && s_.rigid() &&
        (s_.moreau_jean.steps_per_period < s_.output.samples || s_.moreau_jean.steps_per_period % s_.output.samples != 0)) {
      r_.error(root.source(), "timestep.steps_per_period",
               std::to_string(s_.moreau_jean.steps_per_period) + " is not a multiple of output.samples = " +
                   std::to_string(s_.output.samples) + " (Moreau–Jean samples its fixed steps): use powers of two, "
                   "e.g. 65536 steps and 1024 samples");
    }
    return std::move(s_);
  }

 private:
  // [analysis] type first: it decides which sections are read. False when the type is unknown.
  bool analysis(const toml::table& root) {
    const toml::table* t = r_.table(root, "analysis", false);
    if (t == nullptr) return true;
    std::vector<std::string> known;
    for (const auto& k : analysis_keys()) known.emplace_back(k.key);
    r_.only(*t, "analysis", known);
    const size_t errors = r_.error_count();
    const std::string type = r_.choice(*t, "analysis", "type", analysis_names(), "solve");
    if (r_.error_count() != errors && t->contains("type")) return false;
    s_.analysis.kind = value_of(analysis_table(), type);
    for (const auto& k : analysis_keys()) {
      const toml::node* n = t->get(k.key);
      if (n == nullptr || reads(k, s_.analysis.kind)) continue;
      std::string types;
      for (size_t i = 0; i < k.kinds.size(); ++i) {
        types += (i == 0 ? "" : " or ") + std::string("\"") + std::string(to_string(k.kinds[i])) + "\"";
      }
      r_.error(n->source(), std::string("analysis.") + k.key, "only used by type = " + types + "; remove it");
    }
    if (s_.analysis.kind == AnalysisKind::NonlinearModes) nnm(*t);
    if (s_.analysis.kind == AnalysisKind::Continuation) {
      Analysis& a = s_.analysis;
      a.max_step = r_.number(*t, "analysis", "max_step", {"in [1e-6, 1] (scaled arclength per step; below 1e-6 a branch takes millions of steps)",
                              [](double v) { return v >= 1e-6 && v <= 1.0; }},
                             a.max_step);
      a.max_frequency_step_hz = r_.number(*t, "analysis", "max_frequency_step_hz", detail::non_negative("Hz"),
                                          a.max_frequency_step_hz);
      a.max_points = static_cast<int>(r_.integer(*t, "analysis", "max_points", 2, 1000000, a.max_points));
      a.max_state = r_.number(*t, "analysis", "max_state", detail::non_negative("times s_r = max(gap, linear response); 0 = no bound"), a.max_state);
      // Rigid stops have no stability (no saltation matrices): false unless asked for (then refused).
      bool rigid = false;
      auto rigid_law = [](const toml::table* c) {
        return c != nullptr && c->get_as<std::string>("law") != nullptr && c->get_as<std::string>("law")->get() == "rigid";
      };
      if (const toml::node* c = root.get("contact")) {
        if (c->is_table()) rigid = rigid_law(c->as_table());
        if (c->is_array_of_tables()) {
          for (const auto& e : *c->as_array()) rigid = rigid || rigid_law(e.as_table());
        }
      }
      a.stability = r_.boolean(*t, "analysis", "stability", rigid ? false : a.stability);
    }
    return true;
  }

  // [analysis] of type "nnm": energy = [from, to] (normalized, 1 = contact onset), N, m, the
  // outer algorithm, steps and the levels whose mode shapes are written.
  void nnm(const toml::table& t) {
    Analysis& a = s_.analysis;
    const toml::node* e = t.get("energy");
    const toml::array* range = e != nullptr ? e->as_array() : nullptr;
    bool energy_given = false;  // levels are checked against a valid range only (no follow-on errors)
    if (range == nullptr || range->size() != 2) {
      r_.error(e != nullptr ? e->source() : t.source(), "analysis.energy",
               std::string(e == nullptr ? "missing" : "expected") +
                   "; give energy = [from, to], normalized energies (1 = contact onset), 0 < from < to");
    } else {
      a.energy_min = r_.number_value((*range)[0], "analysis.energy", detail::positive("normalized energy"));
      a.energy_max = r_.number_value((*range)[1], "analysis.energy", detail::positive("normalized energy"));
      if (!(a.energy_min < a.energy_max)) {
        r_.error(e->source(), "analysis.energy", "the range is empty or reversed (from >= to); give from < to");
      } else {
        energy_given = true;
      }
    }
    // 256: the cost grows about as N^2.2 (2 DOFs: 0.3 s at N = 32, 7 s at N = 128; N = 512 ran
    // for minutes, issue #40), docs/scenes.md "Sizes".
    a.harmonics = static_cast<int>(r_.integer(t, "analysis", "harmonics", 1, 256, a.harmonics,
                                              " (the cost grows about as N^2.2: N = 128 takes 7 s on 2 DOFs, "
                                              "N = 512 minutes)"));
    a.samples = static_cast<int>(r_.integer(t, "analysis", "samples", 3, 1 << 16, std::max(a.samples, 8 * a.harmonics)));
    if (a.samples <= 2 * a.harmonics) {
      r_.error(Reader::source_of(t, "samples"), "analysis.samples",
               "m = " + std::to_string(a.samples) + " must exceed 2N = " + std::to_string(2 * a.harmonics) +
                   " (the contact conditions are imposed at m samples of a degree-N trigonometric polynomial)");
    }
    a.algorithm = value_of(nnm_algorithm_table(), r_.choice(t, "analysis", "algorithm", names(nnm_algorithm_table()),
                                                            std::string(to_string(a.algorithm))));
    a.max_step = r_.number(t, "analysis", "max_step", {"in [1e-6, 1] (scaled arclength per step; below 1e-6 a branch takes millions of steps)",
                              [](double v) { return v >= 1e-6 && v <= 1.0; }},
                           5e-2);
    a.max_energy_step = r_.number(t, "analysis", "max_energy_step", detail::positive("normalized energy"),
                                  a.max_energy_step);
    a.max_points = static_cast<int>(r_.integer(t, "analysis", "max_points", 2, 1000000, a.max_points));
    if (const toml::node* l = t.get("levels")) {
      const toml::array* list = l->as_array();
      if (list == nullptr) {
        r_.error(l->source(), "analysis.levels", "expected a list of normalized energies inside analysis.energy");
      } else {
        for (const auto& v : *list) {
          const double level = r_.number_value(v, "analysis.levels", detail::positive("normalized energy"));
          if (energy_given && (level < a.energy_min || level > a.energy_max)) {
            r_.error(v.source(), "analysis.levels", "energy " + detail::number_text(level) + " outside analysis.energy = [" +
                                                      detail::number_text(a.energy_min) + ", " +
                                                      detail::number_text(a.energy_max) + "]");
          }
          a.levels.push_back(level);
        }
      }
    }
  }

  void structure(const toml::table& root) {
    const size_t errors = r_.error_count();
    const toml::table* t = r_.table(root, "structure", true);
    if (t == nullptr) return;
    Structure st;
    bool matrices = t->contains("mass") || t->contains("stiffness") || t->contains("damping") || t->contains("dofs");
    bool deck = t->contains("deck");
    if (t->contains("type")) {
      const std::string type = r_.choice(*t, "structure", "type", {"rod", "matrices", "deck"});
      matrices = type == "matrices";
      deck = type == "deck";
    }
    if (deck) {
      deck_structure(*t, st);
    } else if (!matrices) {
      r_.only(*t, "structure", {"type", "young_modulus", "density", "area", "length", "elements"});
      st.kind = StructureKind::Rod;
      st.rod.young_modulus = r_.number(*t, "structure", "young_modulus", detail::positive("Pa"));
      st.rod.density = r_.number(*t, "structure", "density", detail::positive("kg/m^3"));
      st.rod.area = r_.number(*t, "structure", "area", detail::positive("m^2"));
      st.rod.length = r_.number(*t, "structure", "length", detail::positive("m"));
      st.rod.elements = static_cast<int>(r_.integer(*t, "structure", "elements", 1, 100000));
      for (int j = 1; j <= st.rod.elements; ++j) st.dof_names.push_back("node" + std::to_string(j));
    } else {
      r_.only(*t, "structure", {"type", "mass", "stiffness", "damping", "dofs"});
      st.kind = StructureKind::Matrices;
      auto mass = matrix(*t, "mass", true, st.mass_file);
      auto stiffness = matrix(*t, "stiffness", true, st.stiffness_file);
      auto damping = matrix(*t, "damping", false, st.damping_file);
      // Each matrix that parsed is checked, so one pass reports every problem.
      if (mass) st.mass = *mass;
      if (stiffness) st.stiffness = *stiffness;
      if (damping) st.damping = *damping;
      if (mass) {
        check_matrices(*t, st, stiffness.has_value());
        dof_names(*t, st);
      }
    }
    if (r_.error_count() == errors) s_.structure = std::move(st);
  }

  // [structure] deck = "…" (interface, modes, ccx, axis): the deck assembled by ccx and reduced
  // by Craig–Bampton now (scene/reduce.hpp); M_r, K_r and the names of wbm reduce's dofs.txt.
  void deck_structure(const toml::table& t, Structure& st) {
    r_.only(t, "structure", {"type", "deck", "interface", "modes", "ccx", "axis", "units"});
    const size_t errors = r_.error_count();
    DeckStructure d;
    const toml::node* file = t.get("deck");
    if (file == nullptr || !file->is_string()) {
      r_.error(file != nullptr ? file->source() : t.source(), "structure.deck",
               "expected the file name of a CalculiX/Abaqus deck (.inp), relative to the scene");
      return;
    }
    d.file = std::filesystem::absolute(base_ / file->as_string()->get()).lexically_normal().string();
    const toml::node* in = t.get("interface");
    if (in == nullptr) {
      r_.error(t.source(), "structure.interface", "missing: the contact interface, a node set of the deck (\"TIP\") "
                                                  "or a list of node numbers");
      return;
    }
    if (in->is_string()) {
      d.interface = in->as_string()->get();
    } else if (const toml::array* a = in->as_array(); a != nullptr && !a->empty() && a->is_homogeneous<int64_t>()) {
      for (const auto& v : *a) d.interface += (d.interface.empty() ? "" : ",") + std::to_string(v.value<int64_t>().value_or(0));
    } else {
      r_.error(in->source(), "structure.interface", "expected a node set name or a non-empty list of node numbers");
      return;
    }
    d.modes = static_cast<int>(r_.integer(t, "structure", "modes", 0, 100000, 40));
    d.ccx = r_.text(t, "structure", "ccx", "ccx");
    d.units = r_.choice(t, "structure", "units", deck_unit_names(), "SI");
    if (const toml::node* a = t.get("axis")) {
      const toml::table* at = a->as_table();
      if (at == nullptr) {
        r_.error(a->source(), "structure.axis", "expected { point = [x, y, z], direction = [x, y, z] }");
      } else {
        r_.only(*at, "structure.axis", {"point", "direction"});
        const auto point = vector3(*at, "structure.axis", "point"), dir = vector3(*at, "structure.axis", "direction");
        if (point && dir) {
          if (!(dir->norm() > 0.0)) {
            r_.error(Reader::source_of(*at, "direction"), "structure.axis.direction", "is zero; give the axis direction");
          } else {
            d.axis = std::pair{*point, dir->normalized()};
          }
        }
      }
    }
    if (r_.error_count() != errors) return;
    try {
      ReductionRequest request;
      request.deck = d.file;
      request.interface = d.interface;
      request.modes = d.modes;
      request.ccx = d.ccx;
      request.units = d.units;
      ReducedModel reduced = reduce_model(request);
      d.node_sets = std::move(reduced.node_sets);
      d.coordinates = reduced.coordinates;
      d.reduction = std::move(reduced.summary);
      st.kind = StructureKind::Matrices;
      st.stiffness = reduced.stiffness.sparseView();
      st.mass = reduced.mass.sparseView();
      st.dof_names = std::move(reduced.names);
      st.deck = std::move(d);
    } catch (const std::invalid_argument& e) {
      r_.error(file->source(), "structure.deck", e.what());
    } catch (const std::exception& e) {  // CalculiX or the reduction failed: a tool, not the scene
      r_.tool_error(file->source(), "structure.deck", e.what());
    }
  }

  // A list of three finite numbers.
  std::optional<Eigen::Vector3d> vector3(const toml::table& t, const std::string& section, const std::string& key) {
    const toml::node* n = t.get(key);
    const toml::array* a = n != nullptr ? n->as_array() : nullptr;
    if (a == nullptr || a->size() != 3) {
      r_.error(n != nullptr ? n->source() : t.source(), section + "." + key, "expected [x, y, z], three numbers");
      return std::nullopt;
    }
    Eigen::Vector3d v;
    for (int i = 0; i < 3; ++i) v(i) = r_.number_value((*a)[static_cast<size_t>(i)], section + "." + key, detail::finite(""));
    return v;
  }

  // A number (1 DOF), a list (diagonal), a list of rows, or a Matrix Market file.
  std::optional<Eigen::SparseMatrix<double>> matrix(const toml::table& t, const std::string& key, bool required,
                                                    std::string& file) {
    const std::string full = "structure." + key;
    const std::string forms =
        "a number (1 DOF), a list of numbers (diagonal), a list of rows, or a Matrix Market file name";
    const toml::node* n = t.get(key);
    if (n == nullptr) {
      if (required) r_.error(t.source(), full, "missing; expected " + forms);
      return std::nullopt;
    }
    const size_t errors = r_.error_count();
    Eigen::SparseMatrix<double> a;
    if (n->is_integer() || n->is_floating_point()) {
      a.resize(1, 1);
      a.insert(0, 0) = r_.number_value(*n, full, detail::finite(""));
    } else if (n->is_string()) {
      const std::filesystem::path p = std::filesystem::absolute(base_ / n->as_string()->get()).lexically_normal();
      file = p.string();
      read_market(*n, full, p, a);
    } else if (n->is_array() && !n->as_array()->empty()) {
      const toml::array& rows = *n->as_array();
      const auto size = static_cast<Eigen::Index>(rows.size());
      if (rows.is_homogeneous<toml::array>()) {
        std::vector<Eigen::Triplet<double>> entries;
        for (Eigen::Index i = 0; i < size; ++i) {
          const toml::array& row = *rows[static_cast<size_t>(i)].as_array();
          if (static_cast<Eigen::Index>(row.size()) != size) {
            r_.error(row.source(), full, "row " + std::to_string(i) + " has " + std::to_string(row.size()) +
                                             " entries; a square matrix of " + std::to_string(size) + " rows needs " +
                                             std::to_string(size));
            return std::nullopt;
          }
          for (Eigen::Index j = 0; j < size; ++j) {
            const double v = r_.number_value(row[static_cast<size_t>(j)], full, detail::finite(""));
            if (v != 0.0) entries.emplace_back(i, j, v);
          }
        }
        a.resize(size, size);
        a.setFromTriplets(entries.begin(), entries.end());
      } else {
        a.resize(size, size);
        for (Eigen::Index i = 0; i < size; ++i) {
          a.insert(i, i) = r_.number_value(rows[static_cast<size_t>(i)], full, detail::finite(""));
        }
      }
    } else {
      r_.error(n->source(), full, "expected " + forms + ", got " + Reader::type_name(*n));
    }
    if (r_.error_count() != errors) return std::nullopt;
    a.makeCompressed();
    return a;
  }

  // Matrix Market coordinate format, real or integer, general or symmetric (fem::read_matrix_market).
  void read_market(const toml::node& n, const std::string& full, const std::filesystem::path& p,
                   Eigen::SparseMatrix<double>& a) {
    try {
      a = fem::read_matrix_market_file(p.string());
    } catch (const std::exception& e) {
      r_.error(n.source(), full, e.what());
      return;
    }
    if (a.rows() != a.cols()) {
      r_.error(n.source(), full, p.string() + " is " + std::to_string(a.rows()) + " x " + std::to_string(a.cols()) +
                                     "; expected a square matrix");
    }
  }

  void check_matrices(const toml::table& t, const Structure& st, bool have_stiffness) {
    const auto n = st.mass.rows();
    auto check = [&](const Eigen::SparseMatrix<double>& a, const std::string& key, const std::string& symbol) {
      if (a.rows() != n || a.cols() != n) {
        r_.error(Reader::source_of(t, key), "structure." + key,
                 symbol + " is " + std::to_string(a.rows()) + " x " + std::to_string(a.cols()) + "; M is " +
                     std::to_string(n) + " x " + std::to_string(n) + ": every matrix must have the size of M");
        return;
      }
      // Sparse throughout: a large FE matrix is never made dense.
      const Eigen::SparseMatrix<double> at = a.transpose();
      const Eigen::SparseMatrix<double> diff = a - at;
      const double asymmetry = diff.nonZeros() > 0 ? diff.coeffs().cwiseAbs().maxCoeff() : 0.0;
      const double scale = a.nonZeros() > 0 ? a.coeffs().cwiseAbs().maxCoeff() : 0.0;
      if (asymmetry > 1e-12 * scale) {
        std::ostringstream os;
        os << symbol << " is not symmetric (max |" << symbol << " - " << symbol << "^T| = " << asymmetry
           << "); the solvers need symmetric matrices";
        r_.error(Reader::source_of(t, key), "structure." + key, os.str());
      }
    };
    const size_t errors = r_.error_count();
    check(st.mass, "mass", "M");
    if (have_stiffness) check(st.stiffness, "stiffness", "K");
    if (st.damping.size() > 0) check(st.damping, "damping", "C");
    if (r_.error_count() != errors) return;
    // Massless DOFs (zero rows of M) are condensed statically (solvers/condensation.hpp); the
    // DOFs with mass must have a positive definite M.
    const std::vector<int> massless = solvers::massless_dofs(st.mass);
    Eigen::SparseMatrix<double> massive = st.mass;
    if (!massless.empty() && massless.size() < static_cast<size_t>(n)) {
      std::vector<bool> zero(static_cast<size_t>(n), false);
      for (int d : massless) zero[static_cast<size_t>(d)] = true;
      std::vector<Eigen::Triplet<double>> keep;
      int row = 0;
      std::vector<int> index(static_cast<size_t>(n), -1);
      for (int d = 0; d < n; ++d) if (!zero[static_cast<size_t>(d)]) index[static_cast<size_t>(d)] = row++;
      for (int k = 0; k < st.mass.outerSize(); ++k) {
        for (Eigen::SparseMatrix<double>::InnerIterator it(st.mass, k); it; ++it) {
          const int i = index[static_cast<size_t>(it.row())], j = index[static_cast<size_t>(it.col())];
          if (i >= 0 && j >= 0) keep.emplace_back(i, j, it.value());  // stored zeros of massless rows dropped
        }
      }
      massive.resize(row, row);
      massive.setFromTriplets(keep.begin(), keep.end());
    }
    const Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> llt(massive);
    if (massless.size() == static_cast<size_t>(n)) {
      r_.error(Reader::source_of(t, "mass"), "structure.mass", "M is zero: give the structure mass");
    } else if (llt.info() != Eigen::Success) {
      r_.error(Reader::source_of(t, "mass"), "structure.mass",
               massless.empty() ? "M is not positive definite (Cholesky failed); rows of zeros (massless DOFs) are "
                                  "condensed statically, other DOFs need a positive definite mass block"
                                : "M is not positive definite on the DOFs with mass (Cholesky failed after removing "
                                  "the massless rows of zeros)");
    }
  }

  void dof_names(const toml::table& t, Structure& st) {
    const auto n = static_cast<size_t>(st.mass.rows());
    const toml::node* d = t.get("dofs");
    if (d == nullptr) {
      for (size_t i = 0; i < n; ++i) st.dof_names.push_back("dof" + std::to_string(i));
      return;
    }
    // (name, where it was given) from the list, or from a file of one name per line (the
    // dofs.txt of `wbm reduce`; blank lines and lines starting with # or % skipped).
    std::vector<std::pair<std::string, toml::source_region>> given;
    if (d->is_string()) {
      const std::filesystem::path p = std::filesystem::absolute(base_ / d->as_string()->get()).lexically_normal();
      std::ifstream in(p);
      if (!in) {
        r_.error(d->source(), "structure.dofs", "cannot read the DOF name file " + p.string() +
                                                    " (one name per row of M, e.g. the dofs.txt of wbm reduce)");
        return;
      }
      std::string line;
      while (std::getline(in, line)) {
        const auto first = line.find_first_not_of(" \t\r");
        if (first == std::string::npos || line[first] == '#' || line[first] == '%') continue;
        const auto last = line.find_last_not_of(" \t\r");
        given.emplace_back(line.substr(first, last - first + 1), d->source());
      }
      if (given.size() != n) {
        r_.error(d->source(), "structure.dofs", p.string() + " names " + std::to_string(given.size()) +
                                                    " DOFs, but M has " + std::to_string(n) + " rows: give the file of this model");
        return;
      }
    } else {
      const toml::array* a = d->as_array();
      if (a == nullptr || a->size() != n || !a->is_homogeneous<std::string>()) {
        r_.error(d->source(), "structure.dofs", "expected a list of " + std::to_string(n) +
                                                    " names (one per row of M), or the name of a file of them");
        return;
      }
      for (const auto& e : *a) given.emplace_back(e.as_string()->get(), e.source());
    }
    static const std::regex identifier("[A-Za-z_][A-Za-z0-9_]*");
    std::set<std::string> seen;
    for (const auto& [name, where] : given) {
      if (!std::regex_match(name, identifier)) {
        r_.error(where, "structure.dofs", "\"" + name + "\" is not a name (letters, digits and _, not starting "
                                                        "with a digit); it heads CSV columns");
      } else if (!seen.insert(name).second) {
        r_.error(where, "structure.dofs", "\"" + name + "\" appears twice");
      }
      st.dof_names.push_back(name);
    }
  }

  void damping(const toml::table& root) {
    const toml::table* t = r_.table(root, "damping", false);
    if (t == nullptr) return;
    r_.only(*t, "damping", {"alpha", "beta"});
    s_.damping.alpha = r_.number(*t, "damping", "alpha", detail::non_negative("1/s"), 0.0);
    s_.damping.beta = r_.number(*t, "damping", "beta", detail::non_negative("s"), 0.0);
  }

  // The DOF named by one location value: rod node (1 … E or "tip"), matrix DOF (name or index).
  std::optional<int> location_value(const toml::node& n, const std::string& full) {
    if (!s_.structure) return std::nullopt;  // the structure's own errors are reported already
    const Structure& st = *s_.structure;
    if (st.kind == StructureKind::Rod) {
      if (n.is_string() && n.as_string()->get() == "tip") return st.rod.elements - 1;
      if (n.is_integer()) {
        const long long v = n.as_integer()->get();
        if (v >= 1 && v <= st.rod.elements) return static_cast<int>(v - 1);
      }
      r_.error(n.source(), full, "expected a rod node, an integer in [1, " + std::to_string(st.rod.elements) +
                                     "] (node 0 is clamped) or \"tip\"");
      return std::nullopt;
    }
    if (n.is_string()) {
      const auto it = std::find(st.dof_names.begin(), st.dof_names.end(), n.as_string()->get());
      if (it != st.dof_names.end()) return static_cast<int>(it - st.dof_names.begin());
    }
    if (n.is_integer()) {
      const long long v = n.as_integer()->get();
      if (v >= 0 && v < st.dofs()) return static_cast<int>(v);
    }
    std::string names;
    for (const auto& name : st.dof_names) names += (names.empty() ? "\"" : ", \"") + name + "\"";
    if (st.dof_names.size() > 12) names = "\"" + st.dof_names.front() + "\" … \"" + st.dof_names.back() + "\"";
    r_.error(n.source(), full, "expected a DOF name (" + names + ") or an index in [0, " +
                                   std::to_string(st.dofs() - 1) + "]");
    return std::nullopt;
  }

  // `node` for the rod, `dof` for matrices; `fallback` when neither is given.
  int location(const toml::table& t, const std::string& section, std::optional<int> fallback) {
    if (!s_.structure) return 0;
    const bool rod = s_.structure->kind == StructureKind::Rod;
    const std::string key = rod ? "node" : "dof";
    const std::string other = rod ? "dof" : "node";
    if (const toml::node* wrong = t.get(other)) {
      r_.error(wrong->source(), section + "." + other,
               rod ? "the rod is located by node = 1 … elements or \"tip\"; dof is for [structure] matrices"
                   : "explicit matrices are located by dof = name or index; node is for the rod");
      return 0;
    }
    const toml::node* n = t.get(key);
    if (n == nullptr) {
      if (fallback) return *fallback;
      r_.error(t.source(), section + "." + key, "missing; which DOF (name or 0-based index)?");
      return 0;
    }
    return location_value(*n, section + "." + key).value_or(0);
  }

  std::optional<int> default_location() const {
    if (!s_.structure) return std::nullopt;
    if (s_.structure->kind == StructureKind::Rod) return s_.structure->rod.elements - 1;  // the free tip
    if (s_.structure->dofs() == 1) return 0;
    return std::nullopt;
  }

  void forcing(const toml::table& root) {
    if (const toml::node* n = root.get("forcing"); n != nullptr && n->is_array_of_tables()) {
      r_.error(n->source(), "[[forcing]]",
               "one [forcing] table holds the frequency; several loads go in it as [[forcing.loads]] tables "
               "(amplitude, node or dof, phase_deg or phase_rad, harmonic) or as a force vector file "
               "(vector = \"f.mtx\"): see docs/scenes.md");
      return;
    }
    const toml::table* t = r_.table(root, "forcing", true);
    if (t == nullptr) return;
    r_.only(*t, "forcing", {"amplitude", "node", "dof", "frequency_hz", "frequency_rad_s", "frequencies_hz",
                            "frequencies_rad_s", "points", "loads", "vector"});
    Forcing f;
    loads(*t, f);
    const bool more = !f.loads.empty();
    // With loads or a vector, amplitude/dof (the first load) are optional; the reported DOF is
    // then that of the largest load.
    f.amplitude = r_.number(*t, "forcing", "amplitude", detail::finite("N"), more ? std::optional<double>(0.0) : std::nullopt);
    std::optional<int> fallback = default_location();
    if (more && !t->contains("amplitude")) {
      const auto largest = std::max_element(f.loads.begin(), f.loads.end(), [](const auto& a, const auto& b) {
        return std::abs(a.amplitude) < std::abs(b.amplitude);
      });
      fallback = largest->dof;
    }
    f.dof = location(*t, "forcing", fallback);
    // One of four keys: a frequency or a range [from, to] in Hz or rad/s, or an explicit list.
    std::string key;
    for (const char* k : {"frequency_hz", "frequency_rad_s", "frequencies_hz", "frequencies_rad_s"}) {
      if (!t->contains(k)) continue;
      if (!key.empty()) {
        r_.error(Reader::source_of(*t, k), std::string("forcing.") + k,
                 "given beside forcing." + key + "; give the frequencies once");
        continue;
      }
      key = k;
    }
    const toml::node* freq = key.empty() ? nullptr : t->get(key);
    const bool rad = key.ends_with("rad_s"), list = key.rfind("frequencies", 0) == 0;
    const double to_hz = rad ? 1.0 / (2.0 * std::numbers::pi) : 1.0;  // ω [rad/s] = 2π f
    const std::string full = "forcing." + key, unit = rad ? "rad/s" : "Hz";
    const Range positive = detail::positive(unit);
    if (freq == nullptr) {
      r_.error(t->source(), "forcing.frequency_hz",
               "missing; expected frequency_hz = f or [from, to] [Hz], frequency_rad_s (the same in rad/s), or a "
               "list frequencies_hz = [f1, f2, …] (or frequencies_rad_s) for a sweep at given frequencies");
    } else if (list) {
      const toml::array* a = freq->as_array();
      if (a == nullptr || a->size() < 2) {
        r_.error(freq->source(), full, "expected a list of at least two numbers > 0 [" + unit +
                                           "]; for one frequency use frequency_" + (rad ? "rad_s" : "hz"));
      } else {
        FrequencyRange range;
        for (size_t i = 0; i < a->size(); ++i) {
          range.list_hz.push_back(to_hz * r_.number_value((*a)[i], full + "[" + std::to_string(i) + "]", positive));
        }
        range.from_hz = range.list_hz.front();
        range.to_hz = range.list_hz.back();
        range.points = static_cast<int>(range.list_hz.size());
        if (const toml::node* p = t->get("points")) {
          r_.error(p->source(), "forcing.points", "the list " + key + " gives the points; remove points");
        }
        f.range = range;
      }
    } else if (freq->is_array()) {
      const toml::array& a = *freq->as_array();
      if (a.size() != 2) {
        r_.error(freq->source(), full, "a range is [from, to] (two numbers > 0 [" + unit + "]); for a list of "
                                           "frequencies use frequencies_" + (rad ? "rad_s" : "hz"));
      } else {
        FrequencyRange range;
        range.from_hz = to_hz * r_.number_value(a[0], full + "[0]", positive);
        range.to_hz = to_hz * r_.number_value(a[1], full + "[1]", positive);
        range.points = static_cast<int>(r_.integer(*t, "forcing", "points", 2, 100000, 51));
        if (range.from_hz == range.to_hz) {
          r_.error(freq->source(), full, "the range is empty (from = to); give one number instead");
        }
        f.range = range;
      }
    } else {
      f.frequency_hz = to_hz * r_.number_value(*freq, full, positive);
      if (const toml::node* p = t->get("points")) {
        r_.error(p->source(), "forcing.points", "only used with a range " + key + " = [from, to]; remove it");
      }
    }
    if (freq != nullptr && (!freq->is_array() || list) && s_.analysis.kind == AnalysisKind::Continuation) {
      r_.error(freq->source(), full,
               "analysis \"continuation\" follows the branch over a range: give frequency_hz = [from, to] "
               "(or frequency_rad_s)");
    }
    if (f.range && s_.analysis.kind == AnalysisKind::Continuation && t->contains("points")) {
      r_.error(Reader::source_of(*t, "points"), "forcing.points",
               "continuation chooses its own points (analysis.max_step, max_frequency_step_hz); remove it");
    }
    if (f.range && s_.analysis.kind == AnalysisKind::Timestep) {
      r_.error(freq->source(), full,
               "analysis \"timestep\" integrates at one frequency; give a number, or use type = \"solve\" for a sweep");
    }
    s_.forcing = f;
  }

  // [[forcing.loads]] and forcing.vector: further loads F cos(2π h f t + φ) (Forcing::loads).
  void loads(const toml::table& t, Forcing& f) {
    if (const toml::node* n = t.get("loads")) {
      if (!n->is_array_of_tables()) {
        r_.error(n->source(), "forcing.loads", "expected [[forcing.loads]] tables, each with amplitude, node or dof, "
                                               "and optionally phase_deg or phase_rad and harmonic");
      } else {
        const toml::array& a = *n->as_array();
        for (size_t i = 0; i < a.size(); ++i) {
          const toml::table& l = *a[i].as_table();
          const std::string section = "forcing.loads[" + std::to_string(i) + "]";
          r_.only(l, section, {"amplitude", "node", "dof", "phase_deg", "phase_rad", "harmonic"});
          solvers::HarmonicLoad load{0, 0.0};
          load.amplitude = r_.number(l, section, "amplitude", detail::finite("N"));
          load.dof = location(l, section, default_location());
          if (l.contains("phase_deg") && l.contains("phase_rad")) {
            r_.error(Reader::source_of(l, "phase_rad"), section + ".phase_rad", "given beside phase_deg; give the phase once");
          } else if (l.contains("phase_deg")) {
            load.phase_rad = r_.number(l, section, "phase_deg", detail::finite("deg")) * std::numbers::pi / 180.0;
          } else {
            load.phase_rad = r_.number(l, section, "phase_rad", detail::finite("rad"), 0.0);
          }
          load.harmonic = static_cast<int>(r_.integer(l, section, "harmonic", 0, 1000, 1,
                                                      " (0: a constant load F cos(phase), h: h times the forcing frequency)"));
          f.loads.push_back(load);
          load_sources_.push_back(l.contains("harmonic") ? Reader::source_of(l, "harmonic") : l.source());
        }
      }
    }
    if (const toml::node* v = t.get("vector")) {
      if (!v->is_string()) {
        r_.error(v->source(), "forcing.vector", "expected the name of a Matrix Market file (n x 1: the amplitude [N] "
                                                "of F_i cos 2πft on each DOF), relative to the scene");
      } else if (s_.structure) {
        const std::filesystem::path p = base_ / v->as_string()->get();
        try {
          const Eigen::SparseMatrix<double> a = fem::read_matrix_market_file(p.string());
          if (a.cols() != 1 || a.rows() != s_.structure->dofs()) {
            r_.error(v->source(), "forcing.vector", p.string() + " is " + std::to_string(a.rows()) + " x " +
                                                        std::to_string(a.cols()) + "; expected " +
                                                        std::to_string(s_.structure->dofs()) + " x 1 (one amplitude per DOF)");
          } else {
            for (Eigen::SparseMatrix<double>::InnerIterator it(a, 0); it; ++it) {
              if (it.value() != 0.0) f.loads.push_back({static_cast<int>(it.row()), it.value(), 0.0, 1});
            }
          }
        } catch (const std::exception& e) {
          r_.error(v->source(), "forcing.vector", e.what());
        }
      }
    }
  }

  void contacts(const toml::table& root) {
    const toml::node* n = root.get("contact");
    if (n == nullptr) {
      if (s_.analysis.kind == AnalysisKind::Continuation) {
        r_.error(root.source(), "[contact]",
                 "missing: analysis \"continuation\" traces the branch of a nonlinear response and needs at least "
                 "one [contact]; without contact the response is linear: use type = \"solve\" with frequency_hz = "
                 "[from, to] and points = N (a sweep)");
      }
      return;
    }
    std::vector<std::pair<const toml::table*, std::string>> tables;
    if (n->is_table()) {
      tables.emplace_back(n->as_table(), "contact");
    } else if (n->is_array_of_tables()) {
      const toml::array& a = *n->as_array();
      for (size_t i = 0; i < a.size(); ++i) tables.emplace_back(a[i].as_table(), "contact[" + std::to_string(i) + "]");
    } else {
      r_.error(n->source(), "contact", "expected a table [contact] or tables [[contact]]");
      return;
    }
    std::set<std::pair<int, int>> dofs;  // (dof, against)
    const bool modes = s_.analysis.kind == AnalysisKind::NonlinearModes;
    for (const auto& [t, section] : tables) {
      Contact c;
      const size_t errors = r_.error_count();
      const std::string law = r_.choice(*t, section, "law", names(law_table()));
      if (r_.error_count() != errors) {
        if (const auto given = t->get_as<std::string>("law"); given != nullptr && given->get() == "penalty") {
          r_.error(Reader::source_of(*t, "law"), section + ".law",
                   "a penalty law is \"linear\" (stiffness) or \"exponential\" (coefficient, exponent)");
        }
        continue;  // the law decides the other keys: checking them against a guess would mislead
      }
      c.law = value_of(law_table(), law);
      c.gap = r_.number(*t, section, "gap", modes ? detail::positive("m; nnm normalizes energies by contact onset")
                                                  : detail::finite("m"));
      if (c.law == ContactLawKind::Rigid && s_.analysis.kind == AnalysisKind::Continuation && s_.analysis.stability) {
        r_.error(Reader::source_of(*t, "law"), section + ".law",
                 "\"rigid\" (exact contact) with analysis.stability = true: the stability of impacting orbits "
                 "(saltation matrices) is not computed; set stability = false, or use a stiff \"linear\" penalty");
      }
      if (!modes && !s_.contacts.empty() &&
          (c.law == ContactLawKind::Rigid) != (s_.contacts.front().law == ContactLawKind::Rigid)) {
        r_.error(t->source(), section, "mixes rigid and penalty contacts; a forced response takes all \"rigid\" or "
                                       "all penalty laws (give the rigid ones a stiff \"linear\" law)");
      }
      if (c.law == ContactLawKind::Exponential && modes) {
        r_.error(Reader::source_of(*t, "law"), section + ".law",
                 "analysis \"nnm\" takes law = \"rigid\" (exact contact) or \"linear\" (penalty spring)");
      }
      if (modes && !s_.contacts.empty() && (c.law == ContactLawKind::Rigid) != (s_.contacts.front().law == ContactLawKind::Rigid)) {
        r_.error(t->source(), section, "mixes rigid and penalty stops; nnm takes all \"rigid\" or all \"linear\"");
      }
      if (c.law == ContactLawKind::Rigid) {
        r_.only(*t, section, {"law", "gap", "node", "dof", "against", "direction", "nodes"});
      } else if (c.law == ContactLawKind::Exponential) {
        r_.only(*t, section, {"law", "gap", "coefficient", "exponent", "node", "dof", "against", "direction", "nodes"});
        c.coefficient = r_.number(*t, section, "coefficient", detail::positive("N"));
        c.exponent = r_.number(*t, section, "exponent", detail::positive("1/m"));
      } else if (c.law == ContactLawKind::Linear) {
        r_.only(*t, section, {"law", "gap", "stiffness", "node", "dof", "against", "direction", "nodes"});
        c.stiffness = r_.number(*t, section, "stiffness", detail::positive("N/m"));
        if (modes && !s_.contacts.empty() && s_.contacts.front().law == ContactLawKind::Linear &&
            c.stiffness != s_.contacts.front().stiffness) {
          r_.error(Reader::source_of(*t, "stiffness"), section + ".stiffness",
                   "nnm penalty stops share one stiffness (" + detail::number_text(s_.contacts.front().stiffness) +
                       " N/m in the first [[contact]])");
        }
      }
      if (const toml::node* nn = t->get("nodes")) {  // one contact per node of a deck structure
        node_contacts(*t, *nn, section, c);
        continue;
      }
      c.dof = location(*t, section, default_location());
      if (const toml::node* a = t->get("against"); a != nullptr && s_.structure) {
        if (modes) {
          r_.error(a->source(), section + ".against",
                   "analysis \"nnm\" takes stops against a fixed obstacle; remove against (contacts between two "
                   "DOFs are for forced responses)");
        } else if (const auto other = location_value(*a, section + ".against")) {
          if (*other == c.dof) {
            r_.error(a->source(), section + ".against",
                     "is the contact's own DOF " + s_.structure->dof_name(c.dof) +
                         "; give the other body's DOF, or remove against for a fixed obstacle");
          } else {
            c.against = *other;
          }
        }
      }
      if (const toml::node* d = t->get("direction"); d != nullptr && s_.structure) c.along = direction(*d, section, c);
      if (s_.structure && !dofs.insert({c.dof, c.against}).second && c.along.empty()) {
        r_.error(t->source(), section, "a second contact on " + s_.structure->dof_name(c.dof) +
                                           (c.against >= 0 ? " against " + s_.structure->dof_name(c.against) : std::string()) +
                                           "; one law per DOF (combine them into one)");
      }
      s_.contacts.push_back(c);
    }
  }

  // Static condensation of massless DOFs (solvers/condensation.hpp), checked here so that a
  // scene it cannot condense is refused with the reason.
  // K symmetric positive semidefinite (issue #40): a negative ω² of K φ = ω² M φ is refused;
  // rigid-body modes (ω² = 0) only where a contact can hold them, with a warning, since the
  // harmonic-0 block of G is then singular wherever every stop is open.
  void stiffness_definiteness(const toml::table& root) {
    if (!s_.structure || s_.structure->kind != StructureKind::Matrices || r_.error_count() > 0) return;
    const Structure& st = *s_.structure;
    const solvers::StiffnessInertia inertia =
        solvers::stiffness_inertia({st.mass, Eigen::SparseMatrix<double>(st.mass.rows(), st.mass.cols()), st.stiffness});
    const toml::table* t = root.get_as<toml::table>("structure");
    const toml::source_region where = t != nullptr && t->contains("stiffness") ? Reader::source_of(*t, "stiffness")
                                                                                : root.source();
    if (inertia.factorized && inertia.negative > 0) {
      r_.error(where, "structure.stiffness",
               "K is not positive semidefinite: K φ = ω² M φ has " + std::to_string(inertia.negative) +
                   " eigenvalue(s) ω² < 0 (a negative stiffness: the equilibrium is unstable and no periodic response "
                   "exists around it); check the sign of K and of every spring");
    } else if (inertia.rigid_body > 0 && s_.analysis.kind == AnalysisKind::NonlinearModes) {
      r_.error(where, "structure.stiffness",
               "K has " + std::to_string(inertia.rigid_body) + " rigid-body mode(s) (ω² = 0): analysis \"nnm\" "
                   "continues the first mode from its linear frequency, which must be > 0; clamp a DOF or add a "
                   "spring to ground");
    } else if (inertia.rigid_body > 0 && s_.contacts.empty()) {
      r_.error(where, "structure.stiffness",
               "K has " + std::to_string(inertia.rigid_body) + " rigid-body mode(s) (ω² = 0) and no [[contact]] holds "
                   "them: the mean position is undetermined (G's harmonic-0 block K is singular); clamp a DOF, add a "
                   "spring to ground, or add the stop that holds the structure");
    } else if (inertia.rigid_body > 0) {
      r_.warn(where, "K has " + std::to_string(inertia.rigid_body) + " rigid-body mode(s) (ω² = 0): only the contacts "
                     "hold the structure, and a state where every stop is open has no unique mean position "
                     "(docs/scenes.md, [structure])");
    }
  }

  void condense(const toml::table& root) {
    if (!s_.structure || s_.structure->kind != StructureKind::Matrices || r_.error_count() > 0) return;
    const std::vector<int> massless = solvers::massless_dofs(s_.structure->mass);
    if (massless.empty()) return;
    const toml::node* where = root.get("structure");
    for (const auto& c : s_.contacts) {
      if (c.law == ContactLawKind::Rigid && std::find(massless.begin(), massless.end(), c.dof) != massless.end()) {
        r_.error(where->source(), "contact.law",
                 "\"rigid\" on the massless DOF " + s_.structure->dof_name(c.dof) + ": a rigid stop behind the "
                 "node's spring acts on the structure as that spring (a penalty of stiffness 1/F_jj), which the exact-"
                 "contact solvers do not take; write the stop as law = \"linear\" with a stiffness far above the "
                 "node's springs (the series stiffness k/(1 + F_jj k) then tends to 1/F_jj), or give the DOF a mass");
        return;
      }
    }
    solvers::MechanicalSystem given;
    given.mass = s_.structure->mass;
    given.stiffness = s_.structure->stiffness;
    given.damping = s_.structure->damping.size() > 0 ? s_.structure->damping
                                                     : Eigen::SparseMatrix<double>(given.mass.rows(), given.mass.cols());
    std::vector<int> forced;
    if (s_.forcing) {
      if (s_.forcing->amplitude != 0.0) forced.push_back(s_.forcing->dof);
      for (const auto& l : s_.forcing->loads) forced.push_back(l.dof);
    }
    try {
      s_.condensation = solvers::condense_massless(given, s_.contact_points(), forced, s_.structure->dof_names);
    } catch (const std::invalid_argument& e) {
      r_.error(where->source(), "structure", std::string(e.what()) + " (massless DOFs are condensed statically: "
                                             "docs/scenes.md)");
    }
  }

  // [[contact]] nodes = "SET" | [n, …] on a structure read from a deck: one contact per node,
  // with the law and gap of the table, along direction = "radial" (from structure.axis) or
  // [x, y, z] (the same unit vector at every node), over the node's x, y, z DOFs; the DOF of
  // the largest component names the contact.
  void node_contacts(const toml::table& t, const toml::node& nn, const std::string& section, const Contact& law) {
    const std::string full = section + ".nodes";
    if (!s_.structure) return;  // the structure's own errors are reported already
    if (!s_.structure->deck) {
      r_.error(nn.source(), full, "nodes are for a structure read from a deck ([structure] deck = …); locate the "
                                  "contact with dof (matrices) or node (rod)");
      return;
    }
    const DeckStructure& deck = *s_.structure->deck;
    for (const char* other : {"node", "dof", "against"}) {
      if (t.contains(other)) {
        r_.error(Reader::source_of(t, other), section + "." + other, "beside nodes: give the nodes only (one contact each)");
        return;
      }
    }
    std::vector<int> nodes;
    if (nn.is_string()) {
      std::string name = nn.as_string()->get();
      for (char& ch : name) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
      const auto it = deck.node_sets.find(name);
      if (it == deck.node_sets.end()) {
        std::string sets;
        for (const auto& [set, members] : deck.node_sets) sets += (sets.empty() ? "" : ", ") + set;
        r_.error(nn.source(), full, "no node set '" + nn.as_string()->get() + "' in the deck; it defines: " + sets);
        return;
      }
      nodes = it->second;
    } else if (const toml::array* a = nn.as_array(); a != nullptr && !a->empty() && a->is_homogeneous<int64_t>()) {
      for (const auto& v : *a) nodes.push_back(static_cast<int>(v.value<int64_t>().value_or(0)));
    } else {
      r_.error(nn.source(), full, "expected a node set name of the deck or a non-empty list of node numbers");
      return;
    }
    const toml::node* d = t.get("direction");
    const bool radial = d != nullptr && d->is_string() && d->as_string()->get() == "radial";
    std::optional<Eigen::Vector3d> fixed;
    if (d != nullptr && d->is_array()) fixed = vector3(t, section, "direction");
    if (!radial && !fixed) {
      if (d == nullptr || !d->is_array()) {
        r_.error(d != nullptr ? d->source() : t.source(), section + ".direction",
                 "with nodes: \"radial\" (from structure.axis) or [x, y, z], the contact normal at every node");
      }
      return;
    }
    if (radial && !deck.axis) {
      r_.error(d->source(), section + ".direction",
               "\"radial\" needs structure.axis = { point = [x, y, z], direction = [x, y, z] } (the rotation axis)");
      return;
    }
    if (fixed && std::abs(fixed->norm() - 1.0) > 1e-6) {
      r_.warn(d->source(), section + ".direction: |n| = " + detail::number_text(fixed->norm()) +
                               ", not 1: the gap and the contact force are measured along n as given");
    }
    const auto& names = s_.structure->dof_names;
    static const char* axes[] = {"x", "y", "z"};
    for (int node : nodes) {
      const auto at = deck.coordinates.find(node);
      if (at == deck.coordinates.end()) {
        r_.error(nn.source(), full, "node " + std::to_string(node) + " is not an interface node (structure.interface): "
                                    "a contact acts on the reduced model's interface DOFs; add the node to the interface");
        continue;
      }
      Eigen::Vector3d n;
      if (radial) {
        const auto& [point, axis] = *deck.axis;
        const Eigen::Vector3d r = at->second - point;
        n = r - r.dot(axis) * axis;
        if (!(n.norm() > 1e-12 * std::max(1.0, r.norm()))) {
          r_.error(nn.source(), full, "node " + std::to_string(node) + " lies on structure.axis: no radial direction");
          continue;
        }
        n.normalize();
      } else {
        n = *fixed;
      }
      Contact c = law;
      double largest = 0.0;
      for (int k = 0; k < 3; ++k) {
        if (n(k) == 0.0) continue;
        const std::string name = std::string("n").append(std::to_string(node)).append("_").append(axes[k]);
        const auto it = std::find(names.begin(), names.end(), name);
        if (it == names.end()) {
          r_.error(nn.source(), full, "node " + std::to_string(node) + " has no DOF " + name + " (fixed by *BOUNDARY?) "
                                      "but the direction has a component along " + axes[k]);
          c.along.clear();
          break;
        }
        const int j = static_cast<int>(it - names.begin());
        c.along.emplace_back(j, n(k));
        if (std::abs(n(k)) > largest) {
          largest = std::abs(n(k));
          c.dof = j;
        }
      }
      if (!c.along.empty()) s_.contacts.push_back(c);
    }
  }

  // [contact] direction: ±1 (the side of the stop along the DOF) or a table {DOF name = weight}
  // (matrices); returns the (DOF, weight) pairs, empty for +1.
  std::vector<std::pair<int, double>> direction(const toml::node& d, const std::string& section, const Contact& c) {
    const std::string full = section + ".direction";
    const Structure& st = *s_.structure;
    if (c.against >= 0) {
      r_.error(d.source(), full, "beside against: a contact between two DOFs acts along u[dof] − u[against]; "
                                 "remove one of them");
      return {};
    }
    if (d.is_floating_point() || d.is_integer()) {
      const double v = d.value<double>().value_or(0.0);
      if (v == 1.0) return {};
      if (v == -1.0) return {{c.dof, -1.0}};
      r_.error(d.source(), full, "expected +1 or -1 (the side of the stop along the DOF), or a table of DOF weights "
                                 "{ name = weight, … } for a normal over several DOFs; got " + detail::number_text(v));
      return {};
    }
    const toml::table* t = d.as_table();
    if (t == nullptr || st.kind == StructureKind::Rod) {
      r_.error(d.source(), full, st.kind == StructureKind::Rod
                                     ? "the rod has one DOF per node: direction is +1 or -1"
                                     : "expected +1, -1 or a table { name = weight, … } over DOF names");
      return {};
    }
    std::vector<std::pair<int, double>> along;
    double norm = 0.0;
    bool has_dof = false;
    for (const auto& [key, value] : *t) {
      const std::string name(key.str());
      const auto it = std::find(st.dof_names.begin(), st.dof_names.end(), name);
      if (it == st.dof_names.end()) {
        r_.error(value.source(), full + "." + name, "is not a DOF name of [structure] dofs");
        continue;
      }
      const double w = r_.number_value(value, full + "." + name, detail::finite(""));
      const int j = static_cast<int>(it - st.dof_names.begin());
      has_dof = has_dof || j == c.dof;
      norm += w * w;
      along.emplace_back(j, w);
    }
    if (!(norm > 0.0)) {
      r_.error(d.source(), full, "every weight is zero; give a direction, e.g. a unit normal");
      return {};
    }
    if (!has_dof) {
      r_.error(d.source(), full, "does not include the contact's DOF " + st.dof_name(c.dof) +
                                     "; dof names the contact and must be one of the direction's DOFs");
      return {};
    }
    if (std::abs(norm - 1.0) > 1e-6) {
      r_.warn(d.source(), full + ": |n| = " + detail::number_text(std::sqrt(norm)) +
                              ", not 1: the gap and the contact force are measured along n as given");
    }
    return along;
  }

  void basis(const toml::table& root) {
    const toml::table* t = r_.table(root, "basis", false);
    const bool plot = s_.analysis.kind == AnalysisKind::BasisPlot;
    if (t != nullptr && s_.analysis.kind == AnalysisKind::Timestep) {
      r_.warn(t->source(), "[basis] is not used by analysis \"timestep\" (BDF); ignored");
      return;
    }
    if (t == nullptr) {
      if (plot) r_.error(root.source(), "[basis]", "missing table: basis-plot draws the [basis] trial family");
      // Fourier:Fourier with H harmonics, as for a [basis] without a size: never the M = 2^J
      // basis with its undamped top function by default (issue #19).
      s_.basis.harmonics = Basis::kDefaultHarmonics;
      s_.basis.dimension = 2 * s_.basis.harmonics + 1;
      const bool rigid = !s_.contacts.empty() && s_.contacts.front().law == ContactLawKind::Rigid;
      s_.basis.contact_quadrature = rigid ? solvers::ContactQuadrature::Midpoint : solvers::ContactQuadrature::CellAverage;
      return;
    }
    r_.only(*t, "basis",
            {"trial", "weighting", "dimension", "level", "harmonics", "formulation", "time_samples", "operators",
             "contact_quadrature", "harmonic_selection"});
    Basis& b = s_.basis;
    const std::string trial = r_.text(*t, "basis", "trial", b.trial);
    const std::string weighting = r_.text(*t, "basis", "weighting", trial);
    const auto fourier = [](const std::string& name) {
      try {
        return solvers::TimeBasis::from_name(name, 2).is_fourier();
      } catch (const std::invalid_argument&) {
        return false;  // reported below with the list of names
      }
    };
    const bool harmonic_balance = fourier(trial) && (plot || fourier(weighting));
    const int given = static_cast<int>(t->contains("dimension")) + static_cast<int>(t->contains("level")) +
                      static_cast<int>(t->contains("harmonics"));
    if (given > 1) {
      r_.error(t->source(), "basis", "give one of dimension = M, level = J (M = 2^J) or harmonics = H (M = 2H + 1)");
    } else if (t->contains("harmonics")) {
      const long long h = r_.integer(*t, "basis", "harmonics", 1, 1 << 19);
      if (!harmonic_balance) {
        r_.error(Reader::source_of(*t, "harmonics"), "basis.harmonics",
                 "H harmonics (2H + 1 functions) is the Fourier:Fourier basis; wavelet bases and mixed pairs take "
                 "dimension = M = 2^J");
      } else {
        b.harmonics = static_cast<int>(h);
        b.dimension = 2 * b.harmonics + 1;
      }
    } else if (t->contains("level")) {
      b.dimension = 1 << r_.integer(*t, "basis", "level", 0, 20);
    } else if (t->contains("dimension")) {
      const long long m = r_.integer(*t, "basis", "dimension", 1, 1 << 20, b.dimension);
      if (!is_power_of_two(m)) {
        r_.error(Reader::source_of(*t, "dimension"), "basis.dimension",
                 "M = " + std::to_string(m) + " is not a power of two (M = 2^J: 2, 4, …, 64, …; for Fourier:Fourier "
                 "with H harmonics give harmonics = H)");
      } else {
        b.dimension = static_cast<int>(m);
      }
    } else if (harmonic_balance) {  // no top function without damping by default (issue #19)
      b.harmonics = Basis::kDefaultHarmonics;
      b.dimension = 2 * b.harmonics + 1;
    }
    const std::string form =
        r_.choice(*t, "basis", "formulation", {"strong", "weak", "distributional"}, "distributional");
    b.formulation = solvers::parse_formulation(form);
    b.time_samples = static_cast<int>(r_.integer(*t, "basis", "time_samples", 0, 1 << 24, 0, " (0: max(256, 2M))"));
    if (b.time_samples > 0 && b.time_samples < b.dimension) {
      r_.error(Reader::source_of(*t, "time_samples"), "basis.time_samples",
               "Q = " + std::to_string(b.time_samples) + " < M = " + std::to_string(b.dimension) +
                   ": the Q-point rule needs Q >= M (0 picks max(256, 2M))");
    }
    b.operators = r_.choice(*t, "basis", "operators", {"automatic", "discrete"}, "automatic") == "discrete"
                      ? solvers::OperatorRule::Discrete
                      : solvers::OperatorRule::Automatic;
    const std::string quadrature =
        r_.choice(*t, "basis", "contact_quadrature", {"automatic", "midpoint", "cell-average"}, "automatic");
    // Names and M through the solvers' own parser, so the message lists every valid name.
    std::optional<solvers::TimeBasis> tb, wb;
    try {
      tb = solvers::TimeBasis::from_name(trial, b.dimension);
      b.trial = tb->key();
    } catch (const std::invalid_argument& e) {
      r_.error(Reader::source_of(*t, "trial"), "basis.trial", e.what());
    }
    const bool rigid = !s_.contacts.empty() && s_.contacts.front().law == ContactLawKind::Rigid;
    // "automatic": cell-average for harmonics = H, and for a law with a corner (linear: k (u − g)₊)
    // on a trial with a slope whatever M (issue #35: sampled at midpoints, the residual has a kink
    // wherever a sample crosses the gap, and a stiff stop's continuation stalls there: 50 kg on
    // 1 MN/m against 1e8 N/m, M = 64, at 29.98 Hz); midpoint, the paper's rule, for the smooth
    // exponential law of [JL14] with M = 2^J, and for rigid stops.
    const bool corner = std::any_of(s_.contacts.begin(), s_.contacts.end(),
                                    [](const Contact& k) { return k.law == ContactLawKind::Linear; });
    const bool sloped = tb && tb->max_derivative() >= 1;
    b.contact_quadrature = quadrature == "cell-average" ||
                                   (quadrature == "automatic" && !rigid && (b.harmonics > 0 || (corner && sloped)))
                               ? solvers::ContactQuadrature::CellAverage
                               : solvers::ContactQuadrature::Midpoint;
    if (rigid && quadrature == "cell-average") {
      r_.error(Reader::source_of(*t, "contact_quadrature"), "basis.contact_quadrature",
               "\"cell-average\" integrates a penalty law over each cell; rigid stops impose the Signorini "
               "conditions at the instants (k + 1/2)/M instead: use \"automatic\" or \"midpoint\"");
    }
    if (tb && quadrature == "cell-average" && tb->max_derivative() < 1) {
      r_.error(Reader::source_of(*t, "contact_quadrature"), "basis.contact_quadrature",
               "\"cell-average\" averages the contact law along the slope of the trial functions; " + tb->name() +
                   " has no pointwise derivative: use \"midpoint\" (the paper's rule)");
    }
    if (plot) {
      if (t->contains("weighting")) r_.warn(Reader::source_of(*t, "weighting"), "basis.weighting is not used by basis-plot");
      if (t->contains("harmonic_selection")) {
        r_.warn(Reader::source_of(*t, "harmonic_selection"), "basis.harmonic_selection is not used by basis-plot");
      }
      b.weighting = b.trial;
      return;
    }
    harmonic_selection(*t, harmonic_balance, rigid);
    if (!tb && !t->contains("weighting")) return;  // the weighting defaults to the trial name reported above
    try {
      wb = solvers::TimeBasis::from_name(weighting, b.dimension);
      b.weighting = wb->key();
    } catch (const std::invalid_argument& e) {
      r_.error(Reader::source_of(*t, "weighting"), "basis.weighting", e.what());
    }
    if (tb && wb) {
      const std::string why = solvers::inadmissibility(*tb, *wb, b.formulation, b.operators);
      if (!why.empty()) {
        r_.error(Reader::source_of(*t, "formulation"), "basis",
                 "not admissible: " + why);
      }
    }
  }

  // [basis] harmonic_selection: "all", "odd" (1, 3, …) or a list of harmonic numbers, for
  // Fourier:Fourier with penalty laws; every load must act at a kept harmonic.
  void harmonic_selection(const toml::table& t, bool harmonic_balance, bool rigid) {
    const toml::node* n = t.get("harmonic_selection");
    if (n == nullptr) return;
    Basis& b = s_.basis;
    const int highest = b.dimension / 2;  // H for M = 2H + 1, M/2 for M = 2^J
    const std::string where = "basis.harmonic_selection";
    const std::string allowed = "\"all\", \"odd\" (harmonics 1, 3, …, the usual choice for a symmetric system) or a "
                                "list of harmonic numbers in [0, " + std::to_string(highest) + "], e.g. [0, 1, 2, 3]";
    std::vector<int> kept;
    if (const auto name = n->value<std::string>()) {
      if (*name == "all") return;
      if (*name != "odd") {
        r_.error(n->source(), where, "\"" + *name + "\" is not a selection; use " + allowed);
        return;
      }
      for (int h = 1; h <= highest; h += 2) kept.push_back(h);
      b.harmonic_selection = "odd";
    } else if (const toml::array* list = n->as_array(); list != nullptr && !list->empty()) {
      for (const auto& e : *list) kept.push_back(static_cast<int>(r_.integer_value(e, where, 0, highest)));
      std::sort(kept.begin(), kept.end());
      if (std::adjacent_find(kept.begin(), kept.end()) != kept.end()) {
        r_.error(n->source(), where, "harmonic " + std::to_string(*std::adjacent_find(kept.begin(), kept.end())) +
                                         " is listed twice; list each harmonic once");
        return;
      }
      b.harmonic_selection = "list";
    } else {
      r_.error(n->source(), where, "expected " + allowed + ", got " + Reader::type_name(*n));
      return;
    }
    if (!harmonic_balance) {
      r_.error(n->source(), where, "selects harmonics of the Fourier basis: it needs trial = weighting = \"fourier\" "
                                   "(harmonic balance); wavelet bases have no harmonics. Remove it, or use Fourier");
      return;
    }
    if (rigid) {
      r_.error(n->source(), where, "rigid stops impose the Signorini conditions at M instants, which need every "
                                   "harmonic; remove the selection or use law = \"linear\"");
      return;
    }
    if (s_.forcing) {
      std::vector<solvers::HarmonicLoad> loads = s_.forcing->loads;
      if (s_.forcing->amplitude != 0.0) loads.insert(loads.begin(), {s_.forcing->dof, s_.forcing->amplitude, 0.0, 1});
      for (const auto& l : loads) {
        if (l.amplitude != 0.0 && !std::binary_search(kept.begin(), kept.end(), l.harmonic)) {
          r_.error(n->source(), where, "drops harmonic " + std::to_string(l.harmonic) + ", at which a load acts on DOF " +
                                           (s_.structure ? s_.structure->dof_name(l.dof) : std::to_string(l.dof)) +
                                           " (the projection would remove it): keep harmonic " +
                                           std::to_string(l.harmonic) + " or remove the load");
          return;
        }
      }
    }
    b.selected_harmonics = std::move(kept);
  }

  void basis_plot(const toml::table& root) {
    const toml::table* t = root.get("analysis") ? root.get("analysis")->as_table() : nullptr;
    if (t == nullptr) return;
    Analysis& a = s_.analysis;
    const int m = s_.basis.dimension;
    if (const toml::node* f = t->get("functions")) {
      const toml::array* list = f->as_array();
      if (list == nullptr || list->empty()) {
        r_.error(f->source(), "analysis.functions", "expected a list of shifts k in [0, " + std::to_string(m - 1) + "]");
      } else {
        for (const auto& e : *list) {
          a.functions.push_back(static_cast<int>(r_.integer_value(e, "analysis.functions", 0, m - 1)));
        }
      }
    }
    int max_derivative = 1;
    try {
      max_derivative = std::min(1, solvers::TimeBasis::from_name(s_.basis.trial, m).max_derivative());
    } catch (const std::invalid_argument&) {
    }  // the name error is reported by basis()
    a.derivative = static_cast<int>(r_.integer(*t, "analysis", "derivative", 0, max_derivative, 0,
                                               max_derivative == 0 ? " (this basis has no pointwise derivative)" : ""));
    a.unit_integral =
        r_.choice(*t, "analysis", "normalization", {"orthonormal", "unit-integral"}, "orthonormal") == "unit-integral";
    if (a.unit_integral && s_.basis.trial == "fourier") {
      r_.error(Reader::source_of(*t, "normalization"), "analysis.normalization",
               "\"unit-integral\" is the wavelet normalization ∫₀¹ φ_{J,k} = 1 [JL14 Sec. 3.3]; Fourier functions "
               "are plotted as they are");
    }
  }

  void solver(const toml::table& root) {
    const toml::table* t = r_.table(root, "solver", false);
    if (t == nullptr) return;
    if (s_.analysis.kind == AnalysisKind::Timestep) {
      r_.warn(t->source(), "[solver] (Newton) is not used by analysis \"timestep\"; ignored ([timestep] sets the BDF)");
      return;
    }
    r_.only(*t, "solver", {"tolerance", "max_iterations", "line_search", "linear_solver", "residual_tolerance"});
    s_.solver.residual_tolerance =
        r_.number(*t, "solver", "residual_tolerance", detail::positive(""), s_.solver.residual_tolerance);
    solvers::NewtonOptions& n = s_.solver.newton;
    n.tolerance = r_.number(*t, "solver", "tolerance", detail::positive(""), n.tolerance);
    n.max_iterations = static_cast<int>(r_.integer(*t, "solver", "max_iterations", 0, 100000, n.max_iterations));
    n.line_search = r_.boolean(*t, "solver", "line_search", n.line_search);
    s_.solver.linear_solver = value_of(linear_solver_table(),
                                       r_.choice(*t, "solver", "linear_solver", names(linear_solver_table()), "automatic"));
    if (s_.solver.linear_solver == solvers::LinearSolverPath::Modal && s_.structure &&
        s_.structure->kind == StructureKind::Matrices && s_.structure->damping.nonZeros() > 0) {
      r_.warn(Reader::source_of(*t, "linear_solver"),
              "linear_solver = \"modal\" needs Rayleigh damping; the solve fails if the given C is not αM + βK");
    }
  }

  void timestep(const toml::table& root) {
    const toml::table* t = r_.table(root, "timestep", false);
    if (t == nullptr) return;
    if (s_.analysis.kind != AnalysisKind::Timestep) {
      r_.warn(t->source(), "[timestep] is not used by analysis \"" + std::string(to_string(s_.analysis.kind)) +
                               "\"; ignored");
      return;
    }
    const bool rigid = !s_.contacts.empty() && s_.contacts.front().law == ContactLawKind::Rigid;
    if (rigid) {  // Moreau–Jean: fixed steps and an impact law instead of error control
      r_.only(*t, "timestep", {"steps_per_period", "restitution", "periodicity_tolerance", "max_periods"},
              "rigid stops are integrated by Moreau–Jean; relative_tolerance and absolute_tolerance are the BDF's "
              "(penalty laws)");
      auto& mj = s_.moreau_jean;
      mj.steps_per_period = static_cast<int>(r_.integer(*t, "timestep", "steps_per_period", 4, 1 << 26, mj.steps_per_period));
      mj.restitution = r_.number(*t, "timestep", "restitution", {"in [0, 1]", [](double v) { return v >= 0.0 && v <= 1.0; }},
                                 mj.restitution);
      mj.periodicity_tolerance =
          r_.number(*t, "timestep", "periodicity_tolerance", detail::positive(""), mj.periodicity_tolerance);
      mj.max_periods = static_cast<int>(r_.integer(*t, "timestep", "max_periods", 2, 10000000, mj.max_periods));
      return;
    }
    r_.only(*t, "timestep", {"relative_tolerance", "absolute_tolerance", "periodicity_tolerance", "max_periods"},
            "steps_per_period and restitution are the Moreau–Jean scheme's, for law = \"rigid\"");
    auto& o = s_.timestep;
    o.relative_tolerance = r_.number(*t, "timestep", "relative_tolerance",
                                     {"in (0, 1)", [](double v) { return v > 0.0 && v < 1.0; }}, o.relative_tolerance);
    o.absolute_tolerance = r_.number(*t, "timestep", "absolute_tolerance", detail::positive("m"), o.absolute_tolerance);
    o.periodicity_tolerance =
        r_.number(*t, "timestep", "periodicity_tolerance", detail::positive(""), o.periodicity_tolerance);
    o.max_periods = static_cast<int>(r_.integer(*t, "timestep", "max_periods", 2, 10000000, o.max_periods));
  }

  void output(const toml::table& root) {
    const toml::table* t = r_.table(root, "output", false);
    if (t == nullptr) {
      s_.timestep.samples_per_period = s_.output.samples;
      s_.moreau_jean.samples_per_period = s_.output.samples;
      return;
    }
    r_.only(*t, "output", {"samples", "nodes", "dofs", "harmonics", "formats", "observe"});
    s_.output.samples = static_cast<int>(r_.integer(*t, "output", "samples", 4, 1 << 22, s_.output.samples));
    if (const toml::node* f = t->get("formats")) {
      const toml::array* a = f->as_array();
      std::vector<std::string> formats;
      bool ok = a != nullptr && !a->empty() && a->is_homogeneous<std::string>();
      if (ok) {
        for (const auto& e : *a) {
          const std::string v = e.as_string()->get();
          if ((v != "csv" && v != "mat") || std::find(formats.begin(), formats.end(), v) != formats.end()) ok = false;
          formats.push_back(v);
        }
      }
      if (ok) {
        s_.output.formats = formats;
      } else {
        r_.error(f->source(), "output.formats",
                 "expected a non-empty list of distinct formats among \"csv\" (one CSV file per table) and \"mat\" "
                 "(result.mat, one struct per table, for MATLAB and scipy.io.loadmat), e.g. [\"csv\", \"mat\"]");
      }
    }
    if (t->contains("harmonics")) {
      s_.output.harmonics =
          static_cast<int>(r_.integer(*t, "output", "harmonics", 1, (s_.output.samples - 1) / 2, 0));
      const AnalysisKind k = s_.analysis.kind;
      if (k == AnalysisKind::NonlinearModes || k == AnalysisKind::BasisPlot) {
        r_.error(Reader::source_of(*t, "harmonics"), "output.harmonics",
                 "written for solves (harmonics.csv; per point of a sweep: sweep_harmonics.csv), timestep runs and "
                 "continuation (branch_harmonics.csv); not for nnm or basis plots: remove it");
      }
    }
    s_.timestep.samples_per_period = s_.output.samples;
    s_.moreau_jean.samples_per_period = s_.output.samples;
    if (const toml::node* o = t->get("observe"); o != nullptr && s_.structure) {
      const bool sweep = s_.analysis.kind == AnalysisKind::Solve && s_.forcing && s_.forcing->range;
      if (!sweep && s_.analysis.kind != AnalysisKind::Continuation) {
        r_.error(o->source(), "output.observe",
                 "the DOFs reported per point of a sweep or a continuation branch; for other analyses list the DOFs "
                 "to write with output." + std::string(s_.structure->kind == StructureKind::Rod ? "nodes" : "dofs"));
      } else if (o->is_array() && !o->as_array()->empty()) {
        for (const auto& e : *o->as_array()) {
          if (auto dof = location_value(e, "output.observe")) {
            if (std::find(s_.output.observe.begin(), s_.output.observe.end(), *dof) == s_.output.observe.end()) {
              s_.output.observe.push_back(*dof);
            }
          }
        }
      } else {
        r_.error(o->source(), "output.observe", "expected a non-empty list of locations (rod: nodes, matrices: DOF names)");
      }
    }
    for (const char* key : {"nodes", "dofs"}) {
      const toml::node* n = t->get(key);
      if (n == nullptr) continue;
      if (s_.analysis.kind == AnalysisKind::BasisPlot) {
        r_.warn(n->source(), std::string("output.") + key + " is not used by basis-plot");
        continue;
      }
      if (!s_.structure) continue;
      const bool rod = s_.structure->kind == StructureKind::Rod;
      if (rod != (std::string(key) == "nodes")) {
        r_.error(n->source(), std::string("output.") + key,
                 rod ? "the rod's outputs are nodes = [...] or \"all\"" : "matrix outputs are dofs = [...] or \"all\"");
        continue;
      }
      if (n->is_string() && n->as_string()->get() == "all") {
        s_.output.all_dofs = true;
      } else if (n->is_array() && !n->as_array()->empty()) {
        for (const auto& e : *n->as_array()) {
          if (auto dof = location_value(e, std::string("output.") + key)) s_.output.dofs.push_back(*dof);
        }
      } else {
        r_.error(n->source(), std::string("output.") + key, "expected \"all\" or a non-empty list of locations");
      }
    }
  }

  // A load at harmonic h needs 2h < M trial functions (solve, continuation) or 2h < P output
  // samples (timestep): above, its projection or its samples alias it to a lower harmonic.
  void load_harmonics(const toml::table& root) {
    if (!s_.forcing || s_.analysis.kind == AnalysisKind::NonlinearModes || s_.analysis.kind == AnalysisKind::BasisPlot) {
      return;
    }
    const bool timestep = s_.analysis.kind == AnalysisKind::Timestep;
    const int functions = timestep ? s_.output.samples : s_.basis.dimension;
    const int highest = solvers::highest_resolved_harmonic(functions);
    const std::string fix =
        timestep ? "raise [output] samples above " : s_.basis.harmonics > 0 ? "raise [basis] harmonics to at least "
                                                                             : "raise [basis] dimension (or level) above ";
    if (highest < 1 && s_.forcing->amplitude != 0.0) {
      r_.error(root.source(), timestep ? "output.samples" : "basis.dimension",
               std::to_string(functions) + (timestep ? " output samples per period" : " functions") +
                   " cannot carry the forcing at harmonic 1 (2h < " + std::to_string(functions) +
                   " fails): use at least 3, e.g. " + (timestep ? "samples = 1024" : "harmonics = 16 or level = 6"));
    }
    for (size_t i = 0; i < s_.forcing->loads.size(); ++i) {
      const auto& l = s_.forcing->loads[i];
      if (l.amplitude == 0.0 || l.harmonic <= highest) continue;
      const toml::source_region where = i < load_sources_.size() ? load_sources_[i] : root.source();
      r_.error(where, "forcing.loads[" + std::to_string(i) + "].harmonic",
               std::to_string(l.harmonic) + " is above the highest harmonic " + std::to_string(highest) + " that " +
                   (timestep ? "the " + std::to_string(functions) + " output samples per period"
                             : "the basis' M = " + std::to_string(functions) + " functions") +
                   " resolve (2h < " + std::to_string(functions) + "); the load would be aliased to a lower harmonic: " +
                   fix + std::to_string(timestep || s_.basis.harmonics == 0 ? 2 * l.harmonic : l.harmonic) +
                   ", or remove the load");
    }
  }

  // Sizes this machine cannot serve are refused with the estimate and the key (resources.hpp):
  // memory above half the physical memory, result files above kMaxOutputBytes.
  void resources(const toml::table& root) {
    static constexpr double kMaxOutputBytes = 512e6;
    const ResourceEstimate e = estimate_resources(s_);
    const double available = physical_memory_bytes();
    if (available > 0.0 && e.memory_bytes > 0.5 * available) {
      r_.error(root.source(), e.memory_key,
               "the analysis would need about " + format_bytes(e.memory_bytes) + " of memory (docs/scenes.md, "
               "Sizes), more than half of this machine's " + format_bytes(available) + ": lower " + e.memory_key);
    }
    if (e.output_bytes > kMaxOutputBytes) {
      r_.error(root.source(), "output.samples",
               std::to_string(s_.output.samples) + " samples per period would write about " +
                   format_bytes(e.output_bytes) + " of CSV files (at most " + format_bytes(kMaxOutputBytes) +
                   "): lower output.samples, or output fewer DOFs");
    }
  }

  Reader& r_;
  std::filesystem::path base_;
  Scene s_;
  std::vector<toml::source_region> load_sources_;  // of forcing.loads[i].harmonic, for load_harmonics
};

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

int Structure::dofs() const { return kind == StructureKind::Rod ? rod.elements : static_cast<int>(mass.rows()); }

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
  solvers::MechanicalSystem sys;
  if (condensation) {  // C = C_mm + αM_mm + βK̃ (Rayleigh damping of the condensed model)
    sys = condensation->system;
    sys.damping += damping.beta * sys.stiffness + damping.alpha * sys.mass;
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
    } else {
      law = std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{c.stiffness, c.gap});
    }
    points.push_back({c.dof, law, c.against, c.along});
  }
  return points;
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
  nlohmann::json analysis = {{"type", std::string(to_string(s.analysis.kind))}};
  for (const auto& k : analysis_keys()) {
    if (!k.echo || !reads(k, s.analysis.kind)) continue;
    if (nlohmann::json v = k.echo(s.analysis); !v.is_null()) analysis[k.key] = std::move(v);
  }
  j["analysis"] = analysis;
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
      j["structure"] = {{"type", "rod"},
                        {"young_modulus", st.rod.young_modulus},
                        {"density", st.rod.density},
                        {"area", st.rod.area},
                        {"length", st.rod.length},
                        {"elements", st.rod.elements}};
    } else if (st.deck) {  // the deck again (re-reduced when read back), not the reduced matrices
      j["structure"] = {{"type", "deck"}, {"deck", st.deck->file}, {"interface", st.deck->interface},
                        {"modes", st.deck->modes}, {"ccx", st.deck->ccx}, {"units", st.deck->units}};
      if (st.deck->axis) {
        const auto& [point, direction] = *st.deck->axis;
        j["structure"]["axis"] = {{"point", {point(0), point(1), point(2)}},
                                  {"direction", {direction(0), direction(1), direction(2)}}};
      }
    } else {
      j["structure"] = {{"type", "matrices"},
                        {"mass", matrix_json(st.mass, st.mass_file)},
                        {"stiffness", matrix_json(st.stiffness, st.stiffness_file)},
                        {"dofs", st.dof_names}};
      if (st.damping.size() > 0) j["structure"]["damping"] = matrix_json(st.damping, st.damping_file);
    }
    if (s.analysis.kind != AnalysisKind::NonlinearModes) j["damping"] = {{"alpha", s.damping.alpha}, {"beta", s.damping.beta}};
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
      nlohmann::json o = {{"law", std::string(to_string(c.law))}, {"gap", c.gap}};
      if (c.law == ContactLawKind::Exponential) {
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
      list.push_back(o);
    }
    j["contact"] = list;
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
    j["solver"] = {{"tolerance", s.solver.newton.tolerance},
                   {"max_iterations", s.solver.newton.max_iterations},
                   {"line_search", s.solver.newton.line_search},
                   {"linear_solver", linear_solver_name(s.solver.linear_solver)},
                   {"residual_tolerance", s.solver.residual_tolerance}};
  }
  if (s.analysis.kind == AnalysisKind::Timestep) {
    if (s.rigid()) {
      j["timestep"] = {{"steps_per_period", s.moreau_jean.steps_per_period},
                       {"restitution", s.moreau_jean.restitution},
                       {"periodicity_tolerance", s.moreau_jean.periodicity_tolerance},
                       {"max_periods", s.moreau_jean.max_periods}};
    } else {
      j["timestep"] = {{"relative_tolerance", s.timestep.relative_tolerance},
                       {"absolute_tolerance", s.timestep.absolute_tolerance},
                       {"periodicity_tolerance", s.timestep.periodicity_tolerance},
                       {"max_periods", s.timestep.max_periods}};
    }
  }
  nlohmann::json out = {{"samples", s.output.samples}};
  if (s.output.harmonics > 0) out["harmonics"] = s.output.harmonics;
  out["formats"] = s.output.formats;
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
