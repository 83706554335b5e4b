// Jones & Legrand 2014, Fig. 4: periodized Daubechies DB6 scaling functions, J = 0 … 5, including
// J = 0, 1, 2 where the support [0, 5] is longer than the period [JL14 Sec. 3.4]. Instant.
// Writes out/jl14_fig04/basis.csv, meta.json, report.md. --quick is the same run.
#include "basis_figure.hpp"

int main(int argc, char** argv) {
  auto run = wbm::reproduce::Run::from_args(argc, argv, "jl14_fig04");
  return run.execute([](wbm::reproduce::Run& run) {
    wbm::reproduce::scaling_function_figure(
        run, {wbm::wavelets::Family::daubechies(6), "Fig. 4",
              "Examples of the first six levels of periodized 6 coefficient Daubechies scaling functions (DB6)"});
  });
}
