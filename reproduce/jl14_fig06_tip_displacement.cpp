// Jones & Legrand 2014, Fig. 6: tip displacement over one period, Case 1 of Table 1 (150 Hz).
// Fourier:Fourier with M = 64 against the BDF reference; M = 8..256 error table. About 2 s.
// Writes out/jl14_fig06/{tip_displacement,convergence}.csv, meta.json, report.md.
// --quick: M = 16 and 256 reference samples; run by ctest, never used for the figure.
#include "tip_response.hpp"

int main(int argc, char** argv) {
  auto run = wbm::reproduce::Run::from_args(argc, argv, "jl14_fig06");
  return run.execute([](wbm::reproduce::Run& r) {
    wbm::reproduce::tip_displacement_figure(
        r, {"jl14_case1", "JL14 Fig. 6",
              "HBM with 64 functions approximates the tip displacement well, with Gibbs oscillations "
              "on the contact plateau and rounding of the sharp gradient changes [JL14 Sec. 5.1]."});
  });
}
