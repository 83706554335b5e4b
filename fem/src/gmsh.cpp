#include <wbm/fem/gmsh.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <vector>

#include "process.hpp"

namespace wbm::fem {

void GmshOptions::validate() const {
  if (executable.empty()) throw std::invalid_argument("GmshOptions.executable is empty: give \"gmsh\" or a path to it");
  if (dimension < 1 || dimension > 3) {
    throw std::invalid_argument(
        std::string("GmshOptions.dimension = ").append(std::to_string(dimension)).append(": must be 1, 2 or 3"));
  }
  for (const auto& [name, value] : numbers) {
    const bool identifier = !name.empty() && (std::isalpha(static_cast<unsigned char>(name[0])) != 0 || name[0] == '_') &&
                            std::all_of(name.begin(), name.end(), [](char c) {
                              return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_';
                            });
    if (!identifier) {
      throw std::invalid_argument("GmshOptions.numbers: name '" + name +
                                  "' is not a gmsh identifier ([A-Za-z_][A-Za-z0-9_]*); use the name the script reads");
    }
    if (!std::isfinite(value)) {
      throw std::invalid_argument("GmshOptions.numbers[" + name + "] = " + std::to_string(value) +
                                  ": must be finite");
    }
  }
}

int mesh_with_gmsh(const std::filesystem::path& geo, const std::filesystem::path& output, const GmshOptions& options) {
  namespace fs = std::filesystem;
  if (!fs::is_regular_file(geo)) {
    throw std::invalid_argument("mesh_with_gmsh: geometry script " + geo.string() + " does not exist");
  }
  options.validate();
  const fs::path script = fs::absolute(geo), mesh = fs::absolute(output), dir = mesh.parent_path();
  fs::create_directories(dir);
  // std::string(...).append, not "lit" + std::to_string: GCC 12's -Wrestrict false positive.
  std::vector<std::string> args{std::string("-").append(std::to_string(options.dimension)), script.string()};
  for (const auto& [name, value] : options.numbers) {
    std::ostringstream v;
    v.precision(17);
    v << value;
    args.insert(args.end(), {"-setnumber", name, v.str()});
  }
  args.insert(args.end(), {"-format", "inp", "-o", mesh.string()});
  const std::string log_name = mesh.filename().string() + ".log";
  std::error_code ignored;
  fs::remove(mesh, ignored);
  const auto r = detail::run_program(options.executable, args, dir, log_name);
  const std::string name = geo.string();
  if (r.spawn_error != 0) {
    throw std::runtime_error(name + ": cannot run '" + options.executable + "' (" +
                             std::generic_category().message(r.spawn_error) +
                             "): install gmsh (Debian gmsh) or set GmshOptions::executable");
  }
  const std::string errors = detail::quote_lines(r.log, "Error", 0);
  int nodes = 0;
  if (r.succeeded() && errors.empty() && fs::exists(mesh)) {
    std::istringstream in(detail::read_file(mesh));
    std::string line;
    bool in_nodes = false;
    while (std::getline(in, line)) {
      if (!line.empty() && line[0] == '*') {
        in_nodes = line.rfind("*NODE", 0) == 0;  // "*NODE" or "*NODE, NSET=…" (gmsh writes upper case)
        continue;
      }
      if (in_nodes && !line.empty()) ++nodes;
    }
  }
  if (!r.succeeded() || !errors.empty() || nodes == 0) {
    fs::remove(mesh, ignored);  // gmsh writes a mesh after some errors: never leave one that looks complete
    throw std::runtime_error(name + ": gmsh (" + options.executable + ") could not mesh it" +
                             (r.exited ? std::string(" (exit ").append(std::to_string(r.exit_code)).append(")") : std::string()) +
                             (errors.empty() ? "; it wrote no nodes; its output is in " + (dir / log_name).string()
                                             : "; gmsh says:" + errors) +
                             " (log: " + (dir / log_name).string() + ")");
  }
  fs::remove(dir / log_name, ignored);
  return nodes;
}

}  // namespace wbm::fem
