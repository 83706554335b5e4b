#pragma once
// Private: the declared scalar sections (scene_keys.cpp; the mechanism in scalar_keys.hpp).

#include <vector>

#include <wbm/scene/scene.hpp>
#include <wbm/solvers/time_integration.hpp>

#include "scalar_keys.hpp"

namespace wbm::scene::detail {

const std::vector<ScalarKey<Solver>>& solver_keys();                              // [solver]
const std::vector<ScalarKey<solvers::TimeIntegrationOptions>>& bdf_keys();        // [timestep], penalty laws
const std::vector<ScalarKey<solvers::MoreauJeanOptions>>& moreau_jean_keys();     // [timestep], law = "rigid"

}  // namespace wbm::scene::detail
