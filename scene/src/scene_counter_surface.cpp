// The scene parser (scene_parser.hpp), [[counter_surface]]: moving counter-surfaces (a Fourier
// series in τ, or the oval casing of blade–casing rubbing), and the `counter_surface` key by which
// a [[contact]] names one (solvers::ContactPoint::obstacle; issue #36, item 3).
#include "scene_keys.hpp"
#include "scene_parser.hpp"

namespace wbm::scene::detail {

std::optional<std::vector<std::pair<const toml::table*, std::string>>> Parser::table_list(const toml::node& n,
                                                                                          const std::string& key) {
  std::vector<std::pair<const toml::table*, std::string>> tables;
  if (n.is_table()) {
    tables.emplace_back(n.as_table(), key);
  } else if (n.is_array_of_tables()) {
    const toml::array& a = *n.as_array();
    for (size_t i = 0; i < a.size(); ++i) tables.emplace_back(a[i].as_table(), key + "[" + std::to_string(i) + "]");
  } else {
    r_.error(n.source(), key, "expected a table [" + key + "] or tables [[" + key + "]]");
    return std::nullopt;
  }
  return tables;
}

void Parser::counter_surfaces(const toml::table& root) {
  const toml::node* n = root.get("counter_surface");
  if (n == nullptr) return;
  const auto tables = table_list(*n, "counter_surface");
  if (!tables) return;
  for (const auto& [t, section] : *tables) {
    CounterSurface cs;
    cs.type = r_.choice(*t, section, "type", {"fourier", "oval_casing"}, "fourier");
    read_keys(r_, *t, section, counter_surface_keys(), cs, "", cs.type);
    cs.name = r_.text(*t, section, "name");
    for (const CounterSurface& other : s_.counter_surfaces) {
      if (other.name == cs.name) {
        r_.error(Reader::source_of(*t, "name"), section + ".name",
                 "= \"" + cs.name +
                     "\" is given twice; name each "
                     "[[counter_surface]] once");
      }
    }
    if (cs.type == "fourier") {
      for (const char* key : {"cosine", "sine"}) {
        const toml::node* list = t->get(key);
        if (list == nullptr) continue;
        const toml::array* a = list->as_array();
        if (a == nullptr) {
          r_.error(list->source(), section + "." + key, "expected a list of numbers [m], entry h − 1 for harmonic h");
          continue;
        }
        std::vector<double>& out = std::string(key) == "cosine" ? cs.cosine : cs.sine;
        for (size_t i = 0; i < a->size(); ++i) {
          out.push_back(
              r_.number_value((*a)[i], section + "." + key + "[" + std::to_string(i) + "]", detail::finite("m")));
        }
      }
      if (!cs.motion(false).moving() && !cs.motion(true).moving()) {
        r_.warn(t->source(), section + ": every term (cosine, sine, drift) is zero: the counter-surface does not move");
      }
    }
    s_.counter_surfaces.push_back(std::move(cs));
  }
}

int Parser::counter_surface_of(const toml::table& t, const std::string& section, const Contact& c) {
  const toml::node* n = t.get("counter_surface");
  if (n == nullptr) return -1;
  const std::string full = section + ".counter_surface";
  if (!n->is_string()) {
    r_.error(n->source(), full, "expected the name of a [[counter_surface]], got " + Reader::type_name(*n));
    return -1;
  }
  const std::string name = n->as_string()->get();
  const auto kind = s_.analysis.kind;
  if (kind == AnalysisKind::NonlinearModes || kind == AnalysisKind::Timestep) {
    r_.error(
        n->source(), full,
        kind == AnalysisKind::NonlinearModes
            ? "analysis \"nnm\" computes free motions against fixed stops; a moving counter-surface forces the "
              "structure: use a forced response (solve, sweep, continuation), or remove counter_surface"
            : "analysis \"timestep\": the time-stepping references of scenes (BDF, Moreau–Jean, central "
              "differences) take fixed obstacles; use a weighted-residual analysis (solve, sweep, continuation), "
              "or remove counter_surface");
    return -1;
  }
  int index = -1;
  std::string known;
  for (size_t i = 0; i < s_.counter_surfaces.size(); ++i) {
    if (s_.counter_surfaces[i].name == name) index = static_cast<int>(i);
    known += (known.empty() ? "\"" : ", \"") + s_.counter_surfaces[i].name + "\"";
  }
  if (index < 0) {
    r_.error(n->source(), full,
             "= \"" + name + "\" names no [[counter_surface]]" +
                 (known.empty() ? std::string("; there is none: add one with this name") : "; the names are " + known));
    return -1;
  }
  const CounterSurface& cs = s_.counter_surfaces[static_cast<size_t>(index)];
  const bool friction = c.law == ContactLawKind::Jenkins || c.law == ContactLawKind::Coulomb;
  const bool drifts = cs.motion(friction).drift != 0.0;
  if (!friction && drifts) {
    r_.error(n->source(), full,
             "= \"" + name + "\" slides by " + detail::number_text(cs.drift) +
                 " m per period (its "
                 "drift); on a normal contact (law \"" +
                 std::string(to_string(c.law)) +
                 "\") the gap would "
                 "grow every period: a drift is a \"coulomb\" contact's sliding; set drift = 0 or name "
                 "another counter_surface");
  }
  if (c.law == ContactLawKind::Rigid && kind == AnalysisKind::Continuation && s_.analysis.stability) {
    r_.error(n->source(), full,
             "a \"rigid\" contact on a moving counter-surface with analysis.stability = true (the "
             "default): the exact orbits with impacts are shot against fixed stops; set "
             "analysis.stability = false");
  }
  return index;
}

}  // namespace wbm::scene::detail
