// Scaling table (issue #17; `make bench`): how the cost of a full weighted-residual solve (set-up, Newton,
// recovery) grows with the dimension M and with the number of contact DOFs n_c, with the fitted
// exponent p of t ≈ c·x^p (least squares on log t against log x over the last four points).
//  - Time vs M: every combination of [JL14 Table 2] on Case 1 (reproduce/scenes/jl14_case1.toml,
//    the FE rod, one contact), distributional form, M = 16 … 1024 (the default Q = max(256, 2M)).
//  - Time vs n_c: Fourier:Fourier, M = 16, on a fixed-free chain of 64 unit masses (models/spring_chain.hpp,
//    k = 1e4 N/m, C = 1e-4 K; forcing 1 N at 0.8 of the first natural frequency on the free
//    end), linear penalty stops (k_pen = 1e3 N/m) on the last n_c = 1, 4, 16, 64 masses, each at
//    0.95 of its linear amplitude, so every stop is hit.
// Each time is the median of 5 runs on one core (set-up included). Writes, through
// reproduce::Run, out/bench_scaling/scaling_dimension.csv, scaling_contacts.csv, meta.json and
// report.md (included in out/REPORT.md by reproduce/report.py). A solve that does not converge
// fails the run (the time of a failed solve measures nothing), naming the case and its status.
// Usage: bench_scaling [--quick] [--out DIR]  (--quick: M ≤ 64 and n_c ≤ 16, 3 runs; for ctest).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <memory>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include <wbm/contact/penalty.hpp>
#include <wbm/solvers/weighted_residual.hpp>

#include "combinations.hpp"
#include "spring_chain.hpp"
#include "run.hpp"
#include "scene.hpp"

namespace {

using wbm::solvers::TimeBasis;

struct Row {
  std::string series, label;  // "M" or "contacts"; "Fourier:Fourier"
  int x = 0;                  // M or n_c
  int unknowns = 0;           // n_c·M
  double setup_s = 0.0, total_s = 0.0;
  wbm::solvers::SolveStatus status = wbm::solvers::SolveStatus::MaxIterations;
  wbm::solvers::SolutionPath path{};
  int iterations = 0;  // Newton iterations in all (homotopy correctors included)
  [[nodiscard]] bool converged() const { return status == wbm::solvers::SolveStatus::Converged; }
  [[nodiscard]] std::string outcome() const {  // "converged (direct Newton)"
    return std::string(wbm::solvers::to_string(status)) + " (" + std::string(wbm::solvers::to_string(path)) + ")";
  }
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Times `repeats` full solves (construction + solve) and the construction alone.
Row time_solve(const wbm::solvers::MechanicalSystem& system, const wbm::solvers::HarmonicForcing& forcing,
               const std::vector<wbm::solvers::ContactPoint>& contacts, const std::string& trial,
               const std::string& weighting, int m, int repeats) {
  using clock = std::chrono::steady_clock;
  std::vector<double> setup, total;
  Row row;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = clock::now();
    const wbm::solvers::WeightedResidual wr(system, forcing, contacts, TimeBasis::from_name(trial, m),
                                            TimeBasis::from_name(weighting, m));
    const auto t1 = clock::now();
    const auto sol = wr.solve();
    const auto t2 = clock::now();
    setup.push_back(std::chrono::duration<double>(t1 - t0).count());
    total.push_back(std::chrono::duration<double>(t2 - t0).count());
    row.status = sol.report.status;
    row.path = sol.path;
    row.iterations = sol.report.iterations;
    row.unknowns = sol.contact_unknowns;
  }
  row.setup_s = median(setup);
  row.total_s = median(total);
  return row;
}

// Least-squares slope of log t against log x over the last `tail` rows of a series.
double fitted_exponent(const std::vector<Row>& rows, size_t tail) {
  const size_t first = rows.size() > tail ? rows.size() - tail : 0;
  std::vector<double> x, t;
  for (size_t i = first; i < rows.size(); ++i) x.push_back(rows[i].x), t.push_back(rows[i].total_s);
  return wbm::reproduce::loglog_slope(x, t);
}

// The rows of one series as a table: x, n_c·M, set-up and total time, Newton iterations; the
// status column says "<SolveStatus> (<route>)".
void write_series(wbm::reproduce::Run& run, const std::string& file, const std::string& x_name,
                  const std::vector<std::vector<Row>>& series, bool with_index) {
  std::vector<double> index, x, unknowns, setup, total, iterations;
  std::vector<std::string> status;
  for (size_t s = 0; s < series.size(); ++s) {
    for (const auto& r : series[s]) {
      index.push_back(static_cast<double>(s));
      x.push_back(r.x);
      unknowns.push_back(r.unknowns);
      setup.push_back(r.setup_s);
      total.push_back(r.total_s);
      iterations.push_back(r.iterations);
      status.push_back(r.outcome());
    }
  }
  const auto col = [](const std::vector<double>& v) { return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size())).eval(); };
  std::vector<std::string> header = {x_name, "contact_unknowns [-]", "setup_time [s]", "total_time [s]", "newton_iterations [-]"};
  std::vector<Eigen::VectorXd> columns = {col(x), col(unknowns), col(setup), col(total), col(iterations)};
  if (with_index) {
    header.insert(header.begin(), "combination [-]");
    columns.insert(columns.begin(), col(index));
  }
  run.table(file, header, columns, status);
}

}  // namespace

int main(int argc, char** argv) {
  auto run = wbm::reproduce::Run::from_args(argc, argv, "bench_scaling");
  return run.execute([](wbm::reproduce::Run& run) {
    using wbm::reproduce::format;
    const int repeats = run.quick() ? 3 : 5;
    std::vector<std::vector<Row>> by_dimension;

    // Time vs M, Case 1, every Table 2 pair.
    const auto scene = wbm::reproduce::load_scene("jl14_case1");
    const auto& pairs = wbm::reproduce::table2_combinations();
    const std::vector<int> dims =
        run.quick() ? std::vector<int>{16, 32, 64} : std::vector<int>{16, 32, 64, 128, 256, 512, 1024};
    nlohmann::json combinations = nlohmann::json::array();
    for (const auto& pair : pairs) {
      combinations.push_back(pair.label());
      std::vector<Row> rows;
      for (int m : dims) {
        Row r = time_solve(scene.system(), scene.harmonic_forcing(), scene.contact_points(), pair.trial, pair.weighting,
                           m, repeats);
        r.series = "M";
        r.label = pair.label();
        r.x = m;
        std::cerr << r.label << " M = " << m << ": " << r.total_s * 1e3 << " ms (" << r.outcome() << ")\n";
        rows.push_back(r);
      }
      by_dimension.push_back(rows);
    }

    // Time vs n_c on the chain.
    std::vector<Row> chain_rows;
    const int n = 64, m_chain = 16;
    const double k = 1e4;
    const auto system = wbm::models::spring_chain(n, k, 1e-4);
    const double f1 = std::sqrt(k) * 2.0 * std::sin(std::numbers::pi / (2.0 * (2 * n + 1))) / (2.0 * std::numbers::pi);
    const wbm::solvers::HarmonicForcing forcing{n - 1, 1.0, 0.8 * f1};
    const Eigen::VectorXcd lin = wbm::solvers::frequency_response(system, forcing);
    const std::vector<int> counts = run.quick() ? std::vector<int>{1, 4, 16} : std::vector<int>{1, 4, 16, 64};
    for (int nc : counts) {
      std::vector<wbm::solvers::ContactPoint> contacts;
      for (int c = n - nc; c < n; ++c) {
        contacts.push_back({c, std::make_shared<wbm::contact::LinearPenalty>(
                                   wbm::contact::LinearPenaltyParameters{1e3, 0.95 * std::abs(lin(c))})});
      }
      Row r = time_solve(system, forcing, contacts, "fourier", "fourier", m_chain, repeats);
      r.series = "contacts";
      r.label = "Fourier:Fourier, chain of 64, M = 16";
      r.x = nc;
      std::cerr << "chain n_c = " << nc << ": " << r.total_s * 1e3 << " ms (" << r.outcome() << ")\n";
      chain_rows.push_back(r);
    }

    for (const auto& rows : by_dimension) {
      for (const auto& r : rows) {
        if (!r.converged()) run.fail(r.label + " at M = " + std::to_string(r.x) + " did not converge: " + r.outcome());
      }
    }
    for (const auto& r : chain_rows) {
      if (!r.converged()) run.fail(r.label + " with n_c = " + std::to_string(r.x) + " did not converge: " + r.outcome());
    }
    write_series(run, "scaling_dimension.csv", "M [-]", by_dimension, true);
    write_series(run, "scaling_contacts.csv", "contacts [-]", {chain_rows}, false);
    run.meta({{"combinations", combinations},
              {"repeats", repeats},
              {"time", "median wall time of construction + solve, one core"},
              {"chain", {{"masses", n}, {"spring_N_per_m", k}, {"damping", "C = 1e-4 K"}, {"forcing_N", 1.0},
                         {"frequency_hz", forcing.frequency_hz}, {"penalty_N_per_m", 1e3}, {"gap", "0.95 x linear amplitude"},
                         {"dimension", m_chain}}}});

    std::ostringstream md;
    md << "## Cost scaling of the weighted-residual solve (reproduce/bench_scaling.cpp)\n\n"
       << "Files: `out/bench_scaling/scaling_dimension.csv`, `scaling_contacts.csv`, `meta.json`. Median of "
       << repeats << " full solves on one core (construction with set-up, Newton, recovery). The exponent p fits "
          "t ≈ c·x^p on the last four points (least squares in log–log).\n\n"
       << "### Time vs M (Case 1, distributional, Q = max(256, 2M)), ms\n\n| combination |";
    for (int m : dims) md << " M = " << m << " |";
    md << " p (M) | set-up share at M = " << dims.back() << " |\n|---|";
    for (size_t i = 0; i < dims.size(); ++i) md << "---|";
    md << "---|---|\n";
    std::ostringstream notes;  // solves that did not go by direct Newton, listed under the table
    for (const auto& rows : by_dimension) {
      md << "| " << rows.front().label << " |";
      for (const auto& r : rows) md << " " << format("%.3g", r.total_s * 1e3) << " |";
      md << " " << format("%.2f", fitted_exponent(rows, 4)) << " | "
         << format("%.0f %%", 100.0 * rows.back().setup_s / rows.back().total_s) << " |\n";
      for (const auto& r : rows) {
        if (r.path != wbm::solvers::SolutionPath::DirectNewton) {
          notes << "\n" << r.label << " at M = " << r.x << " went by the " << wbm::solvers::to_string(r.path) << " (" << r.iterations
                << " Newton iterations in all).\n";
        }
      }
    }
    md << notes.str();
    md << "\n### Time vs contact DOFs (" << chain_rows.front().label
       << ")\n\n| n_c | n_c·M | time, ms | Newton iterations | ms per iteration | route | status |\n|---|---|---|---|---|---|---|\n";
    std::vector<Row> per_iteration = chain_rows;
    for (auto& r : per_iteration) r.total_s /= std::max(r.iterations, 1);
    for (size_t i = 0; i < chain_rows.size(); ++i) {
      const auto& r = chain_rows[i];
      md << "| " << r.x << " | " << r.unknowns << " | " << format("%.3g", r.total_s * 1e3) << " | " << r.iterations << " | "
         << format("%.3g", per_iteration[i].total_s * 1e3) << " | " << wbm::solvers::to_string(r.path) << " | "
         << wbm::solvers::to_string(r.status) << " |\n";
    }
    md << "\nFitted exponent in n_c: " << format("%.2f", fitted_exponent(chain_rows, 4)) << " for the solve, "
       << format("%.2f", fitted_exponent(per_iteration, 4)) << " per Newton iteration.\n\n";
    run.report(md.str());
    std::cout << md.str();
  });
}
