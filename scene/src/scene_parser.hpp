// Private to wbm_scene: the scene parser, which reads one TOML table into a Scene through a
// Reader (reader.hpp). The name tables and the [analysis] key table are shared with the JSON echo
// (scene.cpp); the parser's sections are defined one group per file:
//   scene_parser.cpp     the order of the sections; [analysis], [damping], [solver], [timestep],
//                        [output], and the checks across sections (load harmonics, sizes)
//   scene_structure.cpp  [structure]: rod, matrices, CalculiX decks; DOF names, condensation
//   scene_forcing.cpp    [forcing] and its loads, node locations
//   scene_contacts.cpp   [[contact]], at DOFs or deck nodes, and their directions
//   scene_basis.cpp      [basis] and the harmonic selection
#pragma once


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

namespace wbm::scene::detail {

// One table per enumerated scene value: the parser's list of choices, the value it stands for,
// and the name the JSON echo and messages print are read from the same entry.
template <class E>
using NameTable = std::vector<std::pair<E, std::string_view>>;

inline const NameTable<AnalysisKind>& analysis_table() {
  static const NameTable<AnalysisKind> t = {{AnalysisKind::Solve, "solve"},
                                            {AnalysisKind::Timestep, "timestep"},
                                            {AnalysisKind::BasisPlot, "basis-plot"},
                                            {AnalysisKind::Continuation, "continuation"},
                                            {AnalysisKind::NonlinearModes, "nnm"}};
  return t;
}
inline const NameTable<ContactLawKind>& law_table() {
  static const NameTable<ContactLawKind> t = {
      {ContactLawKind::Exponential, "exponential"}, {ContactLawKind::Linear, "linear"}, {ContactLawKind::Rigid, "rigid"},
      {ContactLawKind::Jenkins, "jenkins"}, {ContactLawKind::Coulomb, "coulomb"}};
  return t;
}
inline const NameTable<NnmAlgorithm>& nnm_algorithm_table() {
  static const NameTable<NnmAlgorithm> t = {{NnmAlgorithm::Continuation, "continuation"},
                                            {NnmAlgorithm::Simultaneous, "simultaneous"},
                                            {NnmAlgorithm::Sequential, "sequential"}};
  return t;
}
inline const NameTable<solvers::LinearSolverPath>& linear_solver_table() {
  static const NameTable<solvers::LinearSolverPath> t = {{solvers::LinearSolverPath::Automatic, "automatic"},
                                                         {solvers::LinearSolverPath::SparseLU, "sparse-lu"},
                                                         {solvers::LinearSolverPath::Modal, "modal"}};
  return t;
}

template <class E>
inline std::vector<std::string> names(const NameTable<E>& t) {
  std::vector<std::string> out;
  for (const auto& [value, name] : t) out.emplace_back(name);
  return out;
}
// The name of a value; the table lists every enumerator.
template <class E>
inline std::string_view name_of(const NameTable<E>& t, E value) {
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

inline const std::vector<std::string>& analysis_names() {
  static const std::vector<std::string> n = names(analysis_table());
  return n;
}

inline std::string linear_solver_name(solvers::LinearSolverPath p) { return std::string(name_of(linear_solver_table(), p)); }

inline bool is_power_of_two(long long m) { return m >= 1 && (m & (m - 1)) == 0; }

// Reads one scene table into a Scene, reporting into a Reader.
class Parser {
 public:
  Parser(Reader& reader, std::filesystem::path base) : r_(reader), base_(std::move(base)) {}

  Scene parse(const toml::table& root);

 private:
  // [analysis] type first: it decides which sections are read. False when the type is unknown.
  bool analysis(const toml::table& root);

  // [analysis] of type "nnm": energy = [from, to] (normalized, 1 = contact onset), N, m, the
  // outer algorithm, steps and the levels whose mode shapes are written.
  void branch_parameter(const toml::table& t);
  void nnm(const toml::table& t);

  void structure(const toml::table& root);

  // [structure] deck = "…" (interface, modes, ccx, axis): the deck assembled by ccx and reduced
  // by Craig–Bampton now (scene/reduce.hpp); M_r, K_r and the names of wbm reduce's dofs.txt.
  void deck_structure(const toml::table& t, Structure& st);

  // A list of three finite numbers.
  std::optional<Eigen::Vector3d> vector3(const toml::table& t, const std::string& section, const std::string& key);

  // A number (1 DOF), a list (diagonal), a list of rows, or a Matrix Market file.
  std::optional<Eigen::SparseMatrix<double>> matrix(const toml::table& t, const std::string& key, bool required,
                                                    std::string& file);

  // Matrix Market coordinate format, real or integer, general or symmetric (fem::read_matrix_market).
  void read_market(const toml::node& n, const std::string& full, const std::filesystem::path& p,
                   Eigen::SparseMatrix<double>& a);

  void check_matrices(const toml::table& t, const Structure& st, bool have_stiffness);

  void dof_names(const toml::table& t, Structure& st);

  void damping(const toml::table& root);

  // The DOF named by one location value: rod node (1 … E or "tip"), matrix DOF (name or index).
  std::optional<int> location_value(const toml::node& n, const std::string& full);

  // `node` for the rod, `dof` for matrices; `fallback` when neither is given.
  int location(const toml::table& t, const std::string& section, std::optional<int> fallback);

  std::optional<int> default_location() const;

  void forcing(const toml::table& root);

  // [[forcing.loads]] and forcing.vector: further loads F cos(2π h f t + φ) (Forcing::loads).
  void loads(const toml::table& t, Forcing& f);

  void contacts(const toml::table& root);

  // [[counter_surface]] (scene_counter_surface.cpp), read before the contacts that name them; and
  // a [[contact]]'s counter_surface: the index in Scene::counter_surfaces, −1 for none (errors:
  // an unknown name, an analysis without moving obstacles, a drift the law cannot take).
  void counter_surfaces(const toml::table& root);
  // The tables of `key`, one [key] or an array [[key]], each with the section name its messages
  // give ("key" or "key[i]"); std::nullopt after reporting any other value.
  std::optional<std::vector<std::pair<const toml::table*, std::string>>> table_list(const toml::node& n,
                                                                                    const std::string& key);
  int counter_surface_of(const toml::table& t, const std::string& section, const Contact& c);

  // Static condensation of massless DOFs (solvers/condensation.hpp), checked here so that a
  // scene it cannot condense is refused with the reason.
  // K symmetric positive semidefinite (issue #40): a negative ω² of K φ = ω² M φ is refused;
  // rigid-body modes (ω² = 0) only where a contact can hold them, with a warning, since the
  // harmonic-0 block of G is then singular wherever every stop is open.
  void stiffness_definiteness(const toml::table& root);

  void condense(const toml::table& root);

  // [[contact]] nodes = "SET" | [n, …] on a structure read from a deck: one contact per node,
  // with the law and gap of the table, along direction = "radial" (from structure.axis) or
  // [x, y, z] (the same unit vector at every node), over the node's x, y, z DOFs; the DOF of
  // the largest component names the contact.
  void node_contacts(const toml::table& t, const toml::node& nn, const std::string& section, const Contact& law);

  // [contact] second_tangent of a jenkins table: the DOF of the element's second tangent, or
  // nothing after reporting why (beside against, direction or nodes; stability or a branch in μ;
  // the contact's own DOF).
  std::optional<int> second_tangent(const toml::table& t, const toml::node& st, const std::string& section,
                                    const Contact& c);

  // [contact] normal_contact of the jenkins tables: the named table (index in file order) must be
  // another contact located by node or dof with a linear or exponential law; sets normal_index.
  void normal_contacts(const std::vector<std::pair<const toml::table*, std::string>>& tables,
                       const std::vector<int>& table_contact);

  // [contact] direction: ±1 (the side of the stop along the DOF) or a table {DOF name = weight}
  // (matrices); returns the (DOF, weight) pairs, empty for +1.
  std::vector<std::pair<int, double>> direction(const toml::node& d, const std::string& section, const Contact& c);

  void basis(const toml::table& root);

  // [basis] harmonic_selection: "all", "odd" (1, 3, …) or a list of harmonic numbers, for
  // Fourier:Fourier with penalty laws; every load must act at a kept harmonic.
  void harmonic_selection(const toml::table& t, bool harmonic_balance, bool rigid);

  void basis_plot(const toml::table& root);

  void solver(const toml::table& root);

  void timestep(const toml::table& root);

  void output(const toml::table& root);

  // A load at harmonic h needs 2h < M trial functions (solve, continuation) or 2h < P output
  // samples (timestep): above, its projection or its samples alias it to a lower harmonic.
  void load_harmonics(const toml::table& root);

  // Sizes this machine cannot serve are refused with the estimate and the key (resources.hpp):
  // memory above half the physical memory, result files above kMaxOutputBytes.
  void resources(const toml::table& root);

  Reader& r_;
  std::filesystem::path base_;
  Scene s_;
  std::vector<toml::source_region> load_sources_;  // of forcing.loads[i].harmonic, for load_harmonics
};

}  // namespace wbm::scene::detail
