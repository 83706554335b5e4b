// Connection coefficients: two-scale eigen-system with moment normalization for Haar and
// Daubechies [LRT91; B92], exact B-spline products for the orthogonal cubic B-spline, and the
// periodic wrapping at level J [RL93].
#include <algorithm>
#include <cmath>
#include <complex>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <gsl/gsl_integration.h>

#include <wbm/wavelets/connection_coefficients.hpp>

namespace wbm::wavelets {
namespace {

// Autocorrelation of a sequence p of length L, a_j = ½ Σ_l p_l p_{l+j}, j = −(L−1) … L−1
// (stored at j + L − 1); for refinement coefficients Σ_j a_j = 2.
std::vector<double> autocorrelation(const std::vector<double>& p) {
  const int L = static_cast<int>(p.size());
  std::vector<double> a(static_cast<size_t>(2 * L - 1), 0.0);
  for (int j = -(L - 1); j <= L - 1; ++j) {
    double s = 0.0;
    for (int l = 0; l < L; ++l) {
      if (l + j >= 0 && l + j < L) s += p[static_cast<size_t>(l)] * p[static_cast<size_t>(l + j)];
    }
    a[static_cast<size_t>(j + L - 1)] = 0.5 * s;
  }
  return a;
}

// Transfer matrix T(i, m) = a_{2i−m}, |i|, |m| ≤ n.
Eigen::MatrixXd transfer_matrix(const std::vector<double>& a, int n) {
  const int half = static_cast<int>(a.size() / 2);
  Eigen::MatrixXd t = Eigen::MatrixXd::Zero(2 * n + 1, 2 * n + 1);
  for (int i = -n; i <= n; ++i) {
    for (int m = -n; m <= n; ++m) {
      const int j = 2 * i - m;
      if (j >= -half && j <= half) t(i + n, m + n) = a[static_cast<size_t>(j + half)];
    }
  }
  return t;
}

// ρ′: spectral radius of T once one eigenvalue closest to each 2^{−m}, m = 0 … 2N−1, is removed.
double reduced_spectral_radius(const Family& family) {
  const std::vector<double> p = refinement_coefficients(family);
  const int L = static_cast<int>(p.size());
  const Eigen::MatrixXd t = transfer_matrix(autocorrelation(p), L - 1);
  const Eigen::VectorXcd ev = Eigen::EigenSolver<Eigen::MatrixXd>(t, false).eigenvalues();
  std::vector<std::complex<double>> rest(ev.data(), ev.data() + ev.size());
  for (int m = 0; m < 2 * family.vanishing_moments(); ++m) {
    const double target = std::ldexp(1.0, -m);
    const auto it = std::min_element(rest.begin(), rest.end(), [&](const auto& x, const auto& y) {
      return std::abs(x - target) < std::abs(y - target);
    });
    rest.erase(it);
  }
  double rho = 0.0;
  for (const auto& z : rest) rho = std::max(rho, std::abs(z));
  return rho;
}

ConnectionCoefficients compactly_supported(const Family& family, int d1, int d2) {
  const int d = d1 + d2;
  const std::vector<double> p = refinement_coefficients(family);
  const int L = static_cast<int>(p.size());
  const int n = L - 2;  // Γ^{0,d}[k] = 0 for |k| > L − 2
  // LRT91/B92: (2^d T − I) g = 0 with the moment rows Σ_k k^m g_k = d! δ_{md}, m = 0 … d.
  const Eigen::MatrixXd t = transfer_matrix(autocorrelation(p), n);
  const int size = 2 * n + 1;
  Eigen::MatrixXd a(size + d + 1, size);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(size + d + 1);
  a.topRows(size) = std::ldexp(1.0, d) * t - Eigen::MatrixXd::Identity(size, size);
  for (int m = 0; m <= d; ++m) {
    for (int k = -n; k <= n; ++k) a(size + m, k + n) = std::pow(static_cast<double>(k), m);
  }
  rhs(size + d) = std::tgamma(d + 1.0);  // d!
  const Eigen::VectorXd g = a.colPivHouseholderQr().solve(rhs);
  ConnectionCoefficients out;
  out.d1 = d1;
  out.d2 = d2;
  out.first_shift = -n;
  out.last_shift = n;
  out.values = ((d1 % 2 == 0) ? 1.0 : -1.0) * g;  // Γ^{d1,d2} = (−1)^{d1} Γ^{0,d}
  out.residual = (a * g - rhs).cwiseAbs().maxCoeff();
  const double scale = std::max(1.0, g.cwiseAbs().maxCoeff()) * std::pow(static_cast<double>(std::max(n, 1)), d);
  if (!(out.residual < 1e-9 * scale)) {
    throw std::logic_error("connection_coefficients(" + family.name() + ", " + std::to_string(d1) + ", " +
                           std::to_string(d2) + "): the two-scale eigen-system is inconsistent (residual " +
                           std::to_string(out.residual) + ")");
  }
  return out;
}

// β^{e1,e2}[m] = ∫ B₃^{(e1)}(t) B₃^{(e2)}(t − m) dt, m = −3 … 3, exactly: the integrand is a
// polynomial of degree ≤ 6 on each unit interval, integrated by 4-point Gauss–Legendre (GSL).
std::vector<double> bspline_products(int e1, int e2) {
  gsl_integration_glfixed_table* table = gsl_integration_glfixed_table_alloc(4);
  std::vector<double> beta(7, 0.0);
  for (int m = -3; m <= 3; ++m) {
    double s = 0.0;
    for (int u = 0; u < 4; ++u) {
      for (size_t q = 0; q < 4; ++q) {
        double x = 0.0, w = 0.0;
        gsl_integration_glfixed_point(u, u + 1.0, q, &x, &w, table);
        s += w * cubic_bspline(x, e1) * cubic_bspline(x - m, e2);
      }
    }
    beta[static_cast<size_t>(m + 3)] = s;
  }
  gsl_integration_glfixed_table_free(table);
  return beta;
}

ConnectionCoefficients bspline(int d1, int d2) {
  // Integration by parts moves derivatives so that each factor is differentiated ≤ 3 times.
  int e1 = d1, e2 = d2;
  double sign = 1.0;
  while (e1 > 3) { --e1; ++e2; sign = -sign; }
  while (e2 > 3) { --e2; ++e1; sign = -sign; }
  const BSplineCoefficients& b = orthogonal_cubic_bspline_coefficients();
  const int kk = b.truncation;
  // A[s] = Σ_i c_i c_{i+s} = 2 a_s with a the autocorrelation helper above, s = −2K … 2K.
  const std::vector<double> autocorr = autocorrelation(b.c);
  const std::vector<double> beta = bspline_products(e1, e2);
  const int n = 2 * kk + 3;
  Eigen::VectorXd g = Eigen::VectorXd::Zero(2 * n + 1);
  for (int k = -n; k <= n; ++k) {
    double acc = 0.0;
    for (int m = -3; m <= 3; ++m) {  // Γ[k] = Σ_s A[s] β[k + s], k + s = m
      const int s = m - k;
      if (s >= -2 * kk && s <= 2 * kk) acc += 2.0 * autocorr[static_cast<size_t>(s + 2 * kk)] * beta[static_cast<size_t>(m + 3)];
    }
    g(k + n) = sign * acc;
  }
  // Keep the shifts whose coefficient is above 1e-17 of the largest (below the rounding of any sum).
  const double cut = 1e-17 * g.cwiseAbs().maxCoeff();
  int first = -n, last = n;
  while (first < 0 && std::abs(g(first + n)) < cut) ++first;
  while (last > 0 && std::abs(g(last + n)) < cut) --last;
  ConnectionCoefficients out;
  out.d1 = d1;
  out.d2 = d2;
  out.first_shift = first;
  out.last_shift = last;
  out.values = g.segment(first + n, last - first + 1);
  return out;
}

}  // namespace

double sobolev_exponent(const Family& family) {
  if (family.kind == FamilyKind::OrthogonalCubicBSpline) return 3.5;
  return -std::log(reduced_spectral_radius(family)) / std::log(4.0);
}

int max_connection_order(const Family& family) {
  if (family.kind == FamilyKind::OrthogonalCubicBSpline) return 6;  // d < 2s = 7
  const double rho = reduced_spectral_radius(family);
  int d = 0;
  while (std::ldexp(1.0, -(d + 1)) > rho * (1.0 + 1e-8)) ++d;
  return d;
}

ConnectionCoefficients connection_coefficients(const Family& family, int d1, int d2) {
  const int max_order = max_connection_order(family);
  if (d1 < 0 || d2 < 0 || d1 + d2 > max_order) {
    throw std::invalid_argument(
        "connection_coefficients(" + family.name() + ", d1 = " + std::to_string(d1) + ", d2 = " + std::to_string(d2) +
        "): orders must be >= 0 with d1 + d2 <= " + std::to_string(max_order) + " for " + family.name() +
        " (Sobolev exponent " + std::to_string(sobolev_exponent(family)) +
        "); use a smoother family (DB6 or the B-spline for d = 2) or move derivatives to the other basis");
  }
  return family.kind == FamilyKind::OrthogonalCubicBSpline ? bspline(d1, d2) : compactly_supported(family, d1, d2);
}

Eigen::SparseMatrix<double> periodized_connection_matrix(const ConnectionCoefficients& coefficients, int level) {
  if (level < 0 || level > 20) {
    throw std::invalid_argument("periodized_connection_matrix: level J = " + std::to_string(level) +
                                " must be in [0, 20]");
  }
  const long m = 1L << level;
  const double factor = std::ldexp(1.0, level * (coefficients.d1 + coefficients.d2));
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(static_cast<size_t>(m) * static_cast<size_t>(coefficients.values.size()));
  for (long i = 0; i < m; ++i) {
    for (int k = coefficients.first_shift; k <= coefficients.last_shift; ++k) {
      const long col = ((i + k) % m + m) % m;  // Σ_ℓ Γ[k − i + ℓM] [RL93]
      triplets.emplace_back(i, col, factor * coefficients.at(k));
    }
  }
  Eigen::SparseMatrix<double> c(m, m);
  c.setFromTriplets(triplets.begin(), triplets.end());
  c.makeCompressed();
  return c;
}

}  // namespace wbm::wavelets
