// Jones & Legrand 2014, Fig. 9: contact force f_c(u_tip) of Eq. (5) divided by F over one period,
// Case 1 (150 Hz), all six combinations of Table 2 with M = 64 against BDF. ~2 s.
// Writes out/jl14_fig09/contact_force.csv, meta.json, report.md.
// --quick: M = 16 and 256 reference samples; run by ctest, never used for the figure.
#include "combinations.hpp"

int main(int argc, char** argv) {
  auto run = wbm::reproduce::Run::from_args(argc, argv, "jl14_fig09");
  return run.execute([](wbm::reproduce::Run& r) {
    wbm::reproduce::history_figure(
        r, "jl14_case1", "JL14 Fig. 9", "force",
        "contact lasts as long as the displacement plateau; Gibbs effects in HBM and Galerkin B-spline; Haar trial "
        "functions approximate the force relatively well; DB6 trial functions most accurately [JL14 Sec. 5.3].");
  });
}
