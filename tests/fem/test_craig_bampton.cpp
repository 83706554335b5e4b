// Craig–Bampton reduction (fem/craig_bampton.hpp) of a 3D clamped bar assembled by CalculiX
// (8 × 2 × 2 C3D8 bricks, 216 free DOFs), interface = the 9 tip nodes (27 DOFs). Truths: the full
// model's own statics and eigenfrequencies (dense, Eigen), which the reduction must reproduce —
// statics exactly for interface loads, frequencies from above, converging as modes are added —
// and the identities Φᵀ M_ii Φ = I, symmetric positive definite K_r and M_r.
#include <wbm/fem/craig_bampton.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>
#include <unistd.h>

#include <wbm/fem/calculix.hpp>

#include "testing.hpp"

namespace fs = std::filesystem;

namespace {

struct Bar {
  wbm::fem::AssembledModel model;
  std::vector<int> tip;  // rows of the tip nodes' DOFs
};

// 1 m × 0.1 m × 0.1 m steel bar along x, clamped at x = 0.
const Bar& bar() {
  static const Bar b = [] {
    const fs::path dir = fs::temp_directory_path() / ("wbm_test_cb_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    std::ostringstream m;
    auto id = [](int i, int j, int k) { return 1 + 9 * i + 3 * j + k; };
    m << "*NODE\n";
    for (int i = 0; i <= 8; ++i)
      for (int j = 0; j <= 2; ++j)
        for (int k = 0; k <= 2; ++k) m << id(i, j, k) << ", " << 0.125 * i << ", " << 0.05 * j << ", " << 0.05 * k << "\n";
    m << "*ELEMENT, TYPE=C3D8, ELSET=EALL\n";
    int e = 1;
    for (int i = 0; i < 8; ++i)
      for (int j = 0; j < 2; ++j)
        for (int k = 0; k < 2; ++k)
          m << e++ << ", " << id(i, j, k) << ", " << id(i + 1, j, k) << ", " << id(i + 1, j + 1, k) << ", " << id(i, j + 1, k)
            << ", " << id(i, j, k + 1) << ", " << id(i + 1, j, k + 1) << ", " << id(i + 1, j + 1, k + 1) << ", "
            << id(i, j + 1, k + 1) << "\n";
    m << "*NSET, NSET=ROOT, GENERATE\n1, 9\n*NSET, NSET=TIP, GENERATE\n73, 81\n"
      << "*MATERIAL, NAME=STEEL\n*ELASTIC\n210e9, 0.3\n*DENSITY\n7800.\n*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL\n"
      << "*BOUNDARY\nROOT, 1, 3\n";
    std::ofstream(dir / "bar.inp") << m.str();
    const auto deck = wbm::fem::read_calculix_deck(dir / "bar.inp");
    Bar out{wbm::fem::assemble_with_calculix(deck), {}};
    for (size_t r = 0; r < out.model.dofs.size(); ++r) {
      if (out.model.dofs[r].first >= 73) out.tip.push_back(static_cast<int>(r));
    }
    fs::remove_all(dir);
    return out;
  }();
  return b;
}

Eigen::VectorXd full_frequencies_hz(const wbm::fem::AssembledModel& m) {
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(Eigen::MatrixXd(m.stiffness), Eigen::MatrixXd(m.mass));
  return eig.eigenvalues().cwiseSqrt() / (2.0 * std::numbers::pi);
}

}  // namespace

TEST(CraigBampton, StaticsAreExactForInterfaceLoads) {
  const auto& b = bar();
  ASSERT_EQ(b.model.dofs.size(), 216u);
  ASSERT_EQ(b.tip.size(), 27u);
  const auto r = wbm::fem::craig_bampton(b.model.stiffness, b.model.mass, b.tip, 6);
  // 1 kN down (z) on every tip node.
  Eigen::VectorXd f = Eigen::VectorXd::Zero(216);
  for (int row : b.tip) f(row) = b.model.dofs[static_cast<size_t>(row)].second == 3 ? -1e3 : 0.0;
  const Eigen::VectorXd u = Eigen::MatrixXd(b.model.stiffness).ldlt().solve(f);
  Eigen::VectorXd fr = Eigen::VectorXd::Zero(27 + 6);
  for (size_t k = 0; k < b.tip.size(); ++k) fr(static_cast<Eigen::Index>(k)) = f(b.tip[k]);
  const Eigen::VectorXd q = r.stiffness.ldlt().solve(fr);
  const Eigen::VectorXd expanded = r.expand(q);
  EXPECT_LT((expanded - u).cwiseAbs().maxCoeff(), 1e-9 * u.cwiseAbs().maxCoeff());
  EXPECT_LT(q.tail(6).cwiseAbs().maxCoeff(), 1e-9 * u.cwiseAbs().maxCoeff());  // no modal participation in statics
}

TEST(CraigBampton, FrequenciesConvergeFromAboveAsModesAreAdded) {
  const auto& b = bar();
  const Eigen::VectorXd full = full_frequencies_hz(b.model);
  double previous = INFINITY;
  for (int modes : {2, 5, 10, 20, 40}) {
    const auto r = wbm::fem::craig_bampton(b.model.stiffness, b.model.mass, b.tip, modes);
    // Identities of the reduction.
    EXPECT_LT((r.normal_modes.transpose() * Eigen::MatrixXd(Eigen::MatrixXd(b.model.mass)(r.interior, r.interior)) *
               r.normal_modes - Eigen::MatrixXd::Identity(modes, modes)).cwiseAbs().maxCoeff(), 1e-10);
    EXPECT_EQ(r.mass.llt().info(), Eigen::Success);
    EXPECT_EQ(r.stiffness.llt().info(), Eigen::Success);
    EXPECT_EQ(r.stiffness, r.stiffness.transpose());
    EXPECT_EQ(r.mass, r.mass.transpose());
    const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(r.stiffness, r.mass);
    const Eigen::VectorXd reduced = eig.eigenvalues().cwiseSqrt() / (2.0 * std::numbers::pi);
    double worst = 0.0;
    for (int k = 0; k < 5; ++k) {
      const double e = (reduced(k) - full(k)) / full(k);
      EXPECT_GT(e, -1e-10) << "mode " << k + 1 << ", " << modes << " modes";  // Rayleigh–Ritz: from above
      worst = std::max(worst, e);
    }
    EXPECT_LE(worst, previous * (1.0 + 1e-6) + 1e-12) << modes;
    previous = worst;
    if (modes == 40) {
      EXPECT_LT(worst, 1e-3);  // ≤ 0.1 % for the first five (issue #15)
    }
    std::printf("Craig-Bampton, %2d modes: worst relative error of the first 5 frequencies %.3e\n", modes, worst);
  }
}

// No interface: the reduction is the model's own first modes (Spectra on the sparse matrices),
// equal to a dense eigensolver's, and expand() returns them.
TEST(CraigBampton, WithoutAnInterfaceGivesTheFullModelsModes) {
  const auto& b = bar();
  const Eigen::VectorXd full = full_frequencies_hz(b.model);
  const auto r = wbm::fem::craig_bampton(b.model.stiffness, b.model.mass, {}, 10);
  ASSERT_EQ(r.stiffness.rows(), 10);
  EXPECT_EQ(r.constraint_modes.cols(), 0);
  for (int k = 0; k < 10; ++k) EXPECT_NEAR(r.normal_frequencies_hz(k), full(k), 1e-9 * full(k)) << "mode " << k + 1;
  // A Krylov space holding 10 Ritz pairs takes at least 10 operator applications; the count is
  // Spectra's, reported as used (reduction.json, bench_reduction).
  EXPECT_GE(r.eigensolve_operations, 10);
  EXPECT_GE(r.eigensolve_passes, 1);
  const Eigen::MatrixXd phi = r.expand(Eigen::MatrixXd::Identity(10, 10));
  const Eigen::MatrixXd k = Eigen::MatrixXd(b.model.stiffness) * phi, m = Eigen::MatrixXd(b.model.mass) * phi;
  for (int j = 0; j < 10; ++j) {
    const double w2 = std::pow(2.0 * std::numbers::pi * full(j), 2);
    EXPECT_LT((k.col(j) - w2 * m.col(j)).norm(), 1e-8 * k.col(j).norm()) << "mode " << j + 1;
  }
}

TEST(CraigBampton, RefusesBadInput) {
  const auto& b = bar();
  using wbm::testing::expect_throw_with;
  expect_throw_with<std::invalid_argument>(
      [&] { (void)wbm::fem::craig_bampton(b.model.stiffness, b.model.mass, b.tip, 189); },
      {"craig_bampton: modes = 189: must lie in [0, 189)"});
  expect_throw_with<std::invalid_argument>(
      [&] { (void)wbm::fem::craig_bampton(b.model.stiffness, b.model.mass, {0, 0}, 2); },
      {"boundary DOF 0 appears twice"});
  Eigen::SparseMatrix<double> k3(3, 3), m3(3, 3);
  k3.insert(0, 0) = 1.0;  // DOF 0 held; DOFs 1 and 2 float together
  k3.insert(1, 1) = 1.0;
  k3.insert(1, 2) = -1.0;
  k3.insert(2, 1) = -1.0;
  k3.insert(2, 2) = 1.0;
  m3.setIdentity();
  expect_throw_with<std::runtime_error>([&] { (void)wbm::fem::craig_bampton(k3, m3, {0}, 1); },
                                        {"K restricted to the interior DOFs is not positive definite"});
}
