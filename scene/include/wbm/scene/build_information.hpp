#pragma once
/// Version of wbm and of every library it was built with, for result.json and `wbm --version`.

#include <nlohmann/json.hpp>

namespace wbm::scene {

/// {"wbm": "0.1.0", "git_describe", "compiler", "eigen", "fftw", "gsl", "toml++"}; strings.
[[nodiscard]] nlohmann::json build_information();

}  // namespace wbm::scene
