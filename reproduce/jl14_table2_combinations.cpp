// Jones & Legrand 2014, Table 2: the six trial:weighting combinations, generated: for each, the
// formulation used, how the linear operators are integrated, which formulations are admissible,
// and at M = 64 (16 with --quick) on Cases 1 and 2 the rms tip error against BDF, the energy
// norm, the median wall time of a full solve (7 repeats) and the Newton iterations. ~10 s.
// Writes out/jl14_table2/table2.csv, meta.json, report.md.
#include <sstream>

#include "combinations.hpp"

int main(int argc, char** argv) {
  using namespace wbm;
  auto run = reproduce::Run::from_args(argc, argv, "jl14_table2");
  return run.execute([](reproduce::Run& run) {
    const int m = run.quick() ? 16 : 64;
    const auto& combos = reproduce::table2_combinations();
    std::ostringstream md;
    md << "## JL14 Table 2: trial:weighting combinations at M = " << m << "\n\n"
       << "Files: `out/jl14_table2/table2.csv`, `meta.json`. Scenes: `reproduce/scenes/jl14_case{1,2}.toml`. "
       << "Formulation used in every figure: distributional (Eq. 16). Error: rms(u − u_BDF)/rms(u_BDF) of the tip; "
       << "time: median wall time of 7 full solves (set-up, Newton, recovery), one core.\n\n"
       << "| trial | weighting | admissible forms | linear operators | case | status | tip error | energy norm | "
          "time [ms] | Newton its | cond₁(G) |\n|---|---|---|---|---|---|---|---|---|---|---|\n";
    const auto n = static_cast<Eigen::Index>(2 * combos.size());
    Eigen::VectorXd index(n), case_id(n), ok(n), err(n), energy(n), time(n), its(n), cond(n);
    nlohmann::json meta = nlohmann::json::object();
    meta["dimension"] = m;
    meta["combinations"] = nlohmann::json::array();
    Eigen::Index row = 0;
    for (int c = 1; c <= 2; ++c) {
      const auto ref = reproduce::solve_reference(run, "jl14_case" + std::to_string(c));
      meta["case" + std::to_string(c)] = reproduce::to_json(ref);
      for (size_t i = 0; i < combos.size(); ++i) {
        const auto& combo = combos[i];
        const auto trial = solvers::TimeBasis::from_name(combo.trial, m);
        const auto weighting = solvers::TimeBasis::from_name(combo.weighting, m);
        std::string forms;
        for (auto f : {solvers::Formulation::Strong, solvers::Formulation::Weak, solvers::Formulation::Distributional}) {
          if (solvers::inadmissibility(trial, weighting, f).empty()) {
            forms += std::string(forms.empty() ? "" : ", ") + std::string(solvers::to_string(f));
          }
        }
        const auto r = reproduce::solve_combination(ref, combo, m, 7);
        meta["combinations"].push_back(reproduce::to_json(r));
        meta["combinations"].back()["case"] = c;
        meta["combinations"].back()["admissible_formulations"] = forms;
        index(row) = static_cast<double>(i);
        case_id(row) = c;
        ok(row) = r.converged() ? 1.0 : 0.0;
        err(row) = r.converged() ? r.tip_error : 0.0;
        energy(row) = r.converged() ? r.energy_norm : 0.0;
        time(row) = r.median_time_s;
        its(row) = r.solution.report.iterations;
        cond(row) = std::isfinite(r.solution.condition_number) ? r.solution.condition_number : 0.0;
        ++row;
        md << "| " << trial.name() << " | " << weighting.name() << " | " << forms << " | " << r.solution.operator_rule
           << " | " << c << " | " << solvers::to_string(r.solution.report.status) << " | "
           << (r.converged() ? reproduce::format("%.3e", r.tip_error) : "—") << " | "
           << (r.converged() ? reproduce::format("%.4f", r.energy_norm) : "—") << " | "
           << reproduce::format("%.2f", 1e3 * r.median_time_s) << " | " << r.solution.report.iterations << " | "
           << reproduce::format("%.2e", r.solution.condition_number) << " |\n";
      }
    }
    md << "\nA combination that did not converge keeps its row with its status; `meta.json` has the message.\n\n";
    run.table("table2.csv",
              {"combination [-]", "case [-]", "converged [-]", "tip_error [-]", "energy_norm [-]", "solve_time [s]",
               "newton_iterations [-]", "condition_number [-]"},
              {index, case_id, ok, err, energy, time, its, cond});
    run.meta(meta);
    run.report(md.str());
  });
}
