#pragma once
/// Matrix Market coordinate files [Boisvert, Pozo & Remington 1996, "The Matrix Market Exchange
/// Formats"], the exchange format of FE codes' assembled matrices (mass, stiffness, damping).
/// Units: whatever the file's FE model uses; nothing is converted here.

#include <filesystem>
#include <istream>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace wbm::fem {

/// Reads "%%MatrixMarket matrix coordinate real|integer general|symmetric" text:
///   header line, comment lines (starting with %) and blank lines, then "rows cols entries",
///   then exactly `entries` lines "i j value" (1-based indices, 1 ≤ i ≤ rows, 1 ≤ j ≤ cols).
/// symmetric files hold the lower triangle (i ≥ j) and are mirrored on return; repeated (i, j)
/// entries are summed (as in FE assembly). Returns the rows × cols matrix (compressed,
/// column-major), square or not: the caller checks the shape it needs.
/// Throws std::invalid_argument with "source:line: what was expected" for: a missing or unsupported
/// header (array, complex, pattern, hermitian and skew-symmetric are refused, naming the supported
/// forms), a size line that is not three non-negative integers with rows, cols ≥ 1 and ≤ 10⁸ (a
/// memory guard: ~10× the largest FE models exchanged this way), an index out of range or above the
/// diagonal in a symmetric file, a value that is not a finite number, repeated entries whose sum is
/// not finite, more or fewer entries than the size line states, and trailing text on a line.
/// Numbers are parsed with std::from_chars (no locale). Memory is reserved for at most 2²⁰ entries
/// before they are read, so a size line cannot request more than the file holds. Verified by
/// tests/fem/test_matrix_market.cpp and fuzzed by tests/fuzz/fuzz_matrix_market.cpp.
[[nodiscard]] Eigen::SparseMatrix<double> read_matrix_market(std::istream& in, const std::string& source);

/// The same from a file; throws std::invalid_argument for a directory and std::runtime_error
/// naming the path if it cannot be opened.
[[nodiscard]] Eigen::SparseMatrix<double> read_matrix_market_file(const std::string& path);

/// Writes A as "%%MatrixMarket matrix coordinate real general|symmetric" text that
/// read_matrix_market reads back bit for bit: symmetric = true writes the lower triangle
/// (i ≥ j) of a matrix that must be symmetric (checked exactly; std::invalid_argument naming the
/// first asymmetric entry otherwise, with "write general instead"), general the whole matrix;
/// exact zeros are left out; each value in the shortest decimal form that reads back to the
/// same double (std::to_chars). `comment` lines (split on '\n') are written as "% …" after the header.
/// Throws std::invalid_argument for a non-finite entry (naming it), a non-square symmetric
/// matrix, and std::runtime_error naming the path when the file cannot be written.
void write_matrix_market(std::ostream& out, const Eigen::MatrixXd& a, bool symmetric, const std::string& comment = {});
void write_matrix_market_file(const std::filesystem::path& path, const Eigen::MatrixXd& a, bool symmetric,
                              const std::string& comment = {});

/// A DOF map: what each row of an FE code's matrices is, one line per row in row order:
/// "node.direction" (CalculiX's .dof file), "node direction" or "node, direction", with
/// direction 1, 2, 3 = x, y, z and 4, 5, 6 = rotations about them. Blank lines and comment lines
/// (starting with '%', '#' or "**") are skipped. Returns (node, direction) per row.
/// Throws std::invalid_argument "source:line: expected 'node.direction' …" for anything else,
/// and naming both rows for a (node, direction) given twice.
[[nodiscard]] std::vector<std::pair<int, int>> read_dof_map(std::istream& in, const std::string& source);

/// Mass, stiffness and optional damping from another FE code, as Matrix Market files, with the
/// DOF map of their rows (users whose FE code is not CalculiX; issue #15).
struct MatrixMarketModel {
  Eigen::SparseMatrix<double> stiffness;  // K, n × n [the FE model's units]
  Eigen::SparseMatrix<double> mass;       // M, n × n
  Eigen::SparseMatrix<double> damping;    // C, n × n, or 0 × 0 when no file was given
  std::vector<std::pair<int, int>> dofs;  // per row: (node, direction)
};

/// Reads K, M (and C unless `damping` is empty) and the DOF map. Throws std::runtime_error naming
/// a file that cannot be opened, and std::invalid_argument (naming the files and sizes) unless
/// every matrix is square and of the map's length n.
[[nodiscard]] MatrixMarketModel read_matrix_market_model(const std::filesystem::path& stiffness,
                                                         const std::filesystem::path& mass,
                                                         const std::filesystem::path& dofs,
                                                         const std::filesystem::path& damping = {});

}  // namespace wbm::fem
