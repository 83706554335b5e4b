#pragma once
/// The scenes shipped with the sources (reproduce/scenes/*.toml), read through wbm::scene, so that
/// the reproductions, the tests and the benchmarks take the papers' parameters (JL14 Table 1, the
/// LL11 rod) from the same files users run with `wbm run`.

#include <filesystem>
#include <string>

#include <wbm/scene/scene.hpp>

namespace wbm::models {

/// The directory of the shipped scenes (compile-time WBM_SCENE_DIR: reproduce/scenes).
[[nodiscard]] std::filesystem::path scene_directory();

/// The file of `name`: a stem looked up in scene_directory() ("jl14_case1"), or, if `name` ends
/// in .toml, that path as given. Throws std::runtime_error naming the path and the directory
/// searched if the file does not exist.
[[nodiscard]] std::filesystem::path scene_path(const std::string& name);

/// scene::load_scene(scene_path(name)): throws what scene_path and scene::load_scene throw
/// (std::runtime_error for an unreadable file, std::invalid_argument for the scene's problems).
[[nodiscard]] scene::Scene load_scene(const std::string& name);

}  // namespace wbm::models
