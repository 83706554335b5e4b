// The scene parser (scene_parser.hpp), [forcing]: the frequency or range, the loads and where
// they act (a DOF, a named DOF or a deck node).
#include "scene_keys.hpp"
#include "scene_parser.hpp"

namespace wbm::scene::detail {

std::optional<int> Parser::location_value(const toml::node& n, const std::string& full) {
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

int Parser::location(const toml::table& t, const std::string& section, std::optional<int> fallback) {
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

std::optional<int> Parser::default_location() const {
  if (!s_.structure) return std::nullopt;
  if (s_.structure->kind == StructureKind::Rod) return s_.structure->rod.elements - 1;  // the free tip
  if (s_.structure->dofs() == 1) return 0;
  return std::nullopt;
}

void Parser::forcing(const toml::table& root) {
  if (const toml::node* n = root.get("forcing"); n != nullptr && n->is_array_of_tables()) {
    r_.error(n->source(), "[[forcing]]",
             "one [forcing] table holds the frequency; several loads go in it as [[forcing.loads]] tables "
             "(amplitude, node or dof, phase_deg or phase_rad, harmonic) or as a force vector file "
             "(vector = \"f.mtx\"): see docs/scenes.md");
    return;
  }
  const toml::table* t = r_.table(root, "forcing", true);
  if (t == nullptr) return;
  r_.only(*t, "forcing", names(forcing_keys()));
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
  const bool in_mu = s_.analysis.kind == AnalysisKind::Continuation &&
                     s_.analysis.parameter == BranchParameter::FrictionCoefficient;
  if (freq != nullptr && (!freq->is_array() || list) && s_.analysis.kind == AnalysisKind::Continuation && !in_mu) {
    r_.error(freq->source(), full,
             "analysis \"continuation\" follows the branch over a range: give frequency_hz = [from, to] "
             "(or frequency_rad_s)");
  }
  if (freq != nullptr && freq->is_array() && in_mu) {
    r_.error(freq->source(), full,
             "analysis.parameter = \"friction_coefficient\" follows mu at one forcing frequency: give frequency_hz = "
             "f (one number), or parameter = \"frequency\" for a branch over [from, to]");
  }
  if (f.range && s_.analysis.kind == AnalysisKind::Continuation && !in_mu && t->contains("points")) {
    r_.error(Reader::source_of(*t, "points"), "forcing.points",
             "continuation chooses its own points (analysis.max_step, max_frequency_step_hz); remove it");
  }
  if (f.range && s_.analysis.kind == AnalysisKind::Timestep) {
    r_.error(freq->source(), full,
             "analysis \"timestep\" integrates at one frequency; give a number, or use type = \"solve\" for a sweep");
  }
  s_.forcing = f;
}

void Parser::loads(const toml::table& t, Forcing& f) {
  if (const toml::node* n = t.get("loads")) {
    if (!n->is_array_of_tables()) {
      r_.error(n->source(), "forcing.loads", "expected [[forcing.loads]] tables, each with amplitude, node or dof, "
                                             "and optionally phase_deg or phase_rad and harmonic");
    } else {
      const toml::array& a = *n->as_array();
      for (size_t i = 0; i < a.size(); ++i) {
        const toml::table& l = *a[i].as_table();
        const std::string section = "forcing.loads[" + std::to_string(i) + "]";
        solvers::HarmonicLoad load{0, 0.0};
        read_keys(r_, l, section, load_keys(), load);  // amplitude, phase_rad, harmonic
        load.dof = location(l, section, default_location());
        if (l.contains("phase_deg") && l.contains("phase_rad")) {
          r_.error(Reader::source_of(l, "phase_rad"), section + ".phase_rad", "given beside phase_deg; give the phase once");
        } else if (l.contains("phase_deg")) {
          load.phase_rad = r_.number(l, section, "phase_deg", detail::finite("deg")) * std::numbers::pi / 180.0;
        }
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

}  // namespace wbm::scene::detail
