#pragma once
// Running an external program (ccx, gmsh) without a shell: posix_spawnp in a working folder,
// stdout and stderr into a log file there. Private to wbm::fem.

#include <filesystem>
#include <string>
#include <vector>

namespace wbm::fem::detail {

struct ProcessResult {
  int spawn_error = 0;   // errno of posix_spawnp (0: the program started)
  bool exited = false;   // it ended normally (not by a signal)
  int exit_code = -1;    // its exit status if exited
  std::string log;       // what it printed (stdout and stderr), empty if the log cannot be read
  [[nodiscard]] bool succeeded() const { return spawn_error == 0 && exited && exit_code == 0; }
};

/// Runs `executable` (searched on PATH) with `arguments` in `directory`, its output in
/// directory/log_name, and waits for it.
[[nodiscard]] ProcessResult run_program(const std::string& executable, const std::vector<std::string>& arguments,
                                        const std::filesystem::path& directory, const std::string& log_name);

/// The lines of `log` that contain `marker`, each followed by `context` more non-empty lines,
/// indented by two spaces after a newline (for quoting a tool's own error messages).
[[nodiscard]] std::string quote_lines(const std::string& log, const std::string& marker, int context);

/// The whole text of a file; throws std::runtime_error naming it if it cannot be read.
[[nodiscard]] std::string read_file(const std::filesystem::path& p);

}  // namespace wbm::fem::detail
