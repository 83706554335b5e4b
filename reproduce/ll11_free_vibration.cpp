// Issue #7 check: a free (unforced, undamped) time simulation started from a computed nonlinear
// mode stays on its periodic orbit. The rod of reproduce/scenes/ll11_rod.toml (N = 12, m = 256) at
// normalized energies 1.2, 1.8 and 2.4; the rigid stop is a stiff linear spring k = 1e11 N/m
// (penetration ~1e-4 g0) in GSL's msbdf, from u(0), du/dt(0) of the mode, over 5 periods of the
// orbit's frequency ω = √(r − μω₀²E) and, for comparison, of the paper's Rayleigh quotient √r.
// ~5 s. Writes out/ll11_free_vibration/deviation.csv, mode_E<E>.csv, meta.json, report.md.
// --quick: N = 8, m = 64, E = 1.2 only, 3 periods.
#include <algorithm>
#include <cmath>
#include <sstream>

#include <wbm/solvers/time_integration.hpp>

#include "combinations.hpp"
#include "modes.hpp"

int main(int argc, char** argv) {
  using namespace wbm;
  auto run = reproduce::Run::from_args(argc, argv, "ll11_free_vibration");
  return run.execute([](reproduce::Run& run) {
    using reproduce::format;
    scene::Scene s = reproduce::ll11_scene(run);
    s.analysis.levels = run.quick() ? std::vector<double>{1.2} : std::vector<double>{1.2, 1.8, 2.4};
    s.analysis.energy_max = s.analysis.levels.back();
    s.output.all_dofs = true;
    const int periods = run.quick() ? 3 : 5;
    constexpr double kPenalty = 1e11;  // N/m
    const auto r = reproduce::run_modes(run, s);
    const auto problem = scene::mode_problem(s);
    const int n = problem.system.dofs(), p = s.output.samples;
    const double gap = s.contacts.front().gap;
    std::vector<solvers::ContactPoint> springs;
    for (const auto& stop : problem.stops) {
      springs.push_back({stop.dof, std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{kPenalty, stop.gap})});
    }
    std::vector<double> col_e, col_period, col_orbit, col_rayleigh;
    std::ostringstream rows;
    std::vector<reproduce::Claim> claims;
    nlohmann::json meta = nlohmann::json::array();
    // The tolerances issue #7 stated for this check: a few 1e-3 at the first level (E = 1.2 in the
    // scene), about 1e-2 over all periods at the larger energies.
    const double first_level_tolerance = 5e-3, larger_energy_tolerance = 2e-2;
    bool first_level = true;
    for (const auto& level : r.diagnostics["nnm"]["included"]) {
      if (!level.value("converged", false)) continue;
      const double energy = level["energy"];
      const std::string file = "mode_E" + format("%g", energy) + ".csv";
      Eigen::MatrixXd u(n, p), v(n, p);
      for (int j = 0; j < n; ++j) {
        u.row(j) = reproduce::result_column(r, file, "u_" + s.structure->dof_name(j) + " [m]").transpose();
        v.row(j) = reproduce::result_column(r, file, "v_" + s.structure->dof_name(j) + " [m/s]").transpose();
      }
      const double scale = u.cwiseAbs().maxCoeff();
      std::vector<std::vector<double>> deviation;  // [orbit, rayleigh][period]
      double penetration = 0.0;
      long steps = 0;
      for (const double f : {level["frequency_hz"].get<double>(), level["rayleigh_frequency_hz"].get<double>()}) {
        const auto t = solvers::integrate_free(problem.system, springs, u.col(0), v.col(0), 1.0 / f, periods,
                                               {.samples_per_period = p, .relative_tolerance = 1e-9,
                                                .absolute_tolerance = 1e-12 * gap});
        if (!t.report.converged()) run.fail(file + ": " + t.report.message);
        std::vector<double> d;
        for (int k = 0; k < periods && (k + 1) * p < t.time_s.size(); ++k) {
          d.push_back((t.displacement.middleCols(k * p, p) - u).cwiseAbs().maxCoeff() / scale);
        }
        penetration = std::max(penetration, (t.displacement.row(problem.stops.front().dof).array() - gap).maxCoeff() / gap);
        steps += t.report.steps;
        deviation.push_back(d);
      }
      rows << "| " << format("%g", energy) << " | " << format("%.3f", level["frequency_hz"].get<double>()) << " | "
           << format("%.3f", level["rayleigh_frequency_hz"].get<double>()) << " | ";
      for (size_t k = 0; k < deviation[0].size(); ++k) {
        col_e.push_back(energy);
        col_period.push_back(static_cast<double>(k + 1));
        col_orbit.push_back(deviation[0][k]);
        col_rayleigh.push_back(deviation[1][k]);
        rows << format("%.1e", deviation[0][k]) << (k + 1 < deviation[0].size() ? ", " : " | ");
      }
      for (size_t k = 0; k < deviation[1].size(); ++k) {
        rows << format("%.1e", deviation[1][k]) << (k + 1 < deviation[1].size() ? ", " : " | ");
      }
      rows << format("%.1e", penetration) << " |\n";
      const double worst = *std::max_element(deviation[0].begin(), deviation[0].end());
      const double tolerance = first_level ? first_level_tolerance : larger_energy_tolerance;
      const bool within = worst <= tolerance;
      const bool rayleigh_drifts = deviation[1].back() > deviation[0].back();
      claims.push_back({"at E = " + format("%g", energy) + " the motion from the mode stays on it with the orbit "
                        "frequency, within the stated tolerance " + format("%.0e", tolerance),
                        within,
                        "largest deviation " + format("%.1e", worst) + " over " + std::to_string(deviation[0].size()) +
                            " periods"});
      claims.push_back({"at E = " + format("%g", energy) + " the Rayleigh period drifts past the orbit's", rayleigh_drifts,
                        "last period deviates " + format("%.1e", deviation[1].back()) + " with the Rayleigh frequency, " +
                            format("%.1e", deviation[0].back()) + " with the orbit's"});
      first_level = false;
      meta.push_back({{"energy", energy}, {"orbit_deviation", deviation[0]}, {"rayleigh_deviation", deviation[1]},
                      {"penetration_gaps", penetration}, {"bdf_steps", steps}, {"tolerance", tolerance},
                      {"checks", {{"within_tolerance", within}, {"rayleigh_drifts", rayleigh_drifts}}}});
    }
    auto column = [](const std::vector<double>& x) {
      return Eigen::Map<const Eigen::VectorXd>(x.data(), static_cast<Eigen::Index>(x.size()));
    };
    run.table("deviation.csv", {"energy [-]", "period [-]", "deviation_orbit_frequency [-]", "deviation_rayleigh_frequency [-]"},
              {column(col_e), column(col_period), column(col_orbit), column(col_rayleigh)});
    run.meta({{"check", "free vibration from the computed modes"}, {"scene", s.path}, {"harmonics", s.analysis.harmonics},
              {"samples", s.analysis.samples}, {"penalty_N_per_m", kPenalty}, {"periods", periods}, {"levels", meta}});
    std::ostringstream md;
    md << "## Free vibration from the computed nonlinear modes (issue #7 check)\n\n"
       << "Files: `out/ll11_free_vibration/free_vibration.{png,pdf}`, `deviation.csv`, `mode_E<E>.csv`, `meta.json`. "
          "Modes of `reproduce/scenes/ll11_rod.toml` (N = " << s.analysis.harmonics << ", m = " << s.analysis.samples
       << "); from u(0), du/dt(0) of each mode, GSL msbdf integrates the free, undamped rod with the stop as a spring "
          "of " << format("%.0e", kPenalty) << " N/m over " << periods << " periods T, sampled at the mode's " << p
       << " instants per period. Deviation of period k: max over nodes and instants of |u(t + (k−1)T) − u_mode(t)| "
          "divided by max |u_mode|.\n\n"
       << "| E | orbit f [Hz] | Rayleigh f [Hz] | deviation per period, T = 1/f_orbit | deviation per period, T = "
          "1/f_Rayleigh | largest penetration [g0] |\n|---|---|---|---|---|---|\n"
       << rows.str()
       << "\nWith the orbit's frequency the motion stays on the computed mode within the first-period deviation "
          "(the truncation to N harmonics, which cannot represent the impacts exactly, and the spring's "
          "penetration), growing slowly; with the paper's Rayleigh-quotient frequency the phase drifts and the "
          "deviation grows by about the same amount every period. Checks against the tolerances stated for this "
          "check (a few 1e-3 at the first level, about 1e-2 at the larger energies).\n\n"
       << reproduce::claims_markdown(claims);
    run.report(md.str());
  });
}
