#pragma once
/// Piece of pseudo_arclength (continuation.hpp), not API: restarting a branch beyond a corner of
/// a nonsmooth (complementarity) branch.

#include <algorithm>
#include <utility>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <wbm/solvers/detail/continuation_corrector.hpp>

namespace wbm::solvers::detail {

// Σ_j |a_ij − b_ij| per row.
inline Eigen::VectorXd row_change(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).cwiseAbs().rowwise().sum();
}
inline Eigen::VectorXd row_change(const LowRankJacobian& a, const LowRankJacobian& b) {
  return row_change(a.dense(), b.dense());
}
inline Eigen::VectorXd row_change(const Eigen::SparseMatrix<double>& a, const Eigen::SparseMatrix<double>& b) {
  const Eigen::SparseMatrix<double> d = a - b;
  return d.cwiseAbs() * Eigen::VectorXd::Ones(d.cols());
}


// A corner where the corrector fails for every small step (a complementarity condition
// switching, the new piece turning back by more than 90°, so that no hyperplane normal to the
// old tangent meets it): the Jacobian a little beyond the corner along the old tangent already
// has the new piece's active set; its null direction is the new tangent. The rows in which
// that Jacobian differs from the last point's by more than a tenth of the largest difference
// are the switching rows; the corner is located by bisection along the old tangent (where
// they switch). Both orientations of the new tangent are tried from the corner, with steps
// from 1000 kink_step (at most max_step) down to kink_step, and a landing is taken only if its
// Jacobian's switching rows are the new piece's (closer to those beyond the corner than to the
// last point's) and no other row switched (a landing across another corner, e.g. on a piece
// passed earlier, is refused): pieces can meet at a fraction of a degree, so directions cannot
// tell them apart. `attempt(direction, z, step)` is one predictor–corrector attempt
// (attempt_along); `corrector_iterations` accumulates the iterations spent. Returns true and
// the landing in `out` on success.
template <class S, class Solver, class AttemptFn>
bool restart_at_corner(const S& system, Solver& solver, double xs, double ls, const Eigen::VectorXd& last_tangent,
                       const Eigen::VectorXd& z_last, double kink_step, double max_step, AttemptFn&& attempt,
                       long& corrector_iterations, Attempt& out) {
  const auto n = z_last.size() - 1;
  using Lin = decltype(system.linearize(z_last.head(n), z_last(n)));
  const Eigen::VectorXd probe = z_last + kink_step * last_tangent;
  const Lin beyond = system.linearize(probe.head(n) * xs, probe(n) * ls);
  const Lin here = system.linearize(z_last.head(n) * xs, z_last(n) * ls);
  if (!finite(beyond) || !finite(here)) return false;
  const Eigen::VectorXd change = row_change(beyond.jacobian, here.jacobian);
  if (!(change.maxCoeff() > 0.0)) return false;  // no switching row: not a corner
  const Eigen::ArrayXd switching = (change.array() > 0.1 * change.maxCoeff()).cast<double>();
  const Eigen::VectorXd t_new = tangent(solver, beyond, last_tangent, xs, ls);
  if (!t_new.allFinite()) return false;
  // The corner itself, to first order: bisection along the old tangent for where the switching
  // rows change; the restarts leave from there.
  double lo = 0.0, hi = kink_step;
  const double total = (change.array() * switching).sum();
  for (int k = 0; k < 30; ++k) {
    const double mid = 0.5 * (lo + hi);
    const Eigen::VectorXd z = z_last + mid * last_tangent;
    const Lin l = system.linearize(z.head(n) * xs, z(n) * ls);
    if ((row_change(l.jacobian, here.jacobian).array() * switching).sum() > 0.5 * total) {
      hi = mid;
    } else {
      lo = mid;
    }
  }
  const Eigen::VectorXd z_corner = z_last + hi * last_tangent;
  for (double sign : {1.0, -1.0}) {
    for (double step = std::min(max_step, 1e3 * kink_step); step >= kink_step; step *= 0.25) {
      Attempt c = attempt(Eigen::VectorXd(sign * t_new), z_corner, step);
      corrector_iterations += c.iterations;
      if (!c.converged()) continue;
      const Lin landed = system.linearize(c.z.head(n) * xs, c.z(n) * ls);
      const Eigen::ArrayXd from_here = row_change(landed.jacobian, here.jacobian).array();
      const double to_new = (row_change(landed.jacobian, beyond.jacobian).array() * switching).sum();
      const double to_old = (from_here * switching).sum();
      if (!(to_new < to_old)) continue;                                                 // back on the old piece
      if ((from_here * (1.0 - switching)).maxCoeff() > 0.1 * change.maxCoeff()) continue;  // beyond another corner
      out = std::move(c);
      return true;
    }
  }
  return false;
}

}  // namespace wbm::solvers::detail
