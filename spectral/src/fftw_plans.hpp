#pragma once
// Private to wbm_spectral: FFTW work arrays and the shared r2c/c2r plans of one length, used by
// Aft (aft.cpp) and Circulant (circulant.cpp). No FFTW type leaves spectral/src.

#include <complex>
#include <map>
#include <memory>
#include <mutex>
#include <new>
#include <stdexcept>

#include <fftw3.h>

namespace wbm::spectral::detail {

// Aligned FFTW work arrays for one call (so that const methods can run concurrently with FFTW's
// new-array execute, which needs the alignment of the arrays the plans were made with).
struct Buffers {
  double* real;
  fftw_complex* spectrum;
  explicit Buffers(int q)
      : real(fftw_alloc_real(static_cast<size_t>(q))),
        spectrum(fftw_alloc_complex(static_cast<size_t>(q / 2 + 1))) {
    if (real == nullptr || spectrum == nullptr) {
      fftw_free(real);
      fftw_free(spectrum);
      throw std::bad_alloc();
    }
  }
  ~Buffers() {
    fftw_free(real);
    fftw_free(spectrum);
  }
  Buffers(const Buffers&) = delete;
  Buffers& operator=(const Buffers&) = delete;
  [[nodiscard]] std::complex<double> bin(int m) const { return {spectrum[m][0], spectrum[m][1]}; }
  void set_bin(int m, std::complex<double> z) {
    spectrum[m][0] = z.real();
    spectrum[m][1] = z.imag();
  }
};

// The r2c and c2r plans of one length Q, made once per process and shared by every user of that
// length: FFTW_ESTIMATE planning costs ~50 µs, more than a residual evaluation at M ≤ 64, and the
// weighted residual builds an Aft per frequency. The planner is not thread-safe; the mutex
// serializes it. Plans live until the process exits.
struct FftwPlans {
  fftw_plan forward = nullptr;   // r2c: real -> spectrum
  fftw_plan backward = nullptr;  // c2r: spectrum -> real (destroys spectrum)
  explicit FftwPlans(int q) {
    Buffers b(q);
    forward = fftw_plan_dft_r2c_1d(q, b.real, b.spectrum, FFTW_ESTIMATE);
    backward = fftw_plan_dft_c2r_1d(q, b.spectrum, b.real, FFTW_ESTIMATE);
    if (forward == nullptr || backward == nullptr) throw std::runtime_error("FFTW could not make a plan");
  }
  ~FftwPlans() {
    fftw_destroy_plan(forward);
    fftw_destroy_plan(backward);
  }
  FftwPlans(const FftwPlans&) = delete;
  FftwPlans& operator=(const FftwPlans&) = delete;
};

inline const FftwPlans& plans_for(int q) {
  static std::mutex mutex;
  static std::map<int, std::unique_ptr<const FftwPlans>> cache;
  const std::lock_guard<std::mutex> lock(mutex);
  auto& entry = cache[q];
  if (!entry) entry = std::make_unique<const FftwPlans>(q);
  return *entry;
}

}  // namespace wbm::spectral::detail
