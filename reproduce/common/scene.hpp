#pragma once
/// The JL14 reproductions' scene: a shipped scene (models/shipped_scenes.hpp) checked for what
/// they need, the FE rod and one forcing frequency.

#include <filesystem>
#include <string>

#include <wbm/scene/scene.hpp>

#include "shipped_scenes.hpp"

namespace wbm::reproduce {

using models::scene_directory;

/// Loads `name` (a stem looked up in scene_directory(), or a path to a .toml file) with
/// models::load_scene, and checks what the JL14 reproductions need: the FE rod and one forcing
/// frequency. Throws std::invalid_argument (the scene's problems, or what is missing and why),
/// std::runtime_error if the file cannot be read.
[[nodiscard]] scene::Scene load_scene(const std::string& name);

}  // namespace wbm::reproduce
