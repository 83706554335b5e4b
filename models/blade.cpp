#include "blade.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iterator>
#include <map>
#include <regex>
#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>
#include <unistd.h>

#include <wbm/fem/gmsh.hpp>

namespace wbm::models {

BladeGeometry read_blade_geometry() {
  const std::filesystem::path geo = std::filesystem::path(WBM_BLADE_DIR) / "blade.geo";
  std::ifstream in(geo);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // "name = number;" or "name = number*Pi/180;" (degrees, returned in degrees).
  auto value = [&](const std::string& name, bool degrees) {
    const std::regex assignment("(^|[;\\s])" + name + "\\s*=\\s*([0-9.eE+-]+)" + (degrees ? "\\s*\\*\\s*Pi\\s*/\\s*180" : "") + "\\s*;");
    std::smatch m;
    if (!std::regex_search(text, m, assignment)) {
      throw std::runtime_error(geo.string() + ": no assignment '" + name + " = …;' (blade geometry parameter)");
    }
    return std::stod(m[2].str());
  };
  return {value("span", false), value("c_root", false), value("c_tip", false), value("stag_root", true),
          value("stag_tip", true)};
}

Blade build_blade(const std::filesystem::path& work, double mesh_size, int tip_points) {
  namespace fs = std::filesystem;
  const fs::path source = WBM_BLADE_DIR;
  Blade b;
  auto t = std::chrono::steady_clock::now();
  b.nodes_written = fem::mesh_with_gmsh(
      source / "blade.geo", work / "blade_mesh.inp",
      {.executable = "gmsh", .dimension = 3, .numbers = {{"size", mesh_size}, {"ntip", tip_points}}});
  b.gmsh_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  // The root face z = 0 as a node set (gmsh would write surface elements with it; see README).
  const auto mesh = fem::read_calculix_deck(work / "blade_mesh.inp");
  {
    std::ofstream root(work / "root.inp");
    root << "*NSET, NSET=ROOT\n";
    for (const auto& [id, x] : mesh.nodes) {
      if (std::abs(x(2)) < 1e-9) root << id << "\n";
    }
  }
  fs::copy_file(source / "blade.inp", work / "blade.inp", fs::copy_options::overwrite_existing);
  b.deck = fem::read_calculix_deck(work / "blade.inp");
  t = std::chrono::steady_clock::now();
  b.model = fem::assemble_with_calculix(b.deck);
  b.ccx_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();

  // Tip nodes from leading to trailing edge: along the principal axis of their positions,
  // oriented towards +x (the leading edge faces −x in blade.geo).
  const auto& ids = b.deck.node_set("TIP");
  if (static_cast<int>(ids.size()) != tip_points) {
    throw std::runtime_error("blade: node set TIP has " + std::to_string(ids.size()) + " nodes, expected " +
                             std::to_string(tip_points));
  }
  Eigen::MatrixXd p(static_cast<Eigen::Index>(ids.size()), 3);
  for (size_t i = 0; i < ids.size(); ++i) p.row(static_cast<Eigen::Index>(i)) = b.deck.nodes.at(ids[i]).transpose();
  const Eigen::RowVector3d mean = p.colwise().mean();
  const Eigen::MatrixXd centred = p.rowwise() - mean;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> pca(centred.transpose() * centred);
  Eigen::Vector3d axis = pca.eigenvectors().col(2);
  if (axis(0) < 0.0) axis = -axis;
  std::vector<Eigen::Index> order(ids.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<Eigen::Index>(i);
  std::sort(order.begin(), order.end(), [&](Eigen::Index a, Eigen::Index c) { return centred.row(a).dot(axis) < centred.row(c).dot(axis); });
  std::map<std::pair<int, int>, int> row_of;
  for (size_t r = 0; r < b.model.dofs.size(); ++r) row_of[b.model.dofs[r]] = static_cast<int>(r);
  b.position.resize(p.rows(), 3);
  for (size_t k = 0; k < order.size(); ++k) {
    const int id = ids[static_cast<size_t>(order[k])];
    b.tip_nodes.push_back(id);
    b.position.row(static_cast<Eigen::Index>(k)) = p.row(order[k]);
    for (int d = 1; d <= 3; ++d) b.boundary.push_back(row_of.at({id, d}));
  }
  const Eigen::RowVector3d le = b.position.row(0), te = b.position.row(b.position.rows() - 1);
  b.chord = ((b.position.rowwise() - le) * (te - le).transpose()) / (te - le).squaredNorm();
  return b;
}

ScratchFolder::ScratchFolder(const std::string& prefix)
    : dir(std::filesystem::temp_directory_path() / (prefix + "_" + std::to_string(::getpid()))) {
  std::filesystem::create_directories(dir);
}

ScratchFolder::~ScratchFolder() {
  std::error_code ignored;
  std::filesystem::remove_all(dir, ignored);
}

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

std::vector<solvers::RigidStop> radial_stops(const Blade& blade, double gap) {
  std::vector<solvers::RigidStop> stops;
  for (int i = 0; i < static_cast<int>(blade.position.rows()); ++i) {
    const Eigen::Vector2d n = Eigen::Vector2d(blade.position(i, 1), blade.position(i, 2) + kHubRadius).normalized();
    stops.push_back({3 * i + 2, gap, {{3 * i + 1, n(0)}, {3 * i + 2, n(1)}}});
  }
  return stops;
}

}  // namespace wbm::models
