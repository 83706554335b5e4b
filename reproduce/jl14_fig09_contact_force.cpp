// Jones & Legrand 2014, Fig. 9: contact force over F over one period, Case 1 of Table 1 (150 Hz),
// all six combinations of Table 2 with M = 64 against BDF, and the paper's statements on it
// [JL14 Sec. 5.3] checked. ~5 s. Writes out/jl14_fig09/contact_force.csv, meta.json, report.md.
// --quick: M = 16 and 256 reference samples; run by ctest, never used for the figure.
#include <algorithm>
#include <cmath>

#include "combinations.hpp"

namespace {
constexpr double kGibbs = 1.01;  // Gibbs effects: total variation at least 1 % above the reference's
}  // namespace

int main(int argc, char** argv) {
  using namespace wbm::reproduce;
  auto run = Run::from_args(argc, argv, "jl14_fig09");
  return run.execute([](Run& r) {
    const auto fig = history_figure(
        r, "jl14_case1", "JL14 Fig. 9", "force",
        "contact lasts as long as the displacement plateau; Gibbs effects in HBM and Galerkin B-spline; Haar trial "
        "functions approximate the force relatively well; DB6 trial functions most accurately [JL14 Sec. 5.3].");
    const Eigen::VectorXd f_ref = fig.reference.contact_force;
    std::vector<Claim> claims;
    claims.push_back({"the time duration of the contact forces coincides with the tip displacement plateaus", {},
                      "holds by construction: Eq. (5) gives f_c = 0 exactly where u <= g0"});
    std::vector<std::pair<double, std::string>> ranked;  // rms relative force difference, label
    for (const auto& res : fig.results) {
      if (res.converged()) ranked.emplace_back(wbm::solvers::rms_relative_error(res.contact_force, f_ref), res.combination.label());
    }
    std::sort(ranked.begin(), ranked.end());
    for (const char* key : {"fourier_fourier", "bspline_bspline"}) {
      if (const auto* res = find_converged(fig.results, key)) {
        const double t = total_variation(res->contact_force) / total_variation(f_ref);
        claims.push_back({std::string("Gibbs phenomenon in the ") + (key[0] == 'f' ? "HBM" : "Galerkin B-spline") + " case",
                          t >= kGibbs, "total variation / BDF's " + format("%.3f", t) + " (Gibbs: >= " + format("%g", kGibbs) + ")"});
      }
    }
    const auto* hb = find_converged(fig.results, "fourier_fourier");
    for (const char* key : {"haar_fourier", "haar_bspline"}) {
      const auto* res = find_converged(fig.results, key);
      const std::string claim = std::string("Haar trial functions approximate the contact force relatively well (") + key + ")";
      if (res == nullptr || hb == nullptr) {
        claims.push_back({claim, {}, std::string(key) + " or Fourier:Fourier did not converge"});
        continue;
      }
      const double e = wbm::solvers::rms_relative_error(res->contact_force, f_ref);
      const double e_hb = wbm::solvers::rms_relative_error(hb->contact_force, f_ref);
      claims.push_back({claim, e <= e_hb,
                        "rms relative difference " + format("%.2e", e) + " against HBM's " + format("%.2e", e_hb)});
    }
    claims.push_back({"the DB6 trial functions most accurately approximate the contact forces",
                      !ranked.empty() && ranked.front().second.rfind("DB6", 0) == 0,
                      ranked.empty() ? std::string("no combination converged")
                                     : "smallest rms relative difference: " + ranked.front().second + " " +
                                           format("%.2e", ranked.front().first)});
    r.report(claims_markdown(claims));
  });
}
