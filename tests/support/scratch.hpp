#pragma once
/// A scratch folder for a test file's files: <temp>/wbm_test_<name>_<pid>, created on construction
/// and removed with its contents on destruction. Keep one in a function-local static, so that it
/// lives until the process exits: `static const wbm::testing::ScratchDir s("gmsh"); return s.path();`.

#include <filesystem>
#include <string>
#include <system_error>

#include <unistd.h>

namespace wbm::testing {

class ScratchDir {
 public:
  explicit ScratchDir(const std::string& name)
      : dir_(std::filesystem::temp_directory_path() / ("wbm_test_" + name + "_" + std::to_string(::getpid()))) {
    std::filesystem::create_directories(dir_);
  }
  ~ScratchDir() {
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  [[nodiscard]] const std::filesystem::path& path() const { return dir_; }

 private:
  std::filesystem::path dir_;
};

}  // namespace wbm::testing
