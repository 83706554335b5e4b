#pragma once
/// Alternating frequency/time transfer for the real Fourier basis (fourier_basis.hpp).

#include <memory>

#include <Eigen/Core>

namespace wbm::spectral {

/// Alternating frequency/time transfer [CG89] for the real Fourier basis of dimension M
/// (ordering of FourierBasis), on Q equispaced samples τ_q = q/Q, q = 0 … Q−1, Q ≥ M.
/// Coefficient matrices are n × M (row = DOF, column = basis function: the column-major view
/// of layout.hpp); sample matrices are n × Q (row = DOF, column = time sample).
///  - to_time(A)(i, q) = Σ_k A(i, k) q_k(τ_q).
///  - project(S)(i, j) = (1/Q) Σ_q q_j(τ_q) S(i, q): the Q-point rectangle rule for
///    ∫₀¹ q_j s dτ, exact for trigonometric polynomials s of degree < Q − M/2. This is the
///    weighted residual of a sampled nonlinear force [JL14 Eq. (17), f(a)].
///  - to_frequency(S): least-squares coefficients, the left inverse of to_time:
///    to_frequency(to_time(A)) = A to rounding (the Q-point Gram matrix is diagonal).
/// FFTW's r2c/c2r are unnormalized; the 1/Q factor is applied here and nowhere else.
/// Plans are made once in the constructor (FFTW_ESTIMATE; planning is not thread-safe). The
/// object owns its work buffers: use one Aft per thread. Move-only.
/// Throws std::invalid_argument if M is not a power of two ≥ 2 or Q < M.
class Aft {
 public:
  Aft(int dimension, int samples);
  ~Aft();
  Aft(Aft&&) noexcept;
  Aft& operator=(Aft&&) noexcept;
  Aft(const Aft&) = delete;
  Aft& operator=(const Aft&) = delete;

  [[nodiscard]] int dimension() const noexcept;
  [[nodiscard]] int samples() const noexcept;

  [[nodiscard]] Eigen::MatrixXd to_time(const Eigen::MatrixXd& coefficients) const;
  [[nodiscard]] Eigen::MatrixXd project(const Eigen::MatrixXd& samples) const;
  [[nodiscard]] Eigen::MatrixXd to_frequency(const Eigen::MatrixXd& samples) const;

 private:
  struct Plans;
  std::unique_ptr<Plans> plans_;
};

}  // namespace wbm::spectral
