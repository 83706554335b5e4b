// Jones & Legrand 2014, Fig. 11 (a, b): rms relative tip-displacement error against the BDF
// reference, rms(u − u_BDF)/rms(u_BDF) over the 1024 reference samples, M = 8 … 256,
// distributional form, Cases 1 and 2, all six combinations of Table 2. ~15 s.
// Writes out/jl14_fig11/sweep_case{1,2}.csv, meta.json, report.md.
// --quick: M = 8, 16 and 256 reference samples; run by ctest, never used for the figure.
#include "combinations.hpp"

int main(int argc, char** argv) {
  auto run = wbm::reproduce::Run::from_args(argc, argv, "jl14_fig11");
  return run.execute([](wbm::reproduce::Run& r) {
    wbm::reproduce::convergence_figure(
        r, "JL14 Fig. 11", "tip_error",
        "HBM and Galerkin B-spline have the lowest error with 8 functions; Galerkin B-spline then falls behind HBM "
        "(localized error at the end of the plateau) and stalls from 32 to 128 at 1275 Hz; Galerkin DB6 is poor at "
        "16 and then comparable to HBM; Haar trial functions have the highest error [JL14 Sec. 5.5].");
  });
}
