// CalculiX decks and matrices (fem/calculix.hpp). Truths not produced by this code: the deck's
// own numbers (nodes, sets, element counts), the total mass ρV of a free bar (the sum of the
// consistent mass matrix over one direction), rigid-body motions in the kernel of a free K, and
// the natural frequencies CalculiX's own Lanczos *FREQUENCY step prints for the clamped bar, which
// the eigenvalues of the matrices read back must equal.
#include <wbm/fem/calculix.hpp>
#include <wbm/fem/matrix_market.hpp>

#include <cmath>
#include <algorithm>
#include <filesystem>
#include <map>
#include <set>
#include <fstream>
#include <numbers>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>
#include "scratch.hpp"

#include "testing.hpp"

namespace fs = std::filesystem;

namespace {

const fs::path& work() {
  static const wbm::testing::ScratchDir scratch("calculix");
  static const bool mesh = fs::create_directories(scratch.path() / "mesh");
  (void)mesh;
  return scratch.path();
}

fs::path write(const std::string& name, const std::string& text) {
  const fs::path p = work() / name;
  std::ofstream(p) << text;
  return p;
}

// A 1 m × 0.1 m × 0.1 m steel bar of 4 C3D8 bricks along x, its root face as the set ROOT
// (lower-case keywords: the format is case-insensitive), in mesh/bar.inp.
void write_bar_mesh() {
  std::ostringstream m;
  m << "** a bar of 4 bricks\n*node, nset=NALL\n";
  auto id = [](int i, int j, int k) { return 1 + 4 * i + 2 * j + k; };
  for (int i = 0; i <= 4; ++i) {
    for (int j = 0; j <= 1; ++j) {
      for (int k = 0; k <= 1; ++k) m << id(i, j, k) << ", " << 0.25 * i << ", " << 0.1 * j << ", " << 0.1 * k << "\n";
    }
  }
  m << "*element, type=c3d8, elset=EALL\n";
  for (int i = 0; i < 4; ++i) {
    m << i + 1 << ", " << id(i, 0, 0) << ", " << id(i + 1, 0, 0) << ", " << id(i + 1, 1, 0) << ", " << id(i, 1, 0) << ",\n"
      << id(i, 0, 1) << ", " << id(i + 1, 0, 1) << ", " << id(i + 1, 1, 1) << ", " << id(i, 1, 1) << "\n";
  }
  m << "*nset, nset=root, generate\n1, 4\n*nset, nset=TIP\n17, 18\n19, 20\n*NSET, NSET=ENDS\nroot, tip\n";
  write("mesh/bar.inp", m.str());
}

const std::string kMaterial = "*MATERIAL, NAME=STEEL\n*ELASTIC\n210e9, 0.3\n*DENSITY\n7800.\n"
                              "*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL\n";

}  // namespace

TEST(CalculixDeck, ReadsNodesSetsAndElementsThroughIncludesUpToTheFirstStep) {
  write_bar_mesh();
  const auto deck = wbm::fem::read_calculix_deck(
      write("bar.inp", "*INCLUDE, INPUT=mesh/bar.inp\n" + kMaterial +
                           "*BOUNDARY\nROOT, 1, 3\n*STEP\n*STATIC\n*NODE\n999, 0, 0, 0\n*END STEP\n"));
  EXPECT_EQ(deck.nodes.size(), 20u);  // node 999 lies in the deck's own step: not model data
  EXPECT_EQ(deck.nodes.at(20), Eigen::Vector3d(1.0, 0.1, 0.1));
  EXPECT_EQ(deck.elements(), 4);
  EXPECT_EQ(deck.element_types.at("C3D8"), 4);
  EXPECT_EQ(deck.node_set("root"), (std::vector<int>{1, 2, 3, 4}));
  EXPECT_EQ(deck.node_set("Tip"), (std::vector<int>{17, 18, 19, 20}));
  EXPECT_EQ(deck.node_set("ENDS").size(), 8u);
  EXPECT_EQ(deck.node_set("NALL").size(), 20u);
  EXPECT_EQ(deck.model_data.find("*STEP"), std::string::npos);
  EXPECT_NE(deck.model_data.find("*element, type=c3d8"), std::string::npos);
  using wbm::testing::expect_throw_with;
  expect_throw_with<std::invalid_argument>([&] { (void)deck.node_set("casing"); },
                                           {"no node set 'casing'; the deck defines: ENDS, NALL, ROOT, TIP"});
  expect_throw_with<std::invalid_argument>([&] { (void)wbm::fem::read_calculix_deck(write("b1.inp", "*NODE\n1, 0.0, abc\n")); },
                                           {"b1.inp:2: *NODE 1: coordinate 'abc' is not a number"});
  expect_throw_with<std::invalid_argument>([&] { (void)wbm::fem::read_calculix_deck(write("b2.inp", "*NSET, NSET=A\nB\n")); },
                                           {"b2.inp:2: *NSET A: 'B' is neither a node number nor a node set"});
  expect_throw_with<std::invalid_argument>([&] { (void)wbm::fem::read_calculix_deck(write("b3.inp", "*INCLUDE\n")); },
                                           {"b3.inp:1: *INCLUDE without INPUT=file"});
  expect_throw_with<std::invalid_argument>([&] { (void)wbm::fem::read_calculix_deck(write("b4.inp", "*INCLUDE, INPUT=b4.inp\n")); },
                                           {"*INCLUDE nested more than 16 deep"});
  expect_throw_with<std::runtime_error>([&] { (void)wbm::fem::read_calculix_deck(work() / "absent.inp"); },
                                        {"absent.inp: cannot open the file"});
}

// The free bar: Σ_ij M(x_i, x_j) = ρV = 78 kg per direction (a rigid translation's kinetic
// energy), and K u = 0 for the rigid translations and the rotation about x.
TEST(Calculix, AssemblesAFreeBarWithItsMassAndRigidBodyModes) {
  write_bar_mesh();
  const auto deck = wbm::fem::read_calculix_deck(write("free.inp", "*INCLUDE, INPUT=mesh/bar.inp\n" + kMaterial));
  const auto model = wbm::fem::assemble_with_calculix(deck);
  ASSERT_EQ(model.dofs.size(), 60u);  // 20 nodes × 3
  const Eigen::MatrixXd k(model.stiffness), m(model.mass);
  EXPECT_LT((k - k.transpose()).cwiseAbs().maxCoeff(), 1e-12 * k.cwiseAbs().maxCoeff());
  for (int direction = 1; direction <= 3; ++direction) {
    Eigen::VectorXd u = Eigen::VectorXd::Zero(60);
    for (size_t r = 0; r < 60; ++r) u(static_cast<Eigen::Index>(r)) = model.dofs[r].second == direction ? 1.0 : 0.0;
    EXPECT_NEAR(u.dot(m * u), 7800.0 * 1.0 * 0.1 * 0.1, 1e-9 * 78.0) << direction;
    EXPECT_LT((k * u).cwiseAbs().maxCoeff(), 1e-6 * k.cwiseAbs().maxCoeff()) << direction;
  }
  Eigen::VectorXd spin = Eigen::VectorXd::Zero(60);  // rotation about x: (0, −z, y)
  for (size_t r = 0; r < 60; ++r) {
    const auto& x = deck.nodes.at(model.dofs[r].first);
    spin(static_cast<Eigen::Index>(r)) = model.dofs[r].second == 2 ? -x(2) : model.dofs[r].second == 3 ? x(1) : 0.0;
  }
  EXPECT_LT((k * spin).cwiseAbs().maxCoeff(), 1e-6 * k.cwiseAbs().maxCoeff() * 0.1);
}

// The clamped bar: the first five frequencies of the matrices read back equal those CalculiX's
// own *FREQUENCY step (Lanczos) prints in its .dat file.
TEST(Calculix, ClampedBarFrequenciesEqualCalculixsOwnEigenSolver) {
  write_bar_mesh();
  const std::string model = "*INCLUDE, INPUT=mesh/bar.inp\n" + kMaterial + "*BOUNDARY\nROOT, 1, 3\n";
  const auto deck = wbm::fem::read_calculix_deck(write("clamped.inp", model + "*STEP\n*STATIC\n*END STEP\n"));
  const auto assembled = wbm::fem::assemble_with_calculix(deck);
  ASSERT_EQ(assembled.dofs.size(), 48u);  // the 4 root nodes removed
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(Eigen::MatrixXd(assembled.stiffness),
                                                                      Eigen::MatrixXd(assembled.mass));
  // CalculiX's own frequencies (its *FREQUENCY step, read from its .dat).
  const std::vector<double> reference = wbm::fem::calculix_frequencies(deck, 5);
  ASSERT_EQ(reference.size(), 5u);
  for (size_t i = 0; i < 5; ++i) {
    const double ours = std::sqrt(eig.eigenvalues()(static_cast<Eigen::Index>(i))) / (2.0 * std::numbers::pi);
    EXPECT_NEAR(ours, reference[i], 1e-6 * reference[i]) << "mode " << i + 1;  // .dat prints 7 digits
  }
}

// The .dat eigenvalue table as ccx (Debian calculix-ccx 2.20) printed it for the clamped bar with
// "*FREQUENCY / 3" (participation factors cut short), and malformed tables. Identities of the
// table: ω = 2πf and ω² = the eigenvalue, to the 7 printed digits.
TEST(Calculix, ParsesTheEigenvalueTableOfADatFile) {
  const std::string dat =
      "\n     E I G E N V A L U E   O U T P U T\n\n MODE NO    EIGENVALUE                       FREQUENCY   \n"
      "                                     REAL PART            IMAGINARY PART\n"
      "                           (RAD/TIME)      (CYCLES/TIME     (RAD/TIME)\n\n"
      "      1   0.9754380E+06   0.9876427E+03   0.1571882E+03   0.0000000E+00\n"
      "      2   0.9754380E+06   0.9876427E+03   0.1571882E+03   0.0000000E+00\n"
      "      3   0.2588002E+08   0.5087241E+04   0.8096595E+03   0.0000000E+00\n\n"
      "     P A R T I C I P A T I O N   F A C T O R S\n\n"
      "MODE NO.   X-COMPONENT     Y-COMPONENT     Z-COMPONENT     X-ROTATION      Y-ROTATION      Z-ROTATION\n\n"
      "      1   0.5703771E-14  -0.5840893E+00  -0.6899988E+01  -0.3157949E+00   0.5021917E+01  -0.4251091E+00\n";
  const auto f = wbm::fem::parse_calculix_frequencies(dat, "bar.dat");
  ASSERT_EQ(f.size(), 3u);
  EXPECT_EQ(f[0], 157.1882);
  EXPECT_EQ(f[2], 809.6595);
  EXPECT_NEAR(2.0 * std::numbers::pi * f[2], 5087.241, 1e-3);
  EXPECT_NEAR(std::pow(2.0 * std::numbers::pi * f[2], 2), 0.2588002e8, 1e-6 * 0.2588002e8);
  using wbm::testing::expect_throw_with;
  expect_throw_with<std::invalid_argument>([&] { (void)wbm::fem::parse_calculix_frequencies("no table\n", "x.dat"); },
                                           {"x.dat: no eigenvalue table"});
  expect_throw_with<std::invalid_argument>(
      [&] {
        (void)wbm::fem::parse_calculix_frequencies(
            "E I G E N V A L U E   O U T P U T\n 1 0.1E+01 0.1E+01 nan 0.0\n", "y.dat");
      },
      {"y.dat:2: eigenvalue row of mode 1: 'nan' is not a finite number"});
  expect_throw_with<std::invalid_argument>(
      [&] {
        (void)wbm::fem::parse_calculix_frequencies(
            "E I G E N V A L U E   O U T P U T\n 2 0.1E+01 0.1E+01 0.2E+00 0.0\n", "z.dat");
      },
      {"z.dat:2: mode 2 where mode 1 was expected"});
}

TEST(Calculix, ReportsCalculixErrorsWithTheDeckNameAndAMissingExecutable) {
  write_bar_mesh();
  const auto bad = wbm::fem::read_calculix_deck(
      write("no_material.inp", "*INCLUDE, INPUT=mesh/bar.inp\n*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL\n"));
  wbm::testing::expect_throw_with<std::runtime_error>(
      [&] { (void)wbm::fem::assemble_with_calculix(bad); },
      {"no_material.inp: CalculiX (ccx) could not assemble the model", "*ERROR reading *SOLID SECTION: nonexistent material"});
  wbm::testing::expect_throw_with<std::runtime_error>(
      [&] { (void)wbm::fem::assemble_with_calculix(bad, {.executable = "ccx-not-installed"}); },
      {"cannot run 'ccx-not-installed'", "install CalculiX (Debian calculix-ccx)"});
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)wbm::fem::parse_calculix_matrices("1 1 2.0\n1 3 1.0\n", "1 1 1.0\n", "5.1\n5.2\n", "m"); },
      {"m.sti:2: expected 'row col value' with 1 <= row, col <= 2"});
}

// The DOFs CalculiX keeps, predicted from the deck's text (free_directions), equal the .dof list
// ccx itself writes, node by node: *BOUNDARY by set over a range (the root), by node over one
// direction (17, y) and by set over one direction given as "first," with an empty last (TIP, z);
// a node on no element keeps none. An *EQUATION is recorded as a constraint keyword (ccx then
// drops its dependent DOF, which only ccx's own list shows). Shell nodes and malformed *BOUNDARY
// lines are refused with the line.
TEST(Calculix, PredictedFreeDirectionsEqualTheDofsCalculixKeeps) {
  write_bar_mesh();
  const std::string model = "*INCLUDE, INPUT=mesh/bar.inp\n*NODE\n99, 5.0, 0.0, 0.0\n" + kMaterial +
                            "*BOUNDARY\nROOT, 1, 3\n17, 2\n*boundary\nTIP, 3, , 0.0\n";
  const auto deck = wbm::fem::read_calculix_deck(write("partial.inp", model));
  const auto assembled = wbm::fem::assemble_with_calculix(deck);
  std::map<int, std::vector<int>> kept;
  for (const auto& [node, direction] : assembled.dofs) kept[node].push_back(direction);
  for (auto& [node, directions] : kept) std::sort(directions.begin(), directions.end());
  for (const auto& [node, x] : deck.nodes) {
    const auto it = kept.find(node);
    EXPECT_EQ(wbm::fem::free_directions(deck, node), it == kept.end() ? std::vector<int>{} : it->second) << node;
  }
  EXPECT_EQ(wbm::fem::free_directions(deck, 17), (std::vector<int>{1}));  // y by node, z by TIP
  EXPECT_EQ(wbm::fem::free_directions(deck, 99), std::vector<int>{});      // on no element
  EXPECT_TRUE(deck.constraint_keywords.empty());

  const auto tied = wbm::fem::read_calculix_deck(write("tied.inp", model + "*EQUATION\n2\n18, 2, 1.0, 17, 1, -1.0\n"));
  EXPECT_EQ(tied.constraint_keywords, (std::set<std::string>{"EQUATION"}));
  const auto shell = wbm::fem::read_calculix_deck(
      write("shell.inp", "*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n3, 1, 1, 0\n4, 0, 1, 0\n*ELEMENT, TYPE=S4\n1, 1, 2, 3, 4\n"));
  using wbm::testing::expect_throw_with;
  expect_throw_with<std::invalid_argument>([&] { (void)wbm::fem::free_directions(shell, 3); },
                                           {"node 3 of", "lies on S4 elements", "choose interface nodes of 3D solid elements"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)wbm::fem::read_calculix_deck(write("b5.inp", "*NODE\n1, 0, 0, 0\n*BOUNDARY\nCASING, 1, 3\n")); },
      {"b5.inp:4: *BOUNDARY: 'CASING' is neither a node number nor a node set defined before"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)wbm::fem::read_calculix_deck(write("b6.inp", "*NODE\n1, 0, 0, 0\n*BOUNDARY\n1, 3, 1\n")); },
      {"b6.inp:4: *BOUNDARY data: the last direction '1' is not a number >= the first (3)"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)wbm::fem::read_calculix_deck(write("b7.inp", "*NODE\n1, 0, 0, 0\n*BOUNDARY\n1\n")); },
      {"b7.inp:4: *BOUNDARY data: expected 'node or node set, first direction[, last direction[, value]]'"});
}

// The options are checked before ccx is started: no executable, or a work folder that is a file.
TEST(Calculix, OptionsValidateNamingTheField) {
  write_bar_mesh();
  const auto deck = wbm::fem::read_calculix_deck(
      write("valid_options.inp", "*INCLUDE, INPUT=mesh/bar.inp\n"));
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)wbm::fem::assemble_with_calculix(deck, {.executable = ""}); },
      {"CalculixOptions.executable is empty", "calculix-ccx"});
  const fs::path file = write("not_a_folder", "x\n");
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)wbm::fem::calculix_frequencies(deck, 1, {.executable = "ccx", .work_directory = file}); },
      {"CalculixOptions.work_directory = ", "not_a_folder: exists and is not a folder"});
  EXPECT_NO_THROW(wbm::fem::CalculixOptions{}.validate());
}

namespace {

// K as a Matrix Market symmetric file (lower triangle, 17 significant digits).
void write_matrix_market(const fs::path& p, const Eigen::SparseMatrix<double>& a) {
  std::ofstream out(p);
  out.precision(17);
  Eigen::Index entries = 0;
  for (Eigen::Index c = 0; c < a.outerSize(); ++c) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(a, c); it; ++it) entries += it.row() >= it.col() ? 1 : 0;
  }
  out << "%%MatrixMarket matrix coordinate real symmetric\n% written by test_calculix\n"
      << a.rows() << " " << a.cols() << " " << entries << "\n";
  for (Eigen::Index c = 0; c < a.outerSize(); ++c) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(a, c); it; ++it) {
      if (it.row() >= it.col()) out << it.row() + 1 << " " << it.col() + 1 << " " << it.value() << "\n";
    }
  }
}

}  // namespace

// Another FE code's matrices: K, M, C as Matrix Market files with a DOF map — here CalculiX's
// own .dof file for the clamped bar (its real format, "node.direction"), and the same map as
// "node, direction" lines. The model read back is ccx's, entry for entry, row for row.
TEST(MatrixMarketModel, ReadsAnFeCodesMatricesWithItsDofMap) {
  write_bar_mesh();
  const auto deck = wbm::fem::read_calculix_deck(
      write("mm.inp", "*INCLUDE, INPUT=mesh/bar.inp\n" + kMaterial + "*BOUNDARY\nROOT, 1, 3\n"));
  const fs::path dir = work() / "mm";
  fs::create_directories(dir);
  const auto ccx = wbm::fem::assemble_with_calculix(deck, {.executable = "ccx", .work_directory = dir});
  write_matrix_market(dir / "k.mtx", ccx.stiffness);
  write_matrix_market(dir / "m.mtx", ccx.mass);
  write_matrix_market(dir / "c.mtx", 1e-4 * ccx.stiffness);
  const auto a = wbm::fem::read_matrix_market_model(dir / "k.mtx", dir / "m.mtx", dir / "job.dof", dir / "c.mtx");
  EXPECT_EQ(a.dofs, ccx.dofs);
  EXPECT_EQ(Eigen::MatrixXd(a.stiffness - ccx.stiffness).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(Eigen::MatrixXd(a.mass - ccx.mass).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_LT(Eigen::MatrixXd(a.damping - 1e-4 * ccx.stiffness).cwiseAbs().maxCoeff(), 1e-15 * 1e-4 * ccx.stiffness.coeffs().cwiseAbs().maxCoeff());
  {
    std::ofstream map(dir / "map.txt");
    map << "# node, direction\n";
    for (const auto& [node, d] : ccx.dofs) map << node << ", " << d << "\n";
  }
  const auto b = wbm::fem::read_matrix_market_model(dir / "k.mtx", dir / "m.mtx", dir / "map.txt");
  EXPECT_EQ(b.dofs, ccx.dofs);
  EXPECT_EQ(b.damping.rows(), 0);  // no damping file: none
  // Refusals: a map of another model, a repeated DOF, a malformed line, a missing file.
  std::ofstream(dir / "short.txt") << "5.1\n5.2\n";
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)wbm::fem::read_matrix_market_model(dir / "k.mtx", dir / "m.mtx", dir / "short.txt"); },
      {"stiffness", "k.mtx is 48 x 48, but the DOF map", "short.txt has 2 rows"});
  std::ofstream(dir / "twice.txt") << "5.1\n5 2\n5, 1\n";
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)wbm::fem::read_matrix_market_model(dir / "k.mtx", dir / "m.mtx", dir / "twice.txt"); },
      {"twice.txt:3: node 5 direction 1 is also row 1"});
  std::ofstream(dir / "bad.txt") << "5.1\n5.7\n";
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)wbm::fem::read_matrix_market_model(dir / "k.mtx", dir / "m.mtx", dir / "bad.txt"); },
      {"bad.txt:2: expected 'node.direction'", "direction 1-6, got '5.7'"});
  wbm::testing::expect_throw_with<std::runtime_error>(
      [&] { (void)wbm::fem::read_matrix_market_model(dir / "k.mtx", dir / "m.mtx", dir / "none.txt"); },
      {"cannot read DOF map", "none.txt"});
}
