#include "basis_figure.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>

namespace wbm::reproduce {

void scaling_function_figure(Run& run, const ScalingFigure& figure) {
  constexpr int samples = 1024;  // τ_q = q/1024: dyadic, so every value below is exact (not interpolated)
  constexpr int levels = 6;      // J = 0 … 5 [JL14 Figs. 3–5]
  const Eigen::VectorXd tau = Eigen::VectorXd::LinSpaced(samples, 0.0, 1.0 - 1.0 / samples);
  std::vector<Eigen::VectorXd> columns = {tau};
  std::vector<std::string> header = {"tau [-]"};
  std::ostringstream md;
  md << "## " << figure.figure << ": periodized " << figure.family.name() << " scaling functions, J = 0 … 5\n\n"
     << "Files: `out/" << run.id() << "/basis.csv`, `basis.png`, `basis.pdf`. Paper: \"" << figure.caption
     << "\". Shown: φ_{J,0}, the function of shift k = 0 at each level, in the paper's normalization "
     << "∫₀¹ φ_{J,k} dτ = 1 (the orthonormal function times 2^{J/2}); at J = 0 every family periodizes to the "
     << "constant 1. Values are exact on the 1024-point dyadic grid.\n\n"
     << "| J | M = 2^J | ∫₀¹ φ_{J,0} (rectangle rule) | max φ_{J,0} | min φ_{J,0} | ‖φ_{J,0}‖ orthonormal (rectangle rule) |\n"
     << "|---|---|---|---|---|---|\n";
  nlohmann::json checks = nlohmann::json::array();
  for (int level = 0; level < levels; ++level) {
    const wavelets::PeriodizedBasis unit(figure.family, level, {.normalization = wavelets::Normalization::UnitIntegral});
    Eigen::VectorXd v(samples);
    for (int q = 0; q < samples; ++q) v(q) = unit.value(0, tau(q));
    const double integral = v.mean();
    const double l2 = std::sqrt((v / unit.scale()).squaredNorm() / samples);
    char row[256];
    std::snprintf(row, sizeof row, "| %d | %d | %.15f | %.6g | %.6g | %.6f |\n", level, unit.dimension(), integral,
                  v.maxCoeff(), v.minCoeff(), l2);
    md << row;
    checks.push_back({{"level", level}, {"integral", integral}, {"l2_norm_orthonormal", l2}});
    columns.push_back(v);
    header.push_back("phi_J" + std::to_string(level) + "_0 [-]");
  }
  md << "\nThe ∫ and norm columns check both normalizations by the rectangle rule on the grid (exact for Haar; "
        "for DB6 the norm carries the quadrature error of a Hölder-1.09 function).\n";
  run.table("basis.csv", header, columns);
  run.meta({{"figure", figure.figure}, {"family", figure.family.name()}, {"normalization", "unit integral"},
            {"shift_k", 0}, {"levels", levels}, {"samples", samples}, {"checks", checks}});
  run.report(md.str());
}

}  // namespace wbm::reproduce
