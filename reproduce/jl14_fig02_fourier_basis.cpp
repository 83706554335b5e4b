// Jones & Legrand 2014, Fig. 2: the first six functions of the Fourier basis
// {1, cos 2πτ, sin 2πτ, cos 4πτ, sin 4πτ, cos 6πτ} [JL14 Sec. 3.1], in the ordering of
// wbm::spectral::FourierBasis. Instant. Writes out/jl14_fig02/basis.csv, meta.json, report.md.
#include <wbm/spectral/fourier_basis.hpp>

#include "run.hpp"

int main(int argc, char** argv) {
  auto run = wbm::reproduce::Run::from_args(argc, argv, "jl14_fig02");
  return run.execute([](wbm::reproduce::Run& run) {
    constexpr int samples = 1024;
    const wbm::spectral::FourierBasis basis(8);  // functions 0 … 5 are the first six
    const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(samples, 0.0, 1.0 - 1.0 / samples);
    const Eigen::MatrixXd v = basis.values(tau);
    const char* names[] = {"q0 = 1 [-]", "q1 = cos 2πτ [-]", "q2 = sin 2πτ [-]",
                           "q3 = cos 4πτ [-]", "q4 = sin 4πτ [-]", "q5 = cos 6πτ [-]"};
    std::vector<Eigen::VectorXd> columns = {tau};
    std::vector<std::string> header = {"tau [-]"};
    for (int k = 0; k < 6; ++k) {
      columns.emplace_back(v.col(k));
      header.emplace_back(names[k]);
    }
    run.table("basis.csv", header, columns);
    run.meta({{"figure", "Fig. 2"}, {"basis", "Fourier"}, {"functions", 6}, {"samples", samples}});
    run.report("## Fig. 2: first six functions of the Fourier basis\n\nFiles: `out/jl14_fig02/basis.csv`, "
               "`basis.png`, `basis.pdf`. The functions 1, cos 2πτ, sin 2πτ, cos 4πτ, sin 4πτ, cos 6πτ of "
               "[JL14 Sec. 3.1], as ordered by `wbm::spectral::FourierBasis`. Nothing to compare numerically.\n");
  });
}
