#pragma once
/// Time bases of the weighted-residual method [JL14 Secs. 2.4, 3]: the real Fourier basis
/// (wbm::spectral) or a periodized scaling-function basis (wbm::wavelets), behind one type so
/// that any trial:weighting pair can be assembled. τ ∈ [0, 1) is normalized time; derivatives
/// are with respect to τ.

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <wbm/spectral/fourier_basis.hpp>
#include <wbm/wavelets/periodized_basis.hpp>

namespace wbm::solvers {

/// One basis of dimension M on the circle: Fourier (ordering of spectral::FourierBasis; M = 2^J
/// with the paper's top function cos πMτ, or M = 2H + 1 for H harmonics) or the L²-orthonormal
/// periodized scaling functions φ_{J,k} of a wavelet family (M = 2^J, ordering by shift k,
/// wavelets::PeriodizedBasis). Immutable, cheap to copy.
class TimeBasis {
 public:
  /// Fourier basis of dimension M (power of two ≥ 2, or odd ≥ 3 = 2H + 1). Throws
  /// std::invalid_argument otherwise.
  [[nodiscard]] static TimeBasis fourier(int dimension);
  /// Harmonic balance as usually written: harmonics 0 … H, dimension 2H + 1, every harmonic
  /// with its sine (no undamped top function). Throws std::invalid_argument unless H ≥ 1.
  [[nodiscard]] static TimeBasis fourier_harmonics(int harmonics);
  /// Periodized scaling functions of `family` with M = `dimension` = 2^J functions.
  [[nodiscard]] static TimeBasis wavelet(const wavelets::Family& family, int dimension);
  /// By name, case-insensitive: "fourier", "haar", "db4" … "db20" (or "daubechies6" …),
  /// "bspline" (or "b-spline"). Throws std::invalid_argument naming the value and the list
  /// of valid names, or if M is not a power of two ≥ 2 (≥ 1 for wavelets).
  [[nodiscard]] static TimeBasis from_name(const std::string& name, int dimension);
  /// The names from_name accepts, for messages and `wbm bases`.
  [[nodiscard]] static std::vector<std::string> names();

  /// "Fourier", "Haar", "DB6", "B-spline" (the paper's labels).
  [[nodiscard]] std::string name() const;
  /// Lower-case identifier for files and columns: "fourier", "haar", "db6", "bspline".
  [[nodiscard]] std::string key() const;
  [[nodiscard]] int dimension() const noexcept { return dimension_; }
  [[nodiscard]] bool is_fourier() const noexcept { return wavelet_ == nullptr; }
  /// Same family (and dimension): exact Galerkin operators are then available.
  [[nodiscard]] bool same_family(const TimeBasis& other) const;
  /// The wavelet basis, or nullptr for Fourier.
  [[nodiscard]] const wavelets::PeriodizedBasis* wavelet_basis() const noexcept { return wavelet_.get(); }

  /// Largest pointwise derivative order (Fourier: unlimited, reported as 1000; wavelets:
  /// wavelets::max_pointwise_derivative: Haar 0, DB6 1, B-spline 2).
  [[nodiscard]] int max_derivative() const;
  /// Values (rows = times, columns = basis functions): V(p, k) = q_k^{(d)}(τ_p). Throws
  /// std::invalid_argument for d > max_derivative(), naming the alternative.
  [[nodiscard]] Eigen::MatrixXd values(const Eigen::VectorXd& tau, int derivative = 0) const;
  /// values(τ) on the uniform grid τ_p = (p + s/2)/P, p = 0 … P − 1 (s = 1: `midpoints`):
  /// Fourier through spectral::FourierBasis::grid_values (its arguments reduced exactly),
  /// wavelets through values(). Throws std::invalid_argument unless P ≥ 1.
  [[nodiscard]] Eigen::MatrixXd grid_values(int points, bool midpoints) const;
  /// Exact operator E(j, k) = ∫₀¹ q_j^{(d1)} q_k^{(d2)} dτ (M × M, sparse) between two functions of
  /// this basis: Fourier analytically (periodic integration by parts, (−1)^{d1} A_{d1+d2}),
  /// wavelets by connection coefficients. Throws std::invalid_argument if d1 + d2 exceeds the
  /// family's max_connection_order (Haar 0, DB6 2, B-spline 6) or 2 for Fourier.
  [[nodiscard]] Eigen::SparseMatrix<double> exact_operator(int d1, int d2) const;

 private:
  TimeBasis(int dimension, std::shared_ptr<const wavelets::PeriodizedBasis> wavelet);
  int dimension_;
  std::shared_ptr<const wavelets::PeriodizedBasis> wavelet_;  // null: Fourier
};

}  // namespace wbm::solvers
