#include "modal_damping_structure.hpp"

#include <cmath>

#include <Eigen/SparseCholesky>

namespace wbm::solvers::detail {

bool rayleigh_fit(const MechanicalSystem& s, double& c_m, double& c_k) {
  const auto dot = [](const Eigen::SparseMatrix<double>& a, const Eigen::SparseMatrix<double>& b) {
    return a.cwiseProduct(b).sum();
  };
  const double mm = dot(s.mass, s.mass), kk = dot(s.stiffness, s.stiffness), mk = dot(s.mass, s.stiffness);
  const double cm = dot(s.damping, s.mass), ck = dot(s.damping, s.stiffness);
  const double det = mm * kk - mk * mk;
  const double cc = dot(s.damping, s.damping);
  if (cc == 0.0) {
    c_m = c_k = 0.0;
    return true;
  }
  if (!(std::abs(det) > 1e-14 * mm * kk)) return false;  // M ∝ K: ambiguous, use the general path
  c_m = (cm * kk - ck * mk) / det;
  c_k = (ck * mm - cm * mk) / det;
  const Eigen::SparseMatrix<double> rest = s.damping - c_m * s.mass - c_k * s.stiffness;
  return std::sqrt(dot(rest, rest)) <= 1e-12 * std::sqrt(cc);
}

bool classical_damping_probe(const MechanicalSystem& s) {
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(s.mass);
  if (ldlt.info() != Eigen::Success) return false;
  const Eigen::Index n = s.mass.rows();
  for (int probe = 1; probe <= 3; ++probe) {
    Eigen::VectorXd v(n);
    for (Eigen::Index i = 0; i < n; ++i) v(i) = std::sin(static_cast<double>(probe * (i + 1)));  // fixed, not random
    const Eigen::VectorXd ckv = s.damping * ldlt.solve(s.stiffness * v).eval();
    const Eigen::VectorXd kcv = s.stiffness * ldlt.solve(s.damping * v).eval();
    if (!ckv.allFinite() || !kcv.allFinite()) return false;
    if (!((ckv - kcv).norm() <= 1e-8 * (ckv.norm() + kcv.norm()))) return false;
  }
  return true;
}

std::optional<Eigen::VectorXd> modal_damping_of(const MechanicalSystem& s, const Eigen::MatrixXd& phi) {
  const Eigen::MatrixXd d = phi.transpose() * (s.damping * phi);
  Eigen::MatrixXd off = d;
  off.diagonal().setZero();  // its norm directly: ‖D‖² − ‖diag D‖² would cancel to √eps
  if (!(off.norm() <= 1e-10 * d.norm())) return std::nullopt;
  return Eigen::VectorXd(d.diagonal());
}

}  // namespace wbm::solvers::detail
