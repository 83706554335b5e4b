#include <wbm/fem/craig_bampton.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include <Eigen/CholmodSupport>
#include <Spectra/MatOp/SparseSymMatProd.h>
#include <Spectra/SymGEigsShiftSolver.h>

namespace wbm::fem {
namespace {

// (K_ii − σ M_ii)⁻¹ v for Spectra's shift-invert mode at σ = 0, by the Cholesky factor of K_ii
// already computed for the constraint modes (one CHOLMOD supernodal factorization for both;
// Spectra's own SymShiftInvert would factorize again with a sparse LU).
class CholeskyShiftInvert {
 public:
  using Scalar = double;
  explicit CholeskyShiftInvert(const Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>>& llt, Eigen::Index n)
      : llt_(llt), n_(n) {}
  [[nodiscard]] Eigen::Index rows() const { return n_; }
  [[nodiscard]] Eigen::Index cols() const { return n_; }
  void set_shift(double sigma) {
    if (sigma != 0.0) throw std::logic_error("CholeskyShiftInvert: only the shift 0 is factorized");
  }
  void perform_op(const double* x_in, double* y_out) const {
    Eigen::Map<Eigen::VectorXd>(y_out, n_) = llt_.solve(Eigen::Map<const Eigen::VectorXd>(x_in, n_));
  }

 private:
  const Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>>& llt_;
  Eigen::Index n_;
};

Eigen::SparseMatrix<double> selection(const std::vector<int>& dofs, Eigen::Index n) {
  Eigen::SparseMatrix<double> p(static_cast<Eigen::Index>(dofs.size()), n);
  std::vector<Eigen::Triplet<double>> t;
  for (size_t i = 0; i < dofs.size(); ++i) t.emplace_back(static_cast<int>(i), dofs[i], 1.0);
  p.setFromTriplets(t.begin(), t.end());
  return p;
}

}  // namespace

Eigen::MatrixXd CraigBamptonModel::expand(const Eigen::MatrixXd& reduced) const {
  const auto nb = static_cast<Eigen::Index>(boundary.size());
  const Eigen::MatrixXd inner = constraint_modes * reduced.topRows(nb) + normal_modes * reduced.bottomRows(normal_modes.cols());
  Eigen::MatrixXd u(nb + static_cast<Eigen::Index>(interior.size()), reduced.cols());
  for (Eigen::Index r = 0; r < nb; ++r) u.row(boundary[static_cast<size_t>(r)]) = reduced.row(r);
  for (size_t r = 0; r < interior.size(); ++r) u.row(interior[r]) = inner.row(static_cast<Eigen::Index>(r));
  return u;
}

CraigBamptonModel craig_bampton(const Eigen::SparseMatrix<double>& stiffness, const Eigen::SparseMatrix<double>& mass,
                                const std::vector<int>& boundary, int modes) {
  const Eigen::Index n = stiffness.rows();
  if (stiffness.cols() != n || mass.rows() != n || mass.cols() != n) {
    throw std::invalid_argument("craig_bampton: K is " + std::to_string(n) + " x " + std::to_string(stiffness.cols()) +
                                " and M " + std::to_string(mass.rows()) + " x " + std::to_string(mass.cols()) +
                                "; both must be n x n");
  }
  CraigBamptonModel r;
  r.boundary = boundary;
  std::vector<bool> kept(static_cast<size_t>(n), false);
  for (int b : boundary) {
    if (b < 0 || b >= n) {
      throw std::invalid_argument("craig_bampton: boundary DOF " + std::to_string(b) + " outside [0, " + std::to_string(n) + ")");
    }
    if (kept[static_cast<size_t>(b)]) throw std::invalid_argument("craig_bampton: boundary DOF " + std::to_string(b) + " appears twice");
    kept[static_cast<size_t>(b)] = true;
  }
  for (Eigen::Index d = 0; d < n; ++d) {
    if (!kept[static_cast<size_t>(d)]) r.interior.push_back(static_cast<int>(d));
  }
  const auto ni = static_cast<Eigen::Index>(r.interior.size()), nb = static_cast<Eigen::Index>(boundary.size());
  if (modes < 0 || modes >= ni) {
    throw std::invalid_argument("craig_bampton: modes = " + std::to_string(modes) + ": must lie in [0, " +
                                std::to_string(ni) + ") (the interior has " + std::to_string(ni) + " DOFs)");
  }
  const Eigen::SparseMatrix<double> pb = selection(boundary, n), pi = selection(r.interior, n);
  const Eigen::SparseMatrix<double> kii = pi * stiffness * pi.transpose(), kib = pi * stiffness * pb.transpose();
  const Eigen::SparseMatrix<double> mii = pi * mass * pi.transpose(), mib = pi * mass * pb.transpose();
  const Eigen::SparseMatrix<double> kbb = pb * stiffness * pb.transpose(), mbb = pb * mass * pb.transpose();
  // Constraint modes Ψ = −K_ii⁻¹ K_ib.
  using Clock = std::chrono::steady_clock;
  auto seconds = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
  auto t = Clock::now();
  const Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>> llt(kii);
  r.factorization_s = seconds(t);
  if (llt.info() != Eigen::Success) {
    throw std::runtime_error("craig_bampton: K restricted to the interior DOFs is not positive definite (Cholesky "
                             "failed): the interface and boundary conditions must remove every rigid-body motion");
  }
  t = Clock::now();
  // No interface: no constraint modes (CHOLMOD refuses a right-hand side with no columns); the
  // reduction is then the first `modes` normal modes of the whole model.
  r.constraint_modes = nb > 0 ? Eigen::MatrixXd(-llt.solve(Eigen::MatrixXd(kib))) : Eigen::MatrixXd::Zero(ni, 0);
  r.constraint_modes_s = seconds(t);
  t = Clock::now();
  // Fixed-interface normal modes: the m eigenvalues of K_ii φ = λ M_ii φ closest to 0.
  if (modes > 0) {
    using Op = CholeskyShiftInvert;
    using BOp = Spectra::SparseSymMatProd<double>;
    Op op(llt, ni);
    BOp bop(mii);
    const Eigen::Index ncv = std::min<Eigen::Index>(ni, std::max<Eigen::Index>(2 * modes + 1, modes + 20));
    Spectra::SymGEigsShiftSolver<Op, BOp, Spectra::GEigsMode::ShiftInvert> eigs(op, bop, modes, ncv, 0.0);
    eigs.init();
    eigs.compute(Spectra::SortRule::LargestMagn, 1000, 1e-12);
    if (eigs.info() != Spectra::CompInfo::Successful) {
      throw std::runtime_error("craig_bampton: Spectra's shift-invert Lanczos did not converge for " +
                               std::to_string(modes) + " modes (status " + std::to_string(static_cast<int>(eigs.info())) +
                               "); try fewer modes");
    }
    r.eigensolve_operations = static_cast<long>(eigs.num_operations());
    r.eigensolve_passes = static_cast<long>(eigs.num_iterations());
    Eigen::VectorXd lambda = eigs.eigenvalues();
    Eigen::MatrixXd phi = eigs.eigenvectors();
    std::vector<Eigen::Index> order(static_cast<size_t>(lambda.size()));
    for (size_t k = 0; k < order.size(); ++k) order[k] = static_cast<Eigen::Index>(k);
    std::sort(order.begin(), order.end(), [&](Eigen::Index a, Eigen::Index b) { return lambda(a) < lambda(b); });
    r.normal_modes.resize(ni, modes);
    r.normal_frequencies_hz.resize(modes);
    for (int k = 0; k < modes; ++k) {
      Eigen::VectorXd v = phi.col(order[static_cast<size_t>(k)]);
      v /= std::sqrt(v.dot(mii * v));  // Φᵀ M_ii Φ = I
      r.normal_modes.col(k) = v;
      r.normal_frequencies_hz(k) = std::sqrt(std::max(lambda(order[static_cast<size_t>(k)]), 0.0)) / (2.0 * std::numbers::pi);
    }
  } else {
    r.normal_modes.resize(ni, 0);
    r.normal_frequencies_hz.resize(0);
  }
  r.eigensolve_s = seconds(t);
  t = Clock::now();
  const Eigen::MatrixXd& psi = r.constraint_modes;
  const Eigen::MatrixXd& phi = r.normal_modes;
  const Eigen::Index nr = nb + modes;
  r.stiffness = Eigen::MatrixXd::Zero(nr, nr);
  r.mass = Eigen::MatrixXd::Zero(nr, nr);
  const Eigen::MatrixXd kbi_psi = Eigen::MatrixXd(kib.transpose()) * psi;
  r.stiffness.topLeftCorner(nb, nb) = Eigen::MatrixXd(kbb) + 0.5 * (kbi_psi + kbi_psi.transpose());
  const Eigen::MatrixXd mii_phi = mii * phi;
  r.stiffness.bottomRightCorner(modes, modes) = phi.transpose() * (kii * phi);
  const Eigen::MatrixXd mii_psi = mii * psi;
  const Eigen::MatrixXd mbi_psi = Eigen::MatrixXd(mib.transpose()) * psi;
  r.mass.topLeftCorner(nb, nb) = Eigen::MatrixXd(mbb) + mbi_psi + mbi_psi.transpose() + psi.transpose() * mii_psi;
  const Eigen::MatrixXd coupling = Eigen::MatrixXd(mib.transpose()) * phi + psi.transpose() * mii_phi;
  r.mass.topRightCorner(nb, modes) = coupling;
  r.mass.bottomLeftCorner(modes, nb) = coupling.transpose();
  r.mass.bottomRightCorner(modes, modes) = phi.transpose() * mii_phi;
  r.stiffness = 0.5 * (r.stiffness + r.stiffness.transpose()).eval();
  r.mass = 0.5 * (r.mass + r.mass.transpose()).eval();
  r.assembly_s = seconds(t);
  return r;
}

}  // namespace wbm::fem
