// libFuzzer target: the scene parser on arbitrary bytes as TOML (scene.hpp). Its contract allows
// a Scene or std::invalid_argument (bad input, every problem listed) or std::runtime_error (an
// unreadable Matrix Market file the scene names); anything else is a finding. A parsed scene must
// survive its JSON round trip (to_json, scene_from_json) under the same contract.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string_view>

#include <wbm/scene/scene.hpp>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  // Relative Matrix Market names resolve against a folder that does not exist.
  const std::filesystem::path file = "/nonexistent-wbm-fuzz/scene.toml";
  try {
    const wbm::scene::Scene scene = wbm::scene::parse_scene(text, file);
    const nlohmann::json json = wbm::scene::to_json(scene);
    (void)wbm::scene::scene_from_json(json, file);
  } catch (const std::invalid_argument&) {
  } catch (const std::runtime_error&) {
  }
  return 0;
}
