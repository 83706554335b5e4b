// KroneckerFactorization (kronecker_factorization.hpp), the compliance's structured forms: H v by
// the kept circulant blocks or Fourier-weighting cores, and the dense H formed from the circulant
// blocks only where it is read (issue #39).
#include "kronecker_compliance.hpp"

#include <stdexcept>

#include <wbm/spectral/circulant.hpp>

namespace wbm::solvers::detail {

bool KroneckerFactorization::circulant_compliance() const {
  return compliance_structure_ && !compliance_structure_->circulant.empty();
}

Eigen::MatrixXd KroneckerFactorization::dense_circulant_compliance() const {
  if (!circulant_compliance()) {
    throw std::logic_error("KroneckerFactorization::dense_circulant_compliance: no circulant blocks kept");
  }
  const ComplianceStructure& cs = *compliance_structure_;
  const int nc = cs.contacts;
  const Eigen::Index m = cs.circulant.front().dimension();
  Eigen::MatrixXd h(nc * m, nc * m);  // every entry written, column by column
  for (Eigen::Index l = 0; l < m; ++l) {
    for (int d = 0; d < nc; ++d) {
      double* column = h.col(l * nc + d).data();
      for (int c = 0; c < nc; ++c) {
        const Eigen::VectorXd& first = cs.circulant[static_cast<size_t>(c * nc + d)].first_column();
        for (Eigen::Index k = 0; k < l; ++k) column[k * nc + c] = first(k - l + m);
        for (Eigen::Index k = l; k < m; ++k) column[k * nc + c] = first(k - l);
      }
    }
  }
  return h;
}

Eigen::Index KroneckerFactorization::circulant_compliance_nonzeros() const {
  if (!circulant_compliance()) {
    throw std::logic_error("KroneckerFactorization::circulant_compliance_nonzeros: no circulant blocks kept");
  }
  Eigen::Index nonzeros = 0;
  for (const auto& block : compliance_structure_->circulant) {
    nonzeros += (block.first_column().array() != 0.0).count() * block.dimension();
  }
  return nonzeros;
}

Eigen::MatrixXd KroneckerFactorization::compliance_product(const Eigen::MatrixXd& v) const {
  const ComplianceStructure& cs = *compliance_structure_;
  const int nc = cs.contacts;
  const Eigen::Index m = v.rows() / std::max(nc, 1);
  // Rows of contact d (k·n_c + d), M × columns; with one contact, v itself.
  const auto rows_of = [&](int d) {
    if (nc == 1) return Eigen::MatrixXd(v);
    Eigen::MatrixXd vd(m, v.cols());
    for (Eigen::Index k = 0; k < m; ++k) vd.row(k) = v.row(k * nc + d);
    return vd;
  };
  std::vector<Eigen::MatrixXd> vd;
  for (int d = 0; d < nc; ++d) vd.push_back(rows_of(d));
  Eigen::MatrixXd out(v.rows(), v.cols());
  if (!cs.circulant.empty()) {
    // H_c v = Σ_d C_cd v_d with every C_cd circulant: one real DFT per input contact, the sums
    // over d bin by bin (ĉ_cd,k DFT(v_d)_k), one inverse DFT per output contact: 2 n_c transforms
    // instead of 2 n_c² (the 24 stops of ll11_blade_forced's B-spline:B-spline curve: 1 152 → 48).
    std::vector<Eigen::MatrixXcd> spectra;
    spectra.reserve(static_cast<size_t>(nc));
    for (int d = 0; d < nc; ++d) spectra.push_back(spectral::real_dft_columns(vd[static_cast<size_t>(d)]));
    const Eigen::Index bins = m / 2 + 1;
    for (int c = 0; c < nc; ++c) {
      Eigen::MatrixXcd sum = Eigen::MatrixXcd::Zero(bins, v.cols());
      for (int d = 0; d < nc; ++d) {
        const Eigen::VectorXcd& eig = cs.circulant[static_cast<size_t>(c * nc + d)].eigenvalues();
        sum += eig.asDiagonal() * spectra[static_cast<size_t>(d)];
      }
      const Eigen::MatrixXd hc = spectral::inverse_real_dft_columns(sum, static_cast<int>(m));
      if (nc == 1) return hc;
      for (Eigen::Index k = 0; k < m; ++k) out.row(k * nc + c) = hc.row(k);
    }
    return out;
  }
  for (int c = 0; c < nc; ++c) {
    Eigen::MatrixXd hc = Eigen::MatrixXd::Zero(m, v.cols());
    for (int d = 0; d < nc; ++d) {
      const auto pair = static_cast<size_t>(c * nc + d);
      hc += cs.cores[pair].apply(vd[d], false);
    }
    hc = cs.fourier_weighting->shift_inverse(hc);  // A_K⁻¹ Σ_d S_cd v_d
    if (nc == 1) return hc;
    for (Eigen::Index k = 0; k < m; ++k) out.row(k * nc + c) = hc.row(k);
  }
  return out;
}

}  // namespace wbm::solvers::detail
