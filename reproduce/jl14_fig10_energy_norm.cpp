// Jones & Legrand 2014, Fig. 10 (a, b): energy norm rms(E)/rms(E_BDF) of Eq. (35) against the
// number of basis functions M = 8 … 256, distributional form, Cases 1 and 2, all six
// combinations of Table 2. ~15 s. Writes out/jl14_fig10/sweep_case{1,2}.csv, meta.json, report.md.
// --quick: M = 8, 16 and 256 reference samples; run by ctest, never used for the figure.
#include "combinations.hpp"

int main(int argc, char** argv) {
  auto run = wbm::reproduce::Run::from_args(argc, argv, "jl14_fig10");
  return run.execute([](wbm::reproduce::Run& r) {
    wbm::reproduce::convergence_figure(
        r, "JL14 Fig. 10", "energy_norm",
        "all combinations reach energy norms ≈ 1 with 128 functions; at 150 Hz HBM and Galerkin B-spline are close "
        "to 1 with few functions; Haar trial functions over-predict the energy at small M; DB6:Fourier is closer "
        "to 1 than DB6:DB6. At 1275 Hz convergence is slower [JL14 Sec. 5.4].");
  });
}
