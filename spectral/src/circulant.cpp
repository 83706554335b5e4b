#include <wbm/spectral/circulant.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include <fftw3.h>

#include "fftw_plans.hpp"

namespace wbm::spectral {

Eigen::MatrixXcd real_dft_columns(const Eigen::MatrixXd& x) {
  const auto m = static_cast<int>(x.rows());
  if (m == 0) throw std::invalid_argument("real_dft_columns: x has no rows (M must be >= 1)");
  Eigen::MatrixXcd out(m / 2 + 1, x.cols());
  detail::Buffers w(m);
  const auto& plans = detail::plans_for(m);
  for (Eigen::Index j = 0; j < x.cols(); ++j) {
    for (int i = 0; i < m; ++i) w.real[i] = x(i, j);
    fftw_execute_dft_r2c(plans.forward, w.real, w.spectrum);
    for (int k = 0; k <= m / 2; ++k) out(k, j) = w.bin(k);
  }
  return out;
}

Eigen::MatrixXd inverse_real_dft_columns(const Eigen::MatrixXcd& bins, int dimension) {
  if (dimension < 1 || bins.rows() != dimension / 2 + 1) {
    throw std::invalid_argument("inverse_real_dft_columns: " + std::to_string(bins.rows()) + " bins for M = " +
                                std::to_string(dimension) + "; expected M/2 + 1 (M >= 1)");
  }
  Eigen::MatrixXd out(dimension, bins.cols());
  detail::Buffers w(dimension);
  const auto& plans = detail::plans_for(dimension);
  for (Eigen::Index j = 0; j < bins.cols(); ++j) {
    for (int k = 0; k <= dimension / 2; ++k) w.set_bin(k, bins(k, j));
    fftw_execute_dft_c2r(plans.backward, w.spectrum, w.real);
    for (int i = 0; i < dimension; ++i) out(i, j) = w.real[i] / dimension;
  }
  return out;
}

Circulant::Circulant(Eigen::VectorXd column, Eigen::VectorXcd eigenvalues)
    : column_(std::move(column)), eigenvalues_(std::move(eigenvalues)) {}

Circulant::Circulant(const Eigen::VectorXd& first_column) : column_(first_column) {
  if (column_.size() == 0) throw std::invalid_argument("Circulant: the first column is empty (M must be >= 1)");
  if (!column_.allFinite()) throw std::invalid_argument("Circulant: the first column has a non-finite entry");
  eigenvalues_ = real_dft_columns(column_).col(0);
}

Circulant Circulant::from_eigenvalues(const Eigen::VectorXcd& eigenvalues, int dimension) {
  if (dimension < 1 || eigenvalues.size() != dimension / 2 + 1) {
    throw std::invalid_argument("Circulant::from_eigenvalues: " + std::to_string(eigenvalues.size()) +
                                " eigenvalues for M = " + std::to_string(dimension) + "; expected M/2 + 1 (M >= 1)");
  }
  if (!eigenvalues.allFinite()) {
    throw std::invalid_argument("Circulant::from_eigenvalues: an eigenvalue is not finite");
  }
  Eigen::VectorXcd bins = eigenvalues;
  bins(0) = bins(0).real();
  if (dimension % 2 == 0) bins(dimension / 2) = bins(dimension / 2).real();
  Eigen::VectorXd column = inverse_real_dft_columns(bins, dimension).col(0);
  return {std::move(column), std::move(bins)};
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
  return {inverse_real_dft_columns(inv, dimension()).col(0), inv};
}

Eigen::MatrixXd Circulant::apply(const Eigen::MatrixXd& v, bool transposed) const {
  const int m = dimension();
  if (v.rows() != m) {
    throw std::invalid_argument("Circulant::apply: v has " + std::to_string(v.rows()) + " rows, expected M = " +
                                std::to_string(m));
  }
  Eigen::MatrixXcd bins = real_dft_columns(v);  // DFT(C v)_m = ĉ_m DFT(v)_m
  for (int k = 0; k <= m / 2; ++k) bins.row(k) *= transposed ? std::conj(eigenvalues_(k)) : eigenvalues_(k);
  return inverse_real_dft_columns(bins, m);
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
