// Jones & Legrand 2014, Fig. 8: tip velocity over one period, Case 1 (150 Hz), all six
// combinations of Table 2 with M = 64 (Eq. 34; Haar trial functions by the delta-pair form of
// Sec. 5.2, see solvers/post_processing.hpp) against the BDF velocity. ~2 s.
// Writes out/jl14_fig08/tip_velocity.csv, meta.json, report.md.
// --quick: M = 16 and 256 reference samples; run by ctest, never used for the figure.
#include "combinations.hpp"

int main(int argc, char** argv) {
  auto run = wbm::reproduce::Run::from_args(argc, argv, "jl14_fig08");
  return run.execute([](wbm::reproduce::Run& r) {
    wbm::reproduce::history_figure(
        r, "jl14_case1", "JL14 Fig. 8", "velocity",
        "the velocity jumps at contact; Fourier trial functions ring (Gibbs), more so Galerkin B-spline; DB6 trial "
        "functions do the best job; Haar delta pairs approximate the envelope [JL14 Sec. 5.2].");
  });
}
