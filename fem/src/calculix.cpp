#include <wbm/fem/calculix.hpp>
#include <wbm/fem/matrix_market.hpp>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <system_error>

#include <unistd.h>

#include "process.hpp"

namespace wbm::fem {
namespace {

std::string upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

std::string trim(std::string_view s) {
  size_t a = 0, b = s.size();
  while (a < b && std::isspace(static_cast<unsigned char>(s[a])) != 0) ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1])) != 0) --b;
  return std::string(s.substr(a, b - a));
}

std::vector<std::string> split_whitespace(const std::string& line) {
  std::vector<std::string> out;
  std::istringstream in(line);
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::string field;
  std::istringstream in(line);
  while (std::getline(in, field, ',')) out.push_back(trim(field));
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

using detail::read_file;

template <typename T>
bool parse_number(std::string_view s, T& v) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front())) != 0) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back())) != 0) s.remove_suffix(1);
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  return ec == std::errc() && end == s.data() + s.size() && !s.empty();
}

// A keyword line: the keyword (upper case, spaces removed) and its parameters (upper-case names;
// values as written, trimmed).
struct Keyword {
  std::string name;
  std::map<std::string, std::string> parameters;
};

Keyword keyword(const std::string& line) {
  const auto fields = split(line.substr(1));
  Keyword k;
  for (char c : fields.empty() ? std::string() : fields[0]) {
    if (c != ' ') k.name += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  }
  for (size_t i = 1; i < fields.size(); ++i) {
    const auto eq = fields[i].find('=');
    if (eq == std::string::npos) {
      k.parameters[upper(fields[i])] = "";
    } else {
      k.parameters[upper(trim(fields[i].substr(0, eq)))] = trim(fields[i].substr(eq + 1));
    }
  }
  return k;
}

class DeckReader {
 public:
  explicit DeckReader(CalculixDeck& deck) : d_(deck) {}

  // Returns true when a *STEP was met (the model data ends there).
  bool read(const std::filesystem::path& path, int depth) {
    if (depth > 16) throw std::invalid_argument(path.string() + ": *INCLUDE nested more than 16 deep (a cycle?)");
    const std::string text = read_file(path);
    std::istringstream in(text);
    std::string line;
    int number = 0;
    Keyword current;
    std::string pending;  // an element line continued after a trailing comma
    int pending_line = 0;
    auto fail = [&](int at, const std::string& what) {
      throw std::invalid_argument(path.string() + ":" + std::to_string(at) + ": " + what);
    };
    while (std::getline(in, line)) {
      ++number;
      if (!line.empty() && line.back() == '\r') line.pop_back();
      const std::string t = trim(line);
      if (t.rfind("**", 0) == 0) {
        d_.model_data += line + "\n";
        continue;
      }
      if (t.empty()) continue;
      if (t.front() == '*') {
        if (!pending.empty()) fail(pending_line, "*ELEMENT data line ends with a comma but no line continues it");
        current = keyword(t);
        if (current.name == "STEP") return true;
        if (current.name == "INCLUDE") {
          const auto input = current.parameters.find("INPUT");
          if (input == current.parameters.end() || input->second.empty()) {
            fail(number, "*INCLUDE without INPUT=file");
          }
          std::filesystem::path inc = input->second;
          if (inc.is_relative()) inc = path.parent_path() / inc;
          if (read(inc, depth + 1)) return true;
          current = Keyword{};
          continue;
        }
        d_.model_data += line + "\n";
        static const std::set<std::string> constraints = {"EQUATION", "MPC", "RIGIDBODY", "TIE", "COUPLING",
                                                          "DISTRIBUTING", "KINEMATIC", "TRANSFORM", "NODALTHICKNESS"};
        if (constraints.count(current.name) != 0) d_.constraint_keywords.insert(current.name);
        if (current.name == "ELEMENT") {
          element_type_ = upper(current.parameters.count("TYPE") ? current.parameters.at("TYPE") : "");
          if (element_type_.empty()) fail(number, "*ELEMENT without TYPE= (e.g. TYPE=C3D10)");
        }
        continue;
      }
      d_.model_data += line + "\n";
      if (current.name == "NODE") {
        const auto f = split(t);
        int id = 0;
        Eigen::Vector3d x = Eigen::Vector3d::Zero();
        if (f.size() < 2 || !parse_number(f[0], id)) fail(number, "*NODE data: expected 'number, x[, y[, z]]', got '" + t + "'");
        for (size_t i = 1; i < f.size() && i < 4; ++i) {
          if (!f[i].empty() && !parse_number(f[i], x(static_cast<Eigen::Index>(i - 1)))) {
            fail(number, "*NODE " + std::to_string(id) + ": coordinate '" + f[i] + "' is not a number");
          }
        }
        if (!d_.nodes.emplace(id, x).second) fail(number, "*NODE " + std::to_string(id) + " is defined twice");
        if (current.parameters.count("NSET")) d_.node_sets[upper(current.parameters.at("NSET"))].push_back(id);
      } else if (current.name == "ELEMENT") {
        pending += t;
        if (pending_line == 0) pending_line = number;
        if (t.back() == ',') continue;
        int id = 0;
        const auto f = split(pending);
        if (f.size() < 2 || !parse_number(f[0], id)) fail(pending_line, "*ELEMENT data: expected 'number, node, node, …'");
        for (size_t i = 1; i < f.size(); ++i) {
          int node = 0;
          if (f[i].empty()) continue;
          if (!parse_number(f[i], node)) fail(pending_line, "*ELEMENT " + std::to_string(id) + ": node '" + f[i] + "' is not a number");
          d_.element_types_at[node].insert(element_type_);
        }
        ++d_.element_types[element_type_];
        pending.clear();
        pending_line = 0;
      } else if (current.name == "BOUNDARY") {
        boundary(split(t), number, fail);
      } else if (current.name == "NSET") {
        const auto name = current.parameters.find("NSET");
        if (name == current.parameters.end() || name->second.empty()) fail(number, "*NSET without NSET=name");
        auto& set = d_.node_sets[upper(name->second)];
        const auto f = split(t);
        if (current.parameters.count("GENERATE")) {
          int a = 0, b = 0, step = 1;
          if (f.size() < 2 || !parse_number(f[0], a) || !parse_number(f[1], b) ||
              (f.size() > 2 && !f[2].empty() && !parse_number(f[2], step)) || step <= 0 || b < a) {
            fail(number, "*NSET, GENERATE: expected 'first, last[, step]' with first <= last and step > 0");
          }
          for (int k = a; k <= b; k += step) set.push_back(k);
        } else {
          for (const auto& e : f) {
            if (e.empty()) continue;
            int id = 0;
            if (parse_number(e, id)) {
              set.push_back(id);
            } else if (auto other = d_.node_sets.find(upper(e)); other != d_.node_sets.end() && &other->second != &set) {
              const std::vector<int> copy = other->second;
              set.insert(set.end(), copy.begin(), copy.end());
            } else {
              fail(number, "*NSET " + name->second + ": '" + e + "' is neither a node number nor a node set defined before");
            }
          }
        }
      }
    }
    if (!pending.empty()) fail(pending_line, "*ELEMENT data line ends with a comma but the file ends");
    return false;
  }

 private:
  // "node or set, first[, last[, value]]": directions first … last fixed at the nodes.
  template <typename Fail>
  void boundary(const std::vector<std::string>& f, int number, const Fail& fail) {
    int first = 0, last = 0;
    if (f.size() < 2 || !parse_number(f[1], first) || first < 1) {
      fail(number, "*BOUNDARY data: expected 'node or node set, first direction[, last direction[, value]]'");
    }
    last = first;
    if (f.size() > 2 && !f[2].empty() && (!parse_number(f[2], last) || last < first)) {
      fail(number, "*BOUNDARY data: the last direction '" + f[2] + "' is not a number >= the first (" + std::to_string(first) + ")");
    }
    std::vector<int> nodes;
    int node = 0;
    if (parse_number(f[0], node)) {
      nodes.push_back(node);
    } else if (const auto set = d_.node_sets.find(upper(f[0])); set != d_.node_sets.end()) {
      nodes = set->second;
    } else {
      fail(number, "*BOUNDARY: '" + f[0] + "' is neither a node number nor a node set defined before");
    }
    for (int n : nodes) {
      for (int k = first; k <= std::min(last, 6); ++k) d_.fixed_directions[n].insert(k);
    }
  }

  CalculixDeck& d_;
  std::string element_type_;
};

// "row col value" lines (1-based, upper triangle) → the symmetric n × n matrix.
Eigen::SparseMatrix<double> triangle(const std::string& text, int n, const std::string& source) {
  std::vector<Eigen::Triplet<double>> t;
  size_t pos = 0;
  int number = 0;
  while (pos < text.size()) {
    size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    std::string_view line(text.data() + pos, end - pos);
    pos = end + 1;
    ++number;
    while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back())) != 0) line.remove_suffix(1);
    if (line.empty()) continue;
    const char* p = line.data();
    const char* e = line.data() + line.size();
    int i = 0, j = 0;
    double v = 0.0;
    auto skip = [&] {
      while (p < e && (*p == ' ' || *p == '\t')) ++p;
    };
    skip();
    auto r1 = std::from_chars(p, e, i);
    p = r1.ptr;
    skip();
    auto r2 = std::from_chars(p, e, j);
    p = r2.ptr;
    skip();
    auto r3 = std::from_chars(p, e, v);
    p = r3.ptr;
    skip();
    if (r1.ec != std::errc() || r2.ec != std::errc() || r3.ec != std::errc() || p != e || i < 1 || j < 1 || i > n ||
        j > n || !std::isfinite(v)) {
      throw std::invalid_argument(source + ":" + std::to_string(number) + ": expected 'row col value' with 1 <= row, col <= " +
                                  std::to_string(n) + " and a finite value, got '" + std::string(line) + "'");
    }
    t.emplace_back(i - 1, j - 1, v);
    if (i != j) t.emplace_back(j - 1, i - 1, v);
  }
  Eigen::SparseMatrix<double> a(n, n);
  a.setFromTriplets(t.begin(), t.end());
  return a;
}

}  // namespace

int CalculixDeck::elements() const {
  int n = 0;
  for (const auto& [type, count] : element_types) n += count;
  return n;
}

const std::vector<int>& CalculixDeck::node_set(const std::string& name) const {
  const auto it = node_sets.find(upper(name));
  if (it != node_sets.end()) return it->second;
  std::string known;
  for (const auto& [k, v] : node_sets) known += (known.empty() ? "" : ", ") + k;
  throw std::invalid_argument(file.string() + ": no node set '" + name + "'; the deck defines: " +
                              (known.empty() ? "none" : known));
}

std::vector<int> free_directions(const CalculixDeck& deck, int node) {
  const auto types = deck.element_types_at.find(node);
  if (types == deck.element_types_at.end()) return {};
  std::string expanded;
  for (const auto& type : types->second) {
    const bool kept = type.rfind("C3D", 0) == 0 || type.rfind("SPRING", 0) == 0 || type.rfind("DASHPOT", 0) == 0 ||
                      type == "MASS" || type.rfind("GAP", 0) == 0;
    if (!kept) expanded += (expanded.empty() ? "" : ", ") + type;
  }
  if (!expanded.empty()) {
    throw std::invalid_argument("node " + std::to_string(node) + " of " + deck.file.string() + " lies on " + expanded +
                                " elements, which CalculiX expands into new 3D nodes: its DOFs are not the node's; "
                                "choose interface nodes of 3D solid elements (C3D…)");
  }
  const auto fixed = deck.fixed_directions.find(node);
  std::vector<int> free;
  for (int k = 1; k <= 3; ++k) {
    if (fixed == deck.fixed_directions.end() || fixed->second.count(k) == 0) free.push_back(k);
  }
  return free;
}

CalculixDeck read_calculix_deck(const std::filesystem::path& path) {
  CalculixDeck deck;
  deck.file = std::filesystem::absolute(path).lexically_normal();
  DeckReader(deck).read(deck.file, 0);
  return deck;
}

AssembledModel parse_calculix_matrices(const std::string& stiffness, const std::string& mass, const std::string& dofs,
                                       const std::string& source) {
  AssembledModel m;
  std::istringstream in(dofs);
  m.dofs = read_dof_map(in, source + ".dof");
  if (m.dofs.empty()) throw std::invalid_argument(source + ".dof: no degree of freedom (every DOF constrained?)");
  const int n = static_cast<int>(m.dofs.size());
  m.stiffness = triangle(stiffness, n, source + ".sti");
  m.mass = triangle(mass, n, source + ".mas");
  return m;
}

void CalculixOptions::validate() const {
  if (executable.empty()) {
    throw std::invalid_argument("CalculixOptions.executable is empty: give \"ccx\" (install calculix-ccx) or a path to it");
  }
  std::error_code ec;
  if (!work_directory.empty() && std::filesystem::exists(work_directory, ec) &&
      !std::filesystem::is_directory(work_directory, ec)) {
    throw std::invalid_argument("CalculixOptions.work_directory = " + work_directory.string() +
                                ": exists and is not a folder; give a folder, or leave it empty for a scratch folder");
  }
}

namespace {

// Runs ccx on the driver deck "model data + `step`" in a scratch folder (or options.work_directory)
// and returns the named files it wrote, read whole. Throws std::runtime_error naming the deck:
// ccx not found, ccx failing (its "*ERROR" lines quoted), a file missing.
std::vector<std::string> run_calculix(const CalculixDeck& deck, const std::string& step, const CalculixOptions& options,
                                      const std::vector<std::string>& files, const std::string& what) {
  namespace fs = std::filesystem;
  options.validate();
  const std::string name = deck.file.string();
  static int counter = 0;
  const bool scratch = options.work_directory.empty();
  const fs::path dir = scratch ? fs::temp_directory_path() /
                                     ("wbm-ccx-" + std::to_string(::getpid()) + "-" + std::to_string(counter++))
                               : options.work_directory;
  fs::create_directories(dir);
  struct Cleanup {
    fs::path dir;
    bool on;
    ~Cleanup() {
      std::error_code ignored;
      if (on) fs::remove_all(dir, ignored);
    }
  } cleanup{dir, scratch};
  {
    std::ofstream job(dir / "job.inp");
    job << deck.model_data << step;
    if (!job) throw std::runtime_error(name + ": cannot write the driver deck in " + dir.string());
  }
  // ccx -i job, in dir, output to ccx.log (no shell).
  const auto ccx = detail::run_program(options.executable, {"-i", "job"}, dir, "ccx.log");
  if (ccx.spawn_error != 0) {
    throw std::runtime_error(name + ": cannot run '" + options.executable + "' (" +
                             std::generic_category().message(ccx.spawn_error) +
                             "): install CalculiX (Debian calculix-ccx) or set CalculixOptions::executable");
  }
  const std::string errors = detail::quote_lines(ccx.log, "*ERROR", 1);  // ccx's own "*ERROR" lines and the next
  const bool missing = std::any_of(files.begin(), files.end(), [&](const auto& f) { return !fs::exists(dir / f); });
  if (!ccx.succeeded() || !errors.empty() || missing) {
    throw std::runtime_error(name + ": CalculiX (" + options.executable + ") could not " + what +
                             (ccx.exited ? std::string(" (exit ").append(std::to_string(ccx.exit_code)).append(")") : std::string()) +
                             (errors.empty() ? "; no *ERROR line, see its output:\n" + ccx.log.substr(0, 2000)
                                             : "; ccx says:" + errors));
  }
  std::vector<std::string> text;
  for (const auto& f : files) text.push_back(read_file(dir / f));
  return text;
}

}  // namespace

AssembledModel assemble_with_calculix(const CalculixDeck& deck, const CalculixOptions& options) {
  const auto text = run_calculix(deck, "*STEP\n*FREQUENCY, SOLVER=MATRIXSTORAGE\n*END STEP\n", options,
                                 {"job.sti", "job.mas", "job.dof"}, "assemble the model");
  return parse_calculix_matrices(text[0], text[1], text[2], deck.file.string() + " (ccx job)");
}

std::vector<double> parse_calculix_frequencies(const std::string& dat, const std::string& source) {
  // The table after "E I G E N V A L U E   O U T P U T": "mode eigenvalue ω f imaginary", up to
  // the participation factors (or the end).
  std::vector<double> out;
  std::istringstream in(dat);
  std::string line;
  bool table = false;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.find("E I G E N V A L U E   O U T P U T") != std::string::npos) {
      table = true;
      continue;
    }
    if (!table) continue;
    if (line.find("P A R T I C I P A T I O N") != std::string::npos) break;
    const auto f = split_whitespace(line);
    int mode = 0;
    if (f.size() != 5 || !parse_number(f[0], mode)) continue;  // headings and blank lines
    double values[4];
    for (size_t i = 0; i < 4; ++i) {
      if (!parse_number(f[i + 1], values[i]) || !std::isfinite(values[i])) {
        throw std::invalid_argument(source + ":" + std::to_string(number) + ": eigenvalue row of mode " +
                                    std::to_string(mode) + ": '" + f[i + 1] + "' is not a finite number");
      }
    }
    if (mode != static_cast<int>(out.size()) + 1) {
      throw std::invalid_argument(source + ":" + std::to_string(number) + ": mode " + std::to_string(mode) +
                                  " where mode " + std::to_string(out.size() + 1) + " was expected");
    }
    out.push_back(values[2]);  // CYCLES/TIME
  }
  if (out.empty()) throw std::invalid_argument(source + ": no eigenvalue table (E I G E N V A L U E   O U T P U T)");
  return out;
}

std::vector<double> calculix_frequencies(const CalculixDeck& deck, int count, const CalculixOptions& options) {
  if (count < 1) {
    throw std::invalid_argument(deck.file.string() + ": calculix_frequencies: count = " + std::to_string(count) +
                                ": must be >= 1");
  }
  const auto text = run_calculix(deck, "*STEP\n*FREQUENCY\n" + std::to_string(count) + "\n*END STEP\n", options,
                                 {"job.dat"}, "compute the frequencies");
  auto f = parse_calculix_frequencies(text[0], deck.file.string() + " (ccx job.dat)");
  if (static_cast<int>(f.size()) < count) {
    throw std::runtime_error(deck.file.string() + ": CalculiX printed " + std::to_string(f.size()) + " of the " +
                             std::to_string(count) + " frequencies asked for (see its .dat)");
  }
  f.resize(static_cast<size_t>(count));
  return f;
}

}  // namespace wbm::fem
