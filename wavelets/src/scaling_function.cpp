// Scaling functions on the real line: exact Haar and B-spline, Daubechies at dyadic points by
// the eigenvector/refinement algorithm of Chen, Hwang & Shih [CHS96].
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Dense>

#include <wbm/wavelets/scaling_function.hpp>

namespace wbm::wavelets {
namespace {

[[noreturn]] void throw_no_derivative(const Family& family, int derivative, int max_derivative) {
  std::string alternative =
      family.kind == FamilyKind::Haar
          ? "use Formulation::Distributional (derivatives on the weighting function) or the "
            "delta-pair velocity of JL14 Sec. 5.2"
          : "use the connection coefficients (connection_coefficients(), Galerkin or distributional form)";
  throw std::invalid_argument(family.name() + " has no pointwise derivative of order " + std::to_string(derivative) +
                              " (largest: " + std::to_string(max_derivative) + "); " + alternative);
}

// φ^{(d)} at the integers 0 … L−1 of a Daubechies φ: eigenvector of P(i, m) = p_{2i−m} for the
// eigenvalue 2^{−d}, normalized by Σ_m (−m)^d φ^{(d)}(m) = d! [CHS96].
Eigen::VectorXd integer_values(const std::vector<double>& p, int d) {
  const int L = static_cast<int>(p.size());
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(L + 1, L);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(L + 1);
  const double two_d = std::ldexp(1.0, d);
  for (int i = 0; i < L; ++i) {
    a(i, i) += 1.0;
    for (int m = 0; m < L; ++m) {
      const int l = 2 * i - m;
      if (l >= 0 && l < L) a(i, m) -= two_d * p[static_cast<size_t>(l)];
    }
  }
  for (int m = 0; m < L; ++m) a(L, m) = std::pow(-static_cast<double>(m), d);
  rhs(L) = std::tgamma(d + 1.0);  // d!
  Eigen::VectorXd v = a.colPivHouseholderQr().solve(rhs);
  const double residual = (a * v - rhs).cwiseAbs().maxCoeff();
  if (!(residual < 1e-10)) {
    throw std::logic_error("Daubechies L = " + std::to_string(L) + ": the two-scale eigen-system for derivative " +
                           std::to_string(d) + " has no consistent solution (residual " + std::to_string(residual) + ")");
  }
  return v;
}

// Refines dyadic values of φ^{(d)} on [0, L−1] from level j to level j+1:
// φ^{(d)}(t) = 2^d Σ_l p_l φ^{(d)}(2t − l) [JL14 Eq. (32)] differentiated d times.
Eigen::VectorXd refine(const std::vector<double>& p, const Eigen::VectorXd& coarse, int level, int d) {
  const long L = static_cast<long>(p.size());
  const long step = 1L << level;  // points per unit at the coarse level
  Eigen::VectorXd fine((coarse.size() - 1) * 2 + 1);
  const double two_d = std::ldexp(1.0, d);
  for (long n = 0; n < fine.size(); ++n) {
    if (n % 2 == 0) {
      fine(n) = coarse(n / 2);
      continue;
    }
    double s = 0.0;
    for (long l = 0; l < L; ++l) {
      const long idx = n - l * step;  // 2t − l on the coarse grid
      if (idx >= 0 && idx < coarse.size()) s += p[static_cast<size_t>(l)] * coarse(idx);
    }
    fine(n) = two_d * s;
  }
  return fine;
}

}  // namespace

ScalingFunction::ScalingFunction(const Family& family, int resolution) : family_(family), resolution_(resolution) {
  if (resolution < 0 || resolution > 20) {
    throw std::invalid_argument("ScalingFunction: resolution = " + std::to_string(resolution) +
                                " must be in [0, 20] (dyadic table level; 12 is the default)");
  }
  max_derivative_ = max_pointwise_derivative(family);
  switch (family.kind) {
    case FamilyKind::Haar:
      begin_ = 0.0;
      end_ = 1.0;
      break;
    case FamilyKind::OrthogonalCubicBSpline: {
      const int k = orthogonal_cubic_bspline_coefficients().truncation;
      begin_ = -k;
      end_ = k + 4.0;
      break;
    }
    case FamilyKind::Daubechies: {
      p_ = refinement_coefficients(family);
      begin_ = 0.0;
      end_ = static_cast<double>(p_.size() - 1);
      for (int d = 0; d <= max_derivative_; ++d) tables_.push_back(dyadic_values(resolution, d));
      break;
    }
  }
}

Eigen::VectorXd ScalingFunction::dyadic_values(int level, int derivative) const {
  if (level < 0 || level > 20) {
    throw std::invalid_argument("ScalingFunction::dyadic_values: level j = " + std::to_string(level) +
                                " must be in [0, 20]");
  }
  if (derivative < 0 || derivative > max_derivative_) throw_no_derivative(family_, derivative, max_derivative_);
  const long per_unit = 1L << level;
  const long count = static_cast<long>(std::lround((end_ - begin_) * static_cast<double>(per_unit))) + 1;
  if (family_.kind == FamilyKind::Daubechies) {
    Eigen::VectorXd v = integer_values(p_, derivative);
    for (int j = 0; j < level; ++j) v = refine(p_, v, j, derivative);
    return v;
  }
  Eigen::VectorXd v(count);
  for (long n = 0; n < count; ++n) v(n) = value(begin_ + static_cast<double>(n) / static_cast<double>(per_unit), derivative);
  return v;
}

double ScalingFunction::value(double t, int derivative) const {
  if (derivative < 0 || derivative > max_derivative_) throw_no_derivative(family_, derivative, max_derivative_);
  if (std::isnan(t)) return t;
  switch (family_.kind) {
    case FamilyKind::Haar:
      return (t >= 0.0 && t < 1.0) ? 1.0 : 0.0;  // [JL14 Eq. (33)]
    case FamilyKind::OrthogonalCubicBSpline: {
      // φ(t) = Σ_k c_k B₃(t − k) [JL14 Eq. (28)]: only k ∈ (t − 4, t] contribute.
      const auto& b = orthogonal_cubic_bspline_coefficients();
      const int kmax = b.truncation;
      if (!(t > begin_ && t < end_)) return 0.0;
      const int hi = std::min(kmax, static_cast<int>(std::floor(t)));
      const int lo = std::max(-kmax, static_cast<int>(std::floor(t)) - 3);
      double s = 0.0;
      for (int k = lo; k <= hi; ++k) s += b.c[static_cast<size_t>(k + kmax)] * cubic_bspline(t - k, derivative);
      return s;
    }
    case FamilyKind::Daubechies: {
      if (!(t > begin_ && t < end_)) return 0.0;  // φ^{(d)} vanishes at both ends of its support
      const Eigen::VectorXd& table = tables_[static_cast<size_t>(derivative)];
      const double x = (t - begin_) * std::ldexp(1.0, resolution_);
      const auto i = static_cast<Eigen::Index>(std::floor(x));
      if (i >= table.size() - 1) return table(table.size() - 1);
      const double f = x - static_cast<double>(i);
      return f == 0.0 ? table(i) : (1.0 - f) * table(i) + f * table(i + 1);
    }
  }
  return 0.0;
}

}  // namespace wbm::wavelets
