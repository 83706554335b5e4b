#pragma once
/// Piece of pseudo_arclength (continuation.hpp), not API: one step of a piecewise-smooth system
/// (PiecewiseSmoothSystem, linearization.hpp) on a fixed piece, with the events where the branch
/// leaves it located and crossed.
///
/// On a fixed piece the residual is smooth, so the corrector converges quadratically for a small
/// enough step and nothing depends on which branch of a min Newton's iterates happen to pick. A
/// step that ends with an event function negative has crossed a switching surface: the crossing
/// is located by regula falsi (Illinois) in the step length on φ(s) = min_(j crossing) e_j(z(s)),
/// each evaluation a corrector solve on the old piece, until φ at a point beyond the last lies in
/// the zero band (the
/// corrector tolerance: event functions are not known better than the residual) or the bracket is
/// below 1e-10 of the step. The point on the admissible side is a point of the branch (a corner).
/// Every entry that crossed in the step and lies within the zero band there, or whose own
/// crossing (e_j/rate_j beyond the point, rate_j its mean rate over the step) lies within 1e-6
/// of the step of the first one's, is flipped at once: simultaneous crossings, e.g. samples
/// placed symmetrically in time, switch together whatever the last bits of their event
/// functions, which at the located point are known only to the corrector's tolerance times the
/// conditioning. The new piece's tangent is its null direction, oriented so that the flipped entries'
/// new event functions grow (rate > 0 along it): the half of the new piece that is admissible.
/// This need not be within 90° of the old tangent (complementarity branches turn back at
/// corners). Entries whose new event would decrease whichever way are left unflipped and the
/// tangent recomputed; if none is left, no piece continues the branch and the step says why.
/// A flipped entry whose event function does not move along the new piece (tangent to its
/// surface, the orientation left to rounding) takes the next crossing entry into the group.
/// Where the new piece's own solution through the point has a flipped entry below its surface
/// by more than the crossing threshold (an ill-conditioned piece: its multipliers amplify the
/// point's residual), the switching point is moved along the new piece into its admissible side,
/// by as much as the flipped entries lay below their surfaces, so that the next step does not
/// take them for entries crossing back (onto_new_piece).
/// [Leine & Nijmeijer 2004, Sec. 7.3 (switching in path following); Acary & Brogliato 2008,
/// Sec. 12.2; the parametric LCP's pivoting, Cottle, Pang & Stone 1992, Sec. 4.5.]

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include <wbm/solvers/detail/continuation_corrector.hpp>
#include <wbm/solvers/linearization.hpp>

namespace wbm::solvers::detail {

// A piecewise-smooth system restricted to one piece, as a ParametrizedSystem for attempt_along.
template <class S>
struct OnPiece {
  const S* system;
  const ActiveSet* piece;
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x, double p) const {
    return system->residual(x, p, *piece);
  }
  [[nodiscard]] auto linearize(const Eigen::VectorXd& x, double p) const { return system->linearize(x, p, *piece); }
};

// The same at a fixed parameter, as a NonlinearSystem for newton() (landings).
template <class S>
struct FixedOnPiece {
  const S* system;
  double parameter;
  const ActiveSet* piece;
  [[nodiscard]] Eigen::VectorXd residual(const Eigen::VectorXd& x) const {
    return system->residual(x, parameter, *piece);
  }
  [[nodiscard]] auto jacobian(const Eigen::VectorXd& x) const {
    return system->linearize(x, parameter, *piece).jacobian;
  }
};

// One step on a piece.
struct PieceStep {
  Attempt a;                 // the point reached (a.tangent: of the piece it continues on), or the failure
  double step = 0.0;         // scaled arclength along the old tangent to a's hyperplane (< h at an event)
  bool event = false;        // a is a switching point; the branch continues on `next`
  ActiveSet next;            // the piece beyond the event
  Eigen::VectorXd incoming;  // at an event: the old piece's tangent there
  int switched = 0;          // entries flipped at the event
  long iterations = 0;       // corrector iterations spent, location included
  std::string failure;       // non-empty: an event was located but no piece continues the branch
};

// The tangent of `lin`'s piece: its null direction, bordered by `previous` (or, if that bordered
// matrix is singular, by the parameter direction), normalized; NaN if none is found.
template <class Lin, class Solver>
Eigen::VectorXd piece_tangent(Solver& solver, const Lin& lin, const Eigen::VectorXd& previous, double xs, double ls) {
  Eigen::VectorXd t = tangent(solver, lin, previous, xs, ls);
  if (t.allFinite()) return t;
  Eigen::VectorXd e = Eigen::VectorXd::Zero(previous.size());
  e(e.size() - 1) = 1.0;
  return tangent(solver, lin, e, xs, ls);
}

// The switching point moved onto the new piece. It satisfies the new piece's rows of the flipped
// entries only to the zero band, and where that piece is ill-conditioned its own solution through
// the point can lie measurably beyond their surfaces: their event functions negative by far more
// than the band (LL11 rod, N = 10, m = 128, samples 1 and 127 at E = 2.1493: −1.2e-8, for a band
// of 1e-10). The next step would then take them for entries crossing back and switch them back
// at once, and the branch would retrace itself. So when the new piece's point through it (the
// corrector on the new piece at arclength 0 along its tangent) has a flipped entry below
// −event_tolerance by f₀, the switching point is moved along the new piece into the admissible
// side, by the secant in arclength s on the smallest flipped event function, aimed at +|f₀|: the
// deficit itself measures how well that piece determines its event functions (on the LL11 rod
// at N = 12, m = 512, E = 1.99207, samples 2 and 510: f₀ = −2.8e-7, and two corrector solves at
// the same s gave −2.8e-11 and −1.3e-9, so a target inside the zero band is not reached). The
// aim is held short of the nearest surface of the other entries (linear extrapolation along the
// tangent), at the midpoint between the two; there samples 1 and 511, at 3.5e-7 and falling at
// rate 1, leave contact 3.5e-7 further on. The point is accepted once every entry of the new piece
// lies above −event_tolerance (at most 8 corrections); its tangent is recomputed there. It is left
// as it is if a correction fails or no such point is in reach. Returns the corrector iterations
// spent.
template <class S, class Lin, class Solver>
long onto_new_piece(const S& system, Solver& solver, double xs, double ls, const NewtonOptions& corrector,
                    const ActiveSet& next, const std::vector<Eigen::Index>& group, double event_tolerance,
                    Attempt& point) {
  const auto n = point.z.size() - 1;
  const OnPiece<S> on{&system, &next};
  auto events = [&](const Eigen::VectorXd& z) { return system.events(z.head(n) * xs, z(n) * ls, next); };
  std::vector<bool> flipped(static_cast<size_t>(next.size()), false);
  for (Eigen::Index j : group) flipped[static_cast<size_t>(j)] = true;
  // The smallest event function of the flipped entries and of the others.
  auto smallest = [&](const Eigen::VectorXd& e, bool of_flipped) {
    double m = std::numeric_limits<double>::infinity();
    for (Eigen::Index j = 0; j < e.size(); ++j) {
      if (flipped[static_cast<size_t>(j)] == of_flipped) m = std::min(m, e(j));
    }
    return m;
  };
  long iterations = 0;
  auto at = [&](double s) {
    Attempt a = attempt_along<OnPiece<S>, Lin>(on, solver, xs, ls, corrector, point.tangent, point.z, s, false);
    iterations += a.iterations;
    return a;
  };
  Attempt a = at(0.0);
  if (!a.converged()) return iterations;
  const Eigen::VectorXd e0 = events(a.z);
  double s0 = 0.0, f0 = smallest(e0, true);
  if (f0 >= -event_tolerance) return iterations;  // admissible: the point stays
  constexpr double kProbe = 1e-6;
  const Eigen::VectorXd e_probe = events(Eigen::VectorXd(a.z + kProbe * point.tangent));
  double rate = (smallest(e_probe, true) - f0) / kProbe;
  if (!(rate > 0.0)) return iterations;
  // Where the flipped entries reach their surface, and the nearest surface of the others ahead.
  const double s_surface = -f0 / rate;
  double s_other = std::numeric_limits<double>::infinity();
  for (Eigen::Index j = 0; j < e0.size(); ++j) {
    const double r = (e_probe(j) - e0(j)) / kProbe;
    if (!flipped[static_cast<size_t>(j)] && e0(j) > 0.0 && r < 0.0) s_other = std::min(s_other, e0(j) / -r);
  }
  if (!(s_other > s_surface)) return iterations;
  const double target = f0 + rate * std::min(2.0 * s_surface, 0.5 * (s_surface + s_other));
  for (int it = 0; it < 8; ++it) {
    const double s = s0 + (target - f0) / rate;
    Attempt b = at(s);
    if (!b.converged()) return iterations;
    const Eigen::VectorXd e = events(b.z);
    const double f = smallest(e, true);
    if (f >= -event_tolerance && smallest(e, false) >= -event_tolerance) {
      const Lin lin = system.linearize(b.z.head(n) * xs, b.z(n) * ls, next);
      Eigen::VectorXd t = piece_tangent(solver, lin, point.tangent, xs, ls);
      if (!t.allFinite()) return iterations;
      point.z = std::move(b.z);
      point.tangent = std::move(t);
      return iterations;
    }
    if (!(s != s0) || !(f != f0)) return iterations;
    rate = (f - f0) / (s - s0);
    if (!(rate > 0.0)) return iterations;
    s0 = s;
    f0 = f;
  }
  return iterations;
}

template <class S, class Lin, class Solver>
PieceStep piece_step(const S& system, Solver& solver, double xs, double ls, const NewtonOptions& corrector,
                     const ActiveSet& piece, const Eigen::VectorXd& t_last, const Eigen::VectorXd& z_last, double h,
                     double event_tolerance, double zero_band) {
  const auto n = z_last.size() - 1;
  PieceStep out;
  const OnPiece<S> on{&system, &piece};
  auto at = [&](double step, bool with_tangent = true) {
    Attempt a = attempt_along<OnPiece<S>, Lin>(on, solver, xs, ls, corrector, t_last, z_last, step, with_tangent);
    out.iterations += a.iterations;
    return a;
  };
  auto events = [&](const Eigen::VectorXd& z, const ActiveSet& a) -> Eigen::VectorXd {
    return system.events(z.head(n) * xs, z(n) * ls, a);
  };
  out.a = at(h);
  out.step = h;
  if (!out.a.converged()) return out;
  Eigen::VectorXd e_hi = events(out.a.z, piece);
  if (!(e_hi.minCoeff() < -event_tolerance)) return out;  // still on the piece

  // The entries that crossed; φ(s) = their smallest event function at the point of step s.
  const Eigen::VectorXd e_last = events(z_last, piece);
  std::vector<Eigen::Index> crossing;
  auto add_crossing = [&](const Eigen::VectorXd& e) {
    for (Eigen::Index j = 0; j < e.size(); ++j) {
      if (e(j) < -event_tolerance && std::find(crossing.begin(), crossing.end(), j) == crossing.end()) {
        crossing.push_back(j);
      }
    }
  };
  auto phi = [&](const Eigen::VectorXd& e) {
    double m = std::numeric_limits<double>::infinity();
    for (Eigen::Index j : crossing) m = std::min(m, e(j));
    return m;
  };
  add_crossing(e_hi);
  const Eigen::VectorXd e_end = e_hi;  // at the end of the whole step
  double lo = 0.0, hi = h;
  Eigen::VectorXd e_at_lo = e_last;  // the events at the low end
  double phi_lo = phi(e_last);       // φ at the low end (≥ 0)
  double weight_lo = 1.0, weight_hi = 1.0;  // Illinois: the weights of the ends' events in the secants
  Attempt a_lo;
  a_lo.status = SolveStatus::Converged;
  a_lo.z = z_last;
  a_lo.tangent = t_last;
  int kept = 0;  // Illinois: +1 after the low end moved, −1 after the high end moved
  double width_1 = std::numeric_limits<double>::infinity(), width_2 = width_1;  // the bracket 1 and 2 trials ago
  for (int it = 0; it < 100 && (lo == 0.0 || phi_lo > zero_band) && hi - lo > 1e-10 * h; ++it) {
    // The trial: the earliest point, over the crossing entries negative at the high end, where
    // each one's own secant between the ends reaches a tenth of the zero band (regula falsi with
    // Illinois' weights, per entry, aimed inside the band that ends the search rather than at its
    // edge 0, and near 0: the new piece starts from the located point with that event value as
    // its residual). φ, a minimum of several event functions, has a kink wherever another entry
    // becomes the smallest, and a secant on φ itself crept towards the zero: 20 corrector solves
    // per event on the LL11 rod at N = 24, m = 512, against 5.5 now. A trial within 1e-3 of the
    // bracket from an end is moved to that distance; the midpoint instead when no entry has a
    // secant zero, or when the last two trials did not halve the bracket between them.
    const double width = hi - lo, aim = 0.1 * zero_band;
    double s = hi;
    for (Eigen::Index j : crossing) {
      const double a = weight_lo * std::max(e_at_lo(j), 0.0), b = weight_hi * e_hi(j);
      if (b < 0.0) s = std::min(s, lo + width * (std::max(a - aim, 0.0) / (a - b)));
    }
    const double margin = 1e-3 * width;
    if (!(s < hi) || width > 0.5 * width_2) {
      s = 0.5 * (lo + hi);
    } else {
      s = std::clamp(s, lo + margin, hi - margin);
    }
    width_2 = width_1;
    width_1 = width;
    Attempt a = at(s, false);  // the tangent only at the point kept (below)
    if (!a.converged()) {        // the piece's corrector at this step: bisect instead
      s = 0.5 * (lo + hi);
      a = at(s, false);
      if (!a.converged()) break;
    }
    Eigen::VectorXd e = events(a.z, piece);
    add_crossing(e);  // an entry that crosses and comes back within the step joins
    const double f = phi(e);
    if (f >= 0.0) {
      lo = s;
      phi_lo = f;
      e_at_lo = std::move(e);
      a_lo = std::move(a);
      weight_lo = 1.0;
      if (kept == +1) weight_hi *= 0.5;
      kept = +1;
    } else {
      hi = s;
      e_hi = std::move(e);
      weight_hi = 1.0;
      if (kept == -1) weight_lo *= 0.5;
      kept = -1;
    }
  }
  // The entries that switch: those that crossed in this step and lie within the zero band at the
  // low end, those whose own crossing lies within kSimultaneous·h of the first one's, and once
  // the bracket is tight every one negative at the high end; at least the one closest to its
  // surface. An entry's crossing is placed at lo + e_j(lo)/rate_j, rate_j its event function's
  // mean rate of decrease over the whole step, and at lo itself for an entry in the zero band
  // there: the located crossing is the first, even when its entry comes back above its surface
  // by the step's end (its mean rate then says "no crossing", and measuring simultaneity from
  // the next entry's crossing switched that entry too, far from its surface: LL11 rod, N = 10,
  // m = 512, E = 2.4971, samples ±66/512 with multipliers 3.5e-3 released with ±67/512, the
  // corrector jumped to another orbit and the backbone retraced itself). The second rule makes simultaneous crossings
  // (samples placed symmetrically in time on a time-reversible orbit) switch together whatever
  // the last bits of their event functions: at the located point these are known only to about
  // the corrector's tolerance times the Jacobian's conditioning, which can exceed the zero band
  // (LL11 rod, N = 12, m = 256, K × (1 + 3e-12): samples 1 and 255 at E = 1.98629, 4.0e-11 and
  // 1.2e-10 at the located point, 8e-11 apart all along the bracket; one switched alone, the
  // branch turned back and folded twice within 3.5e-6 of E, which the unperturbed run did not).
  constexpr double kSimultaneous = 1e-6;
  const Eigen::VectorXd& e_lo = e_at_lo;
  const bool tight = !(hi - lo > 1e-10 * h);
  auto crossing_at = [&](Eigen::Index j) {
    if (e_lo(j) <= zero_band) return lo;
    const double rate = (e_last(j) - e_end(j)) / h;
    return rate > 0.0 ? lo + e_lo(j) / rate : std::numeric_limits<double>::infinity();
  };
  double first = std::numeric_limits<double>::infinity();
  for (Eigen::Index j : crossing) first = std::min(first, crossing_at(j));
  std::vector<Eigen::Index> group;
  Eigen::Index closest = crossing.front();
  for (Eigen::Index j : crossing) {
    if (e_lo(j) < e_lo(closest)) closest = j;
    if (e_lo(j) <= zero_band || crossing_at(j) <= first + kSimultaneous * h || (tight && e_hi(j) < -event_tolerance)) {
      group.push_back(j);
    }
  }
  if (group.empty()) {
    for (Eigen::Index j : crossing) {
      if (e_lo(j) <= e_lo(closest) + zero_band) group.push_back(j);
    }
  }
  if (lo > 0.0) {  // the old piece's tangent at the switching point
    const Lin at_lo = system.linearize(a_lo.z.head(n) * xs, a_lo.z(n) * ls, piece);
    a_lo.tangent = tangent(solver, at_lo, t_last, xs, ls);
    if (!a_lo.tangent.allFinite()) a_lo.tangent = t_last;
  }
  out.a = std::move(a_lo);
  out.step = lo;
  out.event = true;
  out.incoming = out.a.tangent;
  const Eigen::VectorXd z = out.a.z;
  // The new piece: flip the group, orient its tangent by the flipped entries' new events; drop
  // the entries that would leave at once and try again.
  constexpr double kProbe = 1e-6;
  constexpr double kTransversal = 1e-6;
  std::vector<Eigen::Index> dropped;  // entries left unflipped: they would leave at once
  bool singular = false;
  while (!group.empty()) {
    out.next = piece;
    for (Eigen::Index j : group) out.next[static_cast<size_t>(j)] ^= 1U;
    const Lin lin = system.linearize(z.head(n) * xs, z(n) * ls, out.next);
    Eigen::VectorXd t = piece_tangent(solver, lin, out.incoming, xs, ls);
    if (!t.allFinite()) {
      singular = true;
      break;
    }
    const Eigen::VectorXd rate = (events(Eigen::VectorXd(z + kProbe * t), out.next) - events(z, out.next)) / kProbe;
    double sum = 0.0;
    for (Eigen::Index j : group) sum += rate(j);
    if (sum < 0.0) t = -t;
    const double sign = sum < 0.0 ? -1.0 : 1.0;
    // A flipped entry whose new event function does not move along the new piece (|rate| at most
    // kTransversal times its rate of crossing over the step on the old piece: zero to the probe's
    // rounding) leaves the orientation to rounding, the new piece being tangent to that entry's
    // surface. The crossing entry whose crossing comes next (not one dropped below) joins the
    // group and the flip is tried again. LL11 rod, N = 4, m = 512, K × (1 + 1e-12), E = 1.4106:
    // samples ±1/512 of the time-symmetric orbit, multipliers 4 % apart (the active samples' rows
    // nearly dependent with nine functions), crossed 7e-5 of the step apart; −1/512 switched alone,
    // its rate on the new piece was −3e-10 against 13 on the old one, and the branch folded back.
    bool transversal = true;
    for (Eigen::Index j : group) {
      const double crossing_rate = std::abs(e_last(j) - e_end(j)) / h;
      if (!(std::abs(rate(j)) > kTransversal * crossing_rate)) transversal = false;
    }
    if (!transversal) {
      Eigen::Index next_entry = -1;
      for (Eigen::Index j : crossing) {
        if (std::find(group.begin(), group.end(), j) != group.end() ||
            std::find(dropped.begin(), dropped.end(), j) != dropped.end()) {
          continue;
        }
        if (next_entry < 0 || crossing_at(j) < crossing_at(next_entry) ||
            (crossing_at(j) == crossing_at(next_entry) && e_lo(j) < e_lo(next_entry))) {
          next_entry = j;
        }
      }
      if (next_entry >= 0) {
        group.push_back(next_entry);
        continue;
      }
    }
    std::vector<Eigen::Index> keep;
    for (Eigen::Index j : group) {
      if (sign * rate(j) > 0.0) {
        keep.push_back(j);
      } else {
        dropped.push_back(j);
      }
    }
    if (keep.size() == group.size()) {
      out.a.tangent = std::move(t);
      out.switched = static_cast<int>(group.size());
      if (lo > 0.0) out.iterations += onto_new_piece<S, Lin>(system, solver, xs, ls, corrector, out.next, group,
                                                              event_tolerance, out.a);
      return out;
    }
    group = std::move(keep);
  }
  out.failure = singular ? "an event (an entry's event function through 0) was located, but the Jacobian of the piece "
                           "beyond it is singular: no tangent continues the branch there (a degenerate switching point)"
                         : "an event (an entry's event function through 0) was located, but no neighbouring piece "
                           "continues the branch: the flipped entries' event functions decrease along either "
                           "orientation of the new piece's tangent (a degenerate switching point)";
  return out;
}

}  // namespace wbm::solvers::detail
