// The scene parser (scene_parser.hpp), [structure]: the rod, matrices inline or in Matrix Market
// files, CalculiX decks (interface DOFs predicted when read, reduced by Craig–Bampton when an analysis
// runs: reduce_structure); DOF names, definiteness, static condensation.
#include "scene_keys.hpp"
#include "scene_parser.hpp"

namespace wbm::scene::detail {

void Parser::structure(const toml::table& root) {
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
    st.kind = StructureKind::Rod;
    read_keys(r_, *t, "structure", structure_keys(), st, "", "rod");  // E, ρ, S, L, elements
    for (int j = 1; j <= st.rod.elements; ++j) st.dof_names.push_back("node" + std::to_string(j));
  } else {
    r_.only(*t, "structure", names(structure_keys(), "matrices"));
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

void Parser::deck_structure(const toml::table& t, Structure& st) {
  std::vector<std::string> known = names(structure_keys(), "deck");  // type
  for (const auto& k : names(deck_keys(), "deck")) known.push_back(k);
  r_.only(t, "structure", known);
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
  read_values(r_, t, "structure", deck_keys(), d, "deck");  // modes, ccx, units
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
  // The interface DOFs are predicted from the deck's text; CalculiX and the reduction run with the
  // analysis (reduce_structure), which checks the prediction against the DOFs ccx keeps.
  try {
    const DeckInterface in = predict_interface(d.file, d.interface);
    const int interior = in.free_dofs - static_cast<int>(in.names.size());
    if (in.free_dofs >= 0 && d.modes >= interior) {
      r_.error(Reader::source_of(t, t.contains("modes") ? "modes" : "deck"), "structure.modes",
               "modes = " + std::to_string(d.modes) + ": the interior has only " + std::to_string(interior) +
                   " DOFs; ask for fewer modes (< " + std::to_string(interior) + ")");
      return;
    }
    const double length = deck_units(d.units).length;
    for (int node : in.nodes) d.coordinates[node] = in.deck.nodes.at(node) * length;
    d.node_sets = in.deck.node_sets;
    d.constraint_keywords.assign(in.deck.constraint_keywords.begin(), in.deck.constraint_keywords.end());
    st.kind = StructureKind::Matrices;
    st.dof_names = in.names;
    for (int k = 1; k <= d.modes; ++k) st.dof_names.push_back(std::string("mode").append(std::to_string(k)));
    st.deck = std::move(d);
  } catch (const std::invalid_argument& e) {
    r_.error(file->source(), "structure.deck", e.what());
  } catch (const std::exception& e) {  // the deck cannot be read: a file system problem, not the scene's text
    r_.tool_error(file->source(), "structure.deck", e.what());
  }
}

std::optional<Eigen::Vector3d> Parser::vector3(const toml::table& t, const std::string& section, const std::string& key) {
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

std::optional<Eigen::SparseMatrix<double>> Parser::matrix(const toml::table& t, const std::string& key, bool required,
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

void Parser::read_market(const toml::node& n, const std::string& full, const std::filesystem::path& p,
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

void Parser::check_matrices(const toml::table& t, const Structure& st, bool have_stiffness) {
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

void Parser::dof_names(const toml::table& t, Structure& st) {
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

namespace {

// What K's inertia means for the analysis: an error, else a warning, else nothing ({"", ""}).
std::pair<std::string, std::string> stiffness_verdict(const solvers::StiffnessInertia& inertia, AnalysisKind kind,
                                                      bool contacts) {
  const std::string rigid = std::to_string(inertia.rigid_body) + " rigid-body mode(s) (ω² = 0)";
  if (inertia.factorized && inertia.negative > 0) {
    return {"K is not positive semidefinite: K φ = ω² M φ has " + std::to_string(inertia.negative) +
                " eigenvalue(s) ω² < 0 (a negative stiffness: the equilibrium is unstable and no periodic response "
                "exists around it); check the sign of K and of every spring",
            ""};
  }
  if (inertia.rigid_body > 0 && kind == AnalysisKind::NonlinearModes) {
    return {"K has " + rigid + ": analysis \"nnm\" continues the first mode from its linear frequency, which must be "
                "> 0; clamp a DOF or add a spring to ground",
            ""};
  }
  if (inertia.rigid_body > 0 && !contacts) {
    return {"K has " + rigid + " and no [[contact]] holds them: the mean position is undetermined (G's harmonic-0 "
                "block K is singular); clamp a DOF, add a spring to ground, or add the stop that holds the structure",
            ""};
  }
  if (inertia.rigid_body > 0) {
    return {"", "K has " + rigid + ": only the contacts hold the structure, and a state where every stop is open has "
                "no unique mean position (docs/scenes.md, [structure])"};
  }
  return {"", ""};
}

solvers::StiffnessInertia inertia_of(const Structure& st) {
  return solvers::stiffness_inertia({st.mass, Eigen::SparseMatrix<double>(st.mass.rows(), st.mass.cols()), st.stiffness});
}

}  // namespace

void Parser::stiffness_definiteness(const toml::table& root) {
  if (!s_.structure || s_.structure->kind != StructureKind::Matrices || r_.error_count() > 0) return;
  if (s_.structure->awaiting_reduction()) return;  // K_r exists after the reduction: reduce_structure checks it
  const toml::table* t = root.get_as<toml::table>("structure");
  const toml::source_region where = t != nullptr && t->contains("stiffness") ? Reader::source_of(*t, "stiffness")
                                                                              : root.source();
  const auto [error, warning] = stiffness_verdict(inertia_of(*s_.structure), s_.analysis.kind, !s_.contacts.empty());
  if (!error.empty()) r_.error(where, "structure.stiffness", error);
  if (!warning.empty()) r_.warn(where, warning);
}

void Parser::condense(const toml::table& root) {
  if (!s_.structure || s_.structure->kind != StructureKind::Matrices || r_.error_count() > 0) return;
  if (s_.structure->awaiting_reduction()) return;  // M_r of Craig–Bampton is positive definite: nothing is massless
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

}  // namespace wbm::scene::detail

namespace wbm::scene {

void reduce_structure(Scene& scene) {
  if (!scene.structure || !scene.structure->awaiting_reduction()) return;
  Structure& st = *scene.structure;
  DeckStructure& d = *st.deck;
  ReductionRequest request;
  request.deck = d.file;
  request.interface = d.interface;
  request.modes = d.modes;
  request.ccx = d.ccx;
  request.units = d.units;
  ReducedModel reduced = reduce_model(request);  // CalculiX, then Craig–Bampton
  if (reduced.names != st.dof_names) {
    const auto differ = [](const std::vector<std::string>& a, const std::vector<std::string>& b) {
      std::string out;
      for (const auto& n : a) {
        if (std::find(b.begin(), b.end(), n) == b.end()) out += (out.empty() ? "" : ", ") + n;
      }
      return out.empty() ? std::string("none") : out;
    };
    std::string keywords;
    for (const auto& k : d.constraint_keywords) keywords += (keywords.empty() ? "*" : ", *") + k;
    throw std::invalid_argument(
        "structure.deck: CalculiX keeps other interface DOFs than the deck's *BOUNDARY lines predict (missing: " +
        differ(st.dof_names, reduced.names) + "; unexpected: " + differ(reduced.names, st.dof_names) + ")" +
        (keywords.empty() ? std::string() : "; the deck has " + keywords + ", which can remove DOFs") +
        ". The scene's contacts and loads were resolved against the predicted names, so it is not run: constrain "
        "no interface DOF by an equation, or reduce the deck with `wbm reduce` and give its matrices and dofs.txt");
  }
  st.stiffness = reduced.stiffness.sparseView();
  st.mass = reduced.mass.sparseView();
  d.reduction = std::move(reduced.summary);
  const auto [error, warning] = detail::stiffness_verdict(detail::inertia_of(st), scene.analysis.kind, !scene.contacts.empty());
  if (!error.empty()) throw std::invalid_argument("structure.deck: the reduced stiffness K_r of " + d.file + ": " + error);
  if (!warning.empty()) scene.warnings.push_back("structure.deck: " + warning);
}

}  // namespace wbm::scene
