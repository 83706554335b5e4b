#pragma once
/// The LL11 Sec. 5.2 blade (reproduce/blade/): gmsh mesh of blade.geo, the root node set, the
/// CalculiX model deck blade.inp, K and M assembled by ccx, the tip interface ordered from the
/// leading to the trailing edge, and its radial contact directions. Shared by reproduce/ll11_blade,
/// reproduce/ll11_blade_forced and bench/bench_reduction. SI units.

#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include <wbm/fem/calculix.hpp>
#include <wbm/solvers/nonlinear_modes.hpp>

namespace wbm::models {

struct Blade {
  fem::CalculixDeck deck;            // the model deck read back (nodes, sets, element counts)
  fem::AssembledModel model;         // K, M after the root clamp, rows (node, direction)
  int nodes_written = 0;             // by gmsh
  std::vector<int> tip_nodes;        // node numbers of the set TIP, leading edge first
  std::vector<int> boundary;         // rows of their x, y, z DOFs, node-major (3 per tip node)
  Eigen::VectorXd chord;             // chord fraction of each tip node (0: leading, 1: trailing edge)
  Eigen::MatrixXd position;          // tip node coordinates, one row per node [m]
  double gmsh_s = 0.0, ccx_s = 0.0;  // wall times
};

/// Builds the blade in `work` (a folder the caller owns): mesh size [m] and the number of tip
/// contact points are blade.geo's parameters `size` and `ntip`. Throws std::runtime_error from
/// gmsh or ccx (their messages), or if the node set TIP does not have `tip_points` nodes.
[[nodiscard]] Blade build_blade(const std::filesystem::path& work, double mesh_size, int tip_points);

/// The design inputs of blade.geo, read from its assignments (span, c_root, c_tip, stag_root,
/// stag_tip; a value is a number, or a number times Pi/180 for degrees): labels of the model for
/// reports, never typed a second time. Throws std::runtime_error naming a missing parameter.
struct BladeGeometry {
  double span = 0.0, chord_root = 0.0, chord_tip = 0.0;  // m
  double stagger_root_deg = 0.0, stagger_tip_deg = 0.0;  // from the engine axis
};
[[nodiscard]] BladeGeometry read_blade_geometry();

/// A scratch folder `<temp>/<prefix>_<pid>` for the mesh and ccx, created at construction and
/// removed on every exit path.
struct ScratchFolder {
  explicit ScratchFolder(const std::string& prefix);
  ~ScratchFolder();
  ScratchFolder(const ScratchFolder&) = delete;
  ScratchFolder& operator=(const ScratchFolder&) = delete;
  std::filesystem::path dir;
};

/// Wall time since `t` [s].
[[nodiscard]] double seconds_since(std::chrono::steady_clock::time_point t);

/// The hub radius of blade.geo: the engine axis is parallel to x at z = −hub_radius [m].
inline constexpr double kHubRadius = 0.25;

/// Exact-contact stops of the reduced model whose first 3·|tip| coordinates are the tip nodes'
/// x, y, z (Craig–Bampton with blade.boundary first): one per tip node along its radial unit
/// vector n = (0, y, z + R)/|·| from the engine axis, g = g0 − n·u, named by its z DOF.
[[nodiscard]] std::vector<solvers::RigidStop> radial_stops(const Blade& blade, double gap);

}  // namespace wbm::models
