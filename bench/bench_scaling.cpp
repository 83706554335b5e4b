// Scaling table (issue #17): how the cost of a full weighted-residual solve (set-up, Newton,
// recovery) grows with the dimension M and with the number of contact DOFs n_c, with the fitted
// exponent p of t ≈ c·x^p (least squares on log t against log x over the last four points).
//  - Time vs M: every combination of [JL14 Table 2] on Case 1 (reproduce/scenes/jl14_case1.toml,
//    the FE rod, one contact), distributional form, M = 16 … 1024 (the default Q = max(256, 2M)).
//  - Time vs n_c: Fourier:Fourier, M = 16, on an explicit fixed-free chain of 64 unit masses
//    (k = 1e4 N/m, C = 1e-4 K, forcing 1 N at 0.8 of the first natural frequency on the free
//    end), linear penalty stops (k_pen = 1e3 N/m) on the last n_c = 1, 4, 16, 64 masses, each at
//    0.95 of its linear amplitude, so every stop is hit.
// Each time is the median of 5 runs on one core (set-up included). Writes out/bench/scaling.csv
// and out/bench/report.md (included in out/REPORT.md by reproduce/report.py). A solve that does
// not converge is reported with its status; its time is still printed, marked.
// Usage: bench_scaling [--out DIR] [--quick]  (--quick: M ≤ 64 and n_c ≤ 16, 3 runs; for CI).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include <wbm/contact/penalty.hpp>
#include <wbm/solvers/weighted_residual.hpp>

#include "scene.hpp"

namespace {

using wbm::solvers::TimeBasis;

struct Row {
  std::string series, label;  // "M" or "contacts"; "Fourier:Fourier"
  int x = 0;                  // M or n_c
  int unknowns = 0;           // n_c·M
  double setup_s = 0.0, total_s = 0.0;
  bool converged = false;
  std::string status, path;  // SolveStatus, SolutionPath
  int iterations = 0;        // Newton iterations in all (homotopy correctors included)
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
    row.converged = sol.converged();
    row.status = std::string(wbm::solvers::to_string(sol.report.status));
    row.path = std::string(wbm::solvers::to_string(sol.path));
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
  double sx = 0, sy = 0, sxx = 0, sxy = 0, n = 0;
  for (size_t i = first; i < rows.size(); ++i) {
    const double x = std::log(rows[i].x), y = std::log(rows[i].total_s);
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
    n += 1;
  }
  const double d = n * sxx - sx * sx;
  return d > 0 ? (n * sxy - sx * sy) / d : std::nan("");
}

// Fixed-free chain: mass i tied to i − 1 (mass 0 to the ground) by k.
wbm::solvers::MechanicalSystem chain(int n, double k) {
  std::vector<Eigen::Triplet<double>> mt, kt;
  for (int i = 0; i < n; ++i) {
    mt.emplace_back(i, i, 1.0);
    kt.emplace_back(i, i, (i + 1 < n ? 2.0 : 1.0) * k);
    if (i + 1 < n) {
      kt.emplace_back(i, i + 1, -k);
      kt.emplace_back(i + 1, i, -k);
    }
  }
  wbm::solvers::MechanicalSystem s;
  s.mass.resize(n, n);
  s.stiffness.resize(n, n);
  s.mass.setFromTriplets(mt.begin(), mt.end());
  s.stiffness.setFromTriplets(kt.begin(), kt.end());
  s.damping = 1e-4 * s.stiffness;
  return s;
}

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

}  // namespace

int main(int argc, char** argv) {
  std::filesystem::path out = WBM_BENCH_OUT_DIR;
  bool quick = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--quick") {
      quick = true;
    } else if (a == "--out" && i + 1 < argc) {
      out = argv[++i];
    } else {
      std::cerr << "bench_scaling: unknown argument '" << a << "'; usage: bench_scaling [--out DIR] [--quick]\n";
      return 2;
    }
  }
  const int repeats = quick ? 3 : 5;
  std::vector<std::vector<Row>> series;

  // Time vs M, Case 1, every Table 2 pair.
  const auto scene = wbm::reproduce::load_scene("jl14_case1");
  const std::vector<std::pair<std::string, std::string>> pairs = {
      {"fourier", "fourier"}, {"bspline", "bspline"}, {"db6", "db6"},
      {"haar", "fourier"},    {"db6", "fourier"},     {"haar", "bspline"}};
  const std::vector<int> dims = quick ? std::vector<int>{16, 32, 64} : std::vector<int>{16, 32, 64, 128, 256, 512, 1024};
  for (const auto& [trial, weighting] : pairs) {
    std::vector<Row> rows;
    for (int m : dims) {
      Row r = time_solve(scene.system(), scene.harmonic_forcing(), scene.contact_points(), trial, weighting, m, repeats);
      r.series = "M";
      r.label = TimeBasis::from_name(trial, 2).name() + ":" + TimeBasis::from_name(weighting, 2).name();
      r.x = m;
      std::cerr << r.label << " M = " << m << ": " << r.total_s * 1e3 << " ms (" << r.status << ")\n";
      rows.push_back(r);
    }
    series.push_back(rows);
  }

  // Time vs n_c on the chain.
  {
    const int n = 64, m = 16;
    const double k = 1e4;
    const auto system = chain(n, k);
    const double f1 = std::sqrt(k) * 2.0 * std::sin(std::numbers::pi / (2.0 * (2 * n + 1))) / (2.0 * std::numbers::pi);  // fixed-free chain
    const wbm::solvers::HarmonicForcing forcing{n - 1, 1.0, 0.8 * f1};
    const Eigen::VectorXcd lin = wbm::solvers::frequency_response(system, forcing);
    std::vector<Row> rows;
    const std::vector<int> counts = quick ? std::vector<int>{1, 4, 16} : std::vector<int>{1, 4, 16, 64};
    for (int nc : counts) {
      std::vector<wbm::solvers::ContactPoint> contacts;
      for (int c = n - nc; c < n; ++c) {
        contacts.push_back({c, std::make_shared<wbm::contact::LinearPenalty>(
                                   wbm::contact::LinearPenaltyParameters{1e3, 0.95 * std::abs(lin(c))})});
      }
      Row r = time_solve(system, forcing, contacts, "fourier", "fourier", m, repeats);
      r.series = "contacts";
      r.label = "Fourier:Fourier, chain of 64, M = 16";
      r.x = nc;
      std::cerr << "chain n_c = " << nc << ": " << r.total_s * 1e3 << " ms (" << r.status << ")\n";
      rows.push_back(r);
    }
    series.push_back(rows);
  }

  std::filesystem::create_directories(out);
  {
    std::ofstream csv(out / "scaling.csv.tmp");
    csv << "series,combination,x,contact_unknowns,setup_s,total_s,newton_iterations,path,converged,status\n";
    for (const auto& rows : series) {
      for (const auto& r : rows) {
        csv << r.series << "," << r.label << "," << r.x << "," << r.unknowns << "," << fmt("%.6e", r.setup_s) << ","
            << fmt("%.6e", r.total_s) << "," << r.iterations << "," << r.path << "," << (r.converged ? 1 : 0) << ","
            << r.status << "\n";
      }
    }
  }
  std::filesystem::rename(out / "scaling.csv.tmp", out / "scaling.csv");

  std::ostringstream md;
  md << "## Cost scaling of the weighted-residual solve (bench/bench_scaling.cpp)\n\n"
     << "Files: `out/bench/scaling.csv`. Median of " << repeats
     << " full solves on one core (set-up, Newton, recovery). The exponent p fits t ≈ c·x^p on the last four "
        "points (least squares in log–log).\n\n"
     << "### Time vs M (Case 1, distributional, Q = max(256, 2M)), ms\n\n| combination |";
  for (int m : dims) md << " M = " << m << " |";
  md << " p (M) | set-up share at M = " << dims.back() << " |\n|---|";
  for (size_t i = 0; i < dims.size(); ++i) md << "---|";
  md << "---|---|\n";
  std::ostringstream notes;  // solves that did not go by direct Newton, listed under the table
  for (size_t s = 0; s + 1 < series.size(); ++s) {
    const auto& rows = series[s];
    md << "| " << rows.front().label << " |";
    for (const auto& r : rows) md << " " << fmt("%.3g", r.total_s * 1e3) << (r.converged ? "" : " (" + r.status + ")") << " |";
    md << " " << fmt("%.2f", fitted_exponent(rows, 4)) << " | " << fmt("%.0f %%", 100.0 * rows.back().setup_s / rows.back().total_s)
       << " |\n";
    for (const auto& r : rows) {
      if (r.path != "direct Newton") {
        notes << "\n" << r.label << " at M = " << r.x << " went by the " << r.path << " (" << r.iterations
              << " Newton iterations in all).\n";
      }
    }
  }
  md << notes.str();
  const auto& chain_rows = series.back();
  md << "\n### Time vs contact DOFs (" << chain_rows.front().label
     << ")\n\n| n_c | n_c·M | time, ms | Newton iterations | ms per iteration | route | status |\n|---|---|---|---|---|---|---|\n";
  std::vector<Row> per_iteration = chain_rows;
  for (auto& r : per_iteration) r.total_s /= std::max(r.iterations, 1);
  for (size_t i = 0; i < chain_rows.size(); ++i) {
    const auto& r = chain_rows[i];
    md << "| " << r.x << " | " << r.unknowns << " | " << fmt("%.3g", r.total_s * 1e3) << " | " << r.iterations << " | "
       << fmt("%.3g", per_iteration[i].total_s * 1e3) << " | " << r.path << " | " << r.status << " |\n";
  }
  md << "\nFitted exponent in n_c: " << fmt("%.2f", fitted_exponent(chain_rows, 4)) << " for the solve, "
     << fmt("%.2f", fitted_exponent(per_iteration, 4)) << " per Newton iteration.\n";
  {
    std::ofstream f(out / "report.md.tmp");
    f << md.str();
  }
  std::filesystem::rename(out / "report.md.tmp", out / "report.md");
  std::cout << md.str();
  return 0;
}
