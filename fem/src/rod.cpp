#include <wbm/fem/rod.hpp>

#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>

namespace wbm::fem {
namespace {

void require_positive(const char* field, double value, const char* unit) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    std::ostringstream os;
    os << "RodParameters." << field << " = " << value << " " << unit
       << ": must be finite and > 0";
    throw std::invalid_argument(os.str());
  }
}

}  // namespace

void RodParameters::validate() const {
  require_positive("young_modulus", young_modulus, "Pa");
  require_positive("density", density, "kg/m^3");
  require_positive("area", area, "m^2");
  require_positive("length", length, "m");
  if (elements < 1) {
    throw std::invalid_argument("RodParameters.elements = " + std::to_string(elements) +
                                ": must be >= 1");
  }
}

Rod::Rod(const RodParameters& parameters) : parameters_(parameters) {
  parameters_.validate();
  const int n = parameters_.elements;
  const double le = parameters_.length / n;
  const double m0 = parameters_.density * parameters_.area * le / 6.0;
  const double k0 = parameters_.young_modulus * parameters_.area / le;
  std::vector<Eigen::Triplet<double>> tm, tk;
  // Element e joins nodes e and e+1; node j has DOF j−1; node 0 is clamped.
  for (int e = 0; e < n; ++e) {
    const int dof[2] = {e - 1, e};
    const double me[2][2] = {{2 * m0, m0}, {m0, 2 * m0}};
    const double ke[2][2] = {{k0, -k0}, {-k0, k0}};
    for (int a = 0; a < 2; ++a) {
      for (int b = 0; b < 2; ++b) {
        if (dof[a] < 0 || dof[b] < 0) continue;
        tm.emplace_back(dof[a], dof[b], me[a][b]);
        tk.emplace_back(dof[a], dof[b], ke[a][b]);
      }
    }
  }
  mass_.resize(n, n);
  stiffness_.resize(n, n);
  mass_.setFromTriplets(tm.begin(), tm.end());
  stiffness_.setFromTriplets(tk.begin(), tk.end());
}

int Rod::dof_of_node(int node) const {
  if (node < 1 || node > parameters_.elements) {
    throw std::out_of_range("Rod::dof_of_node(" + std::to_string(node) +
                            "): free nodes are 1.." + std::to_string(parameters_.elements) +
                            " (node 0 is clamped)");
  }
  return node - 1;
}

Eigen::VectorXd Rod::node_positions() const {
  const int n = parameters_.elements;
  return Eigen::VectorXd::LinSpaced(n, parameters_.length / n, parameters_.length);
}

Eigen::VectorXd Rod::natural_frequencies_hz(int count) const {
  if (count < 1 || count > dofs()) {
    throw std::invalid_argument("Rod::natural_frequencies_hz(count = " + std::to_string(count) +
                                "): count must lie in [1, " + std::to_string(dofs()) + "]");
  }
  const Eigen::MatrixXd k(stiffness_);
  const Eigen::MatrixXd m(mass_);
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> solver(k, m, Eigen::EigenvaluesOnly);
  Eigen::VectorXd f = solver.eigenvalues().head(count).cwiseSqrt() / (2.0 * std::numbers::pi);
  return f;
}

}  // namespace wbm::fem
