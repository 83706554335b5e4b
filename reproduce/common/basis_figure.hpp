#pragma once
// Figures of basis functions over one period [JL14 Figs. 2–5]: CSV of the first function of
// each level J = 0 … 5 (or the first six Fourier functions) on a dyadic grid, plus a report entry.
#include <wbm/wavelets/periodized_basis.hpp>

#include "run.hpp"

namespace wbm::reproduce {

struct ScalingFigure {
  wavelets::Family family;
  const char* figure;      // "Fig. 3"
  const char* caption;     // the paper's caption
};

/// Writes basis.csv: τ on Q = 1024 points (dyadic, so Daubechies values are exact) and
/// φ_{J,0}(τ) for J = 0 … 5 in the paper's ∫₀¹ φ_{J,k} = 1 normalization [JL14 Sec. 3.3], with
/// checks (∫ by the rectangle rule, L² norm of the orthonormal version) in the report.
void scaling_function_figure(Run& run, const ScalingFigure& figure);

}  // namespace wbm::reproduce
