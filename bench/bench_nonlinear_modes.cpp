// Nonlinear modes of the LL11 rod (reproduce/scenes/ll11_rod.toml) with exact contact: the whole
// Fig. 3 backbone by continuation (E from 0.5 to 10, per N), one energy level by LL11 Alg. 1
// (augmented Lagrangian with Powell's updates, warm-started from the neighbouring level), and one
// KKT linearization (sparse residual and Jacobian) at the sizes of the extremes (N up to 64,
// m up to 1024). Counters: levels, corners (events located), time per level.
#include <benchmark/benchmark.h>

#include <wbm/scene/analysis.hpp>
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

void BM_NonlinearModes_KktLinearization(benchmark::State& state) {
  const auto nm = modes(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  const wbm::solvers::NonlinearModes::BackboneSystem system(nm, 0.0);
  const Eigen::VectorXd x = system.linear_state(1.0) * 1.1;
  for (auto _ : state) benchmark::DoNotOptimize(system.linearize(x, 1.2));
  state.counters["unknowns"] = static_cast<double>(system.size());
}

}  // namespace

BENCHMARK(BM_NonlinearModes_Fig3Backbone)
    ->Args({8, 256})
    ->Args({12, 256})
    ->Args({10, 512})  // 689 corners: the event location dominates
    ->Args({24, 512})  // the costliest pair of ll11_robustness's grid but one
    ->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_NonlinearModes_Algorithm1Level)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_NonlinearModes_KktLinearization)->Args({8, 256})->Args({16, 256})->Args({64, 1024})->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
