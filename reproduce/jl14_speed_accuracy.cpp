// Speed against accuracy (beyond the paper): for every combination of JL14 Table 2 and
// M = 8 … 256, the median wall time of a full solve (5 repeats up to M = 64, 3 above) and its rms
// tip error against a tight BDF reference (rtol 1e-12), and the BDF's own cost and error at
// rtol 1e-4 … 1e-10 from rest to the periodic state (period-to-period change below
// max(1e-7, rtol): a loose integrator cannot repeat to 1e-7; at most 200 periods); Pareto front (no other point both faster
// and more accurate) and the fastest method for each target error. Cases 1 and 2. ~90 s.
// Writes out/jl14_speed_accuracy/speed_accuracy_case{1,2}.csv, meta.json, report.md.
// --quick: Case 1, M = 8, 16, BDF at 1e-4 and 1e-6 against rtol 1e-10; run by ctest only.
#include <algorithm>
#include <cmath>
#include <sstream>

#include <wbm/scene/json.hpp>

#include "combinations.hpp"

namespace {

struct Point {
  std::string method;  // "DB6:Fourier, M = 64" or "BDF, rtol = 1e-06"
  int method_index;    // 0 … 5: Table 2 order; 6: BDF
  int dimension;       // M, or 0 for BDF
  double rtol;         // BDF tolerance, or 0
  wbm::solvers::SolveStatus status;  // the solve's (weighted residuals) or the integrator's (BDF)
  double error, time_s;
  int iterations;
  bool pareto = false;
  [[nodiscard]] bool converged() const { return status == wbm::solvers::SolveStatus::Converged; }
};

}  // namespace

int main(int argc, char** argv) {
  using namespace wbm;
  auto run = reproduce::Run::from_args(argc, argv, "jl14_speed_accuracy");
  return run.execute([](reproduce::Run& run) {
    const std::vector<int> dims = run.quick() ? std::vector<int>{8, 16} : std::vector<int>{8, 16, 32, 64, 128, 256};
    const std::vector<double> tolerances = run.quick() ? std::vector<double>{1e-4, 1e-6}
                                                       : std::vector<double>{1e-4, 1e-6, 1e-8, 1e-10};
    const double truth_rtol = run.quick() ? 1e-10 : 1e-12;
    const std::vector<int> cases = run.quick() ? std::vector<int>{1} : std::vector<int>{1, 2};
    const auto& combos = reproduce::table2_combinations();
    std::ostringstream md;
    md << "## Speed against accuracy: which basis for a target error\n\n"
       << "Files: `out/jl14_speed_accuracy/speed_accuracy_case{1,2}.csv`, `speed_accuracy.{png,pdf}`, `meta.json`. "
       << "Error: rms relative tip error against BDF at rtol " << reproduce::format("%.0e", truth_rtol)
       << "; time: median wall time of a full solve on one core (weighted residuals: set-up, Newton and recovery; "
          "BDF: from rest until the period-to-period change is below max(1e-7, rtol), at most 200 periods). Distributional form, Q = max(256, 2M).\n\n";
    nlohmann::json meta = nlohmann::json::object();
    meta["methods"] = nlohmann::json::array();
    for (const auto& c : combos) meta["methods"].push_back(c.label());
    meta["methods"].push_back("BDF (GSL msbdf)");
    for (int case_id : cases) {
      const auto ref = reproduce::solve_reference(run, "jl14_case" + std::to_string(case_id), truth_rtol);
      std::vector<Point> points;
      nlohmann::json solves = nlohmann::json::array();
      for (size_t i = 0; i < combos.size(); ++i) {
        for (int m : dims) {
          const auto r = reproduce::solve_combination(ref, combos[i], m, m <= 64 ? 5 : 3);
          solves.push_back(reproduce::to_json(r));
          points.push_back({combos[i].label() + ", M = " + std::to_string(m), static_cast<int>(i), m, 0.0,
                            r.solution.report.status, r.tip_error, r.median_time_s, r.solution.report.iterations});
        }
      }
      for (double tol : tolerances) {
        const auto bdf = solvers::integrate_to_periodic(ref.system, ref.forcing, ref.contacts,
                                                        {.samples_per_period = static_cast<int>(ref.tau().size()),
                                                         .relative_tolerance = tol,
                                                         .periodicity_tolerance = std::max(1e-7, tol),
                                                         .max_periods = 200});
        const bool ok = bdf.report.converged();
        const double err = ok ? solvers::rms_relative_error(bdf.displacement.row(ref.forcing.dof).transpose(),
                                                            ref.tip_displacement)
                              : NAN;  // no error for a run that did not reach a periodic state
        points.push_back({"BDF, rtol = " + reproduce::format("%.0e", tol), 6, 0, tol, bdf.report.status, err,
                          bdf.report.wall_time_s, static_cast<int>(bdf.report.steps)});
        nlohmann::json solve = bdf.report;  // the integrator's report (wbm/scene/json.hpp)
        solve["method"] = points.back().method;
        solve["tip_error"] = scene::finite_or_null(err);
        solves.push_back(solve);
      }
      for (auto& p : points) {
        p.pareto = p.converged() && std::none_of(points.begin(), points.end(), [&](const Point& o) {
                     return o.converged() && o.time_s <= p.time_s && o.error <= p.error &&
                            (o.time_s < p.time_s || o.error < p.error);
                   });
      }
      const auto n = static_cast<Eigen::Index>(points.size());
      Eigen::VectorXd method(n), dim(n), rtol(n), err(n), time(n), its(n), pareto(n);
      std::vector<std::string> status(static_cast<size_t>(n));
      for (Eigen::Index i = 0; i < n; ++i) {
        const auto& p = points[static_cast<size_t>(i)];
        method(i) = p.method_index;
        dim(i) = p.dimension;
        rtol(i) = p.rtol;
        status[static_cast<size_t>(i)] = std::string(solvers::to_string(p.status));  // details in meta.json
        err(i) = p.converged() && std::isfinite(p.error) ? p.error : NAN;  // missing: an empty cell
        time(i) = p.time_s;
        its(i) = p.iterations;
        pareto(i) = p.pareto ? 1.0 : 0.0;
      }
      run.table("speed_accuracy_case" + std::to_string(case_id) + ".csv",
                {"method [-]", "M [-]", "rtol [-]", "tip_error [-]", "time [s]", "iterations_or_steps [-]",
                 "pareto [-]"},
                {method, dim, rtol, err, time, its, pareto}, status);
      meta["case" + std::to_string(case_id)] = reproduce::to_json(ref);
      meta["case" + std::to_string(case_id)]["points"] = solves;

      md << "### " << ref.scene.title << "\n\nPareto front (fastest first):\n\n| method | tip error | time [ms] |\n"
         << "|---|---|---|\n";
      std::vector<Point> front;
      for (const auto& p : points) {
        if (p.pareto) front.push_back(p);
      }
      std::sort(front.begin(), front.end(), [](const Point& a, const Point& b) { return a.time_s < b.time_s; });
      for (const auto& p : front) {
        md << "| " << p.method << " | " << reproduce::format("%.2e", p.error) << " | "
           << reproduce::format("%.2f", 1e3 * p.time_s) << " |\n";
      }
      md << "\nFastest method reaching a target error (and the fastest per combination):\n\n| target |"
         << " fastest overall |";
      for (const auto& c : combos) md << " " << c.label() << " |";
      md << " BDF |\n|---|---|";
      for (size_t i = 0; i <= combos.size(); ++i) md << "---|";
      md << "\n";
      for (double target : {1e-1, 1e-2, 1e-3, 1e-4}) {
        md << "| " << reproduce::format("%.0e", target) << " |";
        const auto best = [&](int method_index) {
          const Point* b = nullptr;
          for (const auto& p : points) {
            if (p.converged() && p.error <= target && (method_index < 0 || p.method_index == method_index) &&
                (b == nullptr || p.time_s < b->time_s)) {
              b = &p;
            }
          }
          return b;
        };
        const Point* overall = best(-1);
        md << " " << (overall ? overall->method + " (" + reproduce::format("%.2f", 1e3 * overall->time_s) + " ms)" : "—")
           << " |";
        for (int i = 0; i <= static_cast<int>(combos.size()); ++i) {
          const Point* b = best(i);
          md << " "
             << (b ? (i < 6 ? "M = " + std::to_string(b->dimension) : "rtol " + reproduce::format("%.0e", b->rtol)) +
                         ", " + reproduce::format("%.2f", 1e3 * b->time_s) + " ms"
                   : "—")
             << " |";
        }
        md << "\n";
      }
      md << "\n";
    }
    run.meta(meta);
    run.report(md.str());
  });
}
