// Meshes from gmsh (fem/gmsh.hpp). Truths not produced by this code: the geometry's own numbers
// (the volume of a box: the consistent mass of its quadratic tetrahedra, assembled by CalculiX,
// sums to ρV; the nodes on its faces; a point embedded in a face becomes a node there), the
// Euler–Bernoulli first bending frequency of the clamped box as a slender beam (through
// Craig–Bampton), and gmsh's own
// error messages.
#include <wbm/fem/gmsh.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>
#include "scratch.hpp"

#include <wbm/fem/calculix.hpp>
#include <wbm/fem/craig_bampton.hpp>

#include "testing.hpp"

namespace fs = std::filesystem;

namespace {

const fs::path& gmsh_work() {
  static const wbm::testing::ScratchDir scratch("gmsh");
  return scratch.path();
}

fs::path write_file(const std::string& name, const std::string& text) {
  const fs::path p = gmsh_work() / name;
  std::ofstream(p) << text;
  return p;
}

// A 0.2 m × 0.02 m × 0.01 m box along x, quadratic tetrahedra of size `h` (a parameter of the
// script), with a point embedded at the centre of its x = L face as the node set TIP.
const std::string kBox = R"(SetFactory("OpenCASCADE");
If (!Exists(h)) h = 0.01; EndIf
Box(1) = {0, 0, 0, 0.2, 0.02, 0.01};
tip() = Surface In BoundingBox{0.2 - 1e-6, -1, -1, 0.2 + 1e-6, 1, 1};
Point(100) = {0.2, 0.01, 0.005};
Point{100} In Surface{tip[0]};
Physical Volume("SOLID") = {1};
Physical Point("TIP") = {100};
Mesh.CharacteristicLengthMax = h;
Mesh.ElementOrder = 2;
Mesh.SecondOrderLinear = 1;
Mesh.SaveGroupsOfNodes = 1;
)";

const std::string kBoxMaterial = "*MATERIAL, NAME=STEEL\n*ELASTIC\n210e9, 0.3\n*DENSITY\n7800.\n"
                              "*SOLID SECTION, ELSET=SOLID, MATERIAL=STEEL\n";

}  // namespace

TEST(Gmsh, MeshesABoxIntoQuadraticTetrahedraWhoseMassIsRhoV) {
  const fs::path mesh = gmsh_work() / "box.inp";
  const int written = wbm::fem::mesh_with_gmsh(write_file("box.geo", kBox), mesh, {.executable = "gmsh", .dimension = 3, .numbers = {{"h", 0.005}}});
  const auto deck = wbm::fem::read_calculix_deck(write_file("free.inp", "*INCLUDE, INPUT=box.inp\n" + kBoxMaterial));
  EXPECT_EQ(static_cast<size_t>(written), deck.nodes.size());
  ASSERT_EQ(deck.element_types.count("C3D10"), 1u);
  EXPECT_GT(deck.element_types.at("C3D10"), 100);
  EXPECT_EQ(deck.element_types.size(), 1u);  // no surface elements that CalculiX would need a material for
  const auto& tip = deck.node_set("TIP");
  ASSERT_EQ(tip.size(), 1u);  // the embedded point is a node of the mesh, at its coordinates
  EXPECT_LT((deck.nodes.at(tip[0]) - Eigen::Vector3d(0.2, 0.01, 0.005)).norm(), 1e-12);
  const auto free = wbm::fem::assemble_with_calculix(deck);
  Eigen::VectorXd ex = Eigen::VectorXd::Zero(free.mass.rows());
  for (size_t r = 0; r < free.dofs.size(); ++r) ex(static_cast<Eigen::Index>(r)) = free.dofs[r].second == 1 ? 1.0 : 0.0;
  EXPECT_NEAR(ex.dot(free.mass * ex), 7800.0 * 0.2 * 0.02 * 0.01, 1e-12 * 7800.0 * 4e-5);
}

// Clamped at x = 0 (the nodes found by their coordinates), the box's first bending mode (about
// its thin direction z) is close to Euler–Bernoulli's f = (1.8751²/2π) √(EI/(ρAL⁴)) with
// I = b t³/12: within 3 % at L/t = 20 (shear and the clamp's Poisson stiffening remain).
TEST(Gmsh, ClampedBoxBendsAtTheBeamFrequency) {
  const fs::path mesh = gmsh_work() / "box2.inp";
  (void)wbm::fem::mesh_with_gmsh(write_file("box2.geo", kBox), mesh, {.executable = "gmsh", .dimension = 3, .numbers = {{"h", 0.005}}});
  const auto raw = wbm::fem::read_calculix_deck(mesh);
  std::ostringstream root;
  root << "*NSET, NSET=ROOT\n";
  int count = 0;
  for (const auto& [id, x] : raw.nodes) {
    if (std::abs(x(0)) < 1e-12) {
      root << id << "\n";
      ++count;
    }
  }
  ASSERT_GT(count, 10);
  const auto deck = wbm::fem::read_calculix_deck(
      write_file("clamped.inp", "*INCLUDE, INPUT=box2.inp\n" + root.str() + kBoxMaterial + "*BOUNDARY\nROOT, 1, 3\n"));
  const auto model = wbm::fem::assemble_with_calculix(deck);
  ASSERT_EQ(model.mass.rows(), 3 * (static_cast<Eigen::Index>(deck.nodes.size()) - count));
  // The full model is ~12 000 DOFs: its first frequency through Craig–Bampton on the tip node
  // with 6 fixed-interface modes (sparse throughout; an upper bound converged far below 3 %).
  std::vector<int> tip;
  for (size_t r = 0; r < model.dofs.size(); ++r) {
    if (model.dofs[r].first == deck.node_set("TIP").front()) tip.push_back(static_cast<int>(r));
  }
  ASSERT_EQ(tip.size(), 3u);
  const auto cb = wbm::fem::craig_bampton(model.stiffness, model.mass, tip, 6);
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(cb.stiffness, cb.mass);
  const double f1 = std::sqrt(eig.eigenvalues()(0)) / (2.0 * std::numbers::pi);
  const double e = 210e9, rho = 7800.0, b = 0.02, t = 0.01, l = 0.2;
  const double beam = 1.8751 * 1.8751 / (2.0 * std::numbers::pi) * std::sqrt(e * b * t * t * t / 12.0 / (rho * b * t * l * l * l * l));
  EXPECT_NEAR(f1, beam, 0.03 * beam) << "Euler–Bernoulli " << beam << " Hz";
}

TEST(Gmsh, ReportsGmshsOwnErrorsAndAMissingExecutable) {
  wbm::testing::expect_throw_with<std::runtime_error>(
      [&] { (void)wbm::fem::mesh_with_gmsh(write_file("bad.geo", "Box(1) = {0, 0, 0, 1, 1, 1}\nPoint(1) = {0, 0, 0;\n"),
                                           gmsh_work() / "bad.inp"); },
      {"bad.geo: gmsh (gmsh) could not mesh it", "gmsh says:", "Error", "bad.inp.log"});
  EXPECT_FALSE(fs::exists(gmsh_work() / "bad.inp"));
  wbm::testing::expect_throw_with<std::runtime_error>(
      [&] { (void)wbm::fem::mesh_with_gmsh(write_file("ok.geo", kBox), gmsh_work() / "ok.inp", {.executable = "wbm-no-such-gmsh", .dimension = 3, .numbers = {}}); },
      {"cannot run 'wbm-no-such-gmsh'", "install gmsh (Debian gmsh)"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)wbm::fem::mesh_with_gmsh(gmsh_work() / "missing.geo", gmsh_work() / "m.inp"); }, {"missing.geo does not exist"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)wbm::fem::mesh_with_gmsh(write_file("ok2.geo", kBox), gmsh_work() / "m.inp", {.executable = "gmsh", .dimension = 4, .numbers = {}}); },
      {"GmshOptions.dimension = 4: must be 1, 2 or 3"});
}

// The options are checked before gmsh is started, each error naming the field.
TEST(Gmsh, OptionsValidateNamingTheField) {
  using wbm::fem::GmshOptions;
  EXPECT_NO_THROW(GmshOptions{}.validate());
  EXPECT_NO_THROW((GmshOptions{.executable = "gmsh", .dimension = 2, .numbers = {{"lc_2", 0.1}}}.validate()));
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [] { GmshOptions{.executable = "", .dimension = 3, .numbers = {}}.validate(); }, {"GmshOptions.executable is empty"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [] { GmshOptions{.executable = "gmsh", .dimension = 0, .numbers = {}}.validate(); },
      {"GmshOptions.dimension = 0: must be 1, 2 or 3"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [] { GmshOptions{.executable = "gmsh", .dimension = 3, .numbers = {{"2lc", 0.1}}}.validate(); },
      {"name '2lc' is not a gmsh identifier"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [] { GmshOptions{.executable = "gmsh", .dimension = 3, .numbers = {{"lc", std::nan("")}}}.validate(); },
      {"GmshOptions.numbers[lc] = nan: must be finite"});
}
