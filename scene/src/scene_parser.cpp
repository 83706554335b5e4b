// The scene parser (scene_parser.hpp): the order in which sections are read, [analysis],
// [damping], [solver], [timestep], [output], and the checks across sections (load harmonics, sizes).
#include "scene_keys.hpp"
#include "scene_parser.hpp"

namespace wbm::scene::detail {

Scene Parser::parse(const toml::table& root) {
  r_.only(root, "", names(top_keys()));
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
    for (const char* unused : {"structure", "damping", "forcing", "contact", "counter_surface", "solver", "timestep"}) {
      if (const toml::node* n = root.get(unused)) {
        r_.warn(n->source(), std::string("[") + unused + "] is not used by analysis \"basis-plot\" (no structure is "
                             "built); ignored");
      }
    }
  } else if (s_.analysis.kind == AnalysisKind::NonlinearModes) {
    // Modes of the conservative system against its stops: no forcing, damping, basis, solver
    // or time stepping.
    for (const char* unused : {"forcing", "damping", "basis", "solver", "timestep", "counter_surface"}) {
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
    counter_surfaces(root);
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
  if (s_.analysis.kind == AnalysisKind::Timestep && s_.jenkins() &&
      (s_.central_difference.steps_per_period < s_.output.samples ||
       s_.central_difference.steps_per_period % s_.output.samples != 0)) {
    r_.error(root.source(), "timestep.steps_per_period",
             std::to_string(s_.central_difference.steps_per_period) + " is not a multiple of output.samples = " +
                 std::to_string(s_.output.samples) + " (central differences sample their fixed steps): use powers "
                 "of two, e.g. 65536 steps and 1024 samples");
  }
  return std::move(s_);
}

bool Parser::analysis(const toml::table& root) {
  const toml::table* t = r_.table(root, "analysis", false);
  if (t == nullptr) return true;
  r_.only(*t, "analysis", names(analysis_keys()));
  const size_t errors = r_.error_count();
  const std::string type = r_.choice(*t, "analysis", "type", analysis_names(), "solve");
  if (r_.error_count() != errors && t->contains("type")) return false;
  s_.analysis.kind = value_of(analysis_table(), type);
  const std::string kind(to_string(s_.analysis.kind));
  for (const auto& key : names(analysis_keys())) {
    const toml::node* n = t->get(key);
    const std::vector<std::string> readers = variants_of(analysis_keys(), key);
    if (n == nullptr || readers.empty() || std::find(readers.begin(), readers.end(), kind) != readers.end()) continue;
    std::string types;
    for (size_t i = 0; i < readers.size(); ++i) types += (i == 0 ? "\"" : " or \"") + readers[i] + "\"";
    r_.error(n->source(), "analysis." + key, "only used by type = " + types + "; remove it");
  }
  if (s_.analysis.kind == AnalysisKind::NonlinearModes) nnm(*t);
  if (s_.analysis.kind == AnalysisKind::Continuation) {
    Analysis& a = s_.analysis;
    read_values(r_, *t, "analysis", analysis_keys(), a, kind);  // max_step, max_frequency_step_hz, max_points,
                                                                 // max_state, parameter
    a.stability = r_.boolean(*t, "analysis", "stability", a.stability);
    branch_parameter(*t);
  }
  return true;
}

// parameter = "friction_coefficient": its range [from, to] (required), at one forcing frequency
// (scene_forcing.cpp checks that) and without max_frequency_step_hz; otherwise no range.
void Parser::branch_parameter(const toml::table& t) {
  Analysis& a = s_.analysis;
  const toml::node* n = t.get("friction_coefficient");
  if (a.parameter == BranchParameter::Frequency) {
    if (n != nullptr) {
      r_.error(n->source(), "analysis.friction_coefficient",
               "only used with parameter = \"friction_coefficient\" (a branch in mu); remove it, or set that "
               "parameter");
    }
    return;
  }
  if (const toml::node* m = t.get("max_frequency_step_hz")) {
    r_.error(m->source(), "analysis.max_frequency_step_hz",
             "caps |df| of a branch in frequency; a branch in mu (parameter = \"friction_coefficient\") is at one "
             "frequency: remove it (analysis.max_step sets the step)");
  }
  const toml::array* range = n != nullptr ? n->as_array() : nullptr;
  if (range == nullptr || range->size() != 2) {
    r_.error(n != nullptr ? n->source() : t.source(), "analysis.friction_coefficient",
             std::string(n == nullptr ? "missing" : "expected [from, to]") +
                 " with parameter = \"friction_coefficient\"; give friction_coefficient = [from, to], the range of mu "
                 "(>= 0) the branch follows from `from`, e.g. [0.0, 0.5]");
    return;
  }
  a.friction_from = r_.number_value((*range)[0], "analysis.friction_coefficient[0]", detail::non_negative("-"));
  a.friction_to = r_.number_value((*range)[1], "analysis.friction_coefficient[1]", detail::non_negative("-"));
  if (a.friction_from == a.friction_to) {
    r_.error(n->source(), "analysis.friction_coefficient",
             "the range is empty (from = to); give from != to (the branch runs from `from` towards `to`)");
  }
}

void Parser::nnm(const toml::table& t) {
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
  // harmonics (N <= 256: the cost grows about as N^2.2; 2 DOFs: 0.3 s at N = 32, 7 s at N = 128;
  // N = 512 ran for minutes, issue #40, docs/scenes.md "Sizes"), algorithm, max_step,
  // max_energy_step, max_points.
  read_values(r_, t, "analysis", analysis_keys(), a, "nnm");
  a.stability = r_.boolean(t, "analysis", "stability", false);  // the levels' stability costs a shooting each
  a.samples = static_cast<int>(r_.integer(t, "analysis", "samples", 3, 1 << 16, std::max(a.samples, 8 * a.harmonics)));
  if (a.samples <= 2 * a.harmonics) {
    r_.error(Reader::source_of(t, "samples"), "analysis.samples",
             "m = " + std::to_string(a.samples) + " must exceed 2N = " + std::to_string(2 * a.harmonics) +
                 " (the contact conditions are imposed at m samples of a degree-N trigonometric polynomial)");
  }
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

void Parser::damping(const toml::table& root) {
  const toml::table* t = r_.table(root, "damping", false);
  if (t == nullptr) return;
  read_keys(r_, *t, "damping", damping_keys(), s_.damping);
}

void Parser::basis_plot(const toml::table& root) {
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
  read_values(r_, *t, "analysis", analysis_keys(), a, "basis-plot");  // normalization
  if (a.unit_integral && s_.basis.trial == "fourier") {
    r_.error(Reader::source_of(*t, "normalization"), "analysis.normalization",
             "\"unit-integral\" is the wavelet normalization ∫₀¹ φ_{J,k} = 1 [JL14 Sec. 3.3]; Fourier functions "
             "are plotted as they are");
  }
}

void Parser::solver(const toml::table& root) {
  const toml::table* t = r_.table(root, "solver", false);
  if (t == nullptr) return;
  if (s_.analysis.kind == AnalysisKind::Timestep) {
    r_.warn(t->source(), "[solver] (Newton) is not used by analysis \"timestep\"; ignored ([timestep] sets the BDF)");
    return;
  }
  read_keys(r_, *t, "solver", solver_keys(), s_.solver);
  if (s_.solver.linear_solver == solvers::LinearSolverPath::Modal && s_.structure &&
      s_.structure->kind == StructureKind::Matrices && s_.structure->damping.nonZeros() > 0) {
    r_.warn(Reader::source_of(*t, "linear_solver"),
            "linear_solver = \"modal\" needs a damping matrix the undamped modes diagonalize; the solve fails if the "
            "given C is not (C M⁻¹ K ≠ K M⁻¹ C): use \"automatic\"");
  }
}

void Parser::timestep(const toml::table& root) {
  const toml::table* t = r_.table(root, "timestep", false);
  if (t == nullptr) return;
  if (s_.analysis.kind != AnalysisKind::Timestep) {
    r_.warn(t->source(), "[timestep] is not used by analysis \"" + std::string(to_string(s_.analysis.kind)) +
                             "\"; ignored");
    return;
  }
  const bool rigid = !s_.contacts.empty() && s_.contacts.front().law == ContactLawKind::Rigid;
  if (rigid) {  // Moreau–Jean: fixed steps and an impact law instead of error control
    read_keys(r_, *t, "timestep", moreau_jean_keys(), s_.moreau_jean,
                      "rigid stops are integrated by Moreau–Jean; relative_tolerance and absolute_tolerance are the "
                      "BDF's (penalty laws)");
    return;
  }
  if (s_.jenkins()) {  // central differences: fixed explicit steps, the elements' slider state carried
    read_keys(r_, *t, "timestep", central_difference_keys(), s_.central_difference,
              "a Jenkins element is integrated by explicit central differences; relative_tolerance and "
              "absolute_tolerance are the BDF's (memoryless penalty laws), restitution Moreau–Jean's");
    return;
  }
  read_keys(r_, *t, "timestep", bdf_keys(), s_.timestep,
                    "steps_per_period and restitution are the Moreau–Jean scheme's, for law = \"rigid\"");
}

void Parser::output(const toml::table& root) {
  const toml::table* t = r_.table(root, "output", false);
  if (t == nullptr) {
    s_.timestep.samples_per_period = s_.output.samples;
    s_.moreau_jean.samples_per_period = s_.output.samples;
    s_.central_difference.samples_per_period = s_.output.samples;
    return;
  }
  read_keys(r_, *t, "output", output_keys(), s_.output);  // samples; the others below
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
  s_.central_difference.samples_per_period = s_.output.samples;
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

void Parser::load_harmonics(const toml::table& root) {
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
  if (timestep) return;  // a contact there names no counter-surface (refused with the contact)
  const toml::node* surfaces = root.get("counter_surface");
  for (size_t i = 0; i < s_.counter_surfaces.size(); ++i) {
    const int h = s_.counter_surfaces[i].motion(false).highest_harmonic();
    if (h <= highest) continue;
    const std::string section = surfaces != nullptr && surfaces->is_array_of_tables()
                                    ? "counter_surface[" + std::to_string(i) + "]" : std::string("counter_surface");
    r_.error(surfaces != nullptr ? surfaces->source() : root.source(), section,
             "moves at harmonic " + std::to_string(h) + ", above the highest harmonic " + std::to_string(highest) +
                 " that the basis' M = " + std::to_string(functions) + " functions resolve (2h < " +
                 std::to_string(functions) + "): " + fix + std::to_string(s_.basis.harmonics == 0 ? 2 * h : h) +
                 ", or drop that harmonic");
  }
}

void Parser::resources(const toml::table& root) {
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

}  // namespace wbm::scene::detail
