#include <wbm/spectral/aft.hpp>

#include <stdexcept>
#include <string>

#include <fftw3.h>

#include <wbm/spectral/fourier_basis.hpp>

namespace wbm::spectral {

// One RAII holder for the two FFTW plans and their aligned buffers.
struct Aft::Plans {
  int dimension;
  int samples;
  double* real = nullptr;             // Q samples
  fftw_complex* spectrum = nullptr;   // Q/2 + 1 bins
  fftw_plan forward = nullptr;        // r2c: real -> spectrum
  fftw_plan backward = nullptr;       // c2r: spectrum -> real (destroys spectrum)

  Plans(int m, int q) : dimension(m), samples(q) {
    real = fftw_alloc_real(static_cast<size_t>(q));
    spectrum = fftw_alloc_complex(static_cast<size_t>(q / 2 + 1));
    if (real == nullptr || spectrum == nullptr) throw std::bad_alloc();
    forward = fftw_plan_dft_r2c_1d(q, real, spectrum, FFTW_ESTIMATE);
    backward = fftw_plan_dft_c2r_1d(q, spectrum, real, FFTW_ESTIMATE);
  }
  ~Plans() {
    fftw_destroy_plan(forward);
    fftw_destroy_plan(backward);
    fftw_free(real);
    fftw_free(spectrum);
  }
  Plans(const Plans&) = delete;
  Plans& operator=(const Plans&) = delete;

  // Σ_m Y_m e^{2πimq/Q} (Hermitian) equals Σ_k a_k q_k(τ_q) for
  // Y_0 = a_0, Y_m = (a_cos − i a_sin)/2, and for the last function cos πMτ:
  // Y_{M/2} = a/2, or a when M/2 is FFTW's Nyquist bin (Q = M), which c2r counts once.
  void coefficients_to_samples(const double* a, Eigen::Index stride, double* out) {
    const int half = dimension / 2;
    for (int m = 0; m <= samples / 2; ++m) spectrum[m][0] = spectrum[m][1] = 0.0;
    spectrum[0][0] = a[0];
    for (int m = 1; m < half; ++m) {
      spectrum[m][0] = 0.5 * a[(2 * m - 1) * stride];
      spectrum[m][1] = -0.5 * a[(2 * m) * stride];
    }
    spectrum[half][0] = (2 * half == samples ? 1.0 : 0.5) * a[(dimension - 1) * stride];
    fftw_execute(backward);
    for (int q = 0; q < samples; ++q) out[q] = real[q];
  }

  // (1/Q) Σ_q q_j(τ_q) s_q from the unnormalized r2c output X_m = Σ_q s_q e^{−2πimq/Q}:
  // constant Re X_0/Q, cos m: Re X_m/Q, sin m: −Im X_m/Q, cos πMτ: Re X_{M/2}/Q.
  void samples_to_projection(const double* s, Eigen::Index stride, double* out_row,
                             Eigen::Index out_stride) {
    for (int q = 0; q < samples; ++q) real[q] = s[q * stride];
    fftw_execute(forward);
    const double inv_q = 1.0 / samples;
    const int half = dimension / 2;
    out_row[0] = spectrum[0][0] * inv_q;
    for (int m = 1; m < half; ++m) {
      out_row[(2 * m - 1) * out_stride] = spectrum[m][0] * inv_q;
      out_row[(2 * m) * out_stride] = -spectrum[m][1] * inv_q;
    }
    out_row[(dimension - 1) * out_stride] = spectrum[half][0] * inv_q;
  }
};

Aft::Aft(int dimension, int samples) {
  if (dimension < 2 || !is_power_of_two(dimension)) {
    throw std::invalid_argument("Aft(M = " + std::to_string(dimension) +
                                "): M must be a power of two >= 2");
  }
  if (samples < dimension) {
    throw std::invalid_argument("Aft(M = " + std::to_string(dimension) + ", Q = " +
                                std::to_string(samples) +
                                "): Q must be >= M; use Q >= 2M to avoid aliasing of the nonlinear term");
  }
  plans_ = std::make_unique<Plans>(dimension, samples);
}

Aft::~Aft() = default;
Aft::Aft(Aft&&) noexcept = default;
Aft& Aft::operator=(Aft&&) noexcept = default;

int Aft::dimension() const noexcept { return plans_->dimension; }
int Aft::samples() const noexcept { return plans_->samples; }

Eigen::MatrixXd Aft::to_time(const Eigen::MatrixXd& coefficients) const {
  if (coefficients.cols() != plans_->dimension) {
    throw std::invalid_argument("Aft::to_time: coefficients have " +
                                std::to_string(coefficients.cols()) + " columns, expected M = " +
                                std::to_string(plans_->dimension));
  }
  // Work on rows: copy each row contiguous, then write the Q samples into a row-major buffer.
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> out(
      coefficients.rows(), plans_->samples);
  for (Eigen::Index i = 0; i < coefficients.rows(); ++i) {
    plans_->coefficients_to_samples(coefficients.data() + i, coefficients.rows(),
                                    out.row(i).data());
  }
  return out;
}

Eigen::MatrixXd Aft::project(const Eigen::MatrixXd& samples) const {
  if (samples.cols() != plans_->samples) {
    throw std::invalid_argument("Aft::project: samples have " + std::to_string(samples.cols()) +
                                " columns, expected Q = " + std::to_string(plans_->samples));
  }
  Eigen::MatrixXd out(samples.rows(), plans_->dimension);
  for (Eigen::Index i = 0; i < samples.rows(); ++i) {
    plans_->samples_to_projection(samples.data() + i, samples.rows(), out.data() + i, out.rows());
  }
  return out;
}

Eigen::MatrixXd Aft::to_frequency(const Eigen::MatrixXd& samples) const {
  Eigen::MatrixXd a = project(samples);
  // Divide by the Q-point Gram matrix diag(1, ½, …, ½, g_last), g_last = 1 if Q = M else ½.
  const int m = plans_->dimension;
  a.middleCols(1, m - 2) *= 2.0;
  if (plans_->samples > m) a.col(m - 1) *= 2.0;
  return a;
}

}  // namespace wbm::spectral
