#pragma once
/// The scenes shipped with the sources (reproduce/scenes/*.toml), read through wbm::scene so that
/// every figure, test and benchmark takes Table 1 from the same files users run with `wbm run`.

#include <filesystem>
#include <string>

#include <wbm/scene/scene.hpp>

namespace wbm::reproduce {

/// Directory of the scenes shipped with the sources (compile-time WBM_SCENE_DIR).
[[nodiscard]] std::filesystem::path scene_directory();

/// Loads `name` (a stem looked up in scene_directory(), or a path to a .toml file) with
/// scene::load_scene, and checks what the JL14 reproductions need: the FE rod and one forcing
/// frequency. Throws std::invalid_argument (the scene's problems, or what is missing and why),
/// std::runtime_error if the file cannot be read.
[[nodiscard]] scene::Scene load_scene(const std::string& name);

}  // namespace wbm::reproduce
