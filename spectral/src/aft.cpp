#include <wbm/spectral/aft.hpp>

#include <cmath>
#include <complex>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include <fftw3.h>

#include <wbm/spectral/fourier_basis.hpp>

#include "fftw_plans.hpp"

namespace wbm::spectral {
namespace {

using Complex = std::complex<double>;
using detail::Buffers;
using detail::FftwPlans;
using detail::plans_for;

}  // namespace

// The shared plans of length Q and the phase factors e^{2πimδ/Q}, m = 0 … Q/2.
struct Aft::Plans {
  int dimension;
  int samples;
  double offset;
  std::vector<Complex> shift;
  fftw_plan forward;
  fftw_plan backward;

  Plans(int m, int q, double delta) : dimension(m), samples(q), offset(delta) {
    shift.resize(static_cast<size_t>(q / 2 + 1));
    for (int k = 0; k <= q / 2; ++k) shift[k] = std::polar(1.0, 2.0 * std::numbers::pi * k * delta / q);
    const FftwPlans& shared = plans_for(q);
    forward = shared.forward;
    backward = shared.backward;
  }

  // Σ_m Y_m e^{2πim(q+δ)/Q} (Hermitian) equals Σ_k a_k q_k(τ_q) for
  // Y_0 = a_0, Y_m = (a_cos − i a_sin)/2, and for the last function cos πMτ:
  // Y_{M/2} = a/2, or a when M/2 is FFTW's Nyquist bin (Q = M), which c2r counts once (and of
  // which it keeps the real part: a cos πδ (−1)^q, the samples of cos πM(q+δ)/M).
  // For M = 2H + 1 there is no top function: Y_m for m = 1 … H only (H < Q/2 since Q ≥ M).
  [[nodiscard]] bool top() const { return dimension % 2 == 0; }
  [[nodiscard]] int paired() const { return top() ? dimension / 2 - 1 : dimension / 2; }

  void coefficients_to_samples(Buffers& w, const double* a, Eigen::Index stride, double* out,
                               Eigen::Index out_stride) const {
    const int half = dimension / 2;
    for (int m = 0; m <= samples / 2; ++m) w.set_bin(m, 0.0);
    w.set_bin(0, a[0]);
    for (int m = 1; m <= paired(); ++m) {
      w.set_bin(m, 0.5 * Complex(a[(2 * m - 1) * stride], -a[(2 * m) * stride]) * shift[m]);
    }
    if (top()) w.set_bin(half, (2 * half == samples ? 1.0 : 0.5) * a[(dimension - 1) * stride] * shift[half]);
    fftw_execute_dft_c2r(backward, w.spectrum, w.real);
    for (int q = 0; q < samples; ++q) out[q * out_stride] = w.real[q];
  }

  // C_m = (1/Q) Σ_q s_q e^{−2πim(q+δ)/Q} = e^{−2πimδ/Q} X_m / Q for m = 0 … Q/2, with X the
  // unnormalized r2c output; then (1/Q) Σ_q s_q cos 2πmτ_q = Re C_m, … sin … = −Im C_m.
  void transform(Buffers& w, const double* s, Eigen::Index stride) const {
    for (int q = 0; q < samples; ++q) w.real[q] = s[q * stride];
    fftw_execute_dft_r2c(forward, w.real, w.spectrum);
    const double inv_q = 1.0 / samples;
    for (int m = 0; m <= samples / 2; ++m) w.set_bin(m, w.bin(m) * std::conj(shift[m]) * inv_q);
  }

  // C_m for any m ≥ 0 from the transformed bins: C is Q-periodic in m up to the phase,
  // C_{m} = e^{−2πimδ/Q} X_{m mod Q}/Q and X_{Q−m} = conj(X_m) for real samples.
  [[nodiscard]] Complex coefficient(const Buffers& w, int m) const {
    const int r = m % samples;
    if (r <= samples / 2) {
      const Complex unshifted = w.bin(r) * shift[r];  // e^{2πirδ/Q} C_r = X_r / Q
      return unshifted * std::polar(1.0, -2.0 * std::numbers::pi * m * offset / samples);
    }
    const Complex unshifted = std::conj(w.bin(samples - r) * shift[samples - r]);
    return unshifted * std::polar(1.0, -2.0 * std::numbers::pi * m * offset / samples);
  }

  void samples_to_projection(Buffers& w, const double* s, Eigen::Index stride, double* out_row,
                             Eigen::Index out_stride) const {
    transform(w, s, stride);
    const int half = dimension / 2;
    out_row[0] = w.spectrum[0][0];
    for (int m = 1; m <= paired(); ++m) {
      out_row[(2 * m - 1) * out_stride] = w.spectrum[m][0];
      out_row[(2 * m) * out_stride] = -w.spectrum[m][1];
    }
    if (top()) out_row[(dimension - 1) * out_stride] = w.spectrum[half][0];
  }
};

Aft::Aft(int dimension, int samples, double offset) {
  if (!is_fourier_dimension(dimension)) {
    throw std::invalid_argument("Aft(M = " + std::to_string(dimension) +
                                "): M must be a power of two >= 2 or odd >= 3 (2H + 1, H harmonics)");
  }
  if (samples < dimension) {
    throw std::invalid_argument("Aft(M = " + std::to_string(dimension) + ", Q = " +
                                std::to_string(samples) +
                                "): Q must be >= M; use Q >= 2M to avoid aliasing of the nonlinear term");
  }
  if (!(offset >= 0.0 && offset < 1.0)) {
    throw std::invalid_argument("Aft: sample offset delta = " + std::to_string(offset) +
                                " must be in [0, 1) (0: tau_q = q/Q, 0.5: midpoints (q + 1/2)/Q)");
  }
  plans_ = std::make_unique<Plans>(dimension, samples, offset);
}

Aft::~Aft() = default;
Aft::Aft(Aft&&) noexcept = default;
Aft& Aft::operator=(Aft&&) noexcept = default;

int Aft::dimension() const noexcept { return plans_->dimension; }
int Aft::samples() const noexcept { return plans_->samples; }
double Aft::offset() const noexcept { return plans_->offset; }

Eigen::MatrixXd Aft::to_time(const Eigen::MatrixXd& coefficients) const {
  if (coefficients.cols() != plans_->dimension) {
    throw std::invalid_argument("Aft::to_time: coefficients have " +
                                std::to_string(coefficients.cols()) + " columns, expected M = " +
                                std::to_string(plans_->dimension));
  }
  Eigen::MatrixXd out(coefficients.rows(), plans_->samples);
  Buffers w(plans_->samples);
  for (Eigen::Index i = 0; i < coefficients.rows(); ++i) {
    plans_->coefficients_to_samples(w, coefficients.data() + i, coefficients.rows(), out.data() + i, out.rows());
  }
  return out;
}

Eigen::MatrixXd Aft::project(const Eigen::MatrixXd& samples) const {
  if (samples.cols() != plans_->samples) {
    throw std::invalid_argument("Aft::project: samples have " + std::to_string(samples.cols()) +
                                " columns, expected Q = " + std::to_string(plans_->samples));
  }
  Eigen::MatrixXd out(samples.rows(), plans_->dimension);
  Buffers w(plans_->samples);
  for (Eigen::Index i = 0; i < samples.rows(); ++i) {
    plans_->samples_to_projection(w, samples.data() + i, samples.rows(), out.data() + i, out.rows());
  }
  return out;
}

Eigen::MatrixXd Aft::to_frequency(const Eigen::MatrixXd& samples) const {
  Eigen::MatrixXd a = project(samples);
  // Divide by the Q-point Gram matrix diag(1, ½, …, ½, g_last): g_last (top function only) = ½
  // if Q > M, else the mean of cos² π(q + δ) = cos² πδ.
  const int m = plans_->dimension;
  a.middleCols(1, 2 * plans_->paired()) *= 2.0;
  if (!plans_->top()) return a;
  if (plans_->samples > m) {
    a.col(m - 1) *= 2.0;
  } else {
    const double g_last = std::pow(std::cos(std::numbers::pi * plans_->offset), 2);
    if (g_last < 1e-12) {
      throw std::domain_error("Aft::to_frequency: with Q = M = " + std::to_string(m) + " and sample offset " +
                              std::to_string(plans_->offset) +
                              " the last function cos(pi M tau) vanishes at every sample; use Q > M");
    }
    a.col(m - 1) /= g_last;
  }
  return a;
}

Eigen::MatrixXd Aft::jacobian(const Eigen::VectorXd& derivative_samples) const {
  if (derivative_samples.size() != plans_->samples) {
    throw std::invalid_argument("Aft::jacobian: " + std::to_string(derivative_samples.size()) +
                                " derivative samples, expected Q = " + std::to_string(plans_->samples));
  }
  const int m = plans_->dimension;
  Buffers w(plans_->samples);
  plans_->transform(w, derivative_samples.data(), 1);
  // c_h = (1/Q) Σ κ cos 2πhτ_q, s_h = (1/Q) Σ κ sin 2πhτ_q for h = 0 … M.
  Eigen::VectorXd c(m + 1), s(m + 1);
  for (int h = 0; h <= m; ++h) {
    const Complex z = plans_->coefficient(w, h);
    c(h) = z.real();
    s(h) = -z.imag();
  }
  // Function k is cos or sin of harmonic h_k (ordering of FourierBasis).
  const FourierBasis basis(m);
  std::vector<int> harmonic(static_cast<size_t>(m));
  std::vector<bool> sine(static_cast<size_t>(m));
  for (int k = 0; k < m; ++k) {
    harmonic[k] = basis.harmonic(k);
    sine[k] = basis.is_sine(k);
  }
  Eigen::MatrixXd jac(m, m);
  for (int k = 0; k < m; ++k) {
    const int b = harmonic[k];
    const bool sk = sine[k];
    for (int j = 0; j < m; ++j) {
      const int a = harmonic[j];
      const bool sj = sine[j];
      const int d = std::abs(a - b);
      if (!sj && !sk) {
        jac(j, k) = 0.5 * (c(d) + c(a + b));  // cos a cos b
      } else if (sj && sk) {
        jac(j, k) = 0.5 * (c(d) - c(a + b));  // sin a sin b
      } else if (!sj) {
        jac(j, k) = 0.5 * (s(a + b) + (b > a ? s(d) : -s(d)));  // cos a sin b
      } else {
        jac(j, k) = 0.5 * (s(a + b) + (a > b ? s(d) : -s(d)));  // sin a cos b
      }
    }
  }
  return jac;
}

}  // namespace wbm::spectral
