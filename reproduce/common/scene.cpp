#include "scene.hpp"

#include <stdexcept>

namespace wbm::reproduce {

std::filesystem::path scene_directory() { return WBM_SCENE_DIR; }

scene::Scene load_scene(const std::string& name) {
  std::filesystem::path path(name);
  if (path.extension() != ".toml") path = scene_directory() / (name + ".toml");
  if (!std::filesystem::exists(path)) {
    throw std::runtime_error("scene \"" + name + "\": no file " + path.string() +
                             " (give a path to a .toml file or a name from " + scene_directory().string() + ")");
  }
  scene::Scene s = scene::load_scene(path);
  if (!s.structure || s.structure->kind != scene::StructureKind::Rod || !s.forcing || s.forcing->range) {
    throw std::invalid_argument(path.string() + ": the JL14 reproductions need the FE rod [structure] and one "
                                "frequency_hz in [forcing]");
  }
  return s;
}

}  // namespace wbm::reproduce
