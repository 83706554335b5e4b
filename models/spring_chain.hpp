#pragma once
/// A fixed-free chain of n unit masses tied by springs of stiffness k: mass 0 to the ground,
/// mass i to mass i − 1, with stiffness-proportional damping C = β K. The many-contact model of
/// issue #39 (a stop on each of the last n_c masses), shared by reproduce/bench_scaling and the
/// tests of the sparse contact Jacobian. M [kg] = I (n × n), K [N/m] tridiagonal with diagonal
/// 2k (k on the free end) and −k off it, C [N·s/m] = β K. Its first natural frequency is
/// f₁ = √(k) sin(π / (2 (2n + 1))) / π [Hz] (unit masses). Header-only.
/// Throws std::invalid_argument unless n ≥ 1, k > 0 and β ≥ 0 (all finite).

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/SparseCore>

#include <wbm/solvers/mechanical_system.hpp>

namespace wbm::models {

inline solvers::MechanicalSystem spring_chain(int n, double k, double beta) {
  if (n < 1 || !(k > 0.0) || !std::isfinite(k) || !(beta >= 0.0) || !std::isfinite(beta)) {
    throw std::invalid_argument("spring_chain: n = " + std::to_string(n) + ", k = " + std::to_string(k) +
                                " N/m, beta = " + std::to_string(beta) +
                                " s: need n >= 1 masses, k > 0 and beta >= 0, all finite");
  }
  std::vector<Eigen::Triplet<double>> mt, kt;
  for (int i = 0; i < n; ++i) {
    mt.emplace_back(i, i, 1.0);
    kt.emplace_back(i, i, (i + 1 < n ? 2.0 : 1.0) * k);
    if (i + 1 < n) {
      kt.emplace_back(i, i + 1, -k);
      kt.emplace_back(i + 1, i, -k);
    }
  }
  solvers::MechanicalSystem s;
  s.mass.resize(n, n);
  s.stiffness.resize(n, n);
  s.mass.setFromTriplets(mt.begin(), mt.end());
  s.stiffness.setFromTriplets(kt.begin(), kt.end());
  s.damping = beta * s.stiffness;
  return s;
}

}  // namespace wbm::models
