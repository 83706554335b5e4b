// Jones & Legrand 2014, Table 2: the six trial:weighting combinations, generated: for each, the
// formulation used, how the linear operators are integrated, which formulations are admissible,
// and at M = 64 (16 with --quick) on Cases 1 and 2 the rms tip error against BDF, the energy
// norm, the median wall time of a full solve (7 repeats) and the Newton iterations. ~10 s.
// Writes out/jl14_table2/table2_case{1,2}.csv (write_sweep format), meta.json, report.md.
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
       << "Files: `out/jl14_table2/table2_case{1,2}.csv`, `meta.json`. Scenes: `reproduce/scenes/jl14_case{1,2}.toml`. "
       << "Formulation used in every figure: distributional (Eq. 16). Error: rms(u − u_BDF)/rms(u_BDF) of the tip; "
       << "time: median wall time of 7 full solves (set-up, Newton, recovery), one core.\n\n"
       << "| trial | weighting | admissible forms | linear operators | case | status | tip error | energy norm | "
          "time [ms] | Newton its | cond₁(G) |\n|---|---|---|---|---|---|---|---|---|---|---|\n";
    nlohmann::json meta = nlohmann::json::object();
    meta["dimension"] = m;
    meta["combinations"] = nlohmann::json::array();
    for (int c = 1; c <= 2; ++c) {
      const auto ref = reproduce::solve_reference(run, "jl14_case" + std::to_string(c));
      meta["case" + std::to_string(c)] = reproduce::to_json(ref);
      std::vector<reproduce::CombinationResult> results;
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
        md << "| " << trial.name() << " | " << weighting.name() << " | " << forms << " | " << r.solution.operator_rule
           << " | " << c << " | " << solvers::to_string(r.solution.report.status) << " | "
           << (r.converged() ? reproduce::format("%.3e", r.tip_error) : "—") << " | "
           << (r.converged() ? reproduce::format("%.4f", r.energy_norm) : "—") << " | "
           << reproduce::format("%.2f", 1e3 * r.median_time_s) << " | " << r.solution.report.iterations << " | "
           << reproduce::format("%.2e", r.solution.condition_number) << " |\n";
        results.push_back(r);
      }
      reproduce::write_sweep(run, "table2_case" + std::to_string(c) + ".csv", results);
    }
    md << "\nA combination that did not converge keeps its row with its status; `meta.json` has the message.\n\n";
    run.meta(meta);
    run.report(md.str());
  });
}
