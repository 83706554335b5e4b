// Jones & Legrand 2014, Fig. 3: periodized orthogonal cubic B-spline scaling functions, J = 0 … 5
// (c_k of Eq. (30) by GSL quadrature, |k| ≤ 50 [JL14 Sec. 3.3]). Instant.
// Writes out/jl14_fig03/basis.csv, meta.json, report.md. --quick is the same run.
#include "basis_figure.hpp"

int main(int argc, char** argv) {
  auto run = wbm::reproduce::Run::from_args(argc, argv, "jl14_fig03");
  return run.execute([](wbm::reproduce::Run& run) {
    wbm::reproduce::scaling_function_figure(
        run, {wbm::wavelets::Family::orthogonal_cubic_bspline(), "Fig. 3",
              "Examples of the first six levels of periodized orthogonal cubic B-spline scaling functions"});
  });
}
