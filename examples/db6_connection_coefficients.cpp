// Builds the periodized DB6 basis at level J = 3 (M = 8) and prints its second-derivative
// connection-coefficient matrix C(i, k) = ∫₀¹ φ_{3,i} φ''_{3,k} dτ (orthonormal functions).
// Its diagonal is 2^{2J} Γ^{0,2}[0] = 64 · (−295/56) = −337.142857… [LRT91].
#include <cstdio>

#include <wbm/wavelets/connection_coefficients.hpp>
#include <wbm/wavelets/periodized_basis.hpp>

int main() {
  const auto family = wbm::wavelets::Family::daubechies(6);
  const int level = 3;
  const wbm::wavelets::PeriodizedBasis basis(family, level);
  const Eigen::MatrixXd c(basis.connection_matrix(0, 2));
  std::printf("DB6, J = %d, M = %d: Gamma^{0,2} (Sobolev exponent %.4f, largest order %d)\n", level,
              basis.dimension(), wbm::wavelets::sobolev_exponent(family), wbm::wavelets::max_connection_order(family));
  for (Eigen::Index i = 0; i < c.rows(); ++i) {
    for (Eigen::Index k = 0; k < c.cols(); ++k) std::printf("%15.9f", c(i, k));
    std::printf("\n");
  }
  return 0;
}
