// Independence from rounding (issue #35) on the LL11 rod (reproduce/scenes/ll11_rod.toml): the
// backbone by continuation of the KKT conditions over the scene's energy range for every N × m
// of a grid, each again with K scaled by (1 + k 1e-12), k = 1 … 3, and with the DOFs numbered in
// reverse. Every run must complete its range or end with an explained stop, and the perturbed
// runs must agree with the unperturbed one: the same number of folds, fold energies and the
// frequencies at the landed energies (E = 1.8 and the range's end) within 1e-6 relative.
// Writes out/ll11_robustness/runs.csv, meta.json, report.md.
// The grid, from the environment variable WBM_ROBUSTNESS_GRID:
//   full (the default, make reproduce): N ∈ {4, 6, 8, 10, 12, 16, 24, 32} × m ∈ {64, 128, 256, 512};
//   reduced (.ci/run): N ∈ {8, 10, 12, 16} × m ∈ {128, 256}, the N that stopped on 18ad35a;
//   --quick: N ∈ {8, 12} × m ∈ {64, 128}, E ≤ 3.
// Any other value throws std::invalid_argument naming the variable and the allowed values.
// Also (not in --quick) the stiff stop of issue #35 (M = 64 and the defaults) with K perturbed, and
// JL14 Fig. 12 for every Table 2 combination with the five runs. The runs are independent and run
// on oneTBB's workers (tbb::parallel_for), the costliest first; each run's result does not depend
// on the thread count.
// A pair that ends short of the range at a degenerate switching point is listed as an explained
// stop; one whose branch retraced itself, or that ends otherwise, as unexplained (with its
// message); the claims print agrees/disagrees with counts.
#include <algorithm>
#include <chrono>
#include <iostream>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>
#include <tbb/task_arena.h>

#include <wbm/solvers/nonlinear_modes.hpp>
#include <wbm/solvers/response_curve.hpp>

#include <wbm/scene/analysis.hpp>
#include <wbm/scene/scene.hpp>

#include "combinations.hpp"
#include "modes.hpp"

namespace {

using namespace wbm;

// A perturbation of the model: K scaled by 1 + scale, and the DOFs numbered in reverse.
struct Perturbation {
  std::string name;
  double scale = 0.0;
  bool reversed = false;
};

// A run's stop as its tables print it ("not a valid pair" for a pair that was not run).
std::string stop_text(const std::optional<solvers::StopReason>& stop) {
  return stop ? std::string(solvers::to_string(*stop)) : std::string("not a valid pair");
}

// One run's outcome, with NaN for a value it did not reach; no stop: an impossible pair, not run.
struct Outcome {
  std::optional<solvers::StopReason> stop;
  solvers::SolveStatus status = solvers::SolveStatus::PathEnded;  // Backbone::status
  std::string message;
  [[nodiscard]] bool complete() const { return status == solvers::SolveStatus::Converged; }
  int levels = 0, corners = 0;
  std::vector<double> folds;
  double f_check = NAN, f_end = NAN, seconds = 0.0;
};

Outcome run_backbone(const scene::ModeProblem& problem, int harmonics, int samples, double e_min, double e_max,
                     double e_check, const Perturbation& p) {
  Outcome out;
  solvers::MechanicalSystem system = problem.system;
  std::vector<solvers::RigidStop> stops = problem.stops;
  system.stiffness *= 1.0 + p.scale;
  if (p.reversed) {
    const auto n = static_cast<int>(system.stiffness.rows());
    Eigen::VectorXi order(n);
    for (int i = 0; i < n; ++i) order(i) = n - 1 - i;
    const Eigen::PermutationMatrix<Eigen::Dynamic> perm(order);
    system.stiffness = (perm * system.stiffness * perm.transpose()).eval();
    system.mass = (perm * system.mass * perm.transpose()).eval();
    if (system.damping.size() > 0) system.damping = (perm * system.damping * perm.transpose()).eval();
    for (auto& s : stops) {
      s.dof = n - 1 - s.dof;
      for (auto& [dof, w] : s.along) dof = n - 1 - dof;
    }
  }
  const auto t0 = std::chrono::steady_clock::now();
  try {
    const solvers::NonlinearModes nm(system, stops, {.harmonics = harmonics, .samples = samples});
    solvers::BackboneContinuationOptions o;
    o.energy_min = e_min;
    o.energy_max = e_max;
    o.include = {e_check};
    const auto b = nm.continue_backbone(o);
    out.stop = b.stop;
    out.status = b.status;
    out.message = b.message;
    out.levels = static_cast<int>(b.levels.size());
    out.corners = b.kinks;
    out.folds = b.folds;
    if (!b.included.empty() && b.included[0].converged()) out.f_check = b.included[0].frequency_hz;
    if (b.complete()) out.f_end = b.levels.back().frequency_hz;
  } catch (const std::invalid_argument& e) {  // an impossible pair (m <= 2N): explained, not run
    out.message = e.what();
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

// The newcomer's stiff stop of issue #35 (50 kg on 1 MN/m, c = 0.2 √(mk), a 1e8 N/m stop at
// 20 µm, 10 N over 60–210 rad/s, continuation), with K scaled by 1 + scale and `basis` (a TOML
// [basis] line, or empty for the defaults): completion, folds [Hz] and the fold amplitudes [m].
struct StiffStopOutcome {
  solvers::SolveStatus status = solvers::SolveStatus::PathEnded;
  std::optional<solvers::StopReason> stop;
  std::string message;
  [[nodiscard]] bool converged() const { return status == solvers::SolveStatus::Converged; }
  int points = 0;
  std::vector<double> folds, fold_amplitudes;
  double seconds = 0.0;
};

StiffStopOutcome run_stiff_stop(const std::string& basis, double scale) {
  const double m = 50.0, k = 1e6, c = 0.2 * std::sqrt(m * k);
  const std::string text = "structure = { mass = 50.0, stiffness = " + reproduce::format("%.17g", k * (1.0 + scale)) +
                           " }\ndamping = { alpha = " + reproduce::format("%.17g", c / m) +
                           " }\nforcing = { amplitude = 10.0, frequency_rad_s = [60.0, 210.0] }\n"
                           "contact = { law = \"linear\", stiffness = 1e8, gap = 2e-5 }\n" +
                           basis + "analysis = { type = \"continuation\" }\n";
  StiffStopOutcome out;
  const auto t0 = std::chrono::steady_clock::now();
  const scene::AnalysisResult r = scene::run_analysis(scene::parse_scene(text, "stiff_stop.toml"));
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  out.status = r.status;
  out.stop = r.stop;
  const auto& c_json = r.diagnostics["continuation"];
  out.message = c_json["message"].get<std::string>();
  out.points = c_json["points"].get<int>();
  for (const auto& t : r.tables) {
    if (t.file != "folds.csv") continue;
    for (Eigen::Index i = 0; i < t.columns[0].size(); ++i) {
      out.folds.push_back(t.columns[0](i));
      out.fold_amplitudes.push_back(t.columns[4](i));
    }
  }
  return out;
}

// JL14 Fig. 12 for one Table 2 combination (jl14_case2.toml, M = 64, 1000–1700 Hz, steps ≤ 2 Hz,
// at most 10 gaps of contact displacement, as jl14_fig12; no stability), perturbed as `p`: the
// stop, the folds [Hz] and the peak tip amplitude [m].
struct Fig12Outcome {
  solvers::StopReason stop = solvers::StopReason::InitialPointFailed;
  int points = 0;
  std::vector<double> folds;
  double peak = NAN, seconds = 0.0;
};

Fig12Outcome run_fig12(const scene::Scene& scene, const reproduce::Combination& c, const Perturbation& p) {
  solvers::MechanicalSystem system = scene.system();
  std::vector<solvers::ContactPoint> contacts = scene.contact_points();
  solvers::HarmonicForcing forcing = scene.harmonic_forcing(1000.0);
  system.stiffness *= 1.0 + p.scale;
  const auto n = static_cast<int>(system.stiffness.rows());
  if (p.reversed) {
    Eigen::VectorXi order(n);
    for (int i = 0; i < n; ++i) order(i) = n - 1 - i;
    const Eigen::PermutationMatrix<Eigen::Dynamic> perm(order);
    system.stiffness = (perm * system.stiffness * perm.transpose()).eval();
    system.mass = (perm * system.mass * perm.transpose()).eval();
    if (system.damping.size() > 0) system.damping = (perm * system.damping * perm.transpose()).eval();
    for (auto& k : contacts) k.dof = n - 1 - k.dof;
    forcing.dof = n - 1 - forcing.dof;
  }
  const solvers::WeightedResidual base(system, forcing, contacts, solvers::TimeBasis::from_name(c.trial, 64),
                                       solvers::TimeBasis::from_name(c.weighting, 64),
                                       {.formulation = reproduce::kFigureFormulation});
  solvers::ResponseCurveOptions o;
  o.parameter_min = 1000.0;
  o.parameter_max = 1700.0;
  o.max_parameter_step = 2.0;
  o.max_state = 10.0;
  o.stability = false;
  const auto t0 = std::chrono::steady_clock::now();
  const auto curve = solvers::trace_response(base, o);
  Fig12Outcome out;
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  out.stop = curve.stop;
  out.points = static_cast<int>(curve.points.size());
  for (const auto& f : curve.folds) out.folds.push_back(f.parameter);
  for (const auto& pt : curve.points) out.peak = std::isnan(out.peak) ? pt.amplitude : std::max(out.peak, pt.amplitude);
  return out;
}

// Largest relative difference of two values (NaN on either side: infinite, unless both are NaN).
double relative(double a, double b) {
  if (std::isnan(a) && std::isnan(b)) return 0.0;
  if (std::isnan(a) || std::isnan(b)) return INFINITY;
  return std::abs(a - b) / std::max(std::abs(a), 1e-300);
}

// f(i) for every i in [0, costs.size()), on oneTBB's workers, taken in decreasing order of
// costs[i] (an estimate) so that the longest run does not start last and leave a core idle.
// Each f(i) must not depend on another.
template <class T, class F>
std::vector<T> run_all(const std::vector<double>& costs, F f) {
  std::vector<size_t> order(costs.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return costs[a] > costs[b]; });
  std::vector<T> results(costs.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, order.size(), 1), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t k = r.begin(); k != r.end(); ++k) results[order[k]] = f(order[k]);
  }, tbb::simple_partitioner());
  return results;
}

}  // namespace

int main(int argc, char** argv) {
  auto run = reproduce::Run::from_args(argc, argv, "ll11_robustness");
  return run.execute([](reproduce::Run& run) {
    using reproduce::format;
    const scene::Scene base = reproduce::ll11_scene(run);
    const scene::ModeProblem problem = scene::mode_problem(base);
    const double e_min = base.analysis.energy_min;
    const double e_max = run.quick() ? 3.0 : base.analysis.energy_max;
    const double e_check = 1.8;  // LL11 Fig. 5's level
    // The grid (see the file's head): full unless WBM_ROBUSTNESS_GRID says otherwise.
    const char* grid_env = std::getenv("WBM_ROBUSTNESS_GRID");
    const std::string grid = run.quick() ? "quick" : (grid_env != nullptr && *grid_env != 0 ? grid_env : "full");
    if (grid != "quick" && grid != "full" && grid != "reduced") {
      throw std::invalid_argument("ll11_robustness: WBM_ROBUSTNESS_GRID = \"" + grid +
                                  "\" is not a grid: use \"full\" (N 4-32 x m 64-512, the default) or "
                                  "\"reduced\" (N 8-16 x m 128-256, as .ci/run), or leave it unset");
    }
    const std::vector<int> harmonics = grid == "quick"  ? std::vector<int>{8, 12}
                                       : grid == "full" ? std::vector<int>{4, 6, 8, 10, 12, 16, 24, 32}
                                                        : std::vector<int>{8, 10, 12, 16};
    const std::vector<int> samples = grid == "quick"  ? std::vector<int>{64, 128}
                                     : grid == "full" ? std::vector<int>{64, 128, 256, 512}
                                                      : std::vector<int>{128, 256};
    const std::vector<Perturbation> perturbations = {
        {"none", 0.0, false}, {"K (1 + 1e-12)", 1e-12, false}, {"K (1 + 2e-12)", 2e-12, false},
        {"K (1 + 3e-12)", 3e-12, false}, {"DOFs reversed", 0.0, true}};
    constexpr double kAgree = 1e-6;
    // Every run of the grid at once, pair-major: run (i_h, i_m, k) is index (i_h n_m + i_m) n_p + k;
    // cost estimate N m (the continuation's work per level grows with both).
    const auto wall0 = std::chrono::steady_clock::now();
    const size_t n_p = perturbations.size();
    std::vector<double> costs;
    for (int n_h : harmonics) {
      for (int m : samples) costs.insert(costs.end(), n_p, static_cast<double>(n_h) * m);
    }
    const std::vector<Outcome> all = run_all<Outcome>(costs, [&](size_t i) {
      const int n_h = harmonics[i / n_p / samples.size()], m = samples[i / n_p % samples.size()];
      Outcome o = run_backbone(problem, n_h, m, e_min, e_max, e_check, perturbations[i % n_p]);
      std::cerr << ("ll11_robustness: N = " + std::to_string(n_h) + ", m = " + std::to_string(m) + ", " +
                    perturbations[i % n_p].name + ": " + stop_text(o.stop) + ", " + format("%.1f", o.seconds) + " s\n");
      return o;
    });
    const double grid_wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    // runs.csv columns (one row per run) and the status of each row (its stop; why a value is missing).
    std::vector<std::vector<double>> columns(10);
    std::vector<std::string> status;
    std::ostringstream rows;
    nlohmann::json meta = nlohmann::json::array();
    int pairs = 0, completed = 0, explained = 0, stopped = 0, unexplained = 0, disagreeing = 0;
    std::ostringstream fold_differences;  // per perturbed run whose folds differ from the unperturbed one's
    double worst = 0.0, total_seconds = 0.0;
    for (int n_h : harmonics) {
      for (int m : samples) {
        const std::vector<Outcome> outs(all.begin() + static_cast<std::ptrdiff_t>(pairs * n_p),
                                        all.begin() + static_cast<std::ptrdiff_t>((pairs + 1) * n_p));
        ++pairs;
        const Outcome& ref = outs.front();
        // Agreement of each perturbed run with the unperturbed one.
        double diff = 0.0;
        bool same_folds = true, same_outcome = true;
        for (size_t k = 1; k < outs.size(); ++k) {
          const Outcome& o = outs[k];
          same_outcome = same_outcome && o.status == ref.status && o.stop == ref.stop;
          same_folds = same_folds && o.folds.size() == ref.folds.size();
          for (size_t i = 0; same_folds && i < o.folds.size(); ++i) diff = std::max(diff, relative(o.folds[i], ref.folds[i]));
          diff = std::max({diff, relative(o.f_check, ref.f_check), relative(o.f_end, ref.f_end)});
        }
        const bool valid = ref.stop.has_value();
        const bool agree = same_outcome && same_folds && diff <= kAgree;
        // A degenerate switching point is a computed outcome with its reason. A backbone that
        // retraced itself is not: a conservative system's backbone does not turn back onto
        // itself, so that stop is the continuation's failure and counts as unexplained.
        const bool explained_stop = ref.stop == solvers::StopReason::DegenerateEvent;
        if (!valid) {
          ++explained;
        } else if (ref.complete()) {
          ++completed;
        } else if (explained_stop) {
          ++stopped;  // a computed outcome with its reason (a degenerate switching point)
        } else {
          ++unexplained;  // retraced, step below minimum, point limit: listed with the message
        }
        if (valid && !agree) ++disagreeing;
        if (valid && std::isfinite(diff)) worst = std::max(worst, diff);
        // Where the fold sets differ: the folds of each run that have no counterpart within
        // kAgree in the other, and the extent of E they span (a short turn back and forth at a
        // corner whose orientation rounding decides, or a fold of the branch itself).
        for (size_t k = 1; valid && k < outs.size(); ++k) {
          std::vector<double> extra, missing;
          auto unmatched = [](const std::vector<double>& a, const std::vector<double>& b, std::vector<double>& out) {
            for (double x : a) {
              if (std::none_of(b.begin(), b.end(), [&](double y) { return relative(x, y) <= kAgree; })) out.push_back(x);
            }
          };
          unmatched(outs[k].folds, ref.folds, extra);
          unmatched(ref.folds, outs[k].folds, missing);
          if (extra.empty() && missing.empty()) continue;
          auto listed = [&](const std::vector<double>& v) {
            std::string text;
            for (double x : v) text += (text.empty() ? "" : ", ") + format("%.7f", x);
            const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
            return text + " (spanning " + format("%.1e", (*hi - *lo) / *hi) + " of E)";
          };
          fold_differences << "- N = " << n_h << ", m = " << m << ", " << perturbations[k].name << ": "
                           << outs[k].corners << " corners against " << ref.corners << "; "
                           << (extra.empty() ? std::string() : std::to_string(extra.size()) + " more folds, at E = " + listed(extra))
                           << (extra.empty() || missing.empty() ? "" : "; ")
                           << (missing.empty() ? std::string() : std::to_string(missing.size()) + " folds fewer, at E = " + listed(missing))
                           << "\n";
        }
        double seconds = 0.0;
        for (const auto& o : outs) seconds += o.seconds;
        total_seconds += seconds;
        std::cerr << "ll11_robustness: N = " << n_h << ", m = " << m << ": " << (valid ? stop_text(ref.stop) : "not valid")
                  << ", " << outs.size() << " runs in " << format("%.1f", seconds) << " s, largest difference "
                  << format("%.1e", diff) << "\n";
        const std::string outcome =
            !valid ? "not run: " + ref.message
                   : (ref.complete() ? std::string(solvers::to_string(solvers::StopReason::RangeReached)) : ref.message);
        rows << "| " << n_h << " | " << m << " | " << outcome << " | " << (valid ? std::to_string(ref.levels) : "")
             << " | " << (valid ? std::to_string(ref.corners) : "") << " | " << (valid ? std::to_string(ref.folds.size()) : "")
             << " | " << format("%.5f", ref.f_check) << " | " << format("%.5f", ref.f_end) << " | "
             << (valid ? (std::isfinite(diff) ? format("%.1e", diff) : std::string("a value missing")) : "") << " | "
             << (valid ? (agree ? "agree" : "DISAGREE") : "") << " | " << format("%.1f", seconds) << " |\n";
        nlohmann::json runs = nlohmann::json::array();
        for (size_t k = 0; k < outs.size(); ++k) {
          const Outcome& o = outs[k];
          const double row[] = {static_cast<double>(n_h), static_cast<double>(m), static_cast<double>(k),
                                perturbations[k].scale, o.complete() ? 1.0 : 0.0, static_cast<double>(o.levels),
                                static_cast<double>(o.corners), static_cast<double>(o.folds.size()), o.f_check, o.f_end};
          for (size_t c = 0; c < columns.size(); ++c) columns[c].push_back(row[c]);
          status.push_back(stop_text(o.stop));
          runs.push_back({{"perturbation", perturbations[k].name}, {"stop", stop_text(o.stop)}, {"message", o.message},
                          {"complete", o.complete()}, {"levels", o.levels}, {"corners", o.corners}, {"folds", o.folds},
                          {"frequency_at_check_hz", std::isfinite(o.f_check) ? nlohmann::json(o.f_check) : nlohmann::json(nullptr)},
                          {"frequency_at_end_hz", std::isfinite(o.f_end) ? nlohmann::json(o.f_end) : nlohmann::json(nullptr)},
                          {"seconds", o.seconds}});
        }
        meta.push_back({{"harmonics", n_h}, {"samples", m}, {"largest_relative_difference",
                                                             std::isfinite(diff) ? nlohmann::json(diff) : nlohmann::json(nullptr)},
                        {"agree", agree}, {"runs", runs}});
      }
    }
    std::vector<Eigen::VectorXd> table;
    for (const auto& c : columns) table.push_back(Eigen::Map<const Eigen::VectorXd>(c.data(), static_cast<Eigen::Index>(c.size())));
    run.table("runs.csv",
              {"harmonics [-]", "samples [-]", "perturbation [-]", "stiffness_scale [-]", "complete [-]", "levels [-]",
               "corners [-]", "folds [-]", "frequency_at_check [Hz]", "frequency_at_end [Hz]"},
              table, status);
    std::vector<reproduce::Claim> claims;
    claims.push_back({"every valid N × m pair completes the energy range [" + format("%g", e_min) + ", " +
                          format("%g", e_max) + "] or ends with an explained stop (no retracing, no step below minimum, no point limit)",
                      unexplained == 0, std::to_string(completed) + " of " + std::to_string(pairs - explained) +
                                            " valid pairs complete, " + std::to_string(stopped) +
                                            " end with an explained stop, " + std::to_string(unexplained) +
                                            " with another stop; " + std::to_string(explained) + " not valid (m ≤ 2N)"});
    claims.push_back({"the perturbed runs (K × (1 + k 1e-12), DOFs reversed) agree with the unperturbed one: same "
                      "outcome, same number of folds, folds and frequencies within 1e-6 relative",
                      disagreeing == 0, std::to_string(disagreeing) + " pairs disagree; largest relative difference " +
                                            format("%.1e", worst)});
    // The stiff stop, with the paper's M = 64 Fourier basis and with the defaults (H = 32), each
    // as is and with K scaled by (1 + k 1e-12); a 1-DOF model has no other numbering of its DOFs.
    std::ostringstream stiff_rows;
    nlohmann::json stiff_meta = nlohmann::json::array();
    int stiff_incomplete = 0, stiff_disagreeing = 0;
    double stiff_worst = 0.0;
    const std::vector<std::pair<std::string, std::string>> stiff_bases = {
        {"dimension = 64", "basis = { trial = \"fourier\", dimension = 64 }\n"}, {"defaults", ""}};
    std::vector<double> stiff_scales;
    for (const auto& p : perturbations) {
      if (!p.reversed) stiff_scales.push_back(p.scale);
    }
    const std::vector<StiffStopOutcome> stiff_all =
        run_all<StiffStopOutcome>(std::vector<double>(stiff_bases.size() * stiff_scales.size(), 1.0), [&](size_t i) {
          return run_stiff_stop(stiff_bases[i / stiff_scales.size()].second, stiff_scales[i % stiff_scales.size()]);
        });
    for (size_t b = 0; b < stiff_bases.size(); ++b) {
      const std::string& label = stiff_bases[b].first;
      const std::vector<StiffStopOutcome> outs(stiff_all.begin() + static_cast<std::ptrdiff_t>(b * stiff_scales.size()),
                                               stiff_all.begin() + static_cast<std::ptrdiff_t>((b + 1) * stiff_scales.size()));
      const StiffStopOutcome& ref = outs.front();
      double diff = 0.0, seconds = 0.0;
      bool agree = true;
      for (const auto& o : outs) {
        seconds += o.seconds;
        agree = agree && o.status == ref.status && o.stop == ref.stop && o.folds.size() == ref.folds.size();
        for (size_t i = 0; agree && i < o.folds.size(); ++i) {
          diff = std::max({diff, relative(o.folds[i], ref.folds[i]), relative(o.fold_amplitudes[i], ref.fold_amplitudes[i])});
        }
      }
      agree = agree && diff <= kAgree;
      if (!ref.converged()) ++stiff_incomplete;
      if (!agree) ++stiff_disagreeing;
      stiff_worst = std::max(stiff_worst, diff);
      total_seconds += seconds;
      std::string folds_text;
      for (size_t i = 0; i < ref.folds.size(); ++i) {
        folds_text += (i ? ", " : "") + format("%.4f", ref.folds[i]) + " Hz (" + format("%.3f", 1e6 * ref.fold_amplitudes[i]) + " µm)";
      }
      stiff_rows << "| " << label << " | " << (ref.converged() ? std::string(solvers::to_string(solvers::StopReason::RangeReached)) : ref.message) << " | "
                 << ref.points << " | " << (folds_text.empty() ? std::string("none") : folds_text) << " | "
                 << format("%.1e", diff) << " | " << (agree ? "agree" : "DISAGREE") << " | " << format("%.1f", seconds) << " |\n";
      const nlohmann::json stop = ref.stop ? nlohmann::json(std::string(solvers::to_string(*ref.stop))) : nlohmann::json();
      stiff_meta.push_back({{"basis", label}, {"status", std::string(solvers::to_string(ref.status))}, {"stop", stop},
                            {"message", ref.message},
                            {"points", ref.points}, {"folds_hz", ref.folds}, {"fold_amplitudes_m", ref.fold_amplitudes},
                            {"largest_relative_difference", diff}, {"agree", agree}, {"runs", outs.size()}});
    }
    claims.push_back({"the stiff stop (issue #35) completes its range with the paper's M = 64 Fourier basis and with the "
                      "defaults, and its runs with K × (1 + k 1e-12) agree: same folds, fold frequencies and amplitudes "
                      "within 1e-6 relative",
                      stiff_incomplete == 0 && stiff_disagreeing == 0,
                      std::to_string(2 - stiff_incomplete) + " of 2 complete, " + std::to_string(stiff_disagreeing) +
                          " disagree; largest relative difference " + format("%.1e", stiff_worst)});
    // JL14 Fig. 12 for every Table 2 combination, perturbed as the backbone (about 15 s: no
    // stability); not in --quick.
    std::ostringstream fig12_rows;
    nlohmann::json fig12_meta = nullptr;
    if (!run.quick()) {
      fig12_meta = nlohmann::json::array();
      const scene::Scene case2 = reproduce::load_scene("jl14_case2");
      int fig12_disagreeing = 0, fig12_unexplained = 0;
      double fig12_worst = 0.0;
      const auto combinations = reproduce::table2_combinations();
      const std::vector<Fig12Outcome> fig12_all =
          run_all<Fig12Outcome>(std::vector<double>(combinations.size() * n_p, 1.0), [&](size_t i) {
            return run_fig12(case2, combinations[i / n_p], perturbations[i % n_p]);
          });
      for (size_t ci = 0; ci < combinations.size(); ++ci) {
        const reproduce::Combination& c = combinations[ci];
        const std::vector<Fig12Outcome> outs(fig12_all.begin() + static_cast<std::ptrdiff_t>(ci * n_p),
                                             fig12_all.begin() + static_cast<std::ptrdiff_t>((ci + 1) * n_p));
        const Fig12Outcome& ref = outs.front();
        double diff = 0.0, seconds = 0.0;
        bool agree = true;
        for (const auto& o : outs) {
          seconds += o.seconds;
          agree = agree && o.stop == ref.stop && o.folds.size() == ref.folds.size();
          for (size_t i = 0; agree && i < o.folds.size(); ++i) diff = std::max(diff, relative(o.folds[i], ref.folds[i]));
          diff = std::max(diff, relative(o.peak, ref.peak));
        }
        agree = agree && diff <= kAgree;
        const bool explained_stop = ref.stop == solvers::StopReason::RangeReached ||
                                    ref.stop == solvers::StopReason::StateBound ||
                                    ref.stop == solvers::StopReason::UndampedResonance;
        if (!explained_stop) ++fig12_unexplained;
        if (!agree) ++fig12_disagreeing;
        fig12_worst = std::max(fig12_worst, std::isfinite(diff) ? diff : 0.0);
        total_seconds += seconds;
        std::string folds_text;
        for (size_t i = 0; i < ref.folds.size(); ++i) folds_text += (i ? ", " : "") + format("%.2f", ref.folds[i]);
        fig12_rows << "| " << c.label() << " | " << solvers::to_string(ref.stop) << " | " << ref.points << " | "
                   << (folds_text.empty() ? std::string("none") : folds_text) << " | " << format("%.4f", 1e3 * ref.peak)
                   << " | " << (std::isfinite(diff) ? format("%.1e", diff) : std::string("a value missing")) << " | "
                   << (agree ? "agree" : "DISAGREE") << " | " << format("%.1f", seconds) << " |\n";
        std::cerr << "ll11_robustness: Fig. 12 " << c.label() << ": " << solvers::to_string(ref.stop) << ", "
                  << format("%.1f", seconds)
                  << " s, largest difference " << format("%.1e", diff) << "\n";
        fig12_meta.push_back({{"combination", c.label()}, {"stop", std::string(solvers::to_string(ref.stop))},
                              {"points", ref.points}, {"folds_hz", ref.folds},
                              {"peak_amplitude_m", ref.peak}, {"largest_relative_difference", std::isfinite(diff) ? nlohmann::json(diff) : nlohmann::json(nullptr)},
                              {"agree", agree}});
      }
      claims.push_back({"JL14 Fig. 12 for every Table 2 combination ends on the range, the state bound or an explained "
                        "undamped resonance, and its perturbed runs agree: same stop, same folds within 1e-6 relative, "
                        "same peak amplitude",
                        fig12_unexplained == 0 && fig12_disagreeing == 0,
                        std::to_string(fig12_unexplained) + " end otherwise, " + std::to_string(fig12_disagreeing) +
                            " of " + std::to_string(combinations.size()) +
                            " disagree; largest relative difference " + format("%.1e", fig12_worst)});
    }
    run.meta({{"check", "independence of the LL11 rod backbone, the stiff stop and JL14 Fig. 12 from rounding"},
              {"scene", base.path}, {"energy_max", e_max}, {"pairs", meta}, {"stiff_stop", stiff_meta},
              {"jl14_fig12", fig12_meta}, {"grid", grid}, {"total_seconds", total_seconds},
              {"grid_wall_seconds", grid_wall}});
    std::ostringstream md;
    md << "## Robustness: the LL11 rod backbone against rounding (issue #35)\n\n"
       << "Files: `out/ll11_robustness/runs.csv` (one row per run; perturbation 0: none, 1–3: K scaled, 4: DOFs "
          "reversed; status: the stop), `meta.json`. Scene `reproduce/scenes/ll11_rod.toml` with N and m "
          "replaced; continuation of the KKT conditions from E = "
       << format("%g", e_min) << " to " << format("%g", e_max)
       << ", corners crossed as located events (continuation.hpp). Grid: **" << grid << "**"
       << (grid == "full" ? std::string(" (the default of `make reproduce`)")
                          : grid == "reduced" ? std::string(" (`WBM_ROBUSTNESS_GRID=reduced`, as .ci/run; unset it for the full grid)")
                                              : std::string(" (--quick)"))
       << ". Each pair runs five times: as is, with K scaled by "
          "(1 + k·1e-12) for k = 1, 2, 3, and with the DOFs numbered in reverse; the difference column is the "
          "largest relative difference of the folds' energies and of the frequencies at E = "
       << format("%g", e_check) << " and at the range's end from the unperturbed run. Time: the five runs together ("
       << format("%.0f", total_seconds) << " s of runs in all; the grid took " << format("%.0f", grid_wall)
       << " s on " << std::to_string(tbb::this_task_arena::max_concurrency()) << " workers).\n\n"
       << "| N | m | outcome | levels | corners | folds | f at E = " << format("%g", e_check) << " [Hz] | f at E = "
       << format("%g", e_max) << " [Hz] | largest difference | perturbed runs | time [s] |\n"
       << "|---|---|---|---|---|---|---|---|---|---|---|\n"
       << rows.str() << "\n";
    if (!fold_differences.str().empty()) {
      md << "Runs whose folds differ from the unperturbed run's (folds without a counterpart within "
         << format("%.0e", kAgree) << " relative; the frequencies at the landed energies are compared in the table):\n\n"
         << fold_differences.str() << "\n";
    }
    md << "**The stiff stop of issue #35** (50 kg on 1 MN/m, c = 0.2 √(mk), a 1e8 N/m stop at 20 µm, 10 N over "
          "60–210 rad/s, `type = \"continuation\"`), with `basis = { trial = \"fourier\", dimension = 64 }` and with "
          "no [basis] table, each as is and with K scaled by (1 + k·1e-12), k = 1, 2, 3 (one DOF: no renumbering). "
          "The difference column is the largest relative difference of the folds' frequencies and amplitudes.\n\n"
       << "| basis | outcome | points | folds (amplitude) | largest difference | perturbed runs | time [s] |\n"
       << "|---|---|---|---|---|---|---|\n"
       << stiff_rows.str() << "\n";
    if (!run.quick()) {
      md << "**JL14 Fig. 12** (jl14_case2.toml, M = 64, distributional, 1000–1700 Hz, steps ≤ 2 Hz, at most 10 gaps; "
            "no stability) for every Table 2 combination, with the same five runs; the difference column is the "
            "largest relative difference of the folds and of the peak tip amplitude.\n\n"
         << "| combination | stop | points | folds [Hz] | peak amplitude [mm] | largest difference | perturbed runs | time [s] |\n"
         << "|---|---|---|---|---|---|---|---|\n"
         << fig12_rows.str() << "\n";
    }
    md << reproduce::claims_markdown(claims);
    run.report(md.str());
  });
}
