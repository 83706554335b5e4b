// Jones & Legrand 2014, Fig. 6: tip displacement over one period, Case 1 of Table 1 (150 Hz),
// all six trial:weighting combinations of Table 2 with M = 64 against the BDF reference. ~2 s.
// Writes out/jl14_fig06/tip_displacement.csv, meta.json, report.md.
// --quick: M = 16 and 256 reference samples; run by ctest, never used for the figure.
#include "combinations.hpp"

int main(int argc, char** argv) {
  auto run = wbm::reproduce::Run::from_args(argc, argv, "jl14_fig06");
  return run.execute([](wbm::reproduce::Run& r) {
    wbm::reproduce::history_figure(
        r, "jl14_case1", "JL14 Fig. 6", "displacement",
        "HBM approximates the tip displacement well, with Gibbs oscillations on the contact plateau; Haar:Fourier "
        "represents the plateau well but the rest of the response less well (blocky) [JL14 Sec. 5.1].");
  });
}
