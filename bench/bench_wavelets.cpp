// Wavelet bases (wavelets issue): time to build each periodized basis at J = 6 and J = 10,
// including its exact connection-coefficient matrices (all d1 + d2 ≤ min(2, admissible order))
// and its values and derivatives on a Q = max(256, M) point grid, as the weighted-residual
// assembly needs them. Also the pieces: real-line connection coefficients, and the orthogonal
// cubic B-spline coefficients c_k by GSL quadrature (computed once per process in the library).
#include <benchmark/benchmark.h>

#include <algorithm>

#include <wbm/wavelets/periodized_basis.hpp>

namespace {
namespace ww = wbm::wavelets;

ww::Family family_of(long index) {
  switch (index) {
    case 0: return ww::Family::haar();
    case 1: return ww::Family::daubechies(6);
    case 2: return ww::Family::daubechies(20);
    default: return ww::Family::orthogonal_cubic_bspline();
  }
}

void BM_Wavelets_BuildBasis(benchmark::State& state) {
  const ww::Family family = family_of(state.range(0));
  const int level = static_cast<int>(state.range(1));
  state.SetLabel(family.name() + " J=" + std::to_string(level));
  const int order = std::min(2, ww::max_connection_order(family));
  for (auto _ : state) {
    const ww::PeriodizedBasis basis(family, level);
    for (int d = 0; d <= order; ++d) {
      for (int d1 = 0; d1 <= d; ++d1) benchmark::DoNotOptimize(basis.connection_matrix(d1, d - d1));
    }
    const int samples = std::max(256, basis.dimension());
    for (int d = 0; d <= std::min(2, basis.max_derivative()); ++d) benchmark::DoNotOptimize(basis.sampled(samples, d));
  }
}
BENCHMARK(BM_Wavelets_BuildBasis)->ArgsProduct({{0, 1, 2, 3}, {6, 10}})->Unit(benchmark::kMillisecond);

void BM_Wavelets_ConnectionCoefficients(benchmark::State& state) {
  const ww::Family family = family_of(state.range(0));
  state.SetLabel(family.name());
  const int order = std::min(2, ww::max_connection_order(family));
  for (auto _ : state) benchmark::DoNotOptimize(ww::connection_coefficients(family, 0, order));
}
BENCHMARK(BM_Wavelets_ConnectionCoefficients)->DenseRange(0, 3)->Unit(benchmark::kMicrosecond);

void BM_Wavelets_BSplineCoefficientsQuadrature(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(ww::compute_orthogonal_cubic_bspline_coefficients(50));
}
BENCHMARK(BM_Wavelets_BSplineCoefficientsQuadrature)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
