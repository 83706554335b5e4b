// Jones & Legrand 2014, Fig. 5: periodized Haar scaling functions, J = 0 … 5 [JL14 Sec. 3.5,
// Eq. (33)]. Instant. Writes out/jl14_fig05/basis.csv, meta.json, report.md. --quick is the same run.
#include "basis_figure.hpp"

int main(int argc, char** argv) {
  auto run = wbm::reproduce::Run::from_args(argc, argv, "jl14_fig05");
  return run.execute([](wbm::reproduce::Run& run) {
    wbm::reproduce::scaling_function_figure(
        run, {wbm::wavelets::Family::haar(), "Fig. 5", "Examples of the first six levels of periodized Haar scaling functions"});
  });
}
