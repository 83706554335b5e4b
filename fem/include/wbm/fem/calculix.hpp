#pragma once
/// Finite-element models from CalculiX/Abaqus input decks, with the matrices assembled by
/// CalculiX itself (`ccx`, Debian calculix-ccx): wbm writes no 3D elasticity elements. Units:
/// those of the deck (e.g. N-mm-t-s); nothing is converted here.
///
/// Deck format [CalculiX CrunchiX User's Manual, Sec. 7]: keyword lines start with `*`
/// (case-insensitive, parameters `NAME=value` after commas), `**` lines are comments, data lines
/// are comma-separated. The model data is everything before the first `*STEP`; the deck's own
/// steps are dropped and replaced by wbm's.

#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace wbm::fem {

/// What read_calculix_deck gathers from a deck's model data.
struct CalculixDeck {
  std::filesystem::path file;                          // the deck read (absolute)
  /// The model data with every *INCLUDE inlined (its text, in order), up to the first *STEP of
  /// the deck or of an included file: what a driver deck starts with.
  std::string model_data;
  std::map<int, Eigen::Vector3d> nodes;                // node number → (x, y, z) [deck units]
  std::map<std::string, std::vector<int>> node_sets;   // NSET name (upper case) → node numbers, in order
  std::map<std::string, int> element_types;            // TYPE (upper case) → number of elements
  /// node number → the element TYPEs (upper case) it is a node of; nodes on no element absent
  std::map<int, std::set<std::string>> element_types_at;
  /// node number → the directions (1 … 6) the model data's *BOUNDARY fixes at it
  std::map<int, std::set<int>> fixed_directions;
  /// Keywords of the model data that can remove or rotate DOFs beyond *BOUNDARY (*EQUATION,
  /// *MPC, *RIGID BODY, *TIE, *COUPLING, *TRANSFORM, …), upper case, as met.
  std::set<std::string> constraint_keywords;
  [[nodiscard]] int elements() const;
  /// The node numbers of a set, by name (case-insensitive). Throws std::invalid_argument naming
  /// the set and the sets the deck defines.
  [[nodiscard]] const std::vector<int>& node_set(const std::string& name) const;
};

/// Reads a deck: *NODE (id, x[, y[, z]], NSET= adds the nodes to a set), *ELEMENT (TYPE=; data
/// lines "number, node, node, …" may continue after a trailing comma), *BOUNDARY in the model data
/// ("node or set, first direction[, last direction[, value]]"), *NSET (NSET=, GENERATE for first, last[, step];
/// entries are node numbers or names of sets defined before), *INCLUDE (INPUT= relative to the
/// including file; nested at most 16 deep). Other keywords are kept in model_data untouched.
/// Throws std::runtime_error naming the path for a file that cannot be read, and
/// std::invalid_argument with "file:line: what was expected" for a malformed keyword or data line
/// (a node without coordinates, a non-numeric field, an *INCLUDE without INPUT=, a node set
/// entry that is neither a number nor a known set, a repeated node number, too deep includes, a
/// *BOUNDARY line whose directions are not 1 ≤ first ≤ last or whose node set is unknown).
[[nodiscard]] CalculixDeck read_calculix_deck(const std::filesystem::path& path);

/// The directions (1 = x, 2 = y, 3 = z, ascending) CalculiX keeps at `node` in the matrices of
/// assemble_with_calculix, predicted from the deck's text without running ccx: the translations
/// of a node of 3D continuum (C3D…), spring (SPRING…), dashpot (DASHPOT…), mass (MASS) or gap
/// (GAP…) elements, less those *BOUNDARY fixes; empty for a node on no element or fixed in all
/// three. Exact for such decks; a constraint keyword (constraint_keywords) can remove more, which
/// only ccx's own DOF list (AssembledModel::dofs) shows. Throws std::invalid_argument naming the
/// node and its element types for a node of an element ccx expands into new 3D nodes (shells
/// S…/M3D…, beams B3…, plane CPS…/CPE…/CAX…, or another type): its DOFs are not the node's.
[[nodiscard]] std::vector<int> free_directions(const CalculixDeck& deck, int node);

struct CalculixOptions {
  std::string executable = "ccx";  // the CalculiX solver, searched on PATH
  /// Scratch folder for the driver deck and ccx's files; empty: a fresh folder under the system
  /// temporary directory, removed afterwards.
  std::filesystem::path work_directory = {};
  /// Throws std::invalid_argument naming the field: an empty executable, or a work_directory that
  /// exists and is not a folder.
  void validate() const;
};

/// Stiffness and mass of the model as CalculiX assembles them, after its *BOUNDARY conditions:
/// n × n, symmetric (ccx writes the upper triangle, mirrored here), rows in ccx's order.
struct AssembledModel {
  Eigen::SparseMatrix<double> stiffness;  // [force/length in deck units]
  Eigen::SparseMatrix<double> mass;       // [mass in deck units]
  std::vector<std::pair<int, int>> dofs;  // per row: (node number, direction 1 = x, 2 = y, 3 = z)
};

/// Runs `ccx` on a driver deck = the model data + "*STEP / *FREQUENCY, SOLVER=MATRIXSTORAGE /
/// *END STEP" in a scratch folder and reads the .sti, .mas (1-based "row col value", upper
/// triangle) and .dof ("node.direction" per row) files it writes, with std::from_chars.
/// Throws std::invalid_argument if the options are invalid (validate()), and std::runtime_error
/// naming the deck: ccx not found (install calculix-ccx), ccx failing (its "*ERROR" lines
/// quoted), or files missing or malformed.
[[nodiscard]] AssembledModel assemble_with_calculix(const CalculixDeck& deck, const CalculixOptions& options = {});

/// Parses ccx's matrix files (also usable on files from another run): `stiffness` and `mass`
/// text as written by SOLVER=MATRIXSTORAGE, `dofs` the .dof text. `source` names them in
/// messages. Throws std::invalid_argument ("source:line: ...") on malformed content.
[[nodiscard]] AssembledModel parse_calculix_matrices(const std::string& stiffness, const std::string& mass,
                                                     const std::string& dofs, const std::string& source);

/// The first `count` natural frequencies [cycles per time unit of the deck: Hz in SI or N-mm-t-s]
/// of the model as CalculiX's own eigensolver computes them (a "*FREQUENCY / count" step; ccx's
/// Lanczos/ARPACK, not wbm's), read from the eigenvalue table of its .dat file: an independent
/// reference for reduced models (LL11 Sec. 5.2, issue #15). The .dat prints 7 significant digits.
/// Throws std::invalid_argument for count < 1, std::runtime_error as assemble_with_calculix, or
/// when ccx prints fewer frequencies than asked for.
[[nodiscard]] std::vector<double> calculix_frequencies(const CalculixDeck& deck, int count,
                                                       const CalculixOptions& options = {});

/// The frequencies column (CYCLES/TIME) of the "E I G E N V A L U E   O U T P U T" table of a ccx
/// .dat text, mode 1 first. Throws std::invalid_argument ("source:line: ...") for a row whose
/// numbers do not parse or whose mode numbers are out of sequence, and when there is no table.
[[nodiscard]] std::vector<double> parse_calculix_frequencies(const std::string& dat, const std::string& source);

}  // namespace wbm::fem
