#pragma once
/// Meshes from gmsh (Debian gmsh): a `.geo` script meshed by the gmsh executable and written as
/// an Abaqus/CalculiX deck (`-format inp`): *NODE, *ELEMENT per entity (e.g. C3D10 for quadratic
/// tetrahedra, CPS6 for the triangles of a physical surface), *ELSET per physical group, and,
/// with `Mesh.SaveGroupsOfNodes = 1` in the script, an *NSET per physical group — the input of
/// read_calculix_deck. Units: those of the script's coordinates.

#include <filesystem>
#include <map>
#include <string>

namespace wbm::fem {

struct GmshOptions {
  std::string executable = "gmsh";       // searched on PATH
  int dimension = 3;                      // -1, -2 or -3: mesh up to this dimension
  std::map<std::string, double> numbers;  // -setnumber name value: parameters the script reads
  /// Throws std::invalid_argument naming the field, its value and the allowed range: an empty
  /// executable, dimension outside {1, 2, 3}, a number whose name is not a gmsh identifier
  /// ([A-Za-z_][A-Za-z0-9_]*) or whose value is not finite.
  void validate() const;
};

/// Runs `gmsh -<dimension> geo [-setnumber name value]… -format inp -o output` (no shell) in
/// output's folder and returns the number of nodes written (the *NODE data lines). gmsh's log is
/// kept only on failure (output + ".log"), and then `output` is removed.
/// Throws std::invalid_argument if `geo` does not exist or the options are invalid (validate()), and
/// std::runtime_error naming the script if gmsh cannot be run (install gmsh) or reports an
/// error (its "Error" lines quoted; gmsh exits 0 on many meshing errors, so the log is read) or
/// writes no nodes.
int mesh_with_gmsh(const std::filesystem::path& geo, const std::filesystem::path& output,
                   const GmshOptions& options = {});

}  // namespace wbm::fem
