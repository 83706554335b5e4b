#pragma once
/// Alternating frequency/time transfer for the real Fourier basis (fourier_basis.hpp).

#include <memory>

#include <Eigen/Core>

namespace wbm::spectral {

/// Alternating frequency/time transfer [CG89] for the real Fourier basis of dimension M
/// (ordering of FourierBasis: M = 2^J with the top function cos πMτ, or M = 2H + 1), on Q equispaced samples τ_q = (q + δ)/Q, q = 0 … Q−1, Q ≥ M,
/// with the offset δ ∈ [0, 1): δ = 0 samples the period's start, δ = ½ the midpoints (the
/// weighted residual's rule [JL14 Sec. 4.1], which never samples a Haar breakpoint).
/// Coefficient matrices are n × M (row = DOF, column = basis function: the column-major view
/// of layout.hpp); sample matrices are n × Q (row = DOF, column = time sample).
///  - to_time(A)(i, q) = Σ_k A(i, k) q_k(τ_q).
///  - project(S)(i, j) = (1/Q) Σ_q q_j(τ_q) S(i, q): the Q-point rectangle rule for
///    ∫₀¹ q_j s dτ, exact for trigonometric polynomials s of degree < Q − M/2. This is the
///    weighted residual of a sampled nonlinear force [JL14 Eq. (17), f(a)].
///  - to_frequency(S): least-squares coefficients, the left inverse of to_time:
///    to_frequency(to_time(A)) = A to rounding (the Q-point Gram matrix is diagonal).
///  - jacobian(κ)(j, k) = (1/Q) Σ_q q_j(τ_q) κ_q q_k(τ_q) (M × M, row = weighting function j,
///    column = trial function k): the Jacobian ∂ project(f(to_time(a)))/∂a of a pointwise
///    force f with derivative samples κ_q = f′(u(τ_q)). Products of sines and cosines are sums
///    of harmonics |m_j ± m_k| ≤ M, so one r2c transform of κ and O(M²) additions replace the
///    O(Q M²) sum ("Toeplitz plus Hankel" in the transform of κ).
/// The cost is O(Q log Q) per row (FFTW r2c/c2r; bin m is shifted by e^{±2πimδ/Q} for δ ≠ 0)
/// instead of O(QM) for the dense sample matrices. FFTW's transforms are unnormalized; the 1/Q
/// factor is applied here and nowhere else. The FFTW plans (FFTW_ESTIMATE) are made once per Q
/// per process and shared (~50 µs each time otherwise; the planner, not thread-safe, runs under a
/// mutex); the const methods execute them on their own buffers (FFTW's new-array execute), so
/// one Aft may be shared by threads. Move-only.
/// Throws std::invalid_argument if M is not a FourierBasis dimension (is_fourier_dimension),
/// Q < M or δ ∉ [0, 1).
class Aft {
 public:
  Aft(int dimension, int samples, double offset = 0.0);
  ~Aft();
  Aft(Aft&&) noexcept;
  Aft& operator=(Aft&&) noexcept;
  Aft(const Aft&) = delete;
  Aft& operator=(const Aft&) = delete;

  [[nodiscard]] int dimension() const noexcept;
  [[nodiscard]] int samples() const noexcept;
  [[nodiscard]] double offset() const noexcept;

  /// n × M → n × Q. Throws std::invalid_argument unless coefficients has M columns.
  [[nodiscard]] Eigen::MatrixXd to_time(const Eigen::MatrixXd& coefficients) const;
  /// n × Q → n × M. Throws std::invalid_argument unless samples has Q columns.
  [[nodiscard]] Eigen::MatrixXd project(const Eigen::MatrixXd& samples) const;
  /// n × Q → n × M. Throws std::domain_error when Q = M and cos πMτ vanishes at every sample
  /// (δ = ½): the coefficient of the last function is then undetermined; use Q > M.
  [[nodiscard]] Eigen::MatrixXd to_frequency(const Eigen::MatrixXd& samples) const;
  /// Q samples κ_q → M × M. Throws std::invalid_argument unless κ has Q entries.
  [[nodiscard]] Eigen::MatrixXd jacobian(const Eigen::VectorXd& derivative_samples) const;

 private:
  struct Plans;
  std::unique_ptr<Plans> plans_;
};

}  // namespace wbm::spectral
