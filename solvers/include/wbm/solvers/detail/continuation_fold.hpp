#pragma once
/// Piece of pseudo_arclength (continuation.hpp), not API: where a fold lies on one step, and the
/// state there.

#include <algorithm>
#include <cmath>

namespace wbm::solvers::detail {

// The cubic Hermite interpolant on [0, ds] through (0, v0, t0) and (ds, v1, t1), at s ∈ [0, ds]
// (u = s/ds): h00 v0 + h10 ds t0 + h01 v1 + h11 ds t1 with h00 = 2u³ − 3u² + 1,
// h10 = u³ − 2u² + u, h01 = −2u³ + 3u², h11 = u³ − u². V is a double or an Eigen vector.
template <class V>
V hermite(const V& v0, const V& v1, const V& t0, const V& t1, double ds, double s) {
  const double u = s / ds;
  const double h00 = 2 * u * u * u - 3 * u * u + 1, h10 = u * u * u - 2 * u * u + u;
  const double h01 = -2 * u * u * u + 3 * u * u, h11 = u * u * u - u * u;
  return h00 * v0 + (h10 * ds) * t0 + h01 * v1 + (h11 * ds) * t1;
}

// A fold between two points whose λ-tangents d0, d1 (dλ̂/ds) differ in sign: the arclength
// s* ∈ [0, ds] of the extremum of the cubic Hermite interpolant λ̂(s) through (0, l0, d0) and
// (ds, l1, d1). With Δ = l1 − l0,
//   λ̂'(s) = d0 + s (6Δ/ds² − (4 d0 + 2 d1)/ds) + s² (3(d0 + d1)/ds² − 6Δ/ds³),
// whose root in [0, ds] is taken (clamped to it). Exact when λ̂(s) is a polynomial of degree ≤ 3.
inline double fold_arclength(double l0, double l1, double d0, double d1, double ds) {
  const double delta = l1 - l0;
  const double a = 3.0 * (d0 + d1) / (ds * ds) - 6.0 * delta / (ds * ds * ds);
  const double b = 6.0 * delta / (ds * ds) - (4.0 * d0 + 2.0 * d1) / ds;
  double s_star = -d0 / b;
  if (std::abs(a) > 1e-14 * std::abs(b)) {
    const double disc = std::sqrt(std::max(0.0, b * b - 4.0 * a * d0));
    for (double root : {(-b + disc) / (2.0 * a), (-b - disc) / (2.0 * a)}) {
      if (root >= 0.0 && root <= ds) s_star = root;
    }
  }
  return std::clamp(s_star, 0.0, ds);
}

// The parameter at that extremum: λ̂(s*).
inline double fold_parameter(double l0, double l1, double d0, double d1, double ds) {
  return hermite(l0, l1, d0, d1, ds, fold_arclength(l0, l1, d0, d1, ds));
}

}  // namespace wbm::solvers::detail
