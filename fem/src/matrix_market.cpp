#include <wbm/fem/matrix_market.hpp>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <stdexcept>
#include <string_view>
#include <vector>

namespace wbm::fem {
namespace {

// 10⁸ rows: beyond the largest FE models exchanged this way (~10⁷ DOFs), and within Eigen's int
// StorageIndex; a 30-byte size line must not make the reader allocate gigabytes.
constexpr long long kMaxDimension = 100'000'000;
constexpr size_t kMaxReserve = size_t{1} << 20;

std::vector<std::string_view> words(std::string_view line) {
  std::vector<std::string_view> w;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    const size_t start = i;
    while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    if (i > start) w.push_back(line.substr(start, i - start));
  }
  return w;
}

std::string lower(std::string_view w) {
  std::string s(w);
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

bool parse_integer(std::string_view w, long long& out) {
  const auto [end, ec] = std::from_chars(w.data(), w.data() + w.size(), out);
  return ec == std::errc() && end == w.data() + w.size();
}

bool parse_real(std::string_view w, double& out) {
  const auto [end, ec] = std::from_chars(w.data(), w.data() + w.size(), out);
  return ec == std::errc() && end == w.data() + w.size() && std::isfinite(out);
}

// A short, printable excerpt of a line for messages (fuzzed input may hold anything).
std::string excerpt(std::string_view line) {
  std::string s;
  for (char c : line.substr(0, 60)) s += std::isprint(static_cast<unsigned char>(c)) ? c : '?';
  return line.size() > 60 ? s + "..." : s;
}

}  // namespace

Eigen::SparseMatrix<double> read_matrix_market(std::istream& in, const std::string& source) {
  long long line_number = 0;
  auto fail = [&](const std::string& what) -> void {
    throw std::invalid_argument(source + ":" + std::to_string(line_number) + ": " + what);
  };
  std::string line;
  auto next = [&]() {
    if (!std::getline(in, line)) return false;
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return true;
  };

  if (!next()) fail("empty file; expected the header \"%%MatrixMarket matrix coordinate real general\"");
  const auto header = words(line);
  const std::string supported = "\"%%MatrixMarket matrix coordinate real|integer general|symmetric\"";
  if (header.size() != 5 || header[0] != "%%MatrixMarket" || lower(header[1]) != "matrix" ||
      lower(header[2]) != "coordinate" || (lower(header[3]) != "real" && lower(header[3]) != "integer") ||
      (lower(header[4]) != "general" && lower(header[4]) != "symmetric")) {
    fail("header \"" + excerpt(line) + "\" is not supported; expected " + supported +
         " (dense 'array', complex, pattern, hermitian and skew-symmetric files are not read)");
  }
  const bool integer_field = lower(header[3]) == "integer";
  const bool symmetric = lower(header[4]) == "symmetric";

  // Size line: the first line that is neither a comment nor blank.
  long long rows = 0, cols = 0, entries = 0;
  bool sized = false;
  while (next()) {
    const auto w = words(line);
    if (w.empty() || w[0].front() == '%') continue;
    if (w.size() != 3 || !parse_integer(w[0], rows) || !parse_integer(w[1], cols) || !parse_integer(w[2], entries)) {
      fail("size line \"" + excerpt(line) + "\": expected three integers \"rows cols entries\"");
    }
    if (rows < 1 || cols < 1 || rows > kMaxDimension || cols > kMaxDimension) {
      fail("size " + std::to_string(rows) + " x " + std::to_string(cols) + ": rows and cols must lie in [1, " +
           std::to_string(kMaxDimension) + "]");
    }
    if (symmetric && rows != cols) {
      fail("a symmetric matrix must be square; the size line says " + std::to_string(rows) + " x " + std::to_string(cols));
    }
    // entries ≤ rows·cols (or the lower triangle), computed without overflow.
    const long double capacity = symmetric ? 0.5L * static_cast<long double>(rows) * static_cast<long double>(rows + 1)
                                           : static_cast<long double>(rows) * static_cast<long double>(cols);
    if (entries < 0 || static_cast<long double>(entries) > capacity) {
      fail(std::to_string(entries) + " entries for a " + std::to_string(rows) + " x " + std::to_string(cols) + " " +
           (symmetric ? "symmetric (lower triangle) " : "") + "matrix: must lie in [0, " +
           std::to_string(static_cast<long long>(std::min<long double>(capacity, 9.2e18L))) + "]");
    }
    sized = true;
    break;
  }
  if (!sized) fail("no size line \"rows cols entries\" after the header");

  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(static_cast<size_t>(std::min<long long>(entries, static_cast<long long>(kMaxReserve))) *
                   (symmetric ? 2 : 1));
  long long read = 0;
  while (next()) {
    const auto w = words(line);
    if (w.empty() || w[0].front() == '%') continue;
    if (read == entries) {
      fail("more entries than the " + std::to_string(entries) + " the size line states: \"" + excerpt(line) + "\"");
    }
    long long i = 0, j = 0;
    double v = 0.0;
    long long iv = 0;
    const bool value_ok = w.size() == 3 && (integer_field ? parse_integer(w[2], iv) : parse_real(w[2], v));
    if (w.size() != 3 || !parse_integer(w[0], i) || !parse_integer(w[1], j) || !value_ok) {
      fail("entry \"" + excerpt(line) + "\": expected \"i j value\" with integer indices and a finite " +
           (integer_field ? "integer" : "real") + " value");
    }
    if (integer_field) v = static_cast<double>(iv);
    if (i < 1 || i > rows || j < 1 || j > cols) {
      fail("entry (" + std::to_string(i) + ", " + std::to_string(j) + ") outside the " + std::to_string(rows) + " x " +
           std::to_string(cols) + " matrix (indices are 1-based)");
    }
    if (symmetric && i < j) {
      fail("entry (" + std::to_string(i) + ", " + std::to_string(j) +
           ") lies above the diagonal; a symmetric file holds the lower triangle (i >= j) only");
    }
    const auto r = static_cast<int>(i - 1), c = static_cast<int>(j - 1);
    triplets.emplace_back(r, c, v);
    if (symmetric && r != c) triplets.emplace_back(c, r, v);
    ++read;
  }
  if (read != entries) {
    fail("the size line states " + std::to_string(entries) + " entries, the file holds " + std::to_string(read));
  }
  Eigen::SparseMatrix<double> a(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(cols));
  a.setFromTriplets(triplets.begin(), triplets.end());
  a.makeCompressed();
  if (!a.coeffs().allFinite()) {
    fail("repeated entries sum to a value beyond the double range; give each (i, j) once");
  }
  return a;
}

Eigen::SparseMatrix<double> read_matrix_market_file(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw std::invalid_argument(path + ": is a directory, not a Matrix Market file");
  }
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read Matrix Market file " + path);
  return read_matrix_market(in, path);
}

void write_matrix_market(std::ostream& out, const Eigen::MatrixXd& a, bool symmetric, const std::string& comment) {
  const auto at = [](Eigen::Index i, Eigen::Index j) {
    return std::string("(").append(std::to_string(i + 1)).append(", ").append(std::to_string(j + 1)).append(")");
  };
  if (symmetric && a.rows() != a.cols()) {
    throw std::invalid_argument("write_matrix_market: a symmetric matrix must be square, this one is " +
                                std::to_string(a.rows()) + " x " + std::to_string(a.cols()));
  }
  Eigen::Index entries = 0;
  for (Eigen::Index j = 0; j < a.cols(); ++j) {
    for (Eigen::Index i = symmetric ? j : 0; i < a.rows(); ++i) {
      if (!std::isfinite(a(i, j))) throw std::invalid_argument("write_matrix_market: entry " + at(i, j) + " is not finite");
      if (symmetric && a(i, j) != a(j, i)) {
        throw std::invalid_argument("write_matrix_market: entry " + at(i, j) + " differs from " + at(j, i) +
                                    ": not symmetric; write general instead");
      }
      if (a(i, j) != 0.0) ++entries;
    }
  }
  out << "%%MatrixMarket matrix coordinate real " << (symmetric ? "symmetric" : "general") << "\n";
  size_t begin = 0;
  while (!comment.empty() && begin <= comment.size()) {
    const size_t end = std::min(comment.find('\n', begin), comment.size());
    out << "% " << comment.substr(begin, end - begin) << "\n";
    begin = end + 1;
  }
  out << a.rows() << " " << a.cols() << " " << entries << "\n";
  char buffer[64];
  for (Eigen::Index j = 0; j < a.cols(); ++j) {
    for (Eigen::Index i = symmetric ? j : 0; i < a.rows(); ++i) {
      if (a(i, j) == 0.0) continue;
      const auto r = std::to_chars(buffer, buffer + sizeof buffer, a(i, j));
      out << i + 1 << " " << j + 1 << " " << std::string_view(buffer, static_cast<size_t>(r.ptr - buffer)) << "\n";
    }
  }
}

void write_matrix_market_file(const std::filesystem::path& path, const Eigen::MatrixXd& a, bool symmetric,
                              const std::string& comment) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write Matrix Market file " + path.string());
  write_matrix_market(out, a, symmetric, comment);
  if (!out) throw std::runtime_error("writing Matrix Market file " + path.string() + " failed (disk full?)");
}

std::vector<std::pair<int, int>> read_dof_map(std::istream& in, const std::string& source) {
  std::vector<std::pair<int, int>> dofs;
  std::map<std::pair<int, int>, size_t> row_of;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    std::string t = line;
    std::replace(t.begin(), t.end(), ',', ' ');
    const auto w = words(t);
    if (w.empty() || w[0].front() == '%' || w[0].front() == '#' || w[0].rfind("**", 0) == 0) continue;
    long long node = 0, direction = 0;
    bool ok = false;
    if (w.size() == 1) {
      const auto dot = w[0].find('.');
      ok = dot != std::string_view::npos && parse_integer(w[0].substr(0, dot), node) &&
           parse_integer(w[0].substr(dot + 1), direction);
    } else if (w.size() == 2) {
      ok = parse_integer(w[0], node) && parse_integer(w[1], direction);
    }
    if (!ok || node < 1 || node > std::numeric_limits<int>::max() || direction < 1 || direction > 6) {
      throw std::invalid_argument(source + ":" + std::to_string(number) +
                                  ": expected 'node.direction', 'node direction' or 'node, direction' with node >= 1 "
                                  "and direction 1-6, got '" + line + "'");
    }
    const std::pair<int, int> key{static_cast<int>(node), static_cast<int>(direction)};
    if (const auto [it, fresh] = row_of.emplace(key, dofs.size()); !fresh) {
      throw std::invalid_argument(source + ":" + std::to_string(number) + ": node " + std::to_string(node) +
                                  " direction " + std::to_string(direction) + " is also row " +
                                  std::to_string(it->second + 1) + "; each row must be a different DOF");
    }
    dofs.push_back(key);
  }
  return dofs;
}

MatrixMarketModel read_matrix_market_model(const std::filesystem::path& stiffness, const std::filesystem::path& mass,
                                           const std::filesystem::path& dofs, const std::filesystem::path& damping) {
  MatrixMarketModel m;
  {
    std::ifstream in(dofs);
    if (!in) throw std::runtime_error("cannot read DOF map " + dofs.string());
    m.dofs = read_dof_map(in, dofs.string());
  }
  const auto n = static_cast<Eigen::Index>(m.dofs.size());
  auto load = [&](const std::filesystem::path& p, const char* what) {
    Eigen::SparseMatrix<double> a = read_matrix_market_file(p.string());
    if (a.rows() != n || a.cols() != n) {
      throw std::invalid_argument(std::string(what).append(" ").append(p.string()).append(" is ")
                                      .append(std::to_string(a.rows())).append(" x ").append(std::to_string(a.cols()))
                                      .append(", but the DOF map ").append(dofs.string()).append(" has ")
                                      .append(std::to_string(n)).append(" rows: give the matrices and the map of one model"));
    }
    return a;
  };
  m.stiffness = load(stiffness, "stiffness");
  m.mass = load(mass, "mass");
  if (!damping.empty()) m.damping = load(damping, "damping");
  return m;
}

}  // namespace wbm::fem
