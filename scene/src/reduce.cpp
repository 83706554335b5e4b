#include <wbm/scene/reduce.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>

#include <wbm/fem/calculix.hpp>
#include <wbm/fem/craig_bampton.hpp>
#include <wbm/fem/matrix_market.hpp>
#include <wbm/scene/build_information.hpp>

#include "analysis_detail.hpp"

namespace wbm::scene {
namespace {

using detail::seconds_since;  // analysis_detail.hpp (one definition: a unity build put two in one unit)

// Node numbers of `interface`: a list of integers, or a node set of the deck.
std::vector<int> interface_nodes(const fem::CalculixDeck& deck, const std::string& interface) {
  const bool numbers = !interface.empty() && interface.find_first_not_of("0123456789, \t") == std::string::npos;
  std::vector<int> nodes;
  if (numbers) {
    std::string s = interface;
    std::replace(s.begin(), s.end(), ',', ' ');
    std::istringstream in(s);
    long long v = 0;
    while (in >> v) {
      if (v < 1 || v > 2147483647 || deck.nodes.count(static_cast<int>(v)) == 0) {
        throw std::invalid_argument(std::string("interface: node ").append(std::to_string(v)) + " is not a node of " + deck.file.string() +
                                    "; give node numbers of the deck or the name of one of its node sets");
      }
      nodes.push_back(static_cast<int>(v));
    }
  } else {
    nodes = deck.node_set(interface);  // throws naming the sets the deck defines
  }
  if (nodes.empty()) {
    throw std::invalid_argument("interface '" + interface + "' has no node; give a node set of the deck or node numbers");
  }
  std::vector<int> sorted = nodes;
  std::sort(sorted.begin(), sorted.end());
  if (const auto twice = std::adjacent_find(sorted.begin(), sorted.end()); twice != sorted.end()) {
    throw std::invalid_argument(std::string("interface: node ").append(std::to_string(*twice)) + " is listed twice; list each node once");
  }
  return nodes;
}

std::string no_free_dof(const fem::CalculixDeck& deck, int node) {
  return std::string("interface: node ").append(std::to_string(node)) + " has no free DOF in " + deck.file.string() +
         " (fixed by *BOUNDARY, or on no element); remove it from the interface";
}

fem::CalculixDeck read_deck(const std::filesystem::path& path) {
  if (!std::filesystem::is_regular_file(path)) {
    throw std::invalid_argument("deck: no file " + path.string() + " (give the path of a CalculiX/Abaqus .inp deck)");
  }
  return fem::read_calculix_deck(path);
}

std::string direction_name(int direction) {
  static const char* names[] = {"x", "y", "z", "rx", "ry", "rz"};
  return direction >= 1 && direction <= 6 ? names[direction - 1] : std::string("d").append(std::to_string(direction));
}

// max |A − Aᵀ| / max |A|, then A ← (A + Aᵀ)/2.
double symmetrize(Eigen::MatrixXd& a) {
  const double scale = std::max(a.cwiseAbs().maxCoeff(), 1e-300);
  const double defect = (a - a.transpose()).cwiseAbs().maxCoeff() / scale;
  a = (0.5 * (a + a.transpose())).eval();
  return defect;
}

Eigen::VectorXd frequencies_hz(const Eigen::MatrixXd& k, const Eigen::MatrixXd& m, Eigen::Index count) {
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(k, m, Eigen::EigenvaluesOnly);
  if (eig.info() != Eigen::Success) throw std::runtime_error("reduce: the reduced model's eigenproblem failed (is M_r SPD?)");
  const Eigen::Index n = std::min(count, eig.eigenvalues().size());
  return eig.eigenvalues().head(n).cwiseMax(0.0).cwiseSqrt() / (2.0 * 3.14159265358979323846);
}

std::vector<double> as_vector(const Eigen::VectorXd& v) { return {v.data(), v.data() + v.size()}; }

const std::vector<DeckUnits>& unit_systems() {
  static const std::vector<DeckUnits> systems = {{"SI", 1.0, 1.0, 1.0},
                                                 {"N-m-kg-s", 1.0, 1.0, 1.0},
                                                 {"N-mm-t-s", 1e-3, 1e3, 1.0},
                                                 {"kN-mm-kg-ms", 1e-3, 1.0, 1e-3}};
  return systems;
}

}  // namespace

std::vector<std::string> deck_unit_names() {
  std::vector<std::string> names;
  for (const auto& u : unit_systems()) names.push_back(u.name);
  return names;
}

DeckUnits deck_units(const std::string& name) {
  for (const auto& u : unit_systems()) {
    if (u.name == name) return u;
  }
  std::string known;
  for (const auto& n : deck_unit_names()) known += (known.empty() ? "" : ", ") + n;
  throw std::invalid_argument("units = \"" + name + "\": unknown unit system; known: " + known +
                              " (the deck's consistent units, converted to SI)");
}

DeckInterface predict_interface(const std::filesystem::path& deck, const std::string& interface) {
  DeckInterface out;
  out.deck = read_deck(deck);
  out.nodes = interface_nodes(out.deck, interface);
  for (int node : out.nodes) {
    const std::vector<int> free = fem::free_directions(out.deck, node);  // throws for an expanded element's node
    if (free.empty()) throw std::invalid_argument(no_free_dof(out.deck, node));
    for (int direction : free) out.names.push_back(std::string("n").append(std::to_string(node)) + "_" + direction_name(direction));
  }
  int count = 0;
  try {
    for (const auto& [node, types] : out.deck.element_types_at) count += static_cast<int>(fem::free_directions(out.deck, node).size());
    out.free_dofs = count;
  } catch (const std::invalid_argument&) {  // an element ccx expands elsewhere in the model: not predictable
    out.free_dofs = -1;
  }
  return out;
}

ReducedModel reduce_model(const ReductionRequest& request) {
  if (request.modes < 0) {
    throw std::invalid_argument(std::string("modes = ").append(std::to_string(request.modes)) +
                                ": must be >= 0 (fixed-interface normal modes; LL11's blade uses 40)");
  }
  if (request.check_modes < 0) {
    throw std::invalid_argument(std::string("check = ").append(std::to_string(request.check_modes)) +
                                ": must be >= 0 (0: no full-model reference; e.g. 10)");
  }
  const std::optional<DeckUnits> units = request.units.empty() ? std::nullopt : std::optional(deck_units(request.units));
  const auto start = std::chrono::steady_clock::now();
  const fem::CalculixDeck deck = read_deck(request.deck);
  const std::vector<int> nodes = interface_nodes(deck, request.interface);
  auto t = std::chrono::steady_clock::now();
  fem::AssembledModel model = fem::assemble_with_calculix(deck, {.executable = request.ccx});
  const double ccx_s = seconds_since(t);
  const double length = units ? units->length : 1.0, time = units ? units->time : 1.0;
  if (units) {  // to SI: K [force/length] × mass/time², M × mass; u then in metres
    model.stiffness *= units->mass / (time * time);
    model.mass *= units->mass;
  }

  std::map<int, std::vector<std::pair<int, int>>> rows_of;  // node → (direction, row)
  for (size_t r = 0; r < model.dofs.size(); ++r) rows_of[model.dofs[r].first].emplace_back(model.dofs[r].second, static_cast<int>(r));
  std::vector<int> boundary;
  std::vector<std::string> names;
  nlohmann::json coordinates = nlohmann::json::array();
  ReducedModel out;
  for (int node : nodes) {
    auto it = rows_of.find(node);
    if (it == rows_of.end()) throw std::invalid_argument(no_free_dof(deck, node));
    std::sort(it->second.begin(), it->second.end());
    for (const auto& [direction, row] : it->second) {
      boundary.push_back(row);
      names.push_back(std::string("n").append(std::to_string(node)) + "_" + direction_name(direction));
    }
    const Eigen::Vector3d x = deck.nodes.at(node) * length;
    coordinates.push_back({x(0), x(1), x(2)});
    out.coordinates[node] = x;
  }
  const int full = static_cast<int>(model.dofs.size());
  const int interior = full - static_cast<int>(boundary.size());
  if (request.modes >= interior) {
    throw std::invalid_argument(std::string("modes = ").append(std::to_string(request.modes)) + ": the interior has only " +
                                std::to_string(interior) + " DOFs; ask for fewer modes (< " + std::to_string(interior) + ")");
  }
  fem::CraigBamptonModel cb = fem::craig_bampton(model.stiffness, model.mass, boundary, request.modes);
  for (int k = 1; k <= request.modes; ++k) names.push_back(std::string("mode").append(std::to_string(k)));
  Eigen::MatrixXd kr = cb.stiffness, mr = cb.mass;
  const double k_defect = symmetrize(kr), m_defect = symmetrize(mr);
  const Eigen::VectorXd reduced = frequencies_hz(kr, mr, 10);

  nlohmann::json check = nullptr;
  double check_s = 0.0;
  if (request.check_modes > 0) {
    t = std::chrono::steady_clock::now();
    const int count = std::min(request.check_modes, full - 1);
    const fem::CraigBamptonModel whole = fem::craig_bampton(model.stiffness, model.mass, {}, count);
    // CalculiX's own eigensolver on the same deck: a second, independent reference.
    std::vector<double> ccx_hz = fem::calculix_frequencies(deck, count, {.executable = request.ccx});
    for (double& f : ccx_hz) f /= time;  // cycles per deck time unit → Hz
    check_s = seconds_since(t);
    std::vector<double> ccx_differences;
    for (size_t i = 0; i < ccx_hz.size() && static_cast<Eigen::Index>(i) < whole.normal_frequencies_hz.size(); ++i) {
      ccx_differences.push_back(whole.normal_frequencies_hz(static_cast<Eigen::Index>(i)) / ccx_hz[i] - 1.0);
    }
    const Eigen::VectorXd ours = frequencies_hz(kr, mr, count);
    std::vector<double> errors;
    for (Eigen::Index i = 0; i < std::min(ours.size(), whole.normal_frequencies_hz.size()); ++i) {
      errors.push_back(ours(i) / whole.normal_frequencies_hz(i) - 1.0);
    }
    check = {{"full_frequencies_hz", as_vector(whole.normal_frequencies_hz)},
             {"ccx_frequencies_hz", ccx_hz},
             {"full_vs_ccx_relative", ccx_differences},
             {"reduced_frequencies_hz", as_vector(ours)},
             {"relative_errors", errors},
             {"worst_relative_error", errors.empty() ? 0.0 : *std::max_element(errors.begin(), errors.end(),
                                                                               [](double a, double b) { return std::abs(a) < std::abs(b); })}};
  }

  nlohmann::json summary = {
      {"deck", deck.file.string()},
      {"units", units ? "SI (N/m, kg, m, Hz), converted from the deck's " + units->name
                      : std::string("those of the deck, unconverted (K in force/length, M in mass; frequencies in "
                                    "cycles per deck time unit)")},
      {"full_dofs", full},
      {"interface", {{"given", request.interface}, {"nodes", nodes}, {"coordinates", coordinates},
                     {"dofs", static_cast<int>(boundary.size())}}},
      {"modes", request.modes},
      {"reduced_dofs", static_cast<int>(names.size())},
      {"fixed_interface_frequencies_hz", as_vector(cb.normal_frequencies_hz)},
      {"reduced_frequencies_hz", as_vector(reduced)},
      {"check", check},
      {"lanczos", {{"operations", cb.eigensolve_operations}, {"passes", cb.eigensolve_passes}}},
      {"symmetry_defect", {{"stiffness", k_defect}, {"mass", m_defect}}},
      {"timings_s", {{"ccx_and_reading", ccx_s}, {"factorization", cb.factorization_s},
                     {"constraint_modes", cb.constraint_modes_s}, {"eigensolve", cb.eigensolve_s},
                     {"assembly", cb.assembly_s}, {"check", check_s}}},
      {"files", {{"stiffness", "stiffness.mtx"}, {"mass", "mass.mtx"}, {"dofs", "dofs.txt"}}},
      {"scene", "structure = { stiffness = \"stiffness.mtx\", mass = \"mass.mtx\", dofs = \"dofs.txt\" }"},
      {"build", build_information()}};
  if (request.recovery) summary["files"]["recovery"] = {"recovery.mtx", "full_dofs.txt"};
  summary["timings_s"]["total"] = seconds_since(start);
  out.stiffness = std::move(kr);
  out.mass = std::move(mr);
  out.names = std::move(names);
  out.nodes = nodes;
  out.full_dofs = model.dofs;
  if (request.recovery) {
    out.recovery = cb.expand(Eigen::MatrixXd::Identity(static_cast<Eigen::Index>(out.names.size()),
                                                       static_cast<Eigen::Index>(out.names.size())));
  }
  out.summary = std::move(summary);
  out.deck_name = deck.file.filename().string();
  out.node_sets = deck.node_sets;
  out.interface_dofs = static_cast<int>(boundary.size());
  return out;
}

nlohmann::json reduce_deck(const ReductionRequest& request, const std::filesystem::path& output) {
  namespace fs = std::filesystem;
  ReducedModel r = reduce_model(request);
  const auto start = std::chrono::steady_clock::now();
  const auto& names = r.names;
  const Eigen::MatrixXd &kr = r.stiffness, &mr = r.mass;
  nlohmann::json& summary = r.summary;

  // Everything computed: now write.
  auto t = std::chrono::steady_clock::now();
  fs::create_directories(output);
  const std::string origin = "wbm reduce: Craig-Bampton of " + r.deck_name + ", " +
                             std::to_string(r.interface_dofs) + " interface DOFs + " + std::to_string(request.modes) +
                             " fixed-interface modes; rows and columns named in dofs.txt";
  fem::write_matrix_market_file(output / "stiffness.mtx", kr, true, (!request.units.empty() ? std::string("K_r [N/m, SI]\n") : std::string("K_r [deck units]\n")) + origin);
  fem::write_matrix_market_file(output / "mass.mtx", mr, true, (!request.units.empty() ? std::string("M_r [kg, SI]\n") : std::string("M_r [deck units]\n")) + origin);
  {
    std::ofstream d(output / "dofs.txt");
    for (const auto& n : names) d << n << "\n";
    if (!d) throw std::runtime_error("cannot write " + (output / "dofs.txt").string());
  }
  if (request.recovery) {
    fem::write_matrix_market_file(output / "recovery.mtx", r.recovery, false,
                                  "T: full displacements (rows: full_dofs.txt) = T q (columns: dofs.txt)\n" + origin);
    std::ofstream d(output / "full_dofs.txt");
    for (const auto& [node, direction] : r.full_dofs) d << node << "." << direction << "\n";
    if (!d) throw std::runtime_error("cannot write " + (output / "full_dofs.txt").string());
  }
  summary["timings_s"]["writing"] = seconds_since(t);
  summary["timings_s"]["total"] = summary["timings_s"]["total"].get<double>() + seconds_since(start);
  std::ofstream j(output / "reduction.json");
  j << summary.dump(2) << "\n";
  if (!j) throw std::runtime_error("cannot write " + (output / "reduction.json").string());
  return summary;
}

}  // namespace wbm::scene
