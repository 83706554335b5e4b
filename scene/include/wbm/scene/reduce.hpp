#pragma once
/// `wbm reduce`: a CalculiX/Abaqus deck, assembled by CalculiX (fem/calculix.hpp), reduced by
/// Craig–Bampton (fem/craig_bampton.hpp) onto the translations (and rotations, if the elements
/// have them) of an interface node set plus fixed-interface normal modes, and written as Matrix
/// Market files with a DOF name file, so that a scene runs many analyses on one reduction
/// (`structure = { stiffness = "stiffness.mtx", mass = "mass.mtx", dofs = "dofs.txt" }`;
/// docs/scenes.md, issue #15). Units: those of the deck, unconverted (N-mm-t-s decks give K in
/// N/mm and M in t; frequencies are in Hz for any consistent system).

#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <wbm/fem/calculix.hpp>

namespace wbm::scene {

struct ReductionRequest {
  std::filesystem::path deck;  // the deck (*NODE, *ELEMENT, *MATERIAL, *BOUNDARY, …); its *STEPs are ignored
  /// The interface: a node set of the deck (case-insensitive), or node numbers separated by
  /// commas or spaces ("17, 18, 19"). Every DOF CalculiX keeps at these nodes is retained.
  std::string interface;
  int modes = 40;           // fixed-interface normal modes m ≥ 0
  /// > 0: the full model's first check_modes frequencies (Spectra on the sparse matrices, and
  /// CalculiX's own *FREQUENCY step as a second reference) beside the reduced ones
  int check_modes = 0;
  bool recovery = false;    // also write recovery.mtx (n × (|b| + m), u = T q) and full_dofs.txt
  std::string ccx = "ccx";  // the CalculiX executable
  /// The deck's consistent unit system, converted to SI before the reduction (deck_units()):
  /// "" keeps the deck's units unconverted (wbm reduce's default); "SI" (N-m-kg-s, no change),
  /// "N-mm-t-s" or "kN-mm-kg-ms" convert K, M, coordinates and frequencies to N/m, kg, m, Hz.
  std::string units = "";
};

/// A consistent unit system of a deck: SI per deck unit of length [m], mass [kg] and time [s];
/// force = mass·length/time², so K [force/length] scales by mass/time² and M by mass.
struct DeckUnits {
  std::string name;
  double length = 1.0, mass = 1.0, time = 1.0;
};
/// The known systems ("SI", "N-m-kg-s", "N-mm-t-s", "kN-mm-kg-ms"). Throws std::invalid_argument
/// naming the value and the known names.
[[nodiscard]] DeckUnits deck_units(const std::string& name);
[[nodiscard]] std::vector<std::string> deck_unit_names();

/// A reduced model in memory (reduce_model), as reduce_deck writes it.
struct ReducedModel {
  Eigen::MatrixXd stiffness, mass;          // K_r, M_r, symmetrized, (|b| + m) square [deck units]
  std::vector<std::string> names;           // per reduced coordinate, as dofs.txt
  std::vector<int> nodes;                   // the interface nodes, in the order given
  std::map<int, Eigen::Vector3d> coordinates;  // of the interface nodes [deck length unit]
  std::map<std::string, std::vector<int>> node_sets;  // the deck's node sets (upper-case names)
  std::vector<std::pair<int, int>> full_dofs;  // (node, direction) per full row
  Eigen::MatrixXd recovery;                 // T (full rows × reduced columns), with request.recovery only
  nlohmann::json summary;                   // reduction.json
  std::string deck_name;                    // the deck's file name
  int interface_dofs = 0;                   // |b|
};

/// The interface of a deck as reduce_model retains it, predicted from the deck's text without
/// running CalculiX (fem::free_directions: translations of continuum nodes less *BOUNDARY): what
/// a scene resolves its contacts and loads against when it is read, before the reduction runs.
struct DeckInterface {
  fem::CalculixDeck deck;          // the deck as read (text only)
  std::vector<int> nodes;          // the interface nodes, in the order given
  /// "n<node>_<x|y|z>" per retained DOF, nodes in the order given and each node's directions
  /// ascending: the first names of dofs.txt (the "mode<k>" names follow them)
  std::vector<std::string> names;
  /// The DOFs CalculiX keeps in the whole model (every node on an element), or −1 when a node lies
  /// on an element type fem::free_directions cannot predict
  int free_dofs = -1;
};
/// Reads the deck and its interface. Throws std::invalid_argument as reduce_deck does for a deck
/// that is not a file, a syntax error, an empty interface, an unknown node or node set, an
/// interface node listed twice or with no free DOF, or one on an element ccx expands (naming the
/// node and its types); std::runtime_error for an unreadable deck.
[[nodiscard]] DeckInterface predict_interface(const std::filesystem::path& deck, const std::string& interface);

/// The reduction of reduce_deck, computed without writing anything. Throws as reduce_deck.
[[nodiscard]] ReducedModel reduce_model(const ReductionRequest& request);

/// The reduction (Craig & Bampton 1968; LL11 Sec. 5.2): u = T q, q = (u_b, η),
/// T = [I 0; −K_ii⁻¹K_ib Φ], K_ii Φ = M_ii Φ Λ, ΦᵀM_iiΦ = I (the m lowest fixed-interface modes),
/// K_r = TᵀKT = [K_bb − K_bi K_ii⁻¹ K_ib, 0; 0, Λ], M_r = TᵀMT; sizes (|b| + m) × (|b| + m), rows
/// ordered as dofs.txt (interface nodes in the order given, each node's DOFs by direction, then the
/// modes by increasing frequency).
/// Reads and assembles the deck, reduces it, and only when every step succeeded writes into
/// `output` (created): stiffness.mtx and mass.mtx (K_r, M_r, symmetric, Matrix Market),
/// dofs.txt (one name per reduced coordinate: "n<node>_<x|y|z|rx|ry|rz>" for the interface,
/// "mode<k>" for the modal coordinates, k = 1 … m), reduction.json (the returned summary: deck,
/// interface nodes and coordinates, sizes, fixed-interface and reduced frequencies [Hz], with
/// check_modes the full model's and the relative errors, the symmetry defects of K_r and M_r
/// before symmetrization, timings [s]) and, with `recovery`, recovery.mtx and full_dofs.txt
/// ("node.direction" per full row, CalculiX's .dof format).
/// Throws std::invalid_argument naming the option and a way out for: a deck that is not a file,
/// a syntax error in the deck, modes < 0, modes ≥ interior DOFs, check_modes < 0,
/// an empty interface, a node number not in the deck, an unknown node set (listing the deck's
/// sets), an interface node with no free DOF (all fixed by *BOUNDARY); std::runtime_error for an
/// unreadable deck or ccx failing (fem::assemble_with_calculix), a K_ii that is not positive
/// definite, or a file that cannot be written. Nothing is written when it throws.
[[nodiscard]] nlohmann::json reduce_deck(const ReductionRequest& request, const std::filesystem::path& output);

}  // namespace wbm::scene
