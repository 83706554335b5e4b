// From a CalculiX deck to a Craig–Bampton model (issue #15): a steel bar of C3D8 bricks along x,
// clamped at x = 0, generated at four sizes (about 6 000, 19 000, 61 000 and 71 000 free DOFs, the
// third the size of issue #39's 60 000-DOF deck), 24 nodes of its tip face as the interface (72
// DOFs, as LL11's blade) and 40 fixed-interface modes. Reported per size: DOFs, and the wall time
// of each stage — ccx assembling and writing K and M (MATRIXSTORAGE, text), reading them back
// (from_chars), and the reduction (sparse Cholesky of K_ii for the constraint modes, Spectra's
// shift-invert Lanczos for the normal modes, with its number of operator applications). One
// iteration each: the large cases take seconds.
// Also, on the LL11 blade (reproduce/blade/) with 6 … 48 contact nodes: the cost of the KKT
// backbone, and of one factorization of its bordered Jacobian by SparseLu and by KktSolver.
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>

#include <Eigen/Cholesky>
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <wbm/fem/calculix.hpp>
#include <wbm/fem/craig_bampton.hpp>
#include <wbm/solvers/continuation.hpp>
#include <wbm/solvers/nonlinear_modes.hpp>

#include "blade.hpp"

namespace {

namespace fs = std::filesystem;

// nx × n × n bricks over 1 m × 0.1 m × 0.1 m; returns the deck's path.
fs::path bar_deck(const fs::path& dir, int nx, int n) {
  fs::create_directories(dir);
  std::ofstream m(dir / "bar.inp");
  auto id = [&](int i, int j, int k) { return 1 + (n + 1) * (n + 1) * i + (n + 1) * j + k; };
  m << "*NODE\n";
  for (int i = 0; i <= nx; ++i)
    for (int j = 0; j <= n; ++j)
      for (int k = 0; k <= n; ++k) m << id(i, j, k) << ", " << 1.0 * i / nx << ", " << 0.1 * j / n << ", " << 0.1 * k / n << "\n";
  m << "*ELEMENT, TYPE=C3D8, ELSET=EALL\n";
  int e = 1;
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k)
        m << e++ << ", " << id(i, j, k) << ", " << id(i + 1, j, k) << ", " << id(i + 1, j + 1, k) << ", " << id(i, j + 1, k)
          << ", " << id(i, j, k + 1) << ", " << id(i + 1, j, k + 1) << ", " << id(i + 1, j + 1, k + 1) << ", "
          << id(i, j + 1, k + 1) << "\n";
  m << "*NSET, NSET=ROOT, GENERATE\n" << id(0, 0, 0) << ", " << id(0, n, n) << "\n"
    << "*NSET, NSET=TIP, GENERATE\n" << id(nx, 0, 0) << ", " << id(nx, n, n) << "\n"
    << "*MATERIAL, NAME=STEEL\n*ELASTIC\n210e9, 0.3\n*DENSITY\n7800.\n*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL\n"
    << "*BOUNDARY\nROOT, 1, 3\n";
  return dir / "bar.inp";
}

double since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

void BM_CraigBampton_FromCalculixDeck(benchmark::State& state) {
  const int nx = static_cast<int>(state.range(0)), n = static_cast<int>(state.range(1));
  const fs::path dir = fs::temp_directory_path() / ("wbm_bench_reduction_" + std::to_string(::getpid()));
  const auto deck = wbm::fem::read_calculix_deck(bar_deck(dir, nx, n));
  double ccx_s = 0.0, reduce_s = 0.0, dofs = 0.0, interface = 0.0, factor_s = 0.0, psi_s = 0.0, eig_s = 0.0;
  double eig_ops = 0.0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    const auto model = wbm::fem::assemble_with_calculix(deck);  // ccx + reading its files
    ccx_s = since(t0);
    std::vector<int> tip;
    const auto& tip_nodes = deck.node_set("TIP");
    const std::set<int> tip_set(tip_nodes.begin(), tip_nodes.begin() + 24);
    for (size_t r = 0; r < model.dofs.size(); ++r) {
      if (tip_set.count(model.dofs[r].first) != 0) tip.push_back(static_cast<int>(r));
    }
    const auto t1 = std::chrono::steady_clock::now();
    const auto reduced = wbm::fem::craig_bampton(model.stiffness, model.mass, tip, 40);
    reduce_s = since(t1);
    benchmark::DoNotOptimize(reduced.mass.data());
    factor_s = reduced.factorization_s;
    psi_s = reduced.constraint_modes_s;
    eig_s = reduced.eigensolve_s;
    eig_ops = static_cast<double>(reduced.eigensolve_operations);
    dofs = static_cast<double>(model.dofs.size());
    interface = static_cast<double>(tip.size());
  }
  fs::remove_all(dir);
  state.counters["dofs"] = dofs;
  state.counters["interface_dofs"] = interface;
  state.counters["ccx_and_read_s"] = ccx_s;
  state.counters["craig_bampton_s"] = reduce_s;
  state.counters["cholesky_s"] = factor_s;
  state.counters["constraint_modes_s"] = psi_s;
  state.counters["lanczos_s"] = eig_s;
  state.counters["lanczos_solves"] = eig_ops;
}
BENCHMARK(BM_CraigBampton_FromCalculixDeck)
    ->Args({40, 6})
    ->Args({80, 8})
    ->Args({120, 12})
    ->Args({140, 12})
    ->Iterations(1)
    ->Unit(benchmark::kSecond);

// The LL11 blade (reproduce/blade/, mesh size 5 mm, ~12 000 DOFs) with `tip` tip nodes as the
// interface (3 DOFs each) + 20 fixed-interface modes, and one exact radial stop at gap 0.1 mm per
// tip node. Built once per tip count (mesh, ccx and the reduction are set-up, not timed).
struct ReducedBlade {
  wbm::solvers::MechanicalSystem system;
  std::vector<wbm::solvers::RigidStop> stops;
};
const ReducedBlade& reduced_blade(int tip) {
  static std::map<int, ReducedBlade> cache;
  if (auto it = cache.find(tip); it != cache.end()) return it->second;
  const fs::path dir = fs::temp_directory_path() / ("wbm_bench_contacts_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const auto blade = wbm::models::build_blade(dir, 0.005, tip);
  const auto cb = wbm::fem::craig_bampton(blade.model.stiffness, blade.model.mass, blade.boundary, 20);
  fs::remove_all(dir);
  ReducedBlade r;
  r.system.stiffness = (0.5 * (cb.stiffness + cb.stiffness.transpose())).sparseView();
  r.system.mass = (0.5 * (cb.mass + cb.mass.transpose())).sparseView();
  r.system.damping.resize(r.system.mass.rows(), r.system.mass.cols());
  r.stops = wbm::models::radial_stops(blade, 1e-4);
  return cache.emplace(tip, std::move(r)).first->second;
}

// Cost of the first nonlinear mode against the number of contact nodes (issue #15): the reduced
// blade above with 6, 12, 24 or 48 tip nodes, and the KKT backbone from E = 0.5 to 3 at fixed
// N = 4, m = 64 (max energy step 0.1). Timed: the backbone only. Counters: reduced DOFs, KKT
// unknowns, levels, time per level, and whether the branch completed.
void BM_NonlinearMode_ContactNodes(benchmark::State& state) {
  const int tip = static_cast<int>(state.range(0));
  const auto& blade = reduced_blade(tip);
  const int n = 4, m = 64;
  const wbm::solvers::NonlinearModes nnm(blade.system, blade.stops, {.harmonics = n, .samples = m});
  wbm::solvers::BackboneContinuationOptions options;
  options.energy_min = 0.5;
  options.energy_max = 3.0;
  options.max_energy_step = 0.1;
  double levels = 0.0, complete = 0.0;
  for (auto _ : state) {
    const auto b = nnm.continue_backbone(options);
    levels = static_cast<double>(b.levels.size());
    complete = b.complete() ? 1.0 : 0.0;
  }
  state.counters["contact_nodes"] = tip;
  state.counters["reduced_dofs"] = static_cast<double>(blade.system.dofs());
  state.counters["kkt_unknowns"] = static_cast<double>(blade.system.dofs() * (2 * n + 1) + tip * m);
  state.counters["levels"] = levels;
  state.counters["complete"] = complete;
  state.counters["s_per_level"] = benchmark::Counter(levels, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_NonlinearMode_ContactNodes)->Arg(6)->Arg(12)->Arg(24)->Arg(48)->Iterations(1)->Unit(benchmark::kSecond);

// One factorization of the continuation's bordered KKT Jacobian (issue #15) on the reduced blade
// above with 6 … 48 contact nodes, N = 8, m = 96 (LL11's blade settings), at a converged level
// in contact (the last point of the backbone from the linear mode to E = 1.5): Arg 1 = 0, SparseLu (KLU; the symbolic analysis
// reused, as between corrector iterations with an unchanged active set); 1,
// BackboneSystem::KktSolver (block-diagonal harmonic balance and a Schur complement on the
// active samples). Arg 2 = 1: the same stops as penalty springs, 10 × the static radial stiffness
// of the first stop's node (ll11_blade_forced's casing), whose harmonics couple at the stops:
// KktSolver's Schur complement is then on the F harmonics of each stop in contact. Counters: KKT
// unknowns, Schur unknowns besides ω² and E (active samples, or F per stop in contact), the path
// KktSolver took.
void BM_KktFactorization(benchmark::State& state) {
  const int tip = static_cast<int>(state.range(0));
  const bool structured = state.range(1) == 1;
  const bool penalty = state.range(2) == 1;
  const auto& blade = reduced_blade(tip);
  const wbm::solvers::NonlinearModes nnm(blade.system, blade.stops, {.harmonics = 8, .samples = 96});
  double stiffness = 0.0;
  if (penalty) {
    const Eigen::MatrixXd k(blade.system.stiffness);
    Eigen::VectorXd e = Eigen::VectorXd::Zero(k.rows());
    for (const auto& [j, w] : blade.stops.front().terms()) e(j) = w;
    stiffness = 10.0 / e.dot(k.ldlt().solve(e));
  }
  const wbm::solvers::NonlinearModes::BackboneSystem system(nnm, stiffness);
  wbm::solvers::BackboneContinuationOptions options;
  options.penalty_stiffness = stiffness;
  options.energy_min = 0.5;
  options.energy_max = 1.5;
  wbm::solvers::BranchPoint last;
  options.on_point = [&](size_t, const wbm::solvers::BranchPoint& p) { last = p; };
  const auto b = nnm.continue_backbone(options);
  if (!b.complete() || last.parameter <= 1.0) {
    state.SkipWithError(("backbone to E = 1.5: " + b.message).c_str());
    return;
  }
  const auto lin = system.linearize(last.x, last.parameter);
  Eigen::VectorXd tangent = Eigen::VectorXd::Zero(system.size() + 1);
  tangent.head(system.size()) = last.x.normalized();
  tangent(system.size()) = 1.0;
  const Eigen::SparseMatrix<double> j = wbm::solvers::detail::bordered(lin, tangent, 1.0, 1.0);
  wbm::solvers::SparseLu sparse;
  auto kkt = system.linear_solver();
  for (auto _ : state) {
    if (!(structured ? kkt.factorize(j) : sparse.factorize(j))) {
      state.SkipWithError("factorization failed");
      break;
    }
  }
  state.counters["contact_nodes"] = tip;
  state.counters["kkt_unknowns"] = static_cast<double>(j.rows());
  state.counters["nonzeros"] = static_cast<double>(j.nonZeros());
  if (structured) {
    const auto c = kkt.counts();
    state.counters["schur_unknowns"] = c.max_active;
    state.counters["structured"] = c.structured > 0 && c.sparse_lu == 0 ? 1.0 : 0.0;
  }
}
BENCHMARK(BM_KktFactorization)
    ->ArgsProduct({{6, 12, 24, 48}, {0, 1}, {0, 1}})
    ->ArgNames({"contact_nodes", "structured", "penalty"})
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
