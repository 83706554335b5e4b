// Jones & Legrand 2014, Fig. 12 (Sec. 5.6): frequency response of the rod with contact over the
// first resonance by pseudo-arclength continuation, Fourier:Fourier and Haar:Fourier with
// M = 64 (distributional form), with the linear (no-contact) response, BDF points at a few
// frequencies and the stability of every point (Floquet multipliers); and, as an extra
// figure, every combination of Table 2. Physics: Case 2 of Table 1 (reproduce/scenes/
// jl14_case2.toml, "the case near resonance"); range 1000–1700 Hz (the figure's axis).
// Continuation: scaled arclength steps ≤ 0.02 and ≤ 2 Hz, corrector tolerance 1e-9. ~25 s.
// Writes out/jl14_fig12/branches.csv, folds.csv, linear.csv, bdf.csv, meta.json, report.md.
// --quick: M = 32, steps ≤ 10 Hz, two combinations, one BDF point; run by ctest.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include <wbm/scene/json.hpp>
#include <wbm/solvers/response_curve.hpp>
#include <wbm/solvers/time_integration.hpp>

#include "combinations.hpp"

namespace {

using namespace wbm;

constexpr double kFrom = 1000.0, kTo = 1700.0;  // Hz, the range of Fig. 12

struct Traced {
  reproduce::Combination combination;
  solvers::ResponseCurve curve;
};

}  // namespace

int main(int argc, char** argv) {
  auto run = reproduce::Run::from_args(argc, argv, "jl14_fig12");
  return run.execute([](reproduce::Run& run) {
    const auto scene = reproduce::load_scene("jl14_case2");
    const auto system = scene.system();
    const auto contacts = scene.contact_points();
    const int m = run.quick() ? 32 : 64;
    const int tip = scene.forcing->dof;

    // Every combination of Table 2, Fig. 12's two first.
    std::vector<reproduce::Combination> combos = {{"fourier", "fourier"}, {"haar", "fourier"}};
    if (!run.quick()) {
      for (const auto& c : reproduce::table2_combinations()) {
        if (c.key() != "fourier_fourier" && c.key() != "haar_fourier") combos.push_back(c);
      }
    }
    std::vector<Traced> traced;
    const double max_parameter_step = run.quick() ? 10.0 : 2.0;  // Hz per step, for a dense curve
    const solvers::ResponseCurveOptions defaults;
    for (const auto& c : combos) {
      const solvers::WeightedResidual base(system, scene.harmonic_forcing(kFrom), contacts,
                                           solvers::TimeBasis::from_name(c.trial, m),
                                           solvers::TimeBasis::from_name(c.weighting, m),
                                           {.formulation = reproduce::kFigureFormulation});
      solvers::ResponseCurveOptions o;
      o.parameter_min = kFrom;
      o.parameter_max = kTo;
      o.max_parameter_step = max_parameter_step;
      o.max_state = 10.0;  // gaps: a branch beyond 14.5 cm of tip motion has left the physics (see the notes)
      o.observed_dof = tip;
      traced.push_back({c, solvers::trace_response(base, o)});
      const auto& curve = traced.back().curve;
      // A branch that leaves the state bound (10 gaps) is reported in the table, not a failure
      // of the run: the figure shows it up to there.
      if (curve.stop != solvers::StopReason::RangeReached && curve.stop != solvers::StopReason::StateBound) {
        run.fail(c.label() + ": continuation stopped: " + std::string(solvers::to_string(curve.stop)) + ", " +
                 curve.message);
      }
    }

    // branches.csv: every point of every combination (long format, Table 2 index).
    std::vector<double> combo_index;
    for (const auto& t : traced) {
      const auto& all = reproduce::table2_combinations();
      const auto pos = std::find_if(all.begin(), all.end(), [&](const auto& c) { return c.key() == t.combination.key(); });
      combo_index.push_back(static_cast<double>(pos - all.begin()));
    }
    std::vector<double> id, freq, umax, umin, amp, stable, mu, its;
    for (size_t k = 0; k < traced.size(); ++k) {
      for (const auto& p : traced[k].curve.points) {
        id.push_back(combo_index[k]);
        freq.push_back(p.frequency_hz);
        umax.push_back(p.max_displacement);
        umin.push_back(p.min_displacement);
        amp.push_back(p.amplitude);
        stable.push_back(p.stable ? 1.0 : 0.0);
        mu.push_back(p.max_multiplier);
        its.push_back(p.corrector_iterations);
      }
    }
    auto column = [](const std::vector<double>& v) { return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size())); };
    run.table("branches.csv",
              {"combination [-]", "frequency [Hz]", "u_tip_max [m]", "u_tip_min [m]", "amplitude [m]", "stable [-]",
               "max_floquet_multiplier [-]", "corrector_iterations [-]"},
              {column(id), column(freq), column(umax), column(umin), column(amp), column(stable), column(mu), column(its)});

    // folds.csv and the statistics.
    std::vector<double> fold_id, fold_hz, fold_confirmed;
    std::vector<double> peaks, peak_hzs;  // per combination
    nlohmann::json stats = nlohmann::json::array();
    std::ostringstream rows;
    for (size_t k = 0; k < traced.size(); ++k) {
      const auto& curve = traced[k].curve;
      std::vector<double> confirmed_hz;
      for (size_t j = 0; j < curve.folds.size(); ++j) {
        const auto& f = curve.folds[j];
        const bool confirmed = curve.fold_confirmed[j];  // a Floquet multiplier crosses +1 there
        fold_id.push_back(combo_index[k]);
        fold_hz.push_back(f.parameter);
        fold_confirmed.push_back(confirmed ? 1.0 : 0.0);
        if (confirmed) confirmed_hz.push_back(f.parameter);
      }
      double peak = 0.0, peak_hz = 0.0;
      int unstable = 0;
      for (const auto& p : curve.points) {
        if (p.amplitude > peak) {
          peak = p.amplitude;
          peak_hz = p.frequency_hz;
        }
        unstable += p.stable ? 0 : 1;
      }
      peaks.push_back(peak);
      peak_hzs.push_back(peak_hz);
      const double pps = curve.points.size() / std::max(1e-9, curve.wall_time_s);
      stats.push_back({{"combination", traced[k].combination.label()},
                       {"points", curve.points.size()},
                       {"folds_hz", [&] { std::vector<double> v; for (const auto& f : curve.folds) v.push_back(f.parameter); return v; }()},
                       {"folds_with_floquet_crossing_hz", confirmed_hz},
                       {"unstable_points", unstable},
                       {"peak_amplitude_m", peak},
                       {"peak_frequency_hz", peak_hz},
                       {"continuation_time_s", curve.wall_time_s},
                       {"stability_time_s", curve.stability_time_s},
                       {"stability_work_s", curve.stability_work_s},
                       {"points_per_second", pps},
                       {"corrector_iterations", curve.corrector_iterations},
                       {"rejected_steps", curve.rejected_steps},
                       {"corners", curve.kinks},
                       {"stop", std::string(solvers::to_string(curve.stop))},
                       {"message", curve.message}});
      std::string folds_text;
      for (const auto& f : curve.folds) folds_text += (folds_text.empty() ? "" : ", ") + reproduce::format("%.2f", f.parameter);
      std::string confirmed_text;
      for (double f : confirmed_hz) confirmed_text += (confirmed_text.empty() ? "" : ", ") + reproduce::format("%.2f", f);
      rows << "| " << traced[k].combination.label() << " | " << curve.points.size() << " | " << folds_text << " | "
           << confirmed_text << " | " << reproduce::format("%.2f", peak * 1e3) << " mm at "
           << reproduce::format("%.1f", peak_hz) << " Hz | " << unstable << " | "
           << reproduce::format("%.3f", curve.wall_time_s) << " | " << reproduce::format("%.0f", pps) << " | "
           << reproduce::format("%.3f", curve.stability_time_s) << " | "
           << reproduce::format("%.3f", curve.stability_work_s) << " | " << curve.rejected_steps << " / " << curve.kinks
           << " |\n";
    }
    run.table("folds.csv", {"combination [-]", "frequency [Hz]", "floquet_crossing [-]"},
              {column(fold_id), column(fold_hz), column(fold_confirmed)});

    // The linear (no-contact) response, direct solve, every 1 Hz.
    const int nl = static_cast<int>(kTo - kFrom) + 1;
    Eigen::VectorXd lf(nl), la(nl);
    double linear_peak = 0.0, linear_peak_hz = 0.0;
    for (int i = 0; i < nl; ++i) {
      lf(i) = kFrom + i;
      la(i) = std::abs(solvers::frequency_response(system, scene.harmonic_forcing(lf(i)))(tip));
      if (la(i) > linear_peak) {
        linear_peak = la(i);
        linear_peak_hz = lf(i);
      }
    }
    run.table("linear.csv", {"frequency [Hz]", "amplitude [m]"}, {lf, la});

    // BDF from rest at a few frequencies: it lands on one stable branch.
    const std::vector<double> bdf_hz = run.quick() ? std::vector<double>{1200.0}
                                                   : std::vector<double>{1100.0, 1200.0, 1300.0, 1325.0, 1400.0, 1550.0};
    Eigen::VectorXd bf(static_cast<Eigen::Index>(bdf_hz.size())), bmax = bf, bmin = bf, bamp = bf;
    nlohmann::json bdf_reports = nlohmann::json::array();
    for (size_t i = 0; i < bdf_hz.size(); ++i) {
      const auto r = solvers::integrate_to_periodic(system, scene.harmonic_forcing(bdf_hz[i]), contacts,
                                                    {.samples_per_period = 512, .relative_tolerance = 1e-8,
                                                     .periodicity_tolerance = 1e-6});
      if (!r.report.converged()) run.fail("BDF at " + reproduce::format("%g", bdf_hz[i]) + " Hz: " + r.report.message);
      const Eigen::VectorXd u = r.displacement.row(tip).transpose();
      const auto k = static_cast<Eigen::Index>(i);
      bf(k) = bdf_hz[i];
      bmax(k) = u.maxCoeff();
      bmin(k) = u.minCoeff();
      bamp(k) = 0.5 * (bmax(k) - bmin(k));
      nlohmann::json report = r.report;  // the integrator's report (wbm/scene/json.hpp)
      report["frequency_hz"] = bdf_hz[i];
      bdf_reports.push_back(report);
    }
    run.table("bdf.csv", {"frequency [Hz]", "u_tip_max [m]", "u_tip_min [m]", "amplitude [m]"}, {bf, bmax, bmin, bamp});

    // BDF against the Fourier:Fourier branch: the stable point of the branch at that frequency
    // closest in amplitude (BDF from rest picks one attractor).
    std::ostringstream bdf_rows;
    const auto& ff = traced.front().curve.points;
    for (Eigen::Index i = 0; i < bf.size(); ++i) {
      double best = 1e300, best_amp = NAN;  // NaN: no stable branch point at that frequency
      for (size_t j = 0; j + 1 < ff.size(); ++j) {
        const double f0 = ff[j].frequency_hz, f1 = ff[j + 1].frequency_hz;
        if ((f0 - bf(i)) * (f1 - bf(i)) > 0.0 || !ff[j].stable) continue;
        const double t = (bf(i) - f0) / (f1 - f0);
        const double a = ff[j].amplitude + t * (ff[j + 1].amplitude - ff[j].amplitude);
        if (std::abs(a - bamp(i)) < best) {
          best = std::abs(a - bamp(i));
          best_amp = a;
        }
      }
      bdf_rows << "| " << reproduce::format("%.0f", bf(i)) << " | " << reproduce::format("%.4f", bamp(i) * 1e3) << " | "
               << (std::isfinite(best_amp) ? reproduce::format("%.4f", best_amp * 1e3) : std::string("— (no stable point)"))
               << " | "
               << (std::isfinite(best_amp) ? reproduce::format("%.1e", std::abs(best_amp - bamp(i)) / bamp(i)) : std::string("—"))
               << " |\n";
    }

    run.meta({{"figure", "JL14 Fig. 12"},
              {"scene", scene.path},
              {"dimension", m},
              {"range_hz", {kFrom, kTo}},
              {"formulation", std::string(solvers::to_string(reproduce::kFigureFormulation))},
              {"linear_peak_hz", linear_peak_hz},
              {"linear_peak_amplitude_m", linear_peak},
              {"gap_m", scene.contacts.front().gap},
              {"combinations", stats},
              {"bdf", bdf_reports}});

    // Statements of the text, computed from the Fourier:Fourier branch (the paper's first curve).
    const auto& ff_curve = traced.front().curve;
    const double gap = scene.contacts.front().gap;
    double onset_hz = NAN;  // first point of the branch where the tip reaches the gap
    for (const auto& p : ff_curve.points) {
      if (p.max_displacement >= gap) {
        onset_hz = p.frequency_hz;
        break;
      }
    }
    std::string ff_folds;
    int ff_confirmed = 0;
    for (size_t j = 0; j < ff_curve.folds.size(); ++j) {
      ff_folds += (j ? ", " : "") + reproduce::format("%.1f", ff_curve.folds[j].parameter);
      ff_confirmed += ff_curve.fold_confirmed[j] ? 1 : 0;
    }
    const bool peak_moves_up = peak_hzs.front() > linear_peak_hz;
    const bool folds_confirmed = !ff_curve.folds.empty() && ff_confirmed == static_cast<int>(ff_curve.folds.size());
    const auto& cs = scene.contacts.front();
    std::ostringstream md;
    md << "## JL14 Fig. 12: frequency response over the first resonance, " << scene.title << "\n\n"
       << "Files: `out/jl14_fig12/frequency_response.{png,pdf}` (Fourier:Fourier and Haar:Fourier, as in the paper), "
       << "`frequency_response_all.{png,pdf}` (every combination), `branches.csv`, `folds.csv`, `linear.csv`, "
       << "`bdf.csv`, `meta.json`. Scene `reproduce/scenes/" << std::filesystem::path(scene.path).filename().string()
       << "` (β = " << reproduce::format("%g", scene.damping.beta)
       << " s, α = " << reproduce::format("%g", cs.exponent) << " 1/m, g0 = " << reproduce::format("%g", 1e3 * gap)
       << " mm; the paper's caption says \"second fundamental frequency\", its text \"fundamental\": the first "
       << "resonance of the rod, whose linear peak is at " << reproduce::format("%.0f", linear_peak_hz)
       << " Hz, is the one the range covers), M = " << m << ", distributional form, pseudo-arclength continuation in "
       << "f from " << kFrom << " to " << kTo << " Hz (scaled steps ≤ " << reproduce::format("%g", defaults.max_step)
       << " and ≤ " << reproduce::format("%g", max_parameter_step) << " Hz), stability of every point from its "
       << "monodromy matrix.\n\n"
       << "Paper: the penalty stiffens the response, so the resonant peak moves up in frequency from the no-contact "
       << "one; both combinations capture it [JL14 Sec. 5.6].\n\n"
       << "Ours: linear (no-contact) peak " << reproduce::format("%.3f", linear_peak * 1e3) << " mm at "
       << reproduce::format("%.0f", linear_peak_hz) << " Hz. With the stop (Fourier:Fourier) the tip first reaches "
       << "the gap at " << (std::isfinite(onset_hz) ? reproduce::format("%.1f", onset_hz) + " Hz" : std::string("no point"))
       << "; the peak is cut to " << reproduce::format("%.2f", peaks.front() * 1e3) << " mm at "
       << reproduce::format("%.1f", peak_hzs.front()) << " Hz ("
       << reproduce::format("%+.1f", peak_hzs.front() - linear_peak_hz) << " Hz from the linear peak). The branch has "
       << ff_curve.folds.size() << " folds (" << (ff_folds.empty() ? std::string("none") : ff_folds + " Hz") << "), "
       << ff_confirmed << " of them with a Floquet multiplier crossing +1. Folds without a crossing are "
       << "listed separately: a fold of the approximate branch without one is not a fold of the dynamics.\n\n"
       << reproduce::claims_markdown(
              {{"the penalty stiffens the response: the resonant peak moves up in frequency from the no-contact one "
                "(Fourier:Fourier)",
                peak_moves_up,
                reproduce::format("%+.1f", peak_hzs.front() - linear_peak_hz) + " Hz from the linear peak at " +
                    reproduce::format("%.0f", linear_peak_hz) + " Hz"},
               {"every fold of the branch is a fold of the dynamics (a Floquet multiplier crosses +1 there)",
                folds_confirmed,
                std::to_string(ff_confirmed) + " of " + std::to_string(ff_curve.folds.size()) + " folds"}})
       << "| combination | points | folds [Hz] | folds with a Floquet crossing [Hz] | peak amplitude | unstable points | "
          "continuation [s] | points/s | stability [s] | stability, thread time [s] | rejected steps / corners |\n"
       << "|---|---|---|---|---|---|---|---|---|---|---|\n"
       << rows.str()
       << "\nEach point's Floquet multipliers are computed on a second thread while the continuation goes on: the "
          "stability column is the wait after the continuation, the next one the thread time of all points.\n"
       << "\nTime stepping from rest (GSL BDF, rtol 1e-8) against the stable Fourier:Fourier point at the same "
          "frequency:\n\n| f [Hz] | BDF amplitude [mm] | branch amplitude [mm] | relative difference |\n|---|---|---|---|\n"
       << bdf_rows.str() << "\n";
    // Notes, from the branches: turning points closer than 0.1 Hz (a zigzag of a piecewise-constant
    // branch when one cell enters contact, not a hysteresis), and branches stopped before the range end.
    std::ostringstream notes;
    for (const auto& t : traced) {
      const auto& c = t.curve;
      for (size_t j = 0; j + 1 < c.folds.size(); ++j) {
        const double d = std::abs(c.folds[j + 1].parameter - c.folds[j].parameter);
        if (d < 0.1) {
          notes << "- " << t.combination.label() << ": two turning points " << reproduce::format("%.2g", d)
                << " Hz apart near " << reproduce::format("%.1f", c.folds[j].parameter) << " Hz (a zigzag of the "
                << "approximate branch, not a hysteresis of the dynamics).\n";
        }
      }
      if (!c.converged()) {
        notes << "- " << t.combination.label() << ": stopped, " << solvers::to_string(c.stop) << " (" << c.message
              << "); a branch of the truncated penalty system that leaves the physics, reported, not plotted as a "
                 "response (see docs/design.md).\n";
      }
    }
    if (!notes.str().empty()) md << "Notes.\n\n" << notes.str() << "\n";
    run.report(md.str());
  });
}
