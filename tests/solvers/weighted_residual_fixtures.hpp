// Helpers shared by the weighted-residual tests (test_weighted_residual*.cpp, test_rigid_*.cpp):
// the Case 1 scene of [JL14 Table 1], the six basis pairs of [JL14 Table 2], and a response
// curve's amplitude between its points.
#pragma once

#include <limits>

#include <wbm/scene/scene.hpp>
#include <wbm/solvers/response_curve.hpp>

#include "shipped_scenes.hpp"

namespace wbm::testing {

inline wbm::scene::Scene case1() { return wbm::models::load_scene("jl14_case1"); }

struct Pair {
  const char* trial;
  const char* weighting;
};

// The six combinations of [JL14 Table 2].
inline constexpr Pair kTable2[] = {{"fourier", "fourier"}, {"bspline", "bspline"}, {"db6", "db6"},
                                   {"haar", "fourier"},    {"db6", "fourier"},     {"haar", "bspline"}};

// The amplitude of a response curve at f [Hz], linear between the first two consecutive points
// whose frequencies bracket f; NaN if none do.
inline double branch_amplitude_at(const wbm::solvers::ResponseCurve& curve, double f) {
  for (size_t i = 0; i + 1 < curve.points.size(); ++i) {
    const auto& a = curve.points[i];
    const auto& b = curve.points[i + 1];
    if (a.frequency_hz <= f && f <= b.frequency_hz) {
      const double t = b.frequency_hz > a.frequency_hz ? (f - a.frequency_hz) / (b.frequency_hz - a.frequency_hz) : 0.0;
      return a.amplitude + t * (b.amplitude - a.amplitude);
    }
  }
  return std::numeric_limits<double>::quiet_NaN();
}

}  // namespace wbm::testing
