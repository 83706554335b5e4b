#include "shipped_scenes.hpp"

#include <stdexcept>

namespace wbm::models {

std::filesystem::path scene_directory() { return WBM_SCENE_DIR; }

std::filesystem::path scene_path(const std::string& name) {
  std::filesystem::path path(name);
  if (path.extension() != ".toml") path = scene_directory() / (name + ".toml");
  if (!std::filesystem::exists(path)) {
    throw std::runtime_error("scene \"" + name + "\": no file " + path.string() +
                             " (give a path to a .toml file or a name from " + scene_directory().string() + ")");
  }
  return path;
}

scene::Scene load_scene(const std::string& name) { return scene::load_scene(scene_path(name)); }

}  // namespace wbm::models
