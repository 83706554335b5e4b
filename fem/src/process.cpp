#include "process.hpp"

#include <fstream>
#include <sstream>
#include <stdexcept>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

namespace wbm::fem::detail {

std::string read_file(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) throw std::runtime_error(p.string() + ": cannot open the file");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

ProcessResult run_program(const std::string& executable, const std::vector<std::string>& arguments,
                          const std::filesystem::path& directory, const std::string& log_name) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addchdir_np(&actions, directory.c_str());
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log_name.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  std::vector<std::string> words{executable};
  words.insert(words.end(), arguments.begin(), arguments.end());
  std::vector<char*> argv;
  for (auto& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);
  ProcessResult r;
  pid_t pid = 0;
  r.spawn_error = posix_spawnp(&pid, executable.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (r.spawn_error != 0) return r;
  int status = 0;
  waitpid(pid, &status, 0);
  r.exited = WIFEXITED(status);
  r.exit_code = r.exited ? WEXITSTATUS(status) : -1;
  try {
    r.log = read_file(directory / log_name);
  } catch (const std::exception&) {
  }
  return r;
}

std::string quote_lines(const std::string& log, const std::string& marker, int context) {
  std::string out;
  std::istringstream in(log);
  std::string line;
  int keep = 0;
  while (std::getline(in, line)) {
    if (line.find(marker) != std::string::npos) keep = context + 1;
    const auto first = line.find_first_not_of(" \t\r");
    if (keep > 0 && first != std::string::npos) {
      const auto last = line.find_last_not_of(" \t\r");
      out += "\n  " + line.substr(first, last - first + 1);
      --keep;
    }
  }
  return out;
}

}  // namespace wbm::fem::detail
