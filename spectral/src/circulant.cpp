#include <wbm/spectral/circulant.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <fftw3.h>

#include "fftw_plans.hpp"

namespace wbm::spectral {
namespace {

// r2c of a length-M vector: the ⌊M/2⌋ + 1 unnormalized bins.
Eigen::VectorXcd forward_transform(const Eigen::VectorXd& v) {
  const int m = static_cast<int>(v.size());
  detail::Buffers w(m);
  for (int i = 0; i < m; ++i) w.real[i] = v(i);
  fftw_execute_dft_r2c(detail::plans_for(m).forward, w.real, w.spectrum);
  Eigen::VectorXcd out(m / 2 + 1);
  for (int k = 0; k <= m / 2; ++k) out(k) = w.bin(k);
  return out;
}

// Inverse of forward_transform (c2r, normalized by 1/M).
Eigen::VectorXd backward_transform(const Eigen::VectorXcd& bins, int m) {
  detail::Buffers w(m);
  for (int k = 0; k <= m / 2; ++k) w.set_bin(k, bins(k));
  fftw_execute_dft_c2r(detail::plans_for(m).backward, w.spectrum, w.real);
  Eigen::VectorXd out(m);
  for (int i = 0; i < m; ++i) out(i) = w.real[i] / m;
  return out;
}

}  // namespace

Circulant::Circulant(Eigen::VectorXd column, Eigen::VectorXcd eigenvalues)
    : column_(std::move(column)), eigenvalues_(std::move(eigenvalues)) {}

Circulant::Circulant(const Eigen::VectorXd& first_column) : column_(first_column) {
  if (column_.size() == 0) throw std::invalid_argument("Circulant: the first column is empty (M must be >= 1)");
  if (!column_.allFinite()) throw std::invalid_argument("Circulant: the first column has a non-finite entry");
  eigenvalues_ = forward_transform(column_);
}

double Circulant::reciprocal_condition() const {
  const Eigen::VectorXd mag = eigenvalues_.cwiseAbs();
  const double top = mag.maxCoeff();
  return top > 0.0 ? mag.minCoeff() / top : 0.0;
}

Circulant Circulant::inverse() const {
  if (!(eigenvalues_.cwiseAbs().minCoeff() > 0.0)) {
    throw std::domain_error("Circulant::inverse: an eigenvalue is zero (M = " + std::to_string(dimension()) +
                            "): the matrix is singular");
  }
  const Eigen::VectorXcd inv = eigenvalues_.cwiseInverse();
  return {backward_transform(inv, dimension()), inv};
}

Eigen::MatrixXd Circulant::apply(const Eigen::MatrixXd& v, bool transposed) const {
  const int m = dimension();
  if (v.rows() != m) {
    throw std::invalid_argument("Circulant::apply: v has " + std::to_string(v.rows()) + " rows, expected M = " +
                                std::to_string(m));
  }
  Eigen::MatrixXd out(m, v.cols());
  detail::Buffers w(m);
  const auto& plans = detail::plans_for(m);
  for (Eigen::Index c = 0; c < v.cols(); ++c) {
    for (int i = 0; i < m; ++i) w.real[i] = v(i, c);
    fftw_execute_dft_r2c(plans.forward, w.real, w.spectrum);
    for (int k = 0; k <= m / 2; ++k) {
      const std::complex<double> e = transposed ? std::conj(eigenvalues_(k)) : eigenvalues_(k);
      w.set_bin(k, w.bin(k) * e);
    }
    fftw_execute_dft_c2r(plans.backward, w.spectrum, w.real);
    for (int i = 0; i < m; ++i) out(i, c) = w.real[i] / m;
  }
  return out;
}

Eigen::MatrixXd Circulant::dense() const {
  const auto m = column_.size();
  Eigen::MatrixXd a(m, m);
  for (Eigen::Index k = 0; k < m; ++k) {
    for (Eigen::Index i = 0; i < m; ++i) a(i, k) = column_((i - k + m) % m);
  }
  return a;
}

bool Circulant::is_circulant(const Eigen::MatrixXd& a, double rel_tol) {
  const auto m = a.rows();
  if (a.cols() != m || m == 0) return false;
  const double tol = rel_tol * a.cwiseAbs().maxCoeff();
  for (Eigen::Index k = 0; k < m; ++k) {
    for (Eigen::Index i = 0; i < m; ++i) {
      if (!(std::abs(a(i, k) - a((i - k + m) % m, 0)) <= tol)) return false;
    }
  }
  return true;
}

}  // namespace wbm::spectral
