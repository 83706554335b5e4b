#pragma once
/// Shared body of the tip-displacement figures (JL14 Figs. 6 and 7): one scene, the BDF
/// reference and harmonic balance, written as CSV + meta + report fragment.

#include <string>

#include "run.hpp"

namespace wbm::reproduce {

struct TipFigure {
  std::string scene;      // e.g. "jl14_case1"
  std::string figure;     // e.g. "Fig. 6"
  std::string paper_note; // what the paper says of this figure, quoted in the report
};

/// Solves the scene by BDF (1024 samples/period; 256 with --quick) and by Fourier:Fourier
/// harmonic balance with M = 64 (16 with --quick, the paper's 64 otherwise), and additionally
/// M = 8..256 for the error table; writes tip_displacement.csv with one column per combination
/// so later bases add columns. Returns nothing; failures go to run.fail().
void tip_displacement_figure(Run& run, const TipFigure& figure);

}  // namespace wbm::reproduce
