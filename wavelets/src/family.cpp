// Families, refinement coefficients (GSL tables), the cubic B-spline and the orthogonal cubic
// B-spline coefficients c_k (GSL adaptive quadrature of [JL14 Eq. (30)]).
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_integration.h>
#include <gsl/gsl_wavelet.h>

#include <wbm/wavelets/scaling_function.hpp>

namespace wbm::wavelets {

Family Family::daubechies(int filter_length) {
  if (filter_length % 2 != 0 || filter_length < 4 || filter_length > 20) {
    throw std::invalid_argument("daubechies(L = " + std::to_string(filter_length) +
                                "): L must be even, 4 <= L <= 20 (use Family::haar() for L = 2)");
  }
  return {FamilyKind::Daubechies, filter_length};
}

std::string Family::name() const {
  switch (kind) {
    case FamilyKind::Haar: return "Haar";
    case FamilyKind::Daubechies: return "DB" + std::to_string(filter_length);
    case FamilyKind::OrthogonalCubicBSpline: return "B-spline";
  }
  return "unknown";
}

int Family::vanishing_moments() const {
  return kind == FamilyKind::OrthogonalCubicBSpline ? 4 : filter_length / 2;
}

std::vector<double> refinement_coefficients(const Family& family) {
  if (family.kind == FamilyKind::OrthogonalCubicBSpline) {
    throw std::invalid_argument(
        "refinement_coefficients(B-spline): the orthogonal cubic B-spline has an infinite "
        "refinement mask; use orthogonal_cubic_bspline_coefficients() (c_k of JL14 Eq. (28))");
  }
  if (family.kind == FamilyKind::Haar) return {1.0, 1.0};  // [JL14 Sec. 3.5]
  const Family checked = Family::daubechies(family.filter_length);
  gsl_wavelet* w = gsl_wavelet_alloc(gsl_wavelet_daubechies, static_cast<size_t>(checked.filter_length));
  if (w == nullptr) throw std::runtime_error("GSL has no Daubechies table for L = " + std::to_string(checked.filter_length));
  std::vector<double> p(w->nc);
  for (size_t l = 0; l < w->nc; ++l) p[l] = std::numbers::sqrt2 * w->h1[l];  // Σ h = √2 → Σ p = 2
  gsl_wavelet_free(w);
  return p;
}

int max_pointwise_derivative(const Family& family) {
  switch (family.kind) {
    case FamilyKind::Haar: return 0;
    case FamilyKind::OrthogonalCubicBSpline: return 2;
    case FamilyKind::Daubechies: {
      // Integer parts of the Hölder exponents 0.550, 1.088, 1.618, 1.969, 2.189, 2.460, 2.761,
      // 3.073, 3.363 of Daubechies' φ for L = 4, 6, ..., 20 [D92, Ch. 7].
      static constexpr std::array<int, 9> orders = {0, 1, 1, 1, 2, 2, 2, 3, 3};
      return orders.at(static_cast<size_t>(Family::daubechies(family.filter_length).filter_length / 2 - 2));
    }
  }
  return 0;
}

double cubic_bspline(double t, int derivative) {
  if (derivative < 0 || derivative > 3) {
    throw std::invalid_argument("cubic_bspline: derivative = " + std::to_string(derivative) +
                                " must be in [0, 3] (B3''' is piecewise constant)");
  }
  if (!(t >= 0.0 && t < 4.0)) return 0.0;
  // [JL14 Eq. (29)], piece by piece, with its derivatives.
  const double t2 = t * t, t3 = t2 * t;
  if (t < 1.0) {
    const std::array<double, 4> v = {t3 / 6.0, t2 / 2.0, t, 1.0};
    return v[static_cast<size_t>(derivative)];
  }
  if (t < 2.0) {
    const std::array<double, 4> v = {-t3 / 2.0 + 2.0 * t2 - 2.0 * t + 2.0 / 3.0, -1.5 * t2 + 4.0 * t - 2.0,
                                     -3.0 * t + 4.0, -3.0};
    return v[static_cast<size_t>(derivative)];
  }
  if (t < 3.0) {
    const std::array<double, 4> v = {t3 / 2.0 - 4.0 * t2 + 10.0 * t - 22.0 / 3.0, 1.5 * t2 - 8.0 * t + 10.0,
                                     3.0 * t - 8.0, 3.0};
    return v[static_cast<size_t>(derivative)];
  }
  const std::array<double, 4> v = {-t3 / 6.0 + 2.0 * t2 - 8.0 * t + 32.0 / 3.0, -t2 / 2.0 + 4.0 * t - 8.0,
                                   -t + 4.0, -1.0};
  return v[static_cast<size_t>(derivative)];
}

namespace {

// 1/√p₃(cos ξ), p₃(y) = (y³ + 60y² + 297y + 272)/630 [JL14 Eq. (31)].
double inverse_sqrt_p3(double xi, void*) {
  const double y = std::cos(xi);
  return 1.0 / std::sqrt((((y + 60.0) * y + 297.0) * y + 272.0) / 630.0);
}

// RAII holders for the GSL quadrature workspaces (one per computation).
struct Workspace {
  explicit Workspace(size_t n) : w(gsl_integration_workspace_alloc(n)) {}
  ~Workspace() { gsl_integration_workspace_free(w); }
  Workspace(const Workspace&) = delete;
  Workspace& operator=(const Workspace&) = delete;
  gsl_integration_workspace* w;
};
struct QawoTable {
  explicit QawoTable(double omega) : t(gsl_integration_qawo_table_alloc(omega, std::numbers::pi, GSL_INTEG_COSINE, 50)) {}
  ~QawoTable() { gsl_integration_qawo_table_free(t); }
  QawoTable(const QawoTable&) = delete;
  QawoTable& operator=(const QawoTable&) = delete;
  gsl_integration_qawo_table* t;
};

// c_k = (1/π) ∫₀^π cos(kξ)/√p₃(cos ξ) dξ [JL14 Eq. (30)]; returns {c_k, abserr/π}.
std::pair<double, double> bspline_coefficient(int k) {
  constexpr size_t limit = 1000;
  constexpr double epsabs = 1e-16, epsrel = 1e-14;
  Workspace ws(limit);
  gsl_function f{&inverse_sqrt_p3, nullptr};
  double result = 0.0, abserr = 0.0;
  gsl_set_error_handler_off();  // report accuracy through abserr, never abort
  if (k == 0) {
    gsl_integration_qag(&f, 0.0, std::numbers::pi, epsabs, epsrel, limit, GSL_INTEG_GAUSS61, ws.w, &result, &abserr);
  } else {
    QawoTable table(static_cast<double>(k));
    gsl_integration_qawo(&f, 0.0, epsabs, epsrel, limit, ws.w, table.t, &result, &abserr);
  }
  return {result / std::numbers::pi, abserr / std::numbers::pi};
}

}  // namespace

BSplineCoefficients compute_orthogonal_cubic_bspline_coefficients(int truncation) {
  if (truncation < 1 || truncation > 200) {
    throw std::invalid_argument("orthogonal cubic B-spline truncation K = " + std::to_string(truncation) +
                                " must be in [1, 200] (the paper uses K = 50)");
  }
  BSplineCoefficients out;
  out.truncation = truncation;
  out.c.assign(static_cast<size_t>(2 * truncation + 1), 0.0);
  for (int k = 0; k <= 2 * truncation; ++k) {
    const auto [ck, err] = bspline_coefficient(k);
    if (k <= truncation) {
      out.c[static_cast<size_t>(truncation + k)] = ck;
      out.c[static_cast<size_t>(truncation - k)] = ck;  // c_k = c_{−k}
      out.quadrature_error = std::max(out.quadrature_error, err);
    } else {
      out.tail += 2.0 * std::abs(ck);
    }
  }
  return out;
}

const BSplineCoefficients& orthogonal_cubic_bspline_coefficients() {
  static const BSplineCoefficients coefficients = compute_orthogonal_cubic_bspline_coefficients(50);
  return coefficients;
}

}  // namespace wbm::wavelets
