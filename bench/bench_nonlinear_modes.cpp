// Nonlinear modes of the LL11 rod (reproduce/scenes/ll11_rod.toml) with exact contact: the whole
// Fig. 3 backbone by continuation (E from 0.5 to 10, per N), one energy level by LL11 Alg. 1
// (augmented Lagrangian with Powell's updates, warm-started from the neighbouring level), and one
// KKT linearization (sparse residual and Jacobian) at the sizes of the extremes (N up to 64,
// m up to 1024). Alg. 1 also over the first part of the backbone, and its Hessian's solve and
// Levenberg–Marquardt step by the bordered sparse LU against the dense path they replaced.
// The backbone in a wavelet or Fourier time basis (BasisModes, E from 0.5 to 1.3, the range of
// reproduce/ll11_wavelet_modes) per basis and M. Counters: levels, corners (events located),
// time per level. A level's stability (NonlinearModes::stability: the exact orbit with elastic
// impacts shot near it), and one period of that orbit's event-driven flow with its monodromy in
// the free phase's eigen-coordinates and by the dense products (ImpactFlowOptions::dense_monodromy).
#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <vector>

#include <benchmark/benchmark.h>

#include <wbm/contact/signorini.hpp>
#include <wbm/solvers/impact_shooting.hpp>

#include <wbm/scene/analysis.hpp>
#include <wbm/solvers/basis_modes.hpp>
#include <wbm/solvers/nonlinear_modes.hpp>

#include "shipped_scenes.hpp"

namespace {

// Backbone continuation options over [E_min, E_max], the other fields at their defaults.
wbm::solvers::BackboneContinuationOptions range(double energy_min, double energy_max) {
  wbm::solvers::BackboneContinuationOptions o;
  o.energy_min = energy_min;
  o.energy_max = energy_max;
  return o;
}

const wbm::scene::ModeProblem& ll11() {
  static const auto problem =
      wbm::scene::mode_problem(wbm::scene::load_scene(wbm::models::scene_directory() / "ll11_rod.toml"));
  return problem;
}

wbm::solvers::NonlinearModes modes(int harmonics, int samples) {
  const auto& p = ll11();
  return {p.system, p.stops, {.harmonics = harmonics, .samples = samples}};
}

void BM_NonlinearModes_Fig3Backbone(benchmark::State& state) {
  const auto nm = modes(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  size_t levels = 0;
  int corners = 0;
  double seconds = 0.0;
  for (auto _ : state) {
    const auto b = nm.continue_backbone(range(0.5, 10.0));
    if (!b.complete()) state.SkipWithError(b.message.c_str());
    levels = b.levels.size();
    corners = b.kinks;
    seconds = b.wall_time_s;
  }
  state.counters["levels"] = static_cast<double>(levels);
  state.counters["corners"] = static_cast<double>(corners);
  state.counters["ms_per_level"] = 1e3 * seconds / static_cast<double>(std::max<size_t>(levels, 1));
}

void BM_NonlinearModes_Algorithm1Level(benchmark::State& state) {
  const auto nm = modes(8, 256);
  const auto start = nm.solve(1.15);
  if (!start.converged()) state.SkipWithError(start.message.c_str());
  for (auto _ : state) {
    const auto level = nm.solve(1.2, &start);
    if (!level.converged()) state.SkipWithError(level.message.c_str());
    state.counters["powell_iterations"] = level.powell_iterations;
    state.counters["newton_iterations"] = level.newton_iterations;
  }
}

// LL11 Alg. 1 on the scene itself (N = 12, m = 256) from E = 0.5 to `range(0)`/100: the energy
// stepping of `make reproduce`'s ll11_fig03 claim, one level per step.
void BM_NonlinearModes_Algorithm1Backbone(benchmark::State& state) {
  const auto& p = ll11();
  const wbm::solvers::NonlinearModes nm(p.system, p.stops, p.options);
  wbm::solvers::BackboneOptions o;
  o.energy_min = 0.5;
  o.energy_max = static_cast<double>(state.range(0)) / 100.0;
  o.max_step = 0.05;
  size_t levels = 0;
  int newton = 0;
  for (auto _ : state) {
    const auto b = nm.backbone(o);
    if (!b.complete()) state.SkipWithError(b.message.c_str());
    levels = b.levels.size();
    newton = 0;
    for (const auto& l : b.levels) newton += l.newton_iterations;
  }
  state.counters["levels"] = static_cast<double>(levels);
  state.counters["newton_iterations"] = newton;
}

// The Hessian of Alg. 1's augmented Lagrangian at the rod's size (n = 20 DOFs, F = 2N + 1 = 25
// coefficients: 499 unknowns, the phase one removed) in its structure H = S + U C Uᵀ: S block
// tridiagonal per harmonic plus one dense F × F contact block, U the two rank-one directions.
// range(0): 0 the bordered sparse LU (BorderedSparseLu), 1 the dense LU of H formed (DenseLu,
// the path before), both with one solve; range(1): 1 adds a Levenberg–Marquardt step (the
// shifted bordered system, or the dense QR of [H; μI]).
void BM_NonlinearModes_Algorithm1Hessian(benchmark::State& state) {
  constexpr int n = 20, f = 25, size = n * f;
  std::vector<Eigen::Triplet<double>> t;
  for (int k = 0; k < f; ++k) {
    const double shift = k == 1 ? 2.0 - 2.0 * std::cos(std::numbers::pi / (2.0 * n + 1.0)) : -0.3 * k * k;
    for (int i = 0; i < n; ++i) {
      t.emplace_back(k * n + i, k * n + i, 2.0 - shift);
      if (i + 1 < n) {
        t.emplace_back(k * n + i, k * n + i + 1, -1.0);
        t.emplace_back(k * n + i + 1, k * n + i, -1.0);
      }
    }
  }
  for (int k = 0; k < f; ++k) {
    for (int l = 0; l < f; ++l) t.emplace_back(k * n + n - 1, l * n + n - 1, 1e3 / (1.0 + std::abs(k - l)));
  }
  wbm::solvers::SparseLowRankHessian h;
  h.sparse.resize(size, size);
  h.sparse.setFromTriplets(t.begin(), t.end());
  h.u = Eigen::MatrixXd::Random(size, 2);
  h.core.resize(2, 2);
  h.core << 1e2, -1e-2, -1e-2, 0.0;
  const Eigen::VectorXd r = Eigen::VectorXd::Ones(size);
  const bool bordered = state.range(0) == 0, lm = state.range(1) == 1;
  for (auto _ : state) {
    if (bordered) {
      wbm::solvers::BorderedSparseLu solver;
      solver.factorize(h);
      benchmark::DoNotOptimize(solver.solve(r));
      if (lm) benchmark::DoNotOptimize(solver.levenberg_marquardt_step(h, r, 1e-3));
    } else {
      const Eigen::MatrixXd dense = h.dense();
      wbm::solvers::DenseLu solver;
      solver.factorize(dense);
      benchmark::DoNotOptimize(solver.solve(r));
      if (lm) benchmark::DoNotOptimize(wbm::solvers::detail::levenberg_marquardt_step(dense, r, 1e-3));
    }
  }
  state.counters["unknowns"] = size;
}

void BM_NonlinearModes_KktLinearization(benchmark::State& state) {
  const auto nm = modes(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  const wbm::solvers::NonlinearModes::BackboneSystem system(nm, 0.0);
  const Eigen::VectorXd x = system.linear_state(1.0) * 1.1;
  for (auto _ : state) benchmark::DoNotOptimize(system.linearize(x, 1.2));
  state.counters["unknowns"] = static_cast<double>(system.size());
}

// Arg 0: basis (0 Fourier, 1 B-spline, 2 DB6, 3 Haar), arg 1: M. Instants at their default (m = M).
void BM_BasisModes_Backbone(benchmark::State& state) {
  static const char* const names[] = {"fourier", "bspline", "db6", "haar"};
  const auto index = static_cast<size_t>(state.range(0));
  const auto nm = modes(1, 3);
  const wbm::solvers::BasisModes bm(nm, wbm::solvers::TimeBasis::from_name(names[index], static_cast<int>(state.range(1))));
  size_t levels = 0;
  int corners = 0;
  double seconds = 0.0;
  for (auto _ : state) {
    const auto b = bm.continue_backbone(range(0.5, 1.3));
    if (!b.complete()) state.SkipWithError(b.message.c_str());
    levels = b.levels.size();
    corners = b.kinks;
    seconds = b.wall_time_s;
  }
  state.SetLabel(bm.basis().name());
  state.counters["unknowns"] = static_cast<double>(bm.unknowns());
  state.counters["levels"] = static_cast<double>(levels);
  state.counters["corners"] = static_cast<double>(corners);
  state.counters["ms_per_level"] = 1e3 * seconds / static_cast<double>(std::max<size_t>(levels, 1));
}

// The rod's level at E = 1.8 (N = 32, m = 512, the backbone of reproduce/ll11_backbone_stability)
// and its stability, computed once.
const wbm::solvers::ModeStability& level_1_8() {
  static const wbm::solvers::ModeStability st = [] {
    const auto nm = modes(32, 512);
    auto o = range(0.5, 1.8);
    o.include = {1.8};
    const auto b = nm.continue_backbone(o);
    return nm.stability(b.levels.back());
  }();
  return st;
}

void BM_NonlinearModes_LevelStability(benchmark::State& state) {
  const auto nm = modes(32, 512);
  auto o = range(0.5, 1.8);
  o.include = {1.8};
  const auto b = nm.continue_backbone(o);
  for (auto _ : state) {
    const auto st = nm.stability(b.levels.back());
    if (!st.available) state.SkipWithError(st.message.c_str());
    state.counters["impacts"] = st.impacts;
    state.counters["newton_iterations"] = st.orbit.report.iterations;
  }
}

// Arg: 1 for the dense products.
void BM_NonlinearModes_ExactOrbitFlow(benchmark::State& state) {
  const auto& st = level_1_8();
  if (!st.available) {
    state.SkipWithError(st.message.c_str());
    return;
  }
  const auto& p = ll11();
  const int n = p.system.dofs();
  wbm::solvers::MechanicalSystem free = p.system;
  free.damping = Eigen::SparseMatrix<double>(n, n);
  std::vector<wbm::solvers::ContactPoint> stops;
  for (const auto& s : p.stops) stops.push_back({s.dof, std::make_shared<wbm::contact::RigidStop>(s.gap), -1, s.along});
  const wbm::solvers::ImpactFlow flow(free, {0, 0.0, st.orbit.frequency_hz}, stops,
                                      {.restitution = 1.0, .dense_monodromy = state.range(0) == 1});
  for (auto _ : state) {
    const auto r = flow.flow(st.orbit.state, 0.0, st.orbit.period_s);
    state.counters["events"] = static_cast<double>(r.events.size());
  }
  state.counters["states"] = 2.0 * n;
}

}  // namespace

BENCHMARK(BM_NonlinearModes_LevelStability)->Unit(benchmark::kMillisecond)->Iterations(5);
BENCHMARK(BM_NonlinearModes_ExactOrbitFlow)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_NonlinearModes_Fig3Backbone)
    ->Args({8, 256})
    ->Args({12, 256})
    ->Args({10, 512})  // 689 corners: the event location dominates
    ->Args({24, 512})  // the costliest pair of ll11_robustness's grid but one
    ->Args({32, 512})  // the costliest: 65 harmonic-balance blocks, J of about 40 000 entries
    ->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_NonlinearModes_Algorithm1Level)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_NonlinearModes_Algorithm1Backbone)->Arg(150)->Arg(190)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_NonlinearModes_Algorithm1Hessian)
    ->Args({0, 0})
    ->Args({1, 0})
    ->Args({0, 1})
    ->Args({1, 1})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_NonlinearModes_KktLinearization)->Args({8, 256})->Args({16, 256})->Args({64, 1024})->Unit(benchmark::kMillisecond);

BENCHMARK(BM_BasisModes_Backbone)
    ->ArgsProduct({{0, 1, 2, 3}, {32, 64, 128}})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

BENCHMARK_MAIN();
