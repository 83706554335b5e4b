// The scene parser (scene_parser.hpp), [basis]: the trial and weighting bases, their size, the
// formulation, the operator and contact quadrature rules, and the harmonic selection.
#include "scene_keys.hpp"
#include "scene_parser.hpp"

namespace wbm::scene::detail {

void Parser::basis(const toml::table& root) {
  const toml::table* t = r_.table(root, "basis", false);
  const bool plot = s_.analysis.kind == AnalysisKind::BasisPlot;
  if (t != nullptr && s_.analysis.kind == AnalysisKind::Timestep) {
    r_.warn(t->source(), "[basis] is not used by analysis \"timestep\" (time stepping); ignored");
    return;
  }
  if (t == nullptr) {
    if (plot) r_.error(root.source(), "[basis]", "missing table: basis-plot draws the [basis] trial family");
    // Fourier:Fourier with H harmonics, as for a [basis] without a size: never the M = 2^J
    // basis with its undamped top function by default (issue #19).
    s_.basis.harmonics = Basis::kDefaultHarmonics;
    s_.basis.dimension = 2 * s_.basis.harmonics + 1;
    const bool rigid = !s_.contacts.empty() && s_.contacts.front().law == ContactLawKind::Rigid;
    s_.basis.contact_quadrature = rigid || s_.friction() ? solvers::ContactQuadrature::Midpoint
                                                          : solvers::ContactQuadrature::CellAverage;
    return;
  }
  r_.only(*t, "basis", names(basis_keys()));
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
  read_values(r_, *t, "basis", basis_keys(), b);  // formulation, time_samples, operators
  if (b.time_samples > 0 && b.time_samples < b.dimension) {
    r_.error(Reader::source_of(*t, "time_samples"), "basis.time_samples",
             "Q = " + std::to_string(b.time_samples) + " < M = " + std::to_string(b.dimension) +
                 ": the Q-point rule needs Q >= M (0 picks max(256, 2M))");
  }
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
  // A friction law has no f(u) to average: midpoint for every contact of the scene.
  b.contact_quadrature = quadrature == "cell-average" || (quadrature == "automatic" && !rigid && !s_.friction() &&
                                                           (b.harmonics > 0 || (corner && sloped)))
                             ? solvers::ContactQuadrature::CellAverage
                             : solvers::ContactQuadrature::Midpoint;
  if (rigid && quadrature == "cell-average") {
    r_.error(Reader::source_of(*t, "contact_quadrature"), "basis.contact_quadrature",
             "\"cell-average\" integrates a penalty law over each cell; rigid stops impose the Signorini "
             "conditions at the instants (k + 1/2)/M instead: use \"automatic\" or \"midpoint\"");
  }
  if (s_.friction() && quadrature == "cell-average") {
    r_.error(Reader::source_of(*t, "contact_quadrature"), "basis.contact_quadrature",
             "\"cell-average\" averages a law f(u) over each cell; a \"jenkins\" contact's force depends on the "
             "history over the period: use \"automatic\" or \"midpoint\"");
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

void Parser::harmonic_selection(const toml::table& t, bool harmonic_balance, bool rigid) {
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

}  // namespace wbm::scene::detail
