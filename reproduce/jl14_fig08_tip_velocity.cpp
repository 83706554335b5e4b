// Jones & Legrand 2014, Fig. 8: tip velocity over one period, Case 1 of Table 1 (150 Hz), all six
// combinations of Table 2 with M = 64 against BDF (Haar: delta pairs at the jumps, post_processing.hpp),
// and the paper's statements on it [JL14 Sec. 5.2] checked. ~5 s.
// Writes out/jl14_fig08/tip_velocity.csv, meta.json, report.md.
// --quick: M = 16 and 256 reference samples; run by ctest, never used for the figure.
#include <algorithm>
#include <cmath>

#include "combinations.hpp"

namespace {
constexpr double kRinging = 1.01;  // ringing: total variation at least 1 % above the reference's
}  // namespace

int main(int argc, char** argv) {
  using namespace wbm::reproduce;
  auto run = Run::from_args(argc, argv, "jl14_fig08");
  return run.execute([](Run& r) {
    const auto fig = history_figure(
        r, "jl14_case1", "JL14 Fig. 8", "velocity",
        "the velocity jumps at contact; Fourier trial functions ring (Gibbs), more so Galerkin B-spline; DB6 trial "
        "functions do the best job; Haar delta pairs approximate the envelope [JL14 Sec. 5.2].");
    const Eigen::VectorXd v_ref = fig.reference.tip_velocity;
    const double tv_ref = total_variation(v_ref);
    std::vector<Claim> claims;
    const auto* hb = find_converged(fig.results, "fourier_fourier");
    const auto* bs = find_converged(fig.results, "bspline_bspline");
    if (hb != nullptr && bs != nullptr) {
      const double t_hb = total_variation(hb->tip_velocity) / tv_ref, t_bs = total_variation(bs->tip_velocity) / tv_ref;
      claims.push_back({"ringing due to Gibbs phenomenon when the Fourier trial functions are used", t_hb >= kRinging,
                        "total variation / BDF's: " + format("%.3f", t_hb) + " (ringing: >= " + format("%g", kRinging) + ")"});
      claims.push_back({"the ringing is more pronounced in the Galerkin B-spline case", t_bs > t_hb,
                        "total variation / BDF's: B-spline " + format("%.3f", t_bs) + ", HBM " + format("%.3f", t_hb)});
    }
    double best = INFINITY;
    std::string best_label;
    for (const auto& res : fig.results) {
      if (!res.converged()) continue;
      const double e = wbm::solvers::rms_relative_error(res.tip_velocity, v_ref);
      if (e < best) {
        best = e;
        best_label = res.combination.label();
      }
    }
    claims.push_back({"the DB6 trial functions appear to do the best job", best_label.rfind("DB6", 0) == 0,
                      "smallest rms relative velocity difference: " + best_label + " " + format("%.2e", best)});
    claims.push_back({"the velocity envelope of Haar trial functions is reasonably approximated by the delta functions",
                      {}, "qualitative (an envelope is not defined in the paper)"});
    r.report(claims_markdown(claims));
  });
}
