#pragma once
// Private: the declared sections of a scene (the mechanism in declared_keys.hpp): the top level,
// [analysis], [damping], [solver], [timestep] and [output] in scene_keys.cpp; [structure] (with
// its deck keys), [forcing] (with [[forcing.loads]]), [[contact]] and [basis] in
// scene_keys_model.cpp.

#include <string>
#include <vector>

#include <wbm/scene/scene.hpp>
#include <wbm/solvers/mechanical_system.hpp>
#include <wbm/solvers/time_integration.hpp>

#include "declared_keys.hpp"

namespace wbm::scene::detail {

const std::vector<std::string>& section_names();                                  // the top level's tables
const std::vector<DeclaredKey<Scene>>& top_keys();                                // title and the tables
const std::vector<DeclaredKey<Analysis>>& analysis_keys();                        // [analysis], by type
const std::vector<DeclaredKey<Structure>>& structure_keys();                      // [structure]: rod, matrices
const std::vector<DeclaredKey<DeckStructure>>& deck_keys();                       // [structure]: deck
const std::vector<DeclaredKey<Damping>>& damping_keys();                          // [damping]
const std::vector<DeclaredKey<Forcing>>& forcing_keys();                          // [forcing]
const std::vector<DeclaredKey<solvers::HarmonicLoad>>& load_keys();               // [[forcing.loads]]
const std::vector<DeclaredKey<Contact>>& contact_keys();                          // [[contact]], by law
const std::vector<DeclaredKey<CounterSurface>>& counter_surface_keys();           // [[counter_surface]], by type
const std::vector<DeclaredKey<Basis>>& basis_keys();                              // [basis]
const std::vector<DeclaredKey<Solver>>& solver_keys();                            // [solver]
const std::vector<DeclaredKey<solvers::TimeIntegrationOptions>>& bdf_keys();      // [timestep], penalty laws
const std::vector<DeclaredKey<solvers::MoreauJeanOptions>>& moreau_jean_keys();   // [timestep], law = "rigid"
const std::vector<DeclaredKey<solvers::CentralDifferenceOptions>>& central_difference_keys();  // [timestep], "jenkins"
const std::vector<DeclaredKey<Output>>& output_keys();                            // [output]

}  // namespace wbm::scene::detail
