// The scene parser (scene_parser.hpp), [[contact]]: the law, at a DOF, between two DOFs, or on
// the nodes of a deck set with their directions.
#include "scene_keys.hpp"
#include "scene_parser.hpp"

namespace wbm::scene::detail {

void Parser::contacts(const toml::table& root) {
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
  const auto given = table_list(*n, "contact");
  if (!given) return;
  const auto& tables = *given;
  std::set<std::pair<int, int>> dofs;  // (dof, against)
  const bool modes = s_.analysis.kind == AnalysisKind::NonlinearModes;
  std::vector<int> table_contact(tables.size(), -1);  // the contact a table located by node or dof became
  const bool in_mu =
      s_.analysis.kind == AnalysisKind::Continuation && s_.analysis.parameter == BranchParameter::FrictionCoefficient;
  std::string jenkins_section;  // the first "jenkins" table, and its μ (a branch in μ)
  double jenkins_mu = 0.0;
  for (size_t table = 0; table < tables.size(); ++table) {
    const auto& [t, section] = tables[table];
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
    const bool friction = c.law == ContactLawKind::Jenkins || c.law == ContactLawKind::Coulomb;
    if (!friction) {
      c.gap = r_.number(*t, section, "gap", modes ? detail::positive("m; nnm normalizes energies by contact onset")
                                                  : detail::finite("m"));
    }
    if (friction && modes) {
      r_.error(Reader::source_of(*t, "law"), section + ".law",
               "\"" + law + "\" (friction) is for forced responses: solve, sweep, continuation and timestep; analysis "
               "\"nnm\" has no friction law (nonlinear modes are conservative)");
    }
    if (c.law == ContactLawKind::Coulomb && s_.analysis.kind == AnalysisKind::Continuation && s_.analysis.stability) {
      r_.error(Reader::source_of(*t, "law"), section + ".law",
               "\"coulomb\" with analysis.stability = true: the monodromy matrix of an orbit of exact (rigid-plastic) "
               "friction is not computed; set stability = false, or use law = \"jenkins\" (a stiff "
               "tangential_stiffness), whose stability is computed");
    }
    if (!modes && !s_.contacts.empty() && exact(c.law) != exact(s_.contacts.front().law)) {
      r_.error(t->source(), section, "mixes exact contacts (\"rigid\", \"coulomb\") with penalty or \"jenkins\" laws; a "
                                     "forced response takes all exact or none (give the rigid ones a stiff \"linear\" "
                                     "law and the \"coulomb\" ones a stiff \"jenkins\" law)");
    }
    if (c.law == ContactLawKind::Linear && modes && s_.analysis.stability) {
      r_.error(Reader::source_of(*t, "law"), section + ".law",
               "\"linear\" with analysis.stability = true: a backbone's stability is computed for rigid stops only "
               "(through the exact orbits with elastic impacts); set stability = false, or law = \"rigid\"");
    }
    if (c.law == ContactLawKind::Exponential && modes) {
      r_.error(Reader::source_of(*t, "law"), section + ".law",
               "analysis \"nnm\" takes law = \"rigid\" (exact contact) or \"linear\" (penalty spring)");
    }
    if (modes && !s_.contacts.empty() && (c.law == ContactLawKind::Rigid) != (s_.contacts.front().law == ContactLawKind::Rigid)) {
      r_.error(t->source(), section, "mixes rigid and penalty stops; nnm takes all \"rigid\" or all \"linear\"");
    }
    // The law's own keys: coefficient and exponent (exponential), stiffness (linear).
    read_keys(r_, *t, section, contact_keys(), c, "", law);
    c.counter_surface = counter_surface_of(*t, section, c);
    // A branch in μ varies one μ every "jenkins" contact shares (the start, analysis.
    // friction_coefficient's from, replaces it); "coulomb"'s μ is not a parameter of its rigid path.
    if (in_mu && c.law == ContactLawKind::Coulomb) {
      r_.error(Reader::source_of(*t, "law"), section + ".law",
               "\"coulomb\" with analysis.parameter = \"friction_coefficient\": exact Coulomb friction's mu is not a "
               "parameter of its rigid path; use law = \"jenkins\" (a stiff tangential_stiffness)");
    }
    if (in_mu && c.law == ContactLawKind::Jenkins) {
      if (jenkins_section.empty()) {
        jenkins_section = section;
        jenkins_mu = c.friction_coefficient;
      } else if (c.friction_coefficient != jenkins_mu) {
        r_.error(Reader::source_of(*t, "friction_coefficient"), section + ".friction_coefficient",
                 "= " + detail::number_text(c.friction_coefficient) + " beside " + jenkins_section +
                     ".friction_coefficient = " + detail::number_text(jenkins_mu) + ": a branch in mu varies one mu "
                     "shared by every \"jenkins\" contact; give them the same value (analysis.friction_coefficient's "
                     "from replaces it)");
      }
    }
    if (friction) {  // a constant normal load, or one that follows a normal contact (jenkins)
      // Jenkins: a penalty normal contact; coulomb: a rigid one (a 2D contact: the weighted residual
      // and Moreau–Jean solve the stop and the friction together).
      const bool varying = (c.law == ContactLawKind::Jenkins || c.law == ContactLawKind::Coulomb) &&
                           t->contains("normal_contact");
      c.normal_load = r_.number(*t, section, "normal_load", non_negative("N"),
                                varying ? std::optional<double>(0.0) : std::nullopt);
      if (varying && c.law == ContactLawKind::Coulomb && c.normal_load != 0.0) {
        r_.error(Reader::source_of(*t, "normal_load"), section + ".normal_load",
                 "= " + detail::number_text(c.normal_load) + " beside normal_contact: the rigid normal contact's reaction "
                 "is the normal load; remove normal_load and press the normal DOF with a static load "
                 "(a [[forcing.loads]] table with harmonic = 0)");
      }
      if (varying) {
        c.normal_contact = static_cast<int>(r_.integer(*t, section, "normal_contact", 0,
                                                       static_cast<long long>(tables.size()) - 1, std::nullopt,
                                                       " (the index of a [[contact]] table, 0-based in file order)"));
      }
    }
    if (c.law == ContactLawKind::Linear) {
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
    std::optional<int> second;  // the DOF of a second tangent
    if (const toml::node* st = t->get("second_tangent"); st != nullptr && s_.structure) second = second_tangent(*t, *st, section, c);
    if (s_.structure && !dofs.insert({c.dof, c.against}).second && c.along.empty()) {
      r_.error(t->source(), section, "a second contact on " + s_.structure->dof_name(c.dof) +
                                         (c.against >= 0 ? " against " + s_.structure->dof_name(c.against) : std::string()) +
                                         "; one law per DOF (combine them into one)");
    }
    table_contact[table] = static_cast<int>(s_.contacts.size());
    if (second) {
      if (!dofs.insert({*second, -1}).second) {
        r_.error(Reader::source_of(*t, "second_tangent"), section + ".second_tangent",
                 "a second contact on " + s_.structure->dof_name(*second) + "; one law per DOF");
      }
      Contact tangent = c;  // the element's second tangent: the same law, no counter-surface
      tangent.dof = *second;
      tangent.counter_surface = -1;
      const int own = static_cast<int>(s_.contacts.size());
      c.second_tangent = own + 1;
      tangent.second_tangent = own;
      s_.contacts.push_back(c);
      s_.contacts.push_back(tangent);
      continue;
    }
    s_.contacts.push_back(c);
  }
  normal_contacts(tables, table_contact);
  for (size_t i = 0; i < s_.contacts.size(); ++i) {  // the second tangent shares its element's normal load
    Contact& c = s_.contacts[i];
    if (c.second_tangent > static_cast<int>(i)) {
      s_.contacts[static_cast<size_t>(c.second_tangent)].normal_index = c.normal_index;
    }
  }
  if (in_mu && jenkins_section.empty()) {
    r_.error(tables.empty() ? root.source() : tables.front().first->source(), "[contact]",
             "analysis.parameter = \"friction_coefficient\" varies the mu of \"jenkins\" contacts, and there is none; "
             "add one, or set parameter = \"frequency\"");
  }
}

void Parser::normal_contacts(const std::vector<std::pair<const toml::table*, std::string>>& tables,
                             const std::vector<int>& table_contact) {
  for (size_t table = 0; table < tables.size(); ++table) {
    const int own = table_contact[table];
    if (own < 0 || s_.contacts[static_cast<size_t>(own)].normal_contact < 0) continue;
    Contact& c = s_.contacts[static_cast<size_t>(own)];
    const auto& [t, section] = tables[table];
    const auto where = Reader::source_of(*t, "normal_contact");
    const std::string full = section + ".normal_contact";
    const auto target = static_cast<size_t>(c.normal_contact);
    if (target == table) {
      r_.error(where, full, "= " + std::to_string(c.normal_contact) + " is this contact itself; give the index of the "
                            "[[contact]] on the normal DOF (a \"linear\" or \"exponential\" law)");
      continue;
    }
    const int index = table_contact[target];
    if (index < 0) {
      r_.error(where, full, "= " + std::to_string(c.normal_contact) + " names " + tables[target].second +
                            ", which is not one contact located by node or dof (a nodes set, or a table with errors); "
                            "give the normal contact its own [[contact]] with node or dof");
      continue;
    }
    const ContactLawKind law = s_.contacts[static_cast<size_t>(index)].law;
    if (c.law == ContactLawKind::Coulomb) {
      if (law != ContactLawKind::Rigid) {
        r_.error(where, full, "= " + std::to_string(c.normal_contact) + " names " + tables[target].second + " of law \"" +
                              std::string(to_string(law)) + "\"; a \"coulomb\" contact takes its normal load from a "
                              "\"rigid\" contact on the normal DOF (a 2D contact)");
        continue;
      }
      for (const Contact& other : s_.contacts) {
        if (&other != &c && other.law == ContactLawKind::Coulomb && other.normal_index == index) {
          r_.error(where, full, "= " + std::to_string(c.normal_contact) + " names " + tables[target].second +
                                ", which another \"coulomb\" contact already takes its normal load from; one tangent "
                                "per rigid contact");
        }
      }
      c.normal_index = index;
      continue;
    }
    if (law != ContactLawKind::Linear && law != ContactLawKind::Exponential) {
      r_.error(where, full, "= " + std::to_string(c.normal_contact) + " names " + tables[target].second + " of law \"" +
                            std::string(to_string(law)) + "\"; the normal load comes from a \"linear\" or \"exponential\" "
                            "contact on the normal DOF (a gap < 0 is a preload)");
      continue;
    }
    c.normal_index = index;
  }
}

std::optional<int> Parser::second_tangent(const toml::table& t, const toml::node& st, const std::string& section,
                                          const Contact& c) {
  const std::string full = section + ".second_tangent";
  if (c.law != ContactLawKind::Jenkins) return std::nullopt;  // only_in reports it
  if (c.against >= 0 || !c.along.empty() || t.contains("nodes")) {
    r_.error(st.source(), full, "beside against, direction or nodes: a Jenkins element with two tangents acts along "
                                "two DOFs of one body against a fixed counter-surface (+e_dof and +e_second_tangent); "
                                "remove them, or give the element one tangent");
    return std::nullopt;
  }
  const bool continuation = s_.analysis.kind == AnalysisKind::Continuation;
  if (continuation && (s_.analysis.stability || s_.analysis.parameter == BranchParameter::FrictionCoefficient)) {
    r_.error(st.source(), full, "a continuation of a Jenkins element with two tangents follows the frequency "
                                "without stability: the monodromy matrix of an element whose slip direction turns is "
                                "not computed, nor a branch in its mu; set analysis.stability = false and parameter = "
                                "\"frequency\", or give the element one tangent");
    return std::nullopt;
  }
  const auto other = location_value(st, full);
  if (!other) return std::nullopt;
  if (*other == c.dof) {
    r_.error(st.source(), full, "is the contact's own DOF " + s_.structure->dof_name(c.dof) +
                                "; give the DOF of the other tangential direction");
    return std::nullopt;
  }
  return other;
}

void Parser::node_contacts(const toml::table& t, const toml::node& nn, const std::string& section, const Contact& law) {
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

std::vector<std::pair<int, double>> Parser::direction(const toml::node& d, const std::string& section, const Contact& c) {
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

}  // namespace wbm::scene::detail
