// Jones & Legrand 2014, Fig. 7: tip displacement over one period, Case 2 of Table 1 (1275 Hz,
// near the first resonance), all six combinations of Table 2 with M = 64 against BDF, and the
// paper's statements on it [JL14 Sec. 5.1] checked against Case 1. ~10 s.
// Writes out/jl14_fig07/tip_displacement.csv, meta.json, report.md.
// --quick: M = 16 and 256 reference samples; run by ctest, never used for the figure.
#include <algorithm>
#include <cmath>

#include "combinations.hpp"

namespace {
constexpr double kWell = 0.05;  // "approximates well": rms relative difference to BDF at most 5 %

// Spread of u over the samples above the gap, relative to the peak-to-peak amplitude (0: flat).
double plateau_spread(const Eigen::VectorXd& u, double gap) {
  double lo = INFINITY, hi = -INFINITY;
  for (const double v : u) {
    if (v > gap) {
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  }
  return hi > lo ? (hi - lo) / (u.maxCoeff() - u.minCoeff()) : 0.0;
}
}  // namespace

int main(int argc, char** argv) {
  using namespace wbm::reproduce;
  auto run = Run::from_args(argc, argv, "jl14_fig07");
  return run.execute([](Run& r) {
    const auto fig = history_figure(
        r, "jl14_case2", "JL14 Fig. 7", "displacement",
        "at 1275 Hz the contact plateau is smaller and not as flat; the Haar basis is less suited; the tip "
        "penetrates the stop because the exponential penalty is not a hard contact [JL14 Sec. 5.1].");
    const Reference case1 = solve_reference(r, "jl14_case1");
    const Eigen::VectorXd u2 = fig.reference.tip_displacement, u1 = case1.tip_displacement;
    const double g2 = fig.reference.scene.contacts.front().gap, g1 = case1.scene.contacts.front().gap;
    std::vector<Claim> claims;
    if (const auto* hb = find_converged(fig.results, "fourier_fourier")) {
      claims.push_back({"HBM approximates the tip displacements well at " +
                            format("%g", fig.reference.scene.forcing->frequency_hz) + " Hz",
                        hb->tip_error <= kWell,
                        "rms relative difference " + format("%.2e", hb->tip_error) + " (well: <= " + format("%g", kWell) + ")"});
    }
    const double c1 = fraction_above(u1, g1), c2 = fraction_above(u2, g2);
    claims.push_back({"the contact plateau is smaller [than at " + format("%g", case1.scene.forcing->frequency_hz) + " Hz]",
                      c2 < c1,
                      "BDF time in contact " + format("%.3f", c2) + " of the period against " + format("%.3f", c1)});
    const double s1 = plateau_spread(u1, g1), s2 = plateau_spread(u2, g2);
    claims.push_back({"and not as flat", s2 > s1,
                      "spread of u in contact / peak-to-peak: " + format("%.3f", s2) + " against " + format("%.3f", s1)});
    std::vector<std::pair<double, std::string>> ranked;
    for (const auto& res : fig.results) {
      if (res.converged()) ranked.emplace_back(res.tip_error, res.combination.label());
    }
    std::sort(ranked.begin(), ranked.end());
    const auto is_haar = [](const std::string& label) { return label.rfind("Haar", 0) == 0; };
    const bool haar_last = ranked.size() >= 2 && is_haar(ranked[ranked.size() - 1].second) &&
                           is_haar(ranked[ranked.size() - 2].second);
    claims.push_back({"the Haar basis appears to be less suited for the response at " +
                          format("%g", fig.reference.scene.forcing->frequency_hz) + " Hz",
                      haar_last,
                      "the two largest rms differences: " +
                          (ranked.size() >= 2 ? ranked[ranked.size() - 2].second + " " + format("%.2e", ranked[ranked.size() - 2].first) +
                                                    ", " + ranked.back().second + " " + format("%.2e", ranked.back().first)
                                              : std::string("fewer than two converged"))});
    claims.push_back({"the tip penetrates the contact boundary (exponential penalty)", u2.maxCoeff() > g2,
                      "BDF max tip displacement − g0 = " + format("%.3e", u2.maxCoeff() - g2) + " m"});
    r.report(claims_markdown(claims));
  });
}
