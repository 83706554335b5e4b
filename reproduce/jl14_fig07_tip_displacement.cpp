// Jones & Legrand 2014, Fig. 7: tip displacement over one period, Case 2 of Table 1 (1275 Hz,
// near the first resonance), all six combinations of Table 2 with M = 64 against BDF. ~8 s.
// Writes out/jl14_fig07/tip_displacement.csv, meta.json, report.md.
// --quick: M = 16 and 256 reference samples; run by ctest, never used for the figure.
#include "combinations.hpp"

int main(int argc, char** argv) {
  auto run = wbm::reproduce::Run::from_args(argc, argv, "jl14_fig07");
  return run.execute([](wbm::reproduce::Run& r) {
    wbm::reproduce::history_figure(
        r, "jl14_case2", "JL14 Fig. 7", "displacement",
        "at 1275 Hz the contact plateau is smaller and not as flat; the Haar basis is less suited; the tip "
        "penetrates the stop because the exponential penalty is not a hard contact [JL14 Sec. 5.1].");
  });
}
