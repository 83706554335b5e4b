// Stability crossings of a traced curve (response_curve.hpp): where the number of Floquet
// multipliers outside the unit circle changes, located on the segment between two points with a
// verdict and classified by the crossing multiplier's argument (classify_crossing).
#include <wbm/solvers/response_curve.hpp>

#include <algorithm>
#include <cmath>

namespace wbm::solvers {

std::vector<StabilityCrossing> stability_crossings(const ResponseCurve& curve) {
  std::vector<StabilityCrossing> out;
  size_t last = 0;  // the last point with a verdict before i
  for (size_t i = 1; i < curve.points.size(); ++i) {
    if (curve.points[i - 1].stability_available) last = i - 1;
    const ResponsePoint& b = curve.points[i];
    if (b.crossing == Bifurcation::None) continue;
    const ResponsePoint& a = curve.points[last];
    const double span = b.max_multiplier - a.max_multiplier;
    StabilityCrossing c;
    c.before = last;
    c.after = i;
    c.t = std::abs(span) > 0.0 ? std::clamp((1.0 - a.max_multiplier) / span, 0.0, 1.0) : 0.5;
    c.parameter = a.parameter + c.t * (b.parameter - a.parameter);
    c.frequency_hz = a.frequency_hz + c.t * (b.frequency_hz - a.frequency_hz);
    c.amplitude = a.amplitude + c.t * (b.amplitude - a.amplitude);
    c.multiplier = (b.stable ? a : b).leading_multiplier;
    c.kind = b.crossing;
    c.stability_lost = !b.stable;
    out.push_back(c);
  }
  return out;
}

}  // namespace wbm::solvers
