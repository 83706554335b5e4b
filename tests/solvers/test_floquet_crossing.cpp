// classify_crossing (floquet.hpp) when another multiplier is already outside the unit circle:
// the kind is that of the multiplier that crossed, the one nearest the circle at the less stable
// point, not the largest. The multipliers are the closed-form eigenvalues of block-diagonal
// monodromy matrices: a rotation scaled by ρ (ρ e^{±iθ}) beside a real multiplier.
#include <gtest/gtest.h>

#include <complex>
#include <initializer_list>

#include <wbm/solvers/floquet.hpp>

namespace {

using wbm::solvers::Bifurcation;
using wbm::solvers::FloquetResult;

// A result whose multipliers are the given values, by decreasing modulus as floquet_multipliers
// orders them.
FloquetResult with_multipliers(std::initializer_list<std::complex<double>> values) {
  FloquetResult r;
  r.multipliers.resize(static_cast<Eigen::Index>(values.size()));
  Eigen::Index i = 0;
  for (const auto& v : values) r.multipliers(i++) = v;
  r.max_modulus = std::abs(r.multipliers(0));
  return r;
}

TEST(FloquetCrossing, TheMultiplierNearestTheCircleNamesTheKind) {
  // A Neimark–Sacker pair 2.5 e^{±i} is outside at both points.
  const std::complex<double> pair = std::polar(2.5, 1.0), conj = std::conj(pair);
  const auto before = with_multipliers({pair, conj, 0.95});
  // A real multiplier passes +1: a fold, though the largest multiplier is complex.
  EXPECT_EQ(wbm::solvers::classify_crossing(before, with_multipliers({pair, conj, 1.05})), Bifurcation::Fold);
  // … and back inside: the fold again, read at the less stable point (the earlier one).
  EXPECT_EQ(wbm::solvers::classify_crossing(with_multipliers({pair, conj, 1.05}), before), Bifurcation::Fold);
  // A real multiplier passes −1: period doubling.
  EXPECT_EQ(wbm::solvers::classify_crossing(with_multipliers({pair, conj, -0.95}),
                                            with_multipliers({pair, conj, -1.05})),
            Bifurcation::PeriodDoubling);
  // A second complex pair leaves beside a real multiplier already far outside: Neimark–Sacker.
  const std::complex<double> second = std::polar(1.1, 0.7);
  EXPECT_EQ(wbm::solvers::classify_crossing(with_multipliers({3.0, std::polar(0.9, 0.7), std::polar(0.9, -0.7)}),
                                            with_multipliers({3.0, second, std::conj(second)})),
            Bifurcation::NeimarkSacker);
  // The number outside is the same: no crossing.
  EXPECT_EQ(wbm::solvers::classify_crossing(before, with_multipliers({pair, conj, 0.9})), Bifurcation::None);
}

}  // namespace
