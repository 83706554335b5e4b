// libFuzzer target: fem::read_matrix_market and fem::read_dof_map on arbitrary bytes. Its contract (matrix_market.hpp)
// allows a matrix or std::invalid_argument; anything else (another exception, a sanitizer
// report, a timeout, more memory than the input justifies) is a finding. A returned matrix has
// the stated shape, only finite values, and is symmetric when the header says so; a returned DOF
// map has nodes >= 1, directions 1-6 and no DOF twice.
#include <cctype>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

#include <wbm/fem/matrix_market.hpp>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  std::istringstream in(text);
  try {
    const Eigen::SparseMatrix<double> a = wbm::fem::read_matrix_market(in, "fuzz.mtx");
    if (a.rows() < 1 || a.cols() < 1) std::abort();
    for (Eigen::Index k = 0; k < a.nonZeros(); ++k) {
      if (!std::isfinite(a.valuePtr()[k])) std::abort();
    }
    // The header (first line) was accepted, so its last word is general or symmetric (any case).
    std::string header = text.substr(0, text.find('\n'));
    for (char& ch : header) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    if (header.find("symmetric") != std::string::npos) {
      const Eigen::SparseMatrix<double> at = a.transpose();
      if ((a - at).norm() != 0.0) std::abort();
    }
  } catch (const std::invalid_argument&) {
    // bad input, reported with its line: the contract
  }
  std::istringstream map_in(text);
  try {
    const auto dofs = wbm::fem::read_dof_map(map_in, "fuzz.dof");
    std::set<std::pair<int, int>> seen;
    for (const auto& d : dofs) {
      if (d.first < 1 || d.second < 1 || d.second > 6 || !seen.insert(d).second) std::abort();
    }
  } catch (const std::invalid_argument&) {
    // the contract
  }
  return 0;
}
