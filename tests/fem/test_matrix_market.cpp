// Matrix Market reader against hand-written files whose matrices are known entry by entry, the
// format's rules [Boisvert, Pozo & Remington 1996] (1-based indices, lower triangle of a
// symmetric file, exact entry count), and each refusal with its line number.
#include <wbm/fem/matrix_market.hpp>

#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "testing.hpp"

namespace {
Eigen::MatrixXd read(const std::string& text) {
  std::istringstream in(text);
  return Eigen::MatrixXd(wbm::fem::read_matrix_market(in, "m.mtx"));
}

void expect_refused(const std::string& text, const std::vector<std::string>& fragments) {
  wbm::testing::expect_throw_with<std::invalid_argument>([&] { (void)read(text); }, fragments);
}
}  // namespace

// Three 10 kN/m springs in series clamped at one end (examples/scenes/chain.mtx): the
// tridiagonal K = 1e4·[[2, −1, 0], [−1, 2, −1], [0, −1, 1]] from its lower triangle.
TEST(MatrixMarket, SymmetricFileIsMirroredFromItsLowerTriangle) {
  const Eigen::MatrixXd k = read(
      "%%MatrixMarket matrix coordinate real symmetric\n% springs\n\n3 3 5\n1 1 2e4\n2 1 -1e4\n2 2 2e4\n3 2 -1e4\n"
      "3 3 1e4\n");
  Eigen::MatrixXd expected(3, 3);
  expected << 2e4, -1e4, 0, -1e4, 2e4, -1e4, 0, -1e4, 1e4;
  EXPECT_EQ(k, expected);
}

// General file, integer field, CRLF line ends, a repeated entry summed (FE assembly), a
// non-square shape (the caller checks the shape it needs).
TEST(MatrixMarket, GeneralIntegerFileWithRepeatedEntries) {
  const Eigen::MatrixXd a = read("%%MatrixMarket matrix coordinate integer general\r\n2 3 4\r\n1 3 5\r\n2 1 -2\r\n"
                                 "2 1 7\r\n1 1 1\r\n");
  Eigen::MatrixXd expected(2, 3);
  expected << 1, 0, 5, 5, 0, 0;
  EXPECT_EQ(a, expected);
}

// Every refusal names the line and what was expected.
TEST(MatrixMarket, RefusesMalformedFilesNamingTheLine) {
  const std::string real = "%%MatrixMarket matrix coordinate real general\n";
  expect_refused("", {"m.mtx:0:", "empty file"});
  expect_refused("%%MatrixMarket matrix array real general\n2 2\n", {"m.mtx:1:", "not supported", "array"});
  expect_refused("%%MatrixMarket matrix coordinate complex general\n", {"m.mtx:1:", "real|integer"});
  expect_refused(real + "2 2\n", {"m.mtx:2:", "three integers"});
  expect_refused(real + "0 2 0\n", {"m.mtx:2:", "[1, 100000000]"});
  expect_refused(real + "200000000 200000000 0\n", {"m.mtx:2:", "rows and cols"});
  expect_refused(real + "2 2 5\n", {"m.mtx:2:", "5 entries", "[0, 4]"});
  expect_refused(real + "2 2 1\n3 1 1.0\n", {"m.mtx:3:", "(3, 1) outside the 2 x 2"});
  expect_refused(real + "2 2 1\n0 1 1.0\n", {"m.mtx:3:", "1-based"});
  expect_refused(real + "2 2 1\n1 1 nan\n", {"m.mtx:3:", "finite real"});
  expect_refused(real + "2 2 1\n1 1 1e400\n", {"m.mtx:3:", "finite real"});
  expect_refused(real + "2 2 1\n1 1 1.0 7\n", {"m.mtx:3:", "i j value"});
  expect_refused(real + "2 2 2\n1 1 1e308\n1 1 1e308\n", {"m.mtx:4:", "repeated entries sum"});
  expect_refused(real + "2 2 2\n1 1 1.0\n", {"m.mtx:3:", "states 2 entries, the file holds 1"});
  expect_refused(real + "2 2 1\n1 1 1.0\n2 2 1.0\n", {"m.mtx:4:", "more entries"});
  expect_refused("%%MatrixMarket matrix coordinate real symmetric\n2 2 1\n1 2 1.0\n",
                 {"m.mtx:3:", "above the diagonal", "lower triangle"});
  expect_refused("%%MatrixMarket matrix coordinate real symmetric\n2 3 0\n", {"must be square"});
  expect_refused("%%MatrixMarket matrix coordinate integer general\n1 1 1\n1 1 2.5\n", {"finite integer"});
}

TEST(MatrixMarket, MissingFileNamesThePath) {
  wbm::testing::expect_throw_with<std::runtime_error>(
      [] { (void)wbm::fem::read_matrix_market_file("/nonexistent/k.mtx"); }, {"/nonexistent/k.mtx"});
}

// What write_matrix_market writes, the reader gives back bit for bit (shortest round-trip
// decimals), symmetric from the lower triangle and general as a whole, exact zeros left out; the
// text is the format's (header, comment, size line). Asymmetric "symmetric" input and non-finite
// entries are refused.
TEST(MatrixMarket, WrittenMatricesReadBackExactly) {
  Eigen::MatrixXd s = Eigen::MatrixXd::Random(5, 5);
  s = (s + s.transpose()).eval();
  s(3, 1) = s(1, 3) = 0.0;
  s(0, 0) = 1.0 / 3.0;
  std::ostringstream text;
  wbm::fem::write_matrix_market(text, s, true, "reduced stiffness\nunits: N/m");
  EXPECT_EQ(text.str().rfind("%%MatrixMarket matrix coordinate real symmetric\n% reduced stiffness\n% units: N/m\n5 5 14\n", 0), 0u)
      << text.str();
  EXPECT_EQ(read(text.str()), s);
  const Eigen::MatrixXd g = Eigen::MatrixXd::Random(3, 4) * 1e-7;
  std::ostringstream general;
  wbm::fem::write_matrix_market(general, g, false);
  EXPECT_EQ(read(general.str()), g);
  using wbm::testing::expect_throw_with;
  std::ostringstream sink;
  Eigen::MatrixXd a = s;
  a(4, 2) += 1e-15;
  expect_throw_with<std::invalid_argument>([&] { wbm::fem::write_matrix_market(sink, a, true); },
                                           {"entry (5, 3) differs from (3, 5)", "write general"});
  a = s;
  a(2, 2) = std::numeric_limits<double>::quiet_NaN();
  expect_throw_with<std::invalid_argument>([&] { wbm::fem::write_matrix_market(sink, a, false); },
                                           {"entry (3, 3) is not finite"});
}
