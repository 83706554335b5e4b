// Beyond LL11 Sec. 5.2 (issue #15): the forced response of the reduced compressor blade of
// ll11_blade near its first bending resonance, the casing as 24 radial penalty stops at a
// uniform gap (f = k (n·u − g0)₊), traced by pseudo-arclength continuation in the forcing
// frequency [JL14 Sec. 5.6] with Fourier:Fourier (harmonic balance, harmonics 0 … H) and
// B-spline:B-spline (periodized orthogonal cubic B-spline, distributional form, M = 2^J), with
// two backbone branches of the same stops (KKT continuation) overlaid: the one from the linear
// first mode, and the one through harmonic balance's resonance peak (its orbit corrected without
// damping and load, continued both ways in energy). Each level says where its energy sits
// (first mode at the fundamental, or an h:1 internal resonance with mode j, f_j ≈ h f).
// The load is F(t) = s M_r φ₁ cos 2πft (φ₁ the first linear mode, mass-normalized): in the linear
// regime it excites the first mode only. s puts the linear resonance peak of the first stop to
// touch at `overload` gaps. Damping C = β K_r with β = 2ζ/ω₁ (ζ₁ = ζ). Amplitude measure, for the
// curves and the backbone alike: (max − min)/2 over the period of the circumferential (y)
// displacement of the first tip node to touch, in gaps. The same 24 stops rigid (Signorini at the
// 2H + 1 impulse instants, Fourier:Fourier at the file's rigid_harmonics), continued piece by
// piece (solvers::SignoriniResponseFamily, issue #38): the corner continuation stalled on this
// blade at 0.9806 f1 after 9 points (issue #15). Stability of the penalty curves (the file's
// response.stability): every point's Floquet multipliers, by the exact flights of the linear
// penalty stops (FloquetAnalysis's modal path, issue #39: the stops' stiffness sets no step), and
// each change of stability located and classified (solvers::stability_crossings). The rigid
// curve's (response.rigid_stability) would shoot each point's exact orbit against the 24 stops
// (impact_stability): 77 s for the 27 points of the --quick blade (stop 89), so it is off.
// Writes out/ll11_blade_forced/: branches.csv, backbone.csv, linear.csv, bifurcations.csv (when
// a curve changes stability), meta.json, report.md.
// About 3 min on one core, about 60 % of it the two backbones (KKT continuation; stop 62: 229 s
// before KktSolver took the penalty backbone). --quick: mesh size 5 mm, H = 4, M = 16, coarse steps; run by ctest.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <memory>
#include <numbers>
#include <sstream>

#include <Eigen/Eigenvalues>
#include <tbb/task_arena.h>

#include <wbm/contact/penalty.hpp>
#include <wbm/contact/signorini.hpp>
#include <wbm/fem/craig_bampton.hpp>
#include <wbm/solvers/nonlinear_modes.hpp>
#include <wbm/solvers/response_curve.hpp>

#include "blade.hpp"
#include "blade_forced.hpp"
#include "combinations.hpp"
#include "parameters.hpp"
#include "run.hpp"

namespace {

using namespace wbm;

struct Traced {
  std::string label;  // "Fourier:Fourier", "B-spline:B-spline", "Fourier:Fourier, rigid stops (H = 6)"
  std::string key;    // "fourier_fourier", "bspline_bspline", "fourier_fourier_rigid" (timing keys)
  bool rigid = false; // the stops rigid (Signorini)
  bool compared = true;  // its peak compared with the backbones (the penalty curves at the file's H and M)
  bool stability = false;  // Floquet multipliers of every point
  solvers::ResponseCurve curve;
  double time_s = 0.0;
  double condition = 0.0;  // 1-norm condition estimate of G at the start
};

// Backbone levels in branch order: energy, frequency [Hz], amplitude of the observed DOF [gap],
// and where the energy sits (reproduce::modal_components).
struct BackboneCurve {
  Eigen::VectorXd energy, frequency_hz, amplitude, first_share, other_mode, other_harmonic, other_share;
  double time_s = 0.0;
  std::string stop;  // why the continuation ended
};

BackboneCurve backbone_curve(const solvers::NonlinearModes& nnm, const std::vector<solvers::ModeLevel>& levels,
                             int observed, double unit) {
  BackboneCurve b;
  const auto nl = static_cast<Eigen::Index>(levels.size());
  for (auto* v : {&b.energy, &b.frequency_hz, &b.amplitude, &b.first_share, &b.other_mode, &b.other_harmonic, &b.other_share}) {
    v->resize(nl);
  }
  for (Eigen::Index k = 0; k < nl; ++k) {
    const auto& l = levels[static_cast<size_t>(k)];
    const Eigen::RowVectorXd u = nnm.displacement(l, 64).row(observed);
    const auto c = nnm.modal_components(l);
    b.energy(k) = l.energy;
    b.frequency_hz(k) = l.frequency_hz;
    b.amplitude(k) = 0.5 * (u.maxCoeff() - u.minCoeff()) * unit;  // [gap]
    b.first_share(k) = c.first_mode_share;
    b.other_mode(k) = c.mode;
    b.other_harmonic(k) = c.harmonic;
    b.other_share(k) = c.share;
  }
  return b;
}

// Frequency of a backbone at amplitude a [gap] by linear interpolation between levels that
// bracket it: of all bracketing pairs (a branch may pass an amplitude several times), the one
// closest to `near` [Hz]; NaN if no level pair brackets a.
double backbone_frequency_at(const BackboneCurve& b, double a, double near) {
  double best = std::nan("");
  for (Eigen::Index k = 0; k + 1 < b.amplitude.size(); ++k) {
    const double a0 = b.amplitude(k), a1 = b.amplitude(k + 1);
    if ((a0 - a) * (a1 - a) <= 0.0 && a0 != a1) {
      const double f = b.frequency_hz(k) + (a - a0) / (a1 - a0) * (b.frequency_hz(k + 1) - b.frequency_hz(k));
      if (std::isnan(best) || std::abs(f - near) < std::abs(best - near)) best = f;
    }
  }
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  auto run = reproduce::Run::from_args(argc, argv, "ll11_blade_forced");
  return run.execute([](reproduce::Run& run) {
    using reproduce::format;
    const bool quick = run.quick();
    // Every model and run parameter from reproduce/scenes/ll11_blade_forced.toml ([quick] with --quick).
    const auto parameters = reproduce::Parameters::load("ll11_blade_forced", quick);
    const double mesh_size = parameters.number("mesh.size_m");   // m, as ll11_blade
    const double gap = parameters.number("contact.gap_m");       // m, uniform radial gap
    const double zeta = parameters.number("damping.zeta");       // ζ₁, C = β K_r
    const double overload = parameters.number("forcing.overload_gaps");  // linear resonance peak of the first stop to touch [gaps]
    const double stiffness_ratio = parameters.number("contact.stiffness_ratio");  // k = ratio × the static radial stiffness there
    const int n_tip = parameters.integer("interface.tip_nodes"), modes = parameters.integer("interface.modes");
    const int harmonics = parameters.integer("response.harmonics");
    const int rigid_harmonics = parameters.integer("response.rigid_harmonics");  // H of the rigid-stop curve
    const int wavelet_m = parameters.integer("response.wavelet_dimension");
    const int mode_harmonics = parameters.integer("nnm.harmonics"), mode_samples = parameters.integer("nnm.samples");
    const double from = parameters.number("response.from_f1"), to = parameters.number("response.to_f1");  // f/f1
    // ‖G a − b + n(a)‖ ≤ tol ‖b‖ (the file says why it is not the default).
    // The solves' verification: the backward error of the full residual (issue #38), the default
    // unless the parameters set `response.residual_tolerance`.
    const double residual_tolerance =
        parameters.number_or("response.residual_tolerance", solvers::WeightedResidualOptions{}.residual_tolerance);
    const bool penalty_stability = parameters.boolean("response.stability");
    const bool rigid_stability = parameters.boolean("response.rigid_stability");
    const models::ScratchFolder scratch("wbm_ll11_blade_forced");
    nlohmann::json timing;

    // The blade and its Craig–Bampton model, exactly as ll11_blade.
    const auto blade = models::build_blade(scratch.dir, mesh_size, n_tip);
    timing["gmsh_s"] = blade.gmsh_s;
    timing["ccx_and_read_s"] = blade.ccx_s;
    auto t = std::chrono::steady_clock::now();
    const auto cb = fem::craig_bampton(blade.model.stiffness, blade.model.mass, blade.boundary, modes);
    timing["craig_bampton_s"] = models::seconds_since(t);
    // The forced model (models/blade_forced.hpp): coordinates scaled to unit diagonal
    // mass, q = D q̂ (the condition estimate of G from 1.1e9 to 3.1e7 on the --quick mesh; 1.0e7
    // scaled on the full one, meta.json), the radial stops, C = β K̂, the load along the first
    // mode and the penalty stiffness. Every number written is physical.
    auto model = models::blade_forced_model(
        blade, cb,
        {.gap = gap, .zeta = zeta, .overload = overload, .stiffness_ratio = stiffness_ratio, .from_f1 = from,
         .mode_harmonics = mode_harmonics, .mode_samples = mode_samples});
    const auto& reduced = model.reduced;
    const auto n = static_cast<Eigen::Index>(reduced.mass.rows());
    const auto& stops = model.stops;
    auto& nnm = *model.modes;
    const double f1 = model.f1, beta = model.beta, s = model.load_scale, unit = model.unit;
    const int onset = model.onset, observed = model.observed;
    const auto& forcing = model.forcing;
    const double radial_stiffness = model.radial_stiffness, k_pen = model.penalty_stiffness;

    std::vector<solvers::ContactPoint> contacts, rigid_contacts;
    const auto law = std::make_shared<contact::LinearPenalty>(contact::LinearPenaltyParameters{k_pen, gap});
    const auto rigid_law = std::make_shared<contact::RigidStop>(gap);
    for (const auto& st : stops) {
      contacts.push_back({st.dof, law, -1, st.along});
      rigid_contacts.push_back({st.dof, rigid_law, -1, st.along});
    }

    // Forced responses.
    std::vector<Traced> traced;
    auto trace = [&](const std::string& label, const std::string& key, solvers::TimeBasis trial,
                     solvers::TimeBasis weighting, double max_step, bool keep_all, bool rigid = false,
                     bool compared = true) {
      t = std::chrono::steady_clock::now();
      const solvers::WeightedResidual base(reduced, forcing, rigid ? rigid_contacts : contacts, std::move(trial), std::move(weighting),
                                           {.formulation = reproduce::kFigureFormulation,
                                            .residual_tolerance = residual_tolerance});
      solvers::ResponseCurveOptions o;
      o.parameter_min = from * f1;
      o.parameter_max = to * f1;
      o.max_parameter_step = max_step * f1;
      o.observed_dof = observed;
      o.stability = rigid ? rigid_stability : penalty_stability;
      o.max_state = parameters.number("response.max_state");
      if (keep_all) {  // every DOF's trial coefficients: the peak's orbit starts a backbone below
        for (Eigen::Index j = 0; j < n; ++j) o.keep_dofs.push_back(static_cast<int>(j));
      }
      traced.push_back({label, key, rigid, compared, o.stability, solvers::trace_response(base, o), 0.0, 0.0});
      traced.back().time_s = models::seconds_since(t);
      traced.back().condition = base.condition_number();
      const auto& c = traced.back().curve;
      if (!c.converged()) {
        run.fail(label + ": continuation stopped: " + std::string(solvers::to_string(c.stop)) + ", " + c.message);
      }
      std::printf("%s: %zu points, %.1f s, %s\n", label.c_str(), c.points.size(), traced.back().time_s, c.message.c_str());
    };
    // Harmonic balance densely; the wavelet pair (about 4 times the cost per point) with larger steps.
    trace("Fourier:Fourier", "fourier_fourier", solvers::TimeBasis::fourier_harmonics(harmonics),
          solvers::TimeBasis::fourier_harmonics(harmonics), parameters.number("response.max_step_fourier_f1"), true);
    trace("B-spline:B-spline", "bspline_bspline", solvers::TimeBasis::from_name("bspline", wavelet_m),
          solvers::TimeBasis::from_name("bspline", wavelet_m), parameters.number("response.max_step_bspline_f1"), false);
    // The same stops rigid (Signorini at the 2H + 1 impulse instants), continued piece by piece:
    // every impulse that starts or ends is an event, located and crossed (issue #38); beside the
    // penalty stops at the same H, so that the two differ by the contact law only.
    const std::string rigid_h = " (H = " + std::to_string(rigid_harmonics) + ")";
    trace("Fourier:Fourier" + rigid_h, "fourier_fourier_rigid_harmonics", solvers::TimeBasis::fourier_harmonics(rigid_harmonics),
          solvers::TimeBasis::fourier_harmonics(rigid_harmonics), parameters.number("response.max_step_rigid_f1"), false,
          false, false);
    trace("Fourier:Fourier, rigid stops" + rigid_h, "fourier_fourier_rigid", solvers::TimeBasis::fourier_harmonics(rigid_harmonics),
          solvers::TimeBasis::fourier_harmonics(rigid_harmonics), parameters.number("response.max_step_rigid_f1"), false,
          true, false);

    // The backbone of the same stops (damping and load ignored) from the linear mode, and the
    // branch through harmonic balance's resonance peak: its orbit (every DOF's coefficients),
    // corrected by Newton without damping and load, continued down and up in energy.
    t = std::chrono::steady_clock::now();
    solvers::BackboneContinuationOptions co;
    co.energy_min = parameters.number("nnm.energy_min");
    co.energy_max = parameters.number_or("nnm.energy_max", overload * overload);  // default: the linear peak's energy
    co.max_energy_step = parameters.number("nnm.max_energy_step");
    co.penalty_stiffness = k_pen;
    const auto b = nnm.continue_backbone(co);
    if (!b.complete()) run.fail("backbone incomplete: " + b.message);
    BackboneCurve backbone = backbone_curve(nnm, b.levels, observed, unit);
    backbone.time_s = models::seconds_since(t);
    backbone.stop = b.message;
    const auto nl = static_cast<Eigen::Index>(b.levels.size());

    t = std::chrono::steady_clock::now();
    const auto& ff_points = traced[0].curve.points;
    const auto ff_peak = std::max_element(ff_points.begin(), ff_points.end(),
                                          [](const auto& p, const auto& q) { return p.amplitude < q.amplitude; });
    solvers::BackboneContinuationOptions cp = co;
    cp.start = solvers::PeriodicOrbit{ff_peak->kept_coefficients, ff_peak->frequency_hz};
    const double peak_energy = nnm.energy(ff_peak->kept_coefficients);
    // From half to twice the peak's energy (the file's peak_branch_from, peak_branch_to): enough to
    // see where the branch goes on both sides of the peak.
    cp.energy_min = parameters.number("nnm.peak_branch_from") * peak_energy;
    cp.energy_max = parameters.number("nnm.peak_branch_to") * peak_energy;
    std::vector<solvers::ModeLevel> through;
    std::string through_stop;
    bool through_complete = true;
    double down_lowest = std::nan("");  // the lowest energy the continuation started downward reached
    size_t down_folds = 0;
    for (int direction : {-1, +1}) {
      cp.direction = direction;
      const auto part = nnm.continue_backbone(cp);
      through_complete = through_complete && part.complete();
      through_stop += std::string(direction < 0 ? "down: " : "; up: ") + part.message;
      if (direction < 0) {
        through.assign(part.levels.rbegin(), part.levels.rend());
        down_folds = part.folds.size();
        for (const auto& l : part.levels) down_lowest = std::isnan(down_lowest) ? l.energy : std::min(down_lowest, l.energy);
      } else if (!part.levels.empty()) {
        through.insert(through.end(), part.levels.begin() + 1, part.levels.end());  // the start is already in
      }
    }
    if (!through_complete) run.fail("backbone through the forced peak incomplete: " + through_stop);
    BackboneCurve peak_branch = backbone_curve(nnm, through, observed, unit);
    peak_branch.time_s = models::seconds_since(t);
    peak_branch.stop = through_stop;
    const auto np = static_cast<Eigen::Index>(through.size());

    // Files.
    std::vector<double> id, freq, ratio, amp, umax, umin, fmax, its, stable, mu;
    std::vector<std::string> verdict;  // per row: why the stability cells are empty, if they are
    for (size_t k = 0; k < traced.size(); ++k) {
      for (const auto& p : traced[k].curve.points) {
        const bool has = traced[k].stability && p.stability_available;
        stable.push_back(has ? (p.stable ? 1.0 : 0.0) : std::nan(""));
        mu.push_back(has ? p.max_multiplier : std::nan(""));
        verdict.emplace_back(!traced[k].stability ? "stability not computed" : has ? "verdict" : "no verdict");
        id.push_back(static_cast<double>(k));
        freq.push_back(p.frequency_hz);
        ratio.push_back(p.frequency_hz / f1);
        amp.push_back(p.amplitude * unit);
        umax.push_back(p.max_displacement * unit);
        umin.push_back(p.min_displacement * unit);
        fmax.push_back(p.max_contact_force);
        its.push_back(p.corrector_iterations);
      }
    }
    auto column = [](const std::vector<double>& v) {
      return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
    };
    run.table("branches.csv",
              {"curve [-]", "frequency [Hz]", "frequency_over_f1 [-]", "amplitude [gap]", "u_max [gap]", "u_min [gap]",
               "max_contact_force [N]", "corrector_iterations [-]", "stable [-]", "max_floquet_multiplier [-]"},
              {column(id), column(freq), column(ratio), column(amp), column(umax), column(umin), column(fmax), column(its),
               column(stable), column(mu)},
              verdict);
    // bifurcations.csv: each change of stability of each curve, located where the largest |μ|
    // passes 1 between two points and classified by the crossing multiplier (fold: +1, period
    // doubling: −1, Neimark–Sacker: a complex pair).
    std::vector<std::vector<solvers::StabilityCrossing>> crossings;
    {
      std::vector<double> cid, cf, cr, ca, cm, carg, clost;
      std::vector<std::string> ckind;
      for (size_t k = 0; k < traced.size(); ++k) {
        crossings.push_back(solvers::stability_crossings(traced[k].curve));
        for (const auto& c : crossings.back()) {
          cid.push_back(static_cast<double>(k));
          cf.push_back(c.frequency_hz);
          cr.push_back(c.frequency_hz / f1);
          ca.push_back(c.amplitude * unit);
          cm.push_back(std::abs(c.multiplier));
          carg.push_back(std::arg(c.multiplier));
          clost.push_back(c.stability_lost ? 1.0 : 0.0);
          ckind.emplace_back(solvers::to_string(c.kind));
        }
      }
      if (!cid.empty()) {
        run.table("bifurcations.csv",
                  {"curve [-]", "frequency [Hz]", "frequency_over_f1 [-]", "amplitude [gap]",
                   "floquet_multiplier_modulus [-]", "floquet_multiplier_argument [rad]", "stability_lost [-]"},
                  {column(cid), column(cf), column(cr), column(ca), column(cm), column(carg), column(clost)}, ckind);
      }
    }
    {
      const BackboneCurve* parts[] = {&backbone, &peak_branch};
      std::vector<Eigen::VectorXd> cols(9, Eigen::VectorXd(nl + np));
      for (int part = 0; part < 2; ++part) {
        const auto& c = *parts[part];
        const Eigen::Index at = part == 0 ? 0 : nl, len = c.energy.size();
        cols[0].segment(at, len).setConstant(part);
        cols[1].segment(at, len) = c.energy;
        cols[2].segment(at, len) = c.frequency_hz;
        cols[3].segment(at, len) = c.frequency_hz / f1;
        cols[4].segment(at, len) = c.amplitude;
        cols[5].segment(at, len) = c.first_share;
        cols[6].segment(at, len) = c.other_mode;
        cols[7].segment(at, len) = c.other_harmonic;
        cols[8].segment(at, len) = c.other_share;
      }
      run.table("backbone.csv", {"branch [-]", "energy [-]", "frequency [Hz]", "frequency_over_f1 [-]", "amplitude [gap]",
                                 "first_mode_share [-]", "other_mode [-]", "other_harmonic [-]", "other_share [-]"},
                cols);
    }
    const int nlin = parameters.integer("response.linear_points");
    Eigen::VectorXd lf(nlin), lr(nlin), la(nlin);
    for (int i = 0; i < nlin; ++i) {
      lr(i) = from + (to - from) * i / (nlin - 1);
      lf(i) = lr(i) * f1;
      solvers::HarmonicForcing fi = forcing;
      fi.frequency_hz = lf(i);
      la(i) = std::abs(solvers::frequency_response(reduced, fi)(observed)) * unit;
    }
    run.table("linear.csv", {"frequency [Hz]", "frequency_over_f1 [-]", "amplitude [gap]"}, {lf, lr, la});

    // Claims, computed: (a) each curve's resonance peak lies on a backbone branch (the branch's
    // frequency at the peak's amplitude, within 2ζ f1: a lightly damped peak sits on an undamped
    // mode up to O(ζ)); (b) the wavelet pair's peak is harmonic balance's; (c) where the energy
    // of each branch sits (first mode at the fundamental, or an internal resonance).
    std::ostringstream rows;
    nlohmann::json stats = nlohmann::json::array();
    std::vector<double> peak_ratio, peak_amp;
    bool on_linear_branch = true, on_peak_branch = true;
    double worst_off0 = 0.0, worst_offp = 0.0;  // largest |peak − branch| [f1]; NaN: a branch lacks a peak's amplitude
    auto cell = [&](double v) { return std::isfinite(v) ? format("%.5f", v) : std::string("—"); };
    auto json_or_null = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); };
    for (const auto& tr : traced) {
      double pa = 0.0, pf = std::nan("");
      for (const auto& p : tr.curve.points) {
        if (p.amplitude * unit > pa) {
          pa = p.amplitude * unit;
          pf = p.frequency_hz;
        }
      }
      peak_ratio.push_back(pf / f1);
      peak_amp.push_back(pa);
      rows << "| " << tr.label << " | " << tr.curve.points.size() << " | " << tr.curve.folds.size() << " | "
           << tr.curve.events << " | " << format("%.5f", pf / f1) << " | " << format("%.3f", pa) << " | ";
      if (!tr.compared) {  // another H or contact law than the backbones': not compared with them
        rows << "not compared | not compared | not compared | " << format("%.1f", tr.time_s) << " |\n";
        stats.push_back({{"curve", tr.label}, {"points", tr.curve.points.size()}, {"folds", tr.curve.folds.size()},
                         {"events", tr.curve.events}, {"switches", tr.curve.switches},
                         {"peak_frequency_over_f1", pf / f1}, {"peak_amplitude_gap", pa}, {"time_s", tr.time_s},
                         {"condition_number_of_g", tr.condition}, {"corrector_iterations", tr.curve.corrector_iterations},
                         {"rejected_steps", tr.curve.rejected_steps},
                         {"stop", std::string(solvers::to_string(tr.curve.stop))}, {"message", tr.curve.message}});
        continue;
      }
      // NaN: the branch never has this amplitude.
      const double f0 = backbone_frequency_at(backbone, pa, pf), fp = backbone_frequency_at(peak_branch, pa, pf);
      const double off0 = (pf - f0) / f1, offp = (pf - fp) / f1;
      on_linear_branch = on_linear_branch && std::isfinite(off0) && std::abs(off0) <= 2.0 * zeta;
      on_peak_branch = on_peak_branch && std::isfinite(offp) && std::abs(offp) <= 2.0 * zeta;
      worst_off0 = std::isfinite(off0) ? std::max(worst_off0, std::abs(off0)) : std::nan("");
      worst_offp = std::isfinite(offp) ? std::max(worst_offp, std::abs(offp)) : std::nan("");
      rows << cell(f0 / f1) << " | " << cell(fp / f1)
           << " | " << (std::isfinite(offp) ? format("%+.1e", offp) : std::string("—")) << " | "
           << format("%.1f", tr.time_s) << " |\n";
      stats.push_back({{"curve", tr.label}, {"points", tr.curve.points.size()}, {"folds", tr.curve.folds.size()},
                       {"peak_frequency_over_f1", pf / f1}, {"peak_amplitude_gap", pa},
                       {"linear_mode_branch_frequency_over_f1_at_peak", json_or_null(f0 / f1)},
                       {"peak_branch_frequency_over_f1_at_peak", json_or_null(fp / f1)},
                       {"time_s", tr.time_s}, {"condition_number_of_g", tr.condition},
                       {"corrector_iterations", tr.curve.corrector_iterations},
                       {"rejected_steps", tr.curve.rejected_steps}, {"corners", tr.curve.kinks},
                       {"stop", std::string(solvers::to_string(tr.curve.stop))}, {"message", tr.curve.message}});
    }
    const double wavelet_df = peak_ratio[1] - peak_ratio[0], wavelet_da = peak_amp[1] / peak_amp[0] - 1.0;
    const bool wavelet_ok = std::abs(wavelet_df) <= 1e-3 && std::abs(wavelet_da) <= 1e-2;
    // The rigid stops against the penalty ones at the same H: a stiffer casing hardens more.
    const Traced& rigid_curve = traced[3];
    const double rigid_shift = peak_ratio[3] - peak_ratio[2];
    const double linear_peak = la.maxCoeff();
    Eigen::Index top = 0;
    backbone.frequency_hz.maxCoeff(&top);

    // Where the branch from the linear mode leaves the first mode: the first level whose first-mode
    // share is below ½, and at its last level the largest other component (mode j, harmonic h):
    // an h:1 internal resonance if that component holds most of the energy and h f = f_j within 1 %.
    const Eigen::VectorXd& fj = nnm.linear_frequencies_hz();
    auto resonance = [&](const BackboneCurve& c, Eigen::Index k) {
      const int j = static_cast<int>(c.other_mode(k)), h = static_cast<int>(c.other_harmonic(k));
      const double detuning = h * c.frequency_hz(k) / fj(j - 1) - 1.0;  // h f/f_j − 1
      return std::pair{detuning, c.other_share(k) > 0.5 && std::abs(detuning) <= 1e-2};
    };
    auto describe = [&](const BackboneCurve& c, Eigen::Index k) {
      const int j = static_cast<int>(c.other_mode(k)), h = static_cast<int>(c.other_harmonic(k));
      return std::string("E = ").append(format("%.2f", c.energy(k))).append(", f/f1 = ")
          .append(format("%.5f", c.frequency_hz(k) / f1)).append(": mode 1 at the fundamental holds ")
          .append(format("%.3f", c.first_share(k))).append(" of the energy, mode ").append(std::to_string(j))
          .append(" at harmonic ").append(std::to_string(h)).append(" holds ").append(format("%.3f", c.other_share(k)))
          .append(" (f_").append(std::to_string(j)).append(" = ").append(format("%.4f", fj(j - 1) / f1))
          .append(" f1 = ").append(std::to_string(h)).append(" × ").append(format("%.5f", fj(j - 1) / (h * f1)))
          .append(" f1)");
    };
    Eigen::Index leaves = -1;
    for (Eigen::Index k = 0; k < nl && leaves < 0; ++k) {
      if (backbone.first_share(k) < 0.5) leaves = k;
    }
    const auto [end_detuning, linear_branch_resonant] = resonance(backbone, nl - 1);
    // The branch through the peak: its share at the start (the peak's orbit corrected) and its ends.
    Eigen::Index start_level = 0;
    for (Eigen::Index k = 0; k < np; ++k) {
      if (std::abs(peak_branch.energy(k) - peak_energy) < std::abs(peak_branch.energy(start_level) - peak_energy)) {
        start_level = k;
      }
    }
    // Whether the continuation started downward came back along the upward one: its last orbit
    // against the upward continuation's last.
    const double ends_apart = np > 0 ? (through.front().coefficients - through.back().coefficients).norm() /
                                           through.back().coefficients.norm()
                                     : std::nan("");
    const bool came_back = ends_apart <= 1e-6;
    // The levels where mode 1 holds at least half of m̂, and their energy range (the branch
    // passes some energies more than once, so a range in branch order would say little).
    Eigen::Index first_mode_levels = 0;
    double first_mode_lowest = std::nan(""), first_mode_highest = std::nan("");
    for (Eigen::Index k = 0; k < np; ++k) {
      if (peak_branch.first_share(k) < 0.5) continue;
      ++first_mode_levels;
      const double e = peak_branch.energy(k);
      first_mode_lowest = first_mode_levels == 1 ? e : std::min(first_mode_lowest, e);
      first_mode_highest = first_mode_levels == 1 ? e : std::max(first_mode_highest, e);
    }

    // Stability of each curve that has it: verdicts, unstable points, the crossings with their
    // kind, and its cost beside the continuation's.
    std::ostringstream stability_rows;
    // Per curve with stability: whether its lowest fold (the jump-up) is confirmed by a crossing,
    // and how far from its highest fold (the jump-down) the first loss of stability lies [f1]
    // (NaN: no fold or no loss).
    std::vector<bool> jump_up_confirmed(traced.size(), false);
    std::vector<double> loss_before_fold(traced.size(), std::nan(""));
    std::string jump_up_evidence;
    for (size_t k = 0; k < traced.size(); ++k) {
      const auto& tr = traced[k];
      if (!tr.stability) {
        stats[k]["stability"] = nullptr;
        continue;
      }
      const auto& c = tr.curve;
      int unstable = 0, verdicts = 0;
      for (const auto& p : c.points) {
        verdicts += p.stability_available ? 1 : 0;
        unstable += p.stability_available && !p.stable ? 1 : 0;
      }
      const int confirmed = static_cast<int>(std::count(c.fold_confirmed.begin(), c.fold_confirmed.end(), true));
      if (!c.folds.empty()) {
        size_t lo = 0, hi = 0;
        for (size_t j = 1; j < c.folds.size(); ++j) {
          if (c.folds[j].parameter < c.folds[lo].parameter) lo = j;
          if (c.folds[j].parameter > c.folds[hi].parameter) hi = j;
        }
        jump_up_confirmed[k] = c.fold_confirmed[lo];
        jump_up_evidence += (jump_up_evidence.empty() ? "" : "; ") + tr.label + ": fold at " +
                            format("%.5f", c.folds[lo].parameter / f1) + " f1 " +
                            (c.fold_confirmed[lo] ? "confirmed" : "not confirmed");
        for (const auto& x : crossings[k]) {
          if (x.stability_lost) {
            loss_before_fold[k] = (c.folds[hi].parameter - x.frequency_hz) / f1;
            break;
          }
        }
      } else {
        jump_up_evidence += (jump_up_evidence.empty() ? "" : "; ") + tr.label + ": no fold";
      }
      std::string list;
      nlohmann::json jc = nlohmann::json::array();
      for (const auto& x : crossings[k]) {
        list += (list.empty() ? "" : "; ") + std::string(solvers::to_string(x.kind)) + " at " +
                format("%.5f", x.frequency_hz / f1) + " f1 (" + (x.stability_lost ? "lost" : "regained") + ")";
        jc.push_back({{"kind", solvers::to_string(x.kind)}, {"frequency_over_f1", x.frequency_hz / f1},
                      {"amplitude_gap", x.amplitude * unit}, {"stability", x.stability_lost ? "lost" : "regained"}});
      }
      // The continuation alone; the penalty curves' monodromies run beside it on a second thread
      // (stability_work_s), and stability_time_s is the wait that remains after it.
      const double branch_s = c.wall_time_s;
      stability_rows << "| " << tr.label << " | " << verdicts << " of " << c.points.size() << " | " << unstable << " | "
                     << c.unsettled_points << " | " << confirmed << " of " << c.folds.size() << " | "
                     << (list.empty() ? std::string("none") : list) << " | " << format("%.1f", branch_s) << " | "
                     << format("%.1f", c.stability_time_s) << " | " << format("%.1f", c.stability_work_s) << " |\n";
      stats[k]["stability"] = {{"verdicts", verdicts}, {"unstable_points", unstable},
                               {"unsettled_points", c.unsettled_points}, {"folds_confirmed", confirmed},
                               {"crossings", jc}, {"continuation_s", branch_s},
                               {"stability_s", c.stability_time_s}, {"stability_work_s", c.stability_work_s}};
    }

    timing["backbone_s"] = backbone.time_s;
    timing["backbone_through_peak_s"] = peak_branch.time_s;
    for (const auto& tr : traced) timing[tr.key + "_s"] = tr.time_s;
    run.meta({{"figure", "LL11 blade, forced response (beyond the paper)"}, {"parameters", parameters.used()}, {"mesh_size_m", mesh_size},
              {"dofs", blade.model.dofs.size()}, {"reduced_dofs", n}, {"gap_m", gap}, {"zeta", zeta}, {"beta_s", beta},
              {"load_scale", s}, {"overload_gaps", overload}, {"penalty_stiffness_n_per_m", k_pen},
              {"radial_static_stiffness_n_per_m", radial_stiffness}, {"harmonics", harmonics}, {"wavelet_dimension", wavelet_m},
              {"linear_frequency_hz", f1}, {"rigid_harmonics", rigid_harmonics}, {"onset_node_index", onset + 1}, {"curves", stats}, {"timing_s", timing},
              {"linear_peak_amplitude_gap", linear_peak}, {"residual_tolerance", residual_tolerance},
              {"backbone_levels", nl}, {"backbone_max_frequency_over_f1", backbone.frequency_hz(top) / f1},
              {"backbone_stop", backbone.stop}, {"peak_branch_levels", np}, {"peak_branch_stop", peak_branch.stop},
              {"peak_orbit_energy", peak_energy},
              {"linear_mode_branch_leaves_first_mode_at_energy", leaves >= 0 ? nlohmann::json(backbone.energy(leaves)) : nlohmann::json()},
              {"linear_mode_branch_end_internal_resonance", linear_branch_resonant},
              {"linear_mode_branch_end_detuning", end_detuning},
              {"peaks_on_linear_mode_branch", on_linear_branch}, {"peaks_on_peak_branch", on_peak_branch},
              {"wavelet_agrees_with_harmonic_balance", wavelet_ok}});

    std::ostringstream md;
    md << "## Beyond LL11: forced response of the reduced blade against the casing (`ll11_blade_forced`)\n\n"
       << "The blade of `ll11_blade` (" << blade.model.dofs.size() << " DOFs, Craig–Bampton " << n
       << " DOFs), damping C = βK_r with ζ₁ = " << format("%.3f", zeta) << ", load F(t) = s M_r φ₁ cos 2πft (the "
          "first mode's own inertia shape: in the linear regime it excites mode 1 only), s = "
       << format("%.4g", s) << " so that the linear resonance of the first node to touch (#" << onset + 1
       << ") reaches " << format("%g", overload) << " gaps. Casing: " << n_tip << " radial stops at g0 = "
       << format("%g", gap * 1e3) << " mm, as penalty springs k = " << format("%.3g", k_pen) << " N/m ("
       << format("%g", stiffness_ratio) << " × the static radial stiffness " << format("%.3g", radial_stiffness)
       << " N/m at that node), and as rigid stops (Signorini at the M = " << 2 * rigid_harmonics + 1
       << " impulse instants of Fourier:Fourier H = " << rigid_harmonics << ", continued piece by piece: each "
          "impulse that starts or ends is an event, located and crossed). Continuation in f from "
       << format("%.2f", from) << " f1 to " << format("%.2f", to) << " f1, f1 = " << format("%.2f", f1)
       << " Hz; Fourier:Fourier H = " << harmonics << " (M = " << 2 * harmonics + 1 << "), B-spline:B-spline M = "
       << wavelet_m << ", distributional form. Amplitude: half the peak-to-peak circumferential displacement "
          "of node #" << onset + 1 << ", in gaps (the linear peak: " << format("%.3f", linear_peak)
       << "). Solves verified by the backward error of their full residual, η ≤ " << format("%g", residual_tolerance)
       << (residual_tolerance == solvers::WeightedResidualOptions{}.residual_tolerance ? " (the default)" : "")
       << ". Parameters: `reproduce/scenes/ll11_blade_forced.toml`. Figure: "
          "`forced_response.png`.\n\n"
       << "Two backbone branches of the same stops (undamped, unforced; KKT continuation, N = " << mode_harmonics
       << ", m = " << mode_samples << "): (0) from the linear first mode, E = " << format("%g", co.energy_min) << " to " << format("%g", co.energy_max)
       << " (" << nl << " levels); (1) through harmonic balance's resonance peak: the peak's orbit (every DOF's "
          "coefficients, E = " << format("%.3f", peak_energy) << ") corrected by Newton without damping and load, "
          "then continued down and up in energy (" << np << " levels, E = " << format("%.2f", peak_branch.energy.minCoeff())
       << " to " << format("%.2f", peak_branch.energy.maxCoeff()) << "). backbone.csv gives, per level, the share of "
          "m̂ held by the first linear mode at the fundamental and the largest other (mode, harmonic) component "
          "(NonlinearModes::modal_energy_shares).\n\n"
       << "| curve | points | folds | events | peak f/f1 | peak amplitude [gap] | branch 0 f/f1 at that amplitude | "
          "branch 1 f/f1 at that amplitude | peak − branch 1 [f1] | time [s] |\n|---|---|---|---|---|---|---|---|---|---|\n"
       << rows.str() << "\n(\"—\": the branch never has the peak's amplitude. \"not compared\": a curve at another H "
          "or with rigid stops; both backbone branches are the penalty stops', compared with the penalty curves at H = "
       << harmonics << " and M = " << wavelet_m << ". events: impulses starting or ending, located and crossed by the piecewise-smooth "
          "continuation of the rigid stops.)\n\n"
       << "The branch from the linear mode: its highest frequency is " << format("%.5f", backbone.frequency_hz(top) / f1)
       << " f1 at E = " << format("%.2f", backbone.energy(top)) << "; at its end, " << describe(backbone, nl - 1)
       << ". The branch through the peak: at its start, " << describe(peak_branch, start_level) << "; mode 1 holds "
       << "at least half of the energy on " << first_mode_levels << " of its " << np << " levels"
       << (first_mode_levels > 0 ? std::string(" (E from ").append(format("%.2f", first_mode_lowest))
                                       .append(" to ").append(format("%.2f", first_mode_highest)).append(")")
                                 : std::string())
       << ". The continuation started downward went down to E = " << format("%.2f", down_lowest) << " and, after "
       << down_folds << " folds in E, ended at " << describe(peak_branch, 0)
       << "; the one started upward ended at " << describe(peak_branch, np - 1) << ".\n\n";
    md << "Stability (`response.stability`, `response.rigid_stability` in the file): the Floquet multipliers of "
          "every point (FloquetAnalysis: Arnoldi on the monodromy matrix of the 2 × " << n << " states, the "
          "linear penalty stops' flights exact between their gap crossings), each change of stability located "
          "where the largest |μ| passes 1 between two points and classified by the crossing multiplier "
          "(bifurcations.csv). A fold is confirmed when a multiplier crosses +1 within four points of it. "
          "The rigid curve's stability (each point's exact orbit shot against the stops) is "
       << (rigid_stability ? "computed" : "not computed, for its cost") << ". Times are wall times on "
       << tbb::this_task_arena::max_concurrency()
       << " oneTBB workers; the penalty curves' multipliers are computed on a second thread while the continuation "
          "goes on, so their stability column is the wait after it and the last column the thread time of all "
          "points.\n\n"
       << "| curve | points with a verdict | unstable | unsettled | folds confirmed | stability crossings | "
          "continuation [s] | stability [s] | stability, thread time [s] |\n|---|---|---|---|---|---|---|---|---|\n"
       << stability_rows.str() << "\n";
    const auto off = [&](double worst) {
      return std::isfinite(worst) ? "largest |peak − branch| " + format("%.1e", worst) + " f1"
                                  : std::string("a peak's amplitude is not on the branch");
    };
    const std::string within = " (within 2ζ = " + format("%g", 2.0 * zeta) + " f1)";
    std::vector<reproduce::Claim> claims = {
        {"the resonance peaks lie on the branch from the linear mode" + within, on_linear_branch, off(worst_off0)},
        {"the resonance peaks lie on the branch through the peak" + within, on_peak_branch, off(worst_offp)},
        {"the branch from the linear mode stays on the first mode (its fundamental holds at least half of the energy) "
         "up to E = " + format("%g", co.energy_max),
         leaves < 0,
         leaves >= 0 ? "below ½ from E = " + format("%.2f", backbone.energy(leaves))
                     : "at least ½ up to E = " + format("%.2f", backbone.energy(nl - 1))},
        {"the end of the branch from the linear mode is an h:1 internal resonance (the other component holds more than "
         "half and h f within 1 % of f_j)",
         linear_branch_resonant, "h f/f_j − 1 = " + format("%+.1e", end_detuning)},
        {"the continuation started downward turned and came back along the upward one (the two last orbits equal, "
         "‖ΔY‖/‖Y‖ ≤ 1e-6)",
         came_back, "‖ΔY‖/‖Y‖ = " + format("%.1e", ends_apart)},
        {"B-spline:B-spline (M = " + std::to_string(wavelet_m) + ") gives harmonic balance's resonance (peak frequency "
         "within 1e-3 f1 and amplitude within 1 %)",
         wavelet_ok, "Δf = " + format("%+.1e", wavelet_df) + " f1, Δa/a = " + format("%+.1e", wavelet_da)},
        {"with the " + std::to_string(stops.size()) + " stops rigid, the continuation runs over the range to " +
             format("%.2f", to) + " f1, every impulse that starts or ends crossed as an event",
         rigid_curve.curve.converged(),
         std::string(solvers::to_string(rigid_curve.curve.stop)) + ": " + std::to_string(rigid_curve.curve.points.size()) +
             " points, " + std::to_string(rigid_curve.curve.events) + " events (" +
             std::to_string(rigid_curve.curve.switches) + " impulses switched), " +
             std::to_string(rigid_curve.curve.folds.size()) + " folds, " +
             std::to_string(rigid_curve.curve.rejected_steps) + " rejected steps"},
        {"the rigid stops' resonance peak lies above the penalty stops' at the same H = " +
             std::to_string(rigid_harmonics) + " (a stiffer casing hardens the blade more)",
         rigid_shift > 0.0,
         "rigid " + format("%.5f", peak_ratio[3]) + " f1 at " + format("%.3f", peak_amp[3]) + " gaps, penalty " +
             format("%.5f", peak_ratio[2]) + " f1 at " + format("%.3f", peak_amp[2]) + " gaps: " +
             format("%+.2e", rigid_shift) + " f1"}};
    if (penalty_stability) {
      // (d) Stability. At a fold of an exact orbit a multiplier passes +1; about a truncated orbit
      // the crossing may lag its fold, less as the truncation is refined. (e) Two discretizations
      // of the same orbits lose and regain stability at the same frequencies.
      bool all_confirmed = true;
      for (size_t k = 0; k < traced.size(); ++k) {
        if (traced[k].stability && !traced[k].rigid) all_confirmed = all_confirmed && jump_up_confirmed[k];
      }
      claims.push_back({"on each penalty curve a Floquet multiplier crosses +1 within four points of the jump-up fold "
                        "(the lowest turning point)",
                        all_confirmed, jump_up_evidence});
      const double lag6 = loss_before_fold[2], lag12 = loss_before_fold[0];
      const auto lag = [&](double v) { return std::isfinite(v) ? format("%.1e", v) + " f1" : std::string("no loss"); };
      if (rigid_harmonics < harmonics) {  // --quick runs both at one H: nothing to compare
        claims.push_back({"the first loss of stability lies below the jump-down fold by less at H = " +
                              std::to_string(harmonics) + " than at H = " + std::to_string(rigid_harmonics) +
                              " (at an exact orbit's fold a multiplier passes +1: the lag is the truncation's)",
                          std::isfinite(lag6) && std::isfinite(lag12) && std::abs(lag12) < std::abs(lag6),
                          "fold − loss = " + lag(lag6) + " at H = " + std::to_string(rigid_harmonics) + ", " +
                              lag(lag12) + " at H = " + std::to_string(harmonics) + ", " + lag(loss_before_fold[1]) +
                              " for B-spline:B-spline M = " + std::to_string(wavelet_m)});
      }
      const double tolerance = parameters.number("response.max_step_bspline_f1");
      bool same = crossings[0].size() == crossings[1].size();
      double worst = 0.0;
      for (size_t j = 0; same && j < crossings[0].size(); ++j) {
        const auto &a = crossings[0][j], &b = crossings[1][j];
        same = a.kind == b.kind && a.stability_lost == b.stability_lost;
        worst = std::max(worst, std::abs(a.frequency_hz - b.frequency_hz) / f1);
      }
      same = same && worst <= tolerance;
      claims.push_back({"Fourier:Fourier (H = " + std::to_string(harmonics) + ") and B-spline:B-spline (M = " +
                            std::to_string(wavelet_m) + ") change stability in the same way at the same frequencies "
                            "(within the B-spline curve's largest step, " + format("%g", tolerance) + " f1)",
                        same,
                        std::to_string(crossings[0].size()) + " and " + std::to_string(crossings[1].size()) +
                            " crossings" +
                            (crossings[0].size() == crossings[1].size()
                                 ? "; largest |Δf| " + format("%.1e", worst) + " f1"
                                 : std::string(", not paired"))});
    }
    md << reproduce::claims_markdown(claims)
       << "Timings: gmsh " << format("%.1f", blade.gmsh_s) << " s, ccx " << format("%.1f", blade.ccx_s)
       << " s, Craig–Bampton " << format("%.1f", timing["craig_bampton_s"].get<double>()) << " s, backbone from the "
          "linear mode " << format("%.1f", backbone.time_s) << " s, through the peak " << format("%.1f", peak_branch.time_s)
       << " s.\n";
    run.report(md.str());
  });
}
