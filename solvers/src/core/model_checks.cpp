// Physical admissibility of M, C, K and the reasons a dynamic stiffness is singular
// (model_checks.hpp).
#include <wbm/solvers/model_checks.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>

#include <wbm/solvers/status.hpp>

namespace wbm::solvers {
namespace {

double largest_diagonal(const Eigen::SparseMatrix<double>& a) {
  double d = 0.0;
  for (Eigen::Index i = 0; i < a.rows(); ++i) d = std::max(d, std::abs(a.coeff(i, i)));
  return d;
}

// Negative pivots of LDLᵀ(a), or −1 if a pivot is exactly zero.
int negative_pivots(const Eigen::SparseMatrix<double>& a) {
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(a);
  if (ldlt.info() != Eigen::Success) return -1;
  const Eigen::VectorXd d = ldlt.vectorD();
  if ((d.array() == 0.0).any() || !d.allFinite()) return -1;
  return static_cast<int>((d.array() < 0.0).count());
}

}  // namespace

StiffnessInertia stiffness_inertia(const MechanicalSystem& system) {
  system.validate();
  StiffnessInertia out;
  const double k_scale = largest_diagonal(system.stiffness), m_scale = largest_diagonal(system.mass);
  if (k_scale == 0.0) {  // K = 0 (or zero diagonal): every direction with mass is a rigid-body mode
    const Eigen::SparseMatrix<double> k = system.stiffness;
    out.rigid_body = k.nonZeros() == 0 || k.coeffs().cwiseAbs().maxCoeff() == 0.0 ? system.dofs() : 0;
    out.negative = out.rigid_body == 0 ? 1 : 0;  // a zero diagonal with off-diagonal terms is indefinite
    return out;
  }
  out.sigma = 1e-12 * k_scale / std::max(m_scale, std::numeric_limits<double>::min());
  const int below_minus = negative_pivots(system.stiffness + out.sigma * system.mass);
  const int below_plus = negative_pivots(system.stiffness - out.sigma * system.mass);
  if (below_minus < 0 || below_plus < 0) {
    out.factorized = false;
    return out;
  }
  out.negative = below_minus;
  out.rigid_body = std::max(0, below_plus - below_minus);
  return out;
}

void require_physical(const MechanicalSystem& system, const std::string& what) {
  system.validate();
  const Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> llt(system.mass);
  if (llt.info() != Eigen::Success) {
    throw std::invalid_argument(what + ": M is not positive definite (Cholesky failed): a mass matrix has "
                                       "kinetic energy ½ u̇ᵀ M u̇ > 0 for every motion; check its sign and units "
                                       "(kg), or give every DOF a mass");
  }
  const StiffnessInertia inertia = stiffness_inertia(system);
  if (inertia.factorized && inertia.negative > 0) {
    throw std::invalid_argument(
        what + ": K is not positive semidefinite: K φ = ω² M φ has " + std::to_string(inertia.negative) +
        " eigenvalue(s) ω² < −" + format_number(inertia.sigma) +
        " s⁻² (a negative stiffness: the static equilibrium is unstable and no periodic response exists "
        "around it); check the sign of K and of any spring, or the assembly");
  }
}

bool dynamic_stiffness_overflows(const MechanicalSystem& system, double frequency_hz, int highest_harmonic) {
  const double w = 2.0 * std::numbers::pi * frequency_hz * std::max(1, highest_harmonic);
  return !std::isfinite(w * w * largest_diagonal(system.mass)) || !std::isfinite(w * largest_diagonal(system.damping));
}

std::string explain_singular_dynamic_stiffness(const MechanicalSystem& system, double frequency_hz,
                                               int highest_harmonic) {
  std::ostringstream os;
  if (dynamic_stiffness_overflows(system, frequency_hz, highest_harmonic)) {
    os << "(hΩ)² M overflows at f = " << format_number(frequency_hz) << " Hz with harmonics up to "
       << highest_harmonic << " (largest finite double 1.8e308): the frequency is out of any physical range";
    return os.str();
  }
  const StiffnessInertia inertia = stiffness_inertia(system);
  if (inertia.rigid_body > 0) {
    os << "K has " << inertia.rigid_body << " rigid-body mode(s) (K φ = 0 with φ ≠ 0), so the harmonic-0 block "
       << "G_0 = K is singular and the mean position is undetermined: hold the structure (a clamped DOF or a "
          "spring to ground) or let a contact hold it";
    return os.str();
  }
  if (system.dofs() > 2000) return "";
  const Eigen::MatrixXd k(system.stiffness), m(system.mass), c(system.damping);
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(k, m);
  if (es.info() != Eigen::Success) return "";
  for (Eigen::Index j = 0; j < es.eigenvalues().size(); ++j) {
    const double fj = std::sqrt(std::max(0.0, es.eigenvalues()(j))) / (2.0 * std::numbers::pi);
    const Eigen::VectorXd phi = es.eigenvectors().col(j);
    const double modal_damping = phi.dot(c * phi);  // φᵀ M φ = 1
    for (int h = 1; h <= highest_harmonic; ++h) {
      if (std::abs(h * frequency_hz - fj) <= 1e-8 * fj && std::abs(modal_damping) <= 1e-12 * fj) {
        os << "harmonic " << h << " of f = " << format_number(frequency_hz) << " Hz is the undamped natural "
           << "frequency " << format_number(fj) << " Hz of mode " << (j + 1)
           << " (φᵀCφ = 0): add damping or move the frequency";
        return os.str();
      }
    }
  }
  return "";
}

}  // namespace wbm::solvers
