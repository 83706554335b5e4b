#include <wbm/solvers/time_basis.hpp>

#include <algorithm>
#include <charconv>
#include <cctype>
#include <stdexcept>
#include <string>

#include <wbm/wavelets/connection_coefficients.hpp>

namespace wbm::solvers {
namespace {

constexpr int kFourierUnlimited = 1000;

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

int level_of(int dimension, const std::string& name) {
  if (!spectral::is_power_of_two(dimension)) {
    throw std::invalid_argument(name + " basis: M = " + std::to_string(dimension) +
                                " must be a power of two (M = 2^J, J = 0 ... 20)");
  }
  int level = 0;
  while ((1 << level) < dimension) ++level;
  return level;
}

}  // namespace

TimeBasis::TimeBasis(int dimension, std::shared_ptr<const wavelets::PeriodizedBasis> wavelet)
    : dimension_(dimension), wavelet_(std::move(wavelet)) {}

TimeBasis TimeBasis::fourier(int dimension) {
  const spectral::FourierBasis check(dimension);  // validates M
  return {check.dimension(), nullptr};
}

TimeBasis TimeBasis::fourier_harmonics(int harmonics) {
  return fourier(spectral::FourierBasis::with_harmonics(harmonics).dimension());
}

TimeBasis TimeBasis::wavelet(const wavelets::Family& family, int dimension) {
  const int level = level_of(dimension, family.name());
  return {dimension, std::make_shared<const wavelets::PeriodizedBasis>(family, level)};
}

std::vector<std::string> TimeBasis::names() {
  return {"fourier", "haar", "db4", "db6", "db8", "db10", "db12", "db14", "db16", "db18", "db20", "bspline"};
}

TimeBasis TimeBasis::from_name(const std::string& name, int dimension) {
  const std::string s = lower(name);
  if (s == "fourier") return fourier(dimension);
  if (s == "haar") return wavelet(wavelets::Family::haar(), dimension);
  if (s == "bspline" || s == "b-spline") return wavelet(wavelets::Family::orthogonal_cubic_bspline(), dimension);
  std::string digits;
  if (s.rfind("db", 0) == 0) digits = s.substr(2);
  if (s.rfind("daubechies", 0) == 0) digits = s.substr(10);
  // from_chars, not stoi: "db13333…" out of int's range is bad input (std::invalid_argument from
  // daubechies() naming the valid L), not std::out_of_range (found by fuzz_scene, issue #19).
  if (!digits.empty() && std::all_of(digits.begin(), digits.end(), [](unsigned char c) { return std::isdigit(c); })) {
    int taps = 0;
    const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), taps);
    if (ec != std::errc() || end != digits.data() + digits.size()) {
      throw std::invalid_argument("basis '" + name.substr(0, 40) + (name.size() > 40 ? "…" : "") +
                                  "': filter length out of range; Daubechies takes L even, 4 <= L <= 20 (db4 … db20)");
    }
    return wavelet(wavelets::Family::daubechies(taps), dimension);
  }
  std::string list;
  for (const auto& n : names()) list += (list.empty() ? "" : ", ") + n;
  throw std::invalid_argument("basis '" + name + "' is unknown; valid names: " + list);
}

std::string TimeBasis::name() const { return is_fourier() ? "Fourier" : wavelet_->family().name(); }

std::string TimeBasis::key() const {
  std::string k = lower(name());
  k.erase(std::remove(k.begin(), k.end(), '-'), k.end());
  return k;
}

bool TimeBasis::same_family(const TimeBasis& other) const {
  if (dimension_ != other.dimension_ || is_fourier() != other.is_fourier()) return false;
  return is_fourier() || wavelet_->family() == other.wavelet_->family();
}

int TimeBasis::max_derivative() const { return is_fourier() ? kFourierUnlimited : wavelet_->max_derivative(); }

Eigen::MatrixXd TimeBasis::values(const Eigen::VectorXd& tau, int derivative) const {
  if (is_fourier()) return spectral::FourierBasis(dimension_).values(tau, derivative);
  return wavelet_->values(tau, derivative);
}

Eigen::MatrixXd TimeBasis::grid_values(int points, bool midpoints) const {
  if (is_fourier()) return spectral::FourierBasis(dimension_).grid_values(points, midpoints);
  if (points < 1) {
    throw std::invalid_argument("TimeBasis::grid_values(points = " + std::to_string(points) +
                                "): the number of grid points must be >= 1");
  }
  Eigen::VectorXd tau(points);
  for (int p = 0; p < points; ++p) tau(p) = (p + (midpoints ? 0.5 : 0.0)) / points;
  return wavelet_->values(tau, 0);
}

Eigen::SparseMatrix<double> TimeBasis::exact_operator(int d1, int d2) const {
  if (d1 < 0 || d2 < 0) {
    throw std::invalid_argument("TimeBasis::exact_operator: derivative orders d1 = " + std::to_string(d1) +
                                ", d2 = " + std::to_string(d2) + " must be >= 0");
  }
  if (!is_fourier()) return wavelet_->connection_matrix(d1, d2);
  if (d1 + d2 > 2) {
    throw std::invalid_argument("Fourier exact operator of order d1 + d2 = " + std::to_string(d1 + d2) +
                                ": implemented up to 2 (the order of the equation of motion)");
  }
  // ∫ q_j^{(d1)} q_k^{(d2)} = (−1)^{d1} ∫ q_j q_k^{(d1+d2)} on the circle (smooth, periodic).
  Eigen::SparseMatrix<double> a = spectral::FourierBasis(dimension_).galerkin_operator(d1 + d2);
  if (d1 % 2 == 1) a *= -1.0;
  return a;
}

}  // namespace wbm::solvers
