#pragma once
// Private to wbm_solvers: a time basis sampled at the Q midpoints of the period, the operator
// that takes the weighted residual between coefficients and samples (weighted_residual_impl.hpp).

#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <mutex>
#include <numbers>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Sparse>

#include <wbm/solvers/time_basis.hpp>
#include <wbm/spectral/aft.hpp>
#include <wbm/spectral/fourier_basis.hpp>

namespace wbm::solvers::detail {

using SparseRows = Eigen::SparseMatrix<double, Eigen::RowMajor>;

// One time basis at the Q midpoints τ_q = (q + ½)/Q, V(q, k) = v_k^{(d)}(τ_q), d = 0 or 1, used
// without a dense Q × M matrix: by FFTW (spectral::Aft) for the Fourier basis, by a sparse
// row-major matrix for wavelets (compact support: O(Q · support) entries, so that the memory
// and the products grow like M, not M²).
struct SampledBasis {
  std::shared_ptr<const spectral::Aft> aft;  // Fourier
  SparseRows values;                          // wavelets (Q × M)
  Eigen::RowVectorXd top_derivative;          // Fourier, d = 1, M = 2^J: −πM sin πMτ_q (outside the span)
  Eigen::SparseMatrix<double> derivative_matrix;  // Fourier, d = 1: coefficients of the derivative
  // Harmonic selection of a weighting basis: keep(k) = 1 for a kept function, 0 for a dropped
  // one, applied to every projection (Π of WeightedResidualOptions::harmonics); empty: all kept.
  Eigen::RowVectorXd keep;
  int q = 0, m = 0, derivative = 0;
  // Fourier: the dense table of rows_at, filled once (copies and threads share it).
  struct Table {
    std::atomic<Eigen::Index> asked{0};  // rows asked for so far
    std::once_flag once;
    Eigen::MatrixXd values;
  };
  std::shared_ptr<Table> table = std::make_shared<Table>();

  SampledBasis(const TimeBasis& basis, const Eigen::VectorXd& tau, int d, std::shared_ptr<const spectral::Aft> fft)
      : q(static_cast<int>(tau.size())), m(basis.dimension()), derivative(d) {
    if (basis.is_fourier()) {
      aft = std::move(fft);
      if (d == 1) derivative_matrix = spectral::FourierBasis(m).derivative_matrix();
      if (d == 1 && m % 2 == 0) {
        top_derivative.resize(q);
        for (int r = 0; r < q; ++r) top_derivative(r) = -std::numbers::pi * m * std::sin(std::numbers::pi * m * tau(r));
      }
    } else {
      values = basis.wavelet_basis()->sparse_values(tau, d);
    }
  }

  // The functions at the samples `at` (|at| × M, dense; no selection applied), equal entry for
  // entry to basis.values(τ_at, d): for wavelets the stored sparse rows (PeriodizedBasis::values
  // densifies the same sparse_values); for Fourier the rows evaluated at τ_at until the rows asked
  // for add up to Q, then the rows of the Q × M table of basis.values(τ, d), evaluated once, if it
  // holds at most 2^22 entries (32 MB). So the table costs at most as much again as the rows
  // evaluated before it: a friction law's stick samples ask for a large share of the Q rows at
  // every Newton iteration (weighted_residual_contact.cpp), a short solve for a few rows.
  [[nodiscard]] Eigen::MatrixXd rows_at(const std::vector<int>& at, const TimeBasis& basis, const Eigen::VectorXd& tau) const {
    const auto rows = static_cast<Eigen::Index>(at.size());
    if (!aft) {
      Eigen::MatrixXd out = Eigen::MatrixXd::Zero(rows, m);
      for (Eigen::Index i = 0; i < rows; ++i) {
        for (SparseRows::InnerIterator it(values, at[static_cast<size_t>(i)]); it; ++it) out(i, it.col()) = it.value();
      }
      return out;
    }
    if (static_cast<double>(q) * m <= 4194304.0 && table->asked.fetch_add(rows) + rows >= q) {
      std::call_once(table->once, [&] { table->values = basis.values(tau, derivative); });
      Eigen::MatrixXd out(rows, m);
      for (Eigen::Index i = 0; i < rows; ++i) out.row(i) = table->values.row(at[static_cast<size_t>(i)]);
      return out;
    }
    Eigen::VectorXd t(rows);
    for (Eigen::Index i = 0; i < rows; ++i) t(i) = tau(at[static_cast<size_t>(i)]);
    return basis.values(t, derivative);
  }

  // Σ_k X(i, k) v_k^{(d)}(τ_q): n × M coefficients → n × Q samples.
  [[nodiscard]] Eigen::MatrixXd to_time(const Eigen::MatrixXd& x) const {
    if (!aft) return (values * x.transpose()).transpose();
    if (derivative == 0) return aft->to_time(x);
    // The derivative's coefficients x D (spectral::FourierBasis::derivative_matrix), and the top
    // function's derivative −πM sin πMτ (not in the basis) added on the samples.
    const Eigen::MatrixXd dx = x * derivative_matrix;
    Eigen::MatrixXd out = aft->to_time(dx);
    if (top_derivative.size() > 0) out += x.col(m - 1) * top_derivative;
    return out;
  }

  // (1/Q) Σ_q S(i, q) v_j^{(d)}(τ_q): n × Q samples → n × M (the Q-point rule for ∫ v_j s dτ).
  // With a selection, only the kept functions' projections (the others 0).
  [[nodiscard]] Eigen::MatrixXd project(const Eigen::MatrixXd& s) const {
    Eigen::MatrixXd out = unselected_projection(s);
    if (keep.size() > 0) out *= keep.asDiagonal();
    return out;
  }
  // The projection on every function, selection or not.
  [[nodiscard]] Eigen::MatrixXd unselected_projection(const Eigen::MatrixXd& s) const {
    if (aft && derivative == 0) return aft->project(s);
    if (aft) throw std::logic_error("SampledBasis::project: derivative samples of a Fourier basis are not projected");
    return Eigen::MatrixXd(s * values) / static_cast<double>(q);
  }

  // project() of samples that are zero but at the times `at`: S(:, at[i]) = x(:, i) (k × |at|),
  // without forming the k × Q samples for wavelets (their sparse rows at those times).
  [[nodiscard]] Eigen::MatrixXd project_at(const std::vector<int>& at, const Eigen::MatrixXd& x) const {
    if (aft) {
      Eigen::MatrixXd samples = Eigen::MatrixXd::Zero(x.rows(), q);
      for (size_t i = 0; i < at.size(); ++i) samples.col(at[i]) = x.col(static_cast<Eigen::Index>(i));
      return project(samples);
    }
    Eigen::MatrixXd out = Eigen::MatrixXd::Zero(x.rows(), m);
    for (size_t i = 0; i < at.size(); ++i) {
      for (SparseRows::InnerIterator it(values, at[i]); it; ++it) {
        out.col(it.col()) += (it.value() / q) * x.col(static_cast<Eigen::Index>(i));
      }
    }
    if (keep.size() > 0) out *= keep.asDiagonal();
    return out;
  }
};

}  // namespace wbm::solvers::detail
