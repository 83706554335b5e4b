#include <wbm/fem/rod.hpp>

#include <cmath>
#include <numbers>
#include <stdexcept>

#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>

#include "testing.hpp"

using wbm::fem::Rod;
using wbm::fem::RodParameters;

namespace {
// Steel-like rod; the values only need to be physical.
RodParameters rod(int elements) { return {2.1e11, 7800.0, 9e-4, 1.0, elements}; }
}  // namespace

// Continuous clamped-free rod: f_n = (2n − 1) c / (4L), c = √(E/ρ). Linear elements with
// consistent mass converge at O(h²) in frequency.
TEST(Rod, FrequenciesConvergeAtSecondOrder) {
  const auto p = rod(1);
  const double c = std::sqrt(p.young_modulus / p.density);
  std::vector<double> h, err1, err3;
  for (int e : {10, 20, 40, 80}) {
    const Eigen::VectorXd f = Rod(rod(e)).natural_frequencies_hz(3);
    h.push_back(1.0 / e);
    err1.push_back(std::abs(f(0) - c / (4 * p.length)) / (c / (4 * p.length)));
    err3.push_back(std::abs(f(2) - 5 * c / (4 * p.length)) / (5 * c / (4 * p.length)));
  }
  EXPECT_NEAR(wbm::testing::observed_order(h, err1), 2.0, 0.05);
  EXPECT_NEAR(wbm::testing::observed_order(h, err3), 2.0, 0.1);
  EXPECT_LT(err1.back(), 1e-4);
}

// Published value: 20 elements, E = 210 GPa, ρ = 7800 kg/m³, L = 1 m: 1297.5 Hz [LL11 Sec. 5.1].
TEST(Rod, FirstFrequencyMatchesLaxaldeLegrand) {
  const double f1 = Rod(rod(20)).natural_frequencies_hz(1)(0);
  EXPECT_NEAR(f1, 1297.5, 0.5);
}

// Linear elements are nodally exact for a tip-loaded bar: u(x) = F x / (E S).
TEST(Rod, StaticTipLoadIsNodallyExact) {
  const auto p = rod(7);
  const Rod r(p);
  Eigen::VectorXd f = Eigen::VectorXd::Zero(r.dofs());
  f(r.tip_dof()) = 1e4;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(r.stiffness());
  const Eigen::VectorXd u = ldlt.solve(f);
  const Eigen::VectorXd exact = r.node_positions() * 1e4 / (p.young_modulus * p.area);
  EXPECT_LT((u - exact).cwiseAbs().maxCoeff(), 1e-12 * exact.maxCoeff());
}

// Consistent mass: 1ᵀ M_full 1 = ρSL; removing the clamped node's row and column removes
// ρS·le/2 twice and adds back M₀₀ = ρS·le/3, so 1ᵀ M 1 = ρSL − 2ρS·le/3.
TEST(Rod, ConsistentMassHasTheRightTotal) {
  const auto p = rod(5);
  const Rod r(p);
  const double le = p.length / p.elements;
  const double total = Eigen::MatrixXd(r.mass()).sum();
  const double expected = p.density * p.area * (p.length - 2.0 * le / 3.0);
  EXPECT_NEAR(total, expected, 1e-12 * expected);
}

TEST(Rod, RejectsNonPhysicalParameters) {
  using wbm::testing::expect_throw_with;
  auto p = rod(10);
  p.young_modulus = -1.0;
  expect_throw_with<std::invalid_argument>([&] { Rod r(p); }, {"young_modulus", "-1", "> 0"});
  p = rod(10);
  p.density = 0.0;
  expect_throw_with<std::invalid_argument>([&] { Rod r(p); }, {"density", "> 0"});
  p = rod(10);
  p.area = std::nan("");
  expect_throw_with<std::invalid_argument>([&] { Rod r(p); }, {"area", "finite"});
  p = rod(10);
  p.length = 0.0;
  expect_throw_with<std::invalid_argument>([&] { Rod r(p); }, {"length"});
  expect_throw_with<std::invalid_argument>([&] { Rod r(rod(0)); }, {"elements = 0", ">= 1"});
  expect_throw_with<std::out_of_range>([&] { (void)Rod(rod(3)).dof_of_node(0); }, {"clamped"});
}
