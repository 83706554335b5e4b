#include <wbm/scene/build_information.hpp>

#include <string>

#include <Eigen/Core>
#include <fftw3.h>
#include <gsl/gsl_version.h>
#include <toml++/toml.h>

namespace wbm::scene {

nlohmann::json build_information() {
  return {{"wbm", WBM_VERSION},
          {"git_describe", WBM_GIT_DESCRIBE},
          {"compiler", std::string(__VERSION__)},
          {"eigen", std::to_string(EIGEN_WORLD_VERSION) + "." + std::to_string(EIGEN_MAJOR_VERSION) + "." +
                        std::to_string(EIGEN_MINOR_VERSION)},
          {"fftw", std::string(fftw_version)},
          {"gsl", std::string(gsl_version)},
          {"toml++", std::to_string(TOML_LIB_MAJOR) + "." + std::to_string(TOML_LIB_MINOR) + "." +
                         std::to_string(TOML_LIB_PATCH)}};
}

}  // namespace wbm::scene
