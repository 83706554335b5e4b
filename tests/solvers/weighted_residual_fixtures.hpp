// Helpers shared by the weighted-residual tests (test_weighted_residual*.cpp): the Case 1 scene of
// [JL14 Table 1] and the six basis pairs of [JL14 Table 2].
#pragma once

#include <wbm/scene/scene.hpp>

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

}  // namespace wbm::testing
