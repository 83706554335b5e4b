// Jones & Legrand 2014, Fig. 6: tip displacement over one period, Case 1 of Table 1 (150 Hz),
// all six combinations of Table 2 with M = 64 against BDF, and the paper's statements on it
// [JL14 Sec. 5.1] checked. ~5 s. Writes out/jl14_fig06/tip_displacement.csv, meta.json, report.md.
// --quick: M = 16 and 256 reference samples; run by ctest, never used for the figure.
#include <algorithm>
#include <cmath>

#include "combinations.hpp"

namespace {
constexpr double kWell = 0.05;  // "approximates well": rms relative difference to BDF at most 5 %

// Sign changes of the slope v_{q+1} − v_q over consecutive samples that are both in `mask`.
int slope_sign_changes(const Eigen::VectorXd& v, const std::vector<bool>& mask) {
  int changes = 0;
  double last = 0.0;
  for (Eigen::Index q = 0; q + 1 < v.size(); ++q) {
    if (!mask[static_cast<size_t>(q)] || !mask[static_cast<size_t>(q + 1)]) continue;
    const double d = v(q + 1) - v(q);
    if (d != 0.0 && last != 0.0 && (d > 0.0) != (last > 0.0)) ++changes;
    if (d != 0.0) last = d;
  }
  return changes;
}
}  // namespace

int main(int argc, char** argv) {
  using namespace wbm::reproduce;
  auto run = Run::from_args(argc, argv, "jl14_fig06");
  return run.execute([](Run& r) {
    const auto fig = history_figure(
        r, "jl14_case1", "JL14 Fig. 6", "displacement",
        "HBM approximates the tip displacement well, with Gibbs oscillations on the contact plateau; Haar:Fourier "
        "represents the plateau well but the rest of the response less well (blocky) [JL14 Sec. 5.1].");
    const Eigen::VectorXd u_ref = fig.reference.tip_displacement;
    const double g0 = fig.reference.scene.contacts.front().gap;
    std::vector<bool> contact(static_cast<size_t>(u_ref.size())), free(contact.size());
    for (Eigen::Index q = 0; q < u_ref.size(); ++q) {
      contact[static_cast<size_t>(q)] = u_ref(q) > g0;
      free[static_cast<size_t>(q)] = !contact[static_cast<size_t>(q)];
    }
    std::vector<Claim> claims;
    const auto* hb = find_converged(fig.results, "fourier_fourier");
    const auto* hf = find_converged(fig.results, "haar_fourier");
    if (hb == nullptr) {
      claims.push_back({"HBM approximates the tip displacements well", {}, "Fourier:Fourier did not converge"});
    } else {
      claims.push_back({"HBM approximates the tip displacements well", hb->tip_error <= kWell,
                        "rms relative difference " + format("%.2e", hb->tip_error) + " (well: <= " + format("%g", kWell) + ")"});
      const int ours = slope_sign_changes(hb->tip_displacement, contact), bdf = slope_sign_changes(u_ref, contact);
      claims.push_back({"oscillations due to Gibbs phenomenon on the contact plateau", ours > bdf,
                        "slope sign changes on the BDF plateau (u > g0): HBM " + std::to_string(ours) + ", BDF " +
                            std::to_string(bdf)});
    }
    const std::string hf_claim = "Haar:Fourier represents the plateau well, the response outside contact less well";
    if (hf == nullptr) {
      claims.push_back({hf_claim, {}, "Haar:Fourier did not converge at M = " + std::to_string(fig.dimension)});
    } else {
      const double on = rms_relative_error_on(hf->tip_displacement, u_ref, contact);
      const double off = rms_relative_error_on(hf->tip_displacement, u_ref, free);
      claims.push_back({hf_claim, on < off,
                        "rms relative difference in contact " + format("%.2e", on) + ", outside " + format("%.2e", off)});
    }
    r.report(claims_markdown(claims));
  });
}
