#include "scene.hpp"

#include <stdexcept>

namespace wbm::reproduce {

scene::Scene load_scene(const std::string& name) {
  scene::Scene s = models::load_scene(name);
  if (!s.structure || s.structure->kind != scene::StructureKind::Rod || !s.forcing || s.forcing->range) {
    throw std::invalid_argument(models::scene_path(name).string() +
                                ": the JL14 reproductions need the FE rod [structure] and one frequency_hz in [forcing]");
  }
  return s;
}

}  // namespace wbm::reproduce
