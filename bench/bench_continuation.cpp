// Pseudo-arclength continuation of the Fig. 12 branch (Case 2, 1000–1700 Hz, steps ≤ 0.02 and
// ≤ 2 Hz, M = 64, distributional) for the paper's two combinations, without and with the Floquet
// stability of every point (third argument), and the monodromy matrix of one point. Counters:
// points on the branch and points per second. Goals: the whole branch, at least 300 points,
// under 1 s on one core (issue #6); 0.15 s, and 0.3 s with stability (issue #17). And a rod
// branch against the number of elements (issue #39: its cost should grow like n), and NLvib's
// unit rod as `wbm run` traces examples/scenes/nlvib_rod.toml (issue #39, item 7), and Fig. 12
// with its stop rigid, with the stability of the exact orbits (issue #38), one point's
// stability with a linear penalty stop by both methods (exact flights and the stepping), and the
// forced response of the reduced LL11 blade as ll11_blade_forced traces it (issue #39, item 4).
#include <benchmark/benchmark.h>
#include <toml++/toml.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <wbm/contact/penalty.hpp>
#include <wbm/contact/signorini.hpp>
#include <wbm/scene/scene.hpp>
#include <wbm/solvers/floquet.hpp>
#include <wbm/solvers/response_curve.hpp>

#include "blade_forced.hpp"
#include "shipped_scenes.hpp"

namespace {

const wbm::scene::Scene& case2() {
  static const auto scene = wbm::models::load_scene("jl14_case2");
  return scene;
}

const char* const kTrial[] = {"fourier", "haar"};

// One trace_response of `base` with `o`; an error unless it reaches the range's end.
wbm::solvers::ResponseCurve trace(benchmark::State& state, const wbm::solvers::WeightedResidual& base,
                                  const wbm::solvers::ResponseCurveOptions& o) {
  auto curve = wbm::solvers::trace_response(base, o);
  if (curve.stop != wbm::solvers::StopReason::RangeReached) state.SkipWithError(curve.message.c_str());
  return curve;
}

void BM_Continuation_Fig12Branch(benchmark::State& state) {
  const auto& s = case2();
  const int m = static_cast<int>(state.range(0));
  const char* trial = kTrial[state.range(1)];
  state.SetLabel(std::string(trial) + ":fourier" + (state.range(2) != 0 ? ", with Floquet stability" : ""));
  const wbm::solvers::WeightedResidual base(s.system(), s.harmonic_forcing(1000.0), s.contact_points(),
                                            wbm::solvers::TimeBasis::from_name(trial, m),
                                            wbm::solvers::TimeBasis::fourier(m));
  wbm::solvers::ResponseCurveOptions o;
  o.parameter_min = 1000.0;
  o.parameter_max = 1700.0;
  o.max_parameter_step = 2.0;
  o.stability = state.range(2) != 0;
  wbm::solvers::ResponseCurve curve;
  for (auto _ : state) curve = trace(state, base, o);
  const auto points = static_cast<double>(curve.points.size());
  state.counters["points"] = points;
  state.counters["continuation_points_per_s"] = points / curve.wall_time_s;
  if (o.stability) state.counters["stability_work_ms"] = 1e3 * curve.stability_work_s;
}

void BM_Floquet_OnePoint(benchmark::State& state) {
  const auto& s = case2();
  const int p = static_cast<int>(state.range(0));
  const auto sol = wbm::solvers::solve_weighted_residual(s.system(), s.harmonic_forcing(1300.0), s.contact_points(),
                                                         wbm::solvers::TimeBasis::fourier(64),
                                                         wbm::solvers::TimeBasis::fourier(64));
  const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(p, 0.0, 1.0 - 1.0 / p);
  const Eigen::MatrixXd uc =
      (wbm::solvers::TimeBasis::fourier(64).values(tau, 0) * sol.coefficients.row(s.forcing->dof).transpose())
          .transpose();
  const bool modal = state.range(1) != 0;
  state.SetLabel(modal ? "modal path, set up once" : "balanced path (floquet_multipliers)");
  const wbm::solvers::FloquetAnalysis floquet(s.system(), s.contact_points(), {.monodromy = false});
  for (auto _ : state) {
    if (modal) {
      benchmark::DoNotOptimize(floquet(uc, 1300.0));
    } else {
      benchmark::DoNotOptimize(wbm::solvers::floquet_multipliers(s.system(), s.contact_points(), uc, 1300.0));
    }
  }
}

// A continuation scene's branch as `wbm run` sets it up (the weighted residual at the range's
// start, then trace_response with `o`); an error unless it reaches the range's end. Returns the
// number of points.
size_t trace_scene(benchmark::State& state, const wbm::scene::Scene& scene,
                   const wbm::solvers::ResponseCurveOptions& o) {
  const wbm::solvers::WeightedResidual base(scene.system(), scene.harmonic_forcing(scene.forcing->range->from_hz),
                                            scene.contact_points(), scene.trial(), scene.weighting(),
                                            scene.weighted_residual_options());
  return trace(state, base, o).points.size();
}

// The branch's cost against the structure's size (issue #39, item 5): the rod of
// examples/scenes/rod_continuation.toml (clamped-free, one exponential tip stop, 1150–1450 Hz)
// with range(0) elements, harmonic balance with H = 15, without or with (range(1)) the stability of
// every point (FloquetAnalysis: the modal path, C = βK). With one contact DOF a
// point costs O(n): the linear response and the tangent read and write the forced and contact
// DOFs only (gathered_solve); the modal basis (one dense eigenproblem, O(n³)) is set up once.
void BM_Continuation_RodElements(benchmark::State& state) {
  const int elements = static_cast<int>(state.range(0));
  const std::string text =
      "[structure]\nyoung_modulus = 70e9\ndensity = 2700.0\narea = 25e-4\nlength = 1.0\nelements = " +
      std::to_string(elements) +
      "\n[damping]\nbeta = 5e-6\n[forcing]\namplitude = 250e3\nfrequency_hz = [1150.0, 1450.0]\n"
      "[contact]\nlaw = \"exponential\"\ncoefficient = 1e8\nexponent = 20.0\ngap = 14.5e-3\n"
      "[basis]\nharmonics = 15\n[analysis]\ntype = \"continuation\"\n";
  const auto scene = wbm::scene::parse_scene(text, "rod.toml");
  const auto& range = *scene.forcing->range;
  wbm::solvers::ResponseCurveOptions o;
  o.parameter_min = range.from_hz;
  o.parameter_max = range.to_hz;
  o.stability = state.range(1) != 0;
  state.SetLabel(o.stability ? "with Floquet stability" : "without stability");
  o.max_parameter_step = 2.0;  // as the example scene's max_frequency_step_hz
  size_t points = 0;
  for (auto _ : state) points = trace_scene(state, scene, o);
  state.counters["points"] = static_cast<double>(points);
  state.counters["dofs"] = elements;
}

// NLvib's unit rod (issue #39, item 7): examples/scenes/nlvib_rod.toml as `wbm run` traces it
// (H = 15, 1 % modal damping: the modal path of a classical C), without and with the stability
// of every point (range(0)). Counters: points, and wall time per point [ms].
void BM_Continuation_NLvibRod(benchmark::State& state) {
  static const auto scene = wbm::models::load_scene(
      (wbm::models::scene_directory() / ".." / ".." / "examples" / "scenes" / "nlvib_rod.toml").string());
  const auto& range = *scene.forcing->range;
  wbm::solvers::ResponseCurveOptions o;
  o.parameter_min = range.from_hz;
  o.parameter_max = range.to_hz;
  o.max_step = scene.analysis.max_step;
  o.initial_step = std::min(o.initial_step, o.max_step);
  o.max_parameter_step = scene.analysis.max_frequency_step_hz;
  o.corrector_tolerance = scene.solver.newton.tolerance;
  o.stability = state.range(0) != 0;
  state.SetLabel(o.stability ? "with Floquet stability" : "without stability");
  size_t points = 0;
  double seconds = 0.0;
  for (auto _ : state) {
    const auto started = std::chrono::steady_clock::now();
    points = trace_scene(state, scene, o);
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  }
  state.counters["points"] = static_cast<double>(points);
  state.counters["ms_per_point"] = 1e3 * seconds / static_cast<double>(std::max<size_t>(points, 1));
}

// Fig. 12 with its stop rigid (reproduce/jl14_rigid_stop: Fourier:Fourier, M = 64, steps ≤ 5 Hz),
// without and with stability (range(0)): with rigid stops each point's verdict is that of the
// exact orbit with plastic impacts near it, shot from the point, and its saltation monodromy
// (issue #38). Counters: points, and the stability's wall time per point [ms].
void BM_Continuation_Fig12RigidStop(benchmark::State& state) {
  const auto& s = case2();
  std::vector<wbm::solvers::ContactPoint> stops;
  for (const auto& c : s.contact_points()) {
    stops.push_back({c.dof, std::make_shared<wbm::contact::RigidStop>(c.law->gap())});
  }
  const auto fourier = wbm::solvers::TimeBasis::fourier(64);
  const wbm::solvers::WeightedResidual base(s.system(), s.harmonic_forcing(1000.0), stops, fourier, fourier);
  wbm::solvers::ResponseCurveOptions o;
  o.parameter_min = 1000.0;
  o.parameter_max = 1700.0;
  o.max_parameter_step = 5.0;
  o.stability = state.range(0) != 0;
  state.SetLabel(o.stability ? "with the exact orbits' stability" : "without stability");
  wbm::solvers::ResponseCurve curve;
  for (auto _ : state) curve = trace(state, base, o);
  const auto points = static_cast<double>(std::max<size_t>(curve.points.size(), 1));
  state.counters["points"] = static_cast<double>(curve.points.size());
  state.counters["stability_ms_per_point"] = 1e3 * curve.stability_time_s / points;
}


// One point's stability by both methods (issue #39, item 2): the Case 2 rod with its tip stop a
// linear penalty of range(1) times the exponential law's tangent at the gap (a_c α = 2e9 N/m),
// the orbit of Fourier:Fourier M = 64 at 1300 Hz (in contact). range(0) = 1: the exact flights of
// the contact configurations (FloquetOptions::exact_flights) from 512 samples; 0: the stepping,
// from as many samples as resolved_steps asks for (the stop resolved, h ω_c <= 0.5), the slow
// reference. Counters: the steps used and the largest |μ|.
void BM_Floquet_LinearStopOnePoint(benchmark::State& state) {
  const auto& s = case2();
  std::vector<wbm::solvers::ContactPoint> stops;
  for (const auto& c : s.contact_points()) {
    stops.push_back({c.dof, std::make_shared<wbm::contact::LinearPenalty>(
                                wbm::contact::LinearPenaltyParameters{2e9 * static_cast<double>(state.range(1)), c.law->gap()})});
  }
  const auto fourier = wbm::solvers::TimeBasis::fourier(64);
  const auto sol = wbm::solvers::solve_weighted_residual(s.system(), s.harmonic_forcing(1300.0), stops, fourier, fourier);
  const bool exact = state.range(0) != 0;
  state.SetLabel(exact ? "exact flights" : "stepping (slow reference)");
  const wbm::solvers::FloquetAnalysis floquet(s.system(), stops, {.monodromy = false, .exact_flights = exact});
  auto samples = [&](Eigen::Index p) {
    const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(p, 0.0, 1.0 - 1.0 / static_cast<double>(p));
    return Eigen::MatrixXd((fourier.values(tau, 0) * sol.coefficients.row(stops.front().dof).transpose()).transpose());
  };
  Eigen::MatrixXd uc = samples(512);
  if (!exact) uc = samples(floquet.resolved_steps(uc, 1300.0));
  wbm::solvers::FloquetResult r;
  for (auto _ : state) r = floquet(uc, 1300.0);
  state.counters["steps"] = static_cast<double>(r.steps);
  state.counters["max_multiplier"] = r.max_modulus;
}

// The reduced LL11 blade against its 24 radial penalty stops, built and continued as
// ll11_blade_forced does (its parameters read from reproduce/scenes/ll11_blade_forced.toml, the
// full mesh: gmsh, CalculiX and the Craig–Bampton reduction once per process, about 30 s before
// the first run): Fourier:Fourier at response.harmonics (range(0) = 0) or B-spline:B-spline at
// response.wavelet_dimension (1), over the response range with its largest steps, without or
// with the stability of every point (range(1)). Goals (issue #39, item 4): Fourier:Fourier in
// 5 s, B-spline:B-spline in 10 s. Counters: points, the continuation's and the stability's wall
// times [s].
struct BladeForcedBench {
  toml::table parameters;
  wbm::models::BladeForcedModel model;
  std::vector<wbm::solvers::ContactPoint> contacts;
  // A key the reproduction's file must hold (std::runtime_error naming it otherwise).
  template <class T>
  T read(const char* key) const {
    const auto v = parameters.at_path(key).value<T>();
    if (!v) throw std::runtime_error(std::string("ll11_blade_forced.toml: no number at key ") + key);
    return *v;
  }
  double number(const char* key) const { return read<double>(key); }
  int integer(const char* key) const { return static_cast<int>(read<int64_t>(key)); }
  BladeForcedBench() : parameters(toml::parse_file((wbm::models::scene_directory() / "ll11_blade_forced.toml").string())) {
    const wbm::models::ScratchFolder scratch("wbm_bench_blade_forced");
    const auto blade = wbm::models::build_blade(scratch.dir, number("mesh.size_m"), integer("interface.tip_nodes"));
    const auto cb = wbm::fem::craig_bampton(blade.model.stiffness, blade.model.mass, blade.boundary, integer("interface.modes"));
    model = wbm::models::blade_forced_model(
        blade, cb,
        {.gap = number("contact.gap_m"), .zeta = number("damping.zeta"), .overload = number("forcing.overload_gaps"),
         .stiffness_ratio = number("contact.stiffness_ratio"), .from_f1 = number("response.from_f1"),
         .mode_harmonics = integer("nnm.harmonics"), .mode_samples = integer("nnm.samples")});
    const auto law = std::make_shared<wbm::contact::LinearPenalty>(
        wbm::contact::LinearPenaltyParameters{model.penalty_stiffness, number("contact.gap_m")});
    for (const auto& st : model.stops) contacts.push_back({st.dof, law, -1, st.along});
  }
};

void BM_Continuation_BladeForced(benchmark::State& state) {
  static const BladeForcedBench b;
  const bool bspline = state.range(0) != 0;
  const int harmonics = b.integer("response.harmonics"), m = b.integer("response.wavelet_dimension");
  const auto basis = bspline ? wbm::solvers::TimeBasis::from_name("bspline", m) : wbm::solvers::TimeBasis::fourier_harmonics(harmonics);
  state.SetLabel(std::string(bspline ? "B-spline:B-spline M = " + std::to_string(m) : "Fourier:Fourier H = " + std::to_string(harmonics)) +
                 (state.range(1) != 0 ? ", with Floquet stability" : ""));
  const wbm::solvers::WeightedResidual base(b.model.reduced, b.model.forcing, b.contacts, basis, basis,
                                            {.formulation = wbm::solvers::Formulation::Distributional});
  wbm::solvers::ResponseCurveOptions o;
  o.parameter_min = b.number("response.from_f1") * b.model.f1;
  o.parameter_max = b.number("response.to_f1") * b.model.f1;
  o.max_parameter_step = b.number(bspline ? "response.max_step_bspline_f1" : "response.max_step_fourier_f1") * b.model.f1;
  o.observed_dof = b.model.observed;
  o.max_state = b.number("response.max_state");
  o.stability = state.range(1) != 0;
  wbm::solvers::ResponseCurve curve;
  for (auto _ : state) curve = trace(state, base, o);
  state.counters["points"] = static_cast<double>(curve.points.size());
  state.counters["continuation_s"] = curve.wall_time_s;
  state.counters["stability_s"] = curve.stability_time_s;  // the wait after the continuation
  state.counters["stability_work_s"] = curve.stability_work_s;  // thread time, most of it during it
}
}  // namespace

// Not Fourier:Fourier at M = 32: its undamped top function cos 32πτ resonates with mode 8 at
// 1238 Hz and the branch is cut there (ResponseCurve's check), so that pair only reported an error.
BENCHMARK(BM_Continuation_Fig12Branch)
    ->ArgsProduct({{64}, {0, 1}, {0, 1}})
    ->ArgsProduct({{32}, {1}, {0, 1}})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Floquet_OnePoint)->ArgsProduct({{256, 512, 1024, 2048}, {0, 1}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Continuation_RodElements)
    ->ArgsProduct({{20, 80, 320, 1280}, {0}})
    ->ArgsProduct({{20, 80, 320}, {1}})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Continuation_NLvibRod)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Continuation_Fig12RigidStop)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Floquet_LinearStopOnePoint)->ArgsProduct({{1, 0}, {1, 100}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Continuation_BladeForced)->ArgsProduct({{0, 1}, {0, 1}})->Iterations(1)->Unit(benchmark::kSecond);
BENCHMARK_MAIN();
