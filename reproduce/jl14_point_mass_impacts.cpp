// Issue #38 item 3: impacts at point masses. The 1-DOF impact oscillator against a rigid stop,
// solved by the Haar weighted residual with Newton's impact law (solvers/haar_impact.hpp) for
// M = 16 … 2048 cells per period, with a plastic impact (e = 0, the oscillator of issue #16 on
// which the position-level weighted residual stalls beyond M = 64) and with e = 0.8 (Shaw &
// Holmes' one-impact orbit). Reference: the exact orbit with the same impact law, by event-driven
// shooting (impact_shooting.hpp: closed-form flights, events located to 1e-14 T; for e = 0 it is
// issue #16's closed-form orbit, tests/solvers/test_impact_shooting.cpp), sampled at the cells'
// midpoints. Beside it, Moreau–Jean with M steps per period (time_integration.hpp), against the
// same orbit at its samples τ_p = p/M. A few seconds. Writes out/jl14_point_mass_impacts/
// convergence.csv, orbit_e<e>.csv, meta.json, report.md. --quick: M = 16 … 128.
#include <chrono>
#include <limits>
#include <optional>
#include <cmath>
#include <memory>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include <wbm/contact/signorini.hpp>
#include <wbm/solvers/haar_impact.hpp>
#include <wbm/solvers/impact_shooting.hpp>
#include <wbm/solvers/post_processing.hpp>
#include <wbm/solvers/time_integration.hpp>

#include "combinations.hpp"

namespace {

using namespace wbm;

// m ü + c u̇ + k u = F cos 2πft against a stop at u = g0 (issue #16's oscillator and Shaw & Holmes').
struct Oscillator {
  std::string name;
  double mass, natural_hz, zeta, forcing_hz, amplitude, gap, restitution;
  [[nodiscard]] solvers::MechanicalSystem system() const {
    const double k = mass * std::pow(2.0 * std::numbers::pi * natural_hz, 2);
    solvers::MechanicalSystem s;
    s.mass = Eigen::MatrixXd::Constant(1, 1, mass).sparseView();
    s.damping = Eigen::MatrixXd::Constant(1, 1, 2.0 * zeta * std::sqrt(k * mass)).sparseView();
    s.stiffness = Eigen::MatrixXd::Constant(1, 1, k).sparseView();
    return s;
  }
  [[nodiscard]] solvers::HarmonicForcing forcing() const { return {0, amplitude, forcing_hz}; }
  [[nodiscard]] std::vector<solvers::ContactPoint> stops() const {
    return {{0, std::make_shared<contact::RigidStop>(gap)}};
  }
};

// The exact orbit's displacement at t = (s + offset) T/P, s = 0 … P − 1: a flow from the orbit's
// start to the first instant, then one period sampled.
Eigen::VectorXd exact_samples(const solvers::ImpactFlow& flow, const solvers::ImpactOrbit& orbit, int samples,
                              double offset) {
  const double period = flow.period_s();
  const double first = offset * period / samples;
  double lead = std::fmod(first - orbit.start_s, period);
  if (lead <= 0.0) lead += period;
  const auto to_first = flow.flow(orbit.state, orbit.start_s, lead);
  const auto one = flow.flow(to_first.state, first, period, to_first.active, samples);
  return one.contact_displacement.row(0).transpose();
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
  auto run = reproduce::Run::from_args(argc, argv, "jl14_point_mass_impacts");
  return run.execute([](reproduce::Run& run) {
    using reproduce::format;
    // Issue #16's plastic oscillator (1 kg, 10 Hz, ζ = 0.05, forced at 8 Hz, k g0/F = ½) and the
    // e = 0.8 oscillator of test_impact_shooting (1 Hz, forced at 0.9 Hz, F = 1 N, g0 = 1 cm).
    const double k16 = std::pow(2.0 * std::numbers::pi * 10.0, 2);
    const std::vector<Oscillator> cases{{"plastic", 1.0, 10.0, 0.05, 8.0, 10.0, 0.5 * 10.0 / k16, 0.0},
                                        {"restitution", 1.0, 1.0, 0.05, 0.9, 1.0, 0.01, 0.8}};
    std::vector<int> cells{16, 32, 64, 128};
    if (!run.quick()) {
      for (int m : {256, 512, 1024, 2048}) cells.push_back(m);
    }
    const int finest = cells.back();
    std::vector<double> col_e, col_m, col_iter, col_impacts, col_error, col_mj, col_pen, col_time, col_residual;
    std::vector<std::string> status;
    std::vector<reproduce::Claim> claims;
    nlohmann::json meta_cases = nlohmann::json::array();
    std::ostringstream md;
    md << "## Impacts at point masses: the Haar weighted residual with Newton's impact law (issue #38)\n\n"
       << "Files: `out/jl14_point_mass_impacts/point_mass_impacts.{png,pdf}`, `convergence.csv`, "
          "`orbit_<case>.csv`, `meta.json`. The 1-DOF oscillator m ü + c u̇ + k u = F cos 2πft against a rigid stop "
          "at u = g0, by `solve_haar_impact` (solvers/haar_impact.hpp): Haar trial and weighting functions on M "
          "cells per period with JL14's delta-pair velocity, which is the periodic central-difference scheme, and "
          "Newton's impact law in Paoli and Schatzman's form 0 ≤ P_k ⊥ g0 − (u_{k+1} + e u_{k−1})/(1 + e) ≥ 0, "
          "solved as a causal sweep and the fixed point of the period (Newton core, from "
          << solvers::HaarImpactOptions{}.transient_periods
          << " periods of the scheme's own time stepping). Reference: the exact orbit with the same law by "
             "event-driven shooting (closed-form flights, events located to 1e-14 T); for e = 0 it is issue #16's "
             "closed-form orbit. Error: rms(u_k − u_exact)/rms(u_exact) at the cells' midpoints (k + ½)T/M. "
             "Moreau–Jean (θ = ½, the same e) with M steps per period for at most 100 periods from rest, against "
             "the same orbit at its samples kT/M. Penetration: max(u_k − g0), relative to the larger of g0 and "
             "max|u|. Time: one solve on one core.\n\n";
    for (const auto& oc : cases) {
      const auto system = oc.system();
      const auto forcing = oc.forcing();
      const auto stops = oc.stops();
      const double period = 1.0 / oc.forcing_hz;
      // The finest Haar solution seeds the exact orbit's shooting (at the cell of largest gap).
      solvers::HaarImpactOptions fine;
      fine.cells = finest;
      fine.restitution = oc.restitution;
      const auto seed = solvers::solve_haar_impact(system, forcing, stops, fine);
      if (!seed.converged()) run.fail(oc.name + ", M = " + std::to_string(finest) + ": " + seed.message);
      Eigen::Index k_free = 0;
      seed.displacement.row(0).minCoeff(&k_free);
      const double h = period / finest;
      const Eigen::Index kp = (k_free + 1) % finest, km = (k_free + finest - 1) % finest;
      const Eigen::Vector2d x_guess(seed.displacement(0, k_free),
                                    (seed.displacement(0, kp) - seed.displacement(0, km)) / (2.0 * h));
      solvers::ImpactFlowOptions flow_options;
      flow_options.restitution = oc.restitution;
      const solvers::ImpactFlow flow(system, forcing, stops, flow_options);
      const auto orbit = solvers::shoot_periodic_orbit(flow, x_guess, (static_cast<double>(k_free) + 0.5) * h);
      if (!orbit.report.converged()) {
        run.fail(oc.name + ": the exact orbit's shooting: " + orbit.report.message);
        continue;
      }
      std::vector<double> h_ok, errors;
      md << "**" << (oc.restitution == 0.0 ? "Plastic impacts (e = 0)" : "Newton's law, e = " + format("%g", oc.restitution))
         << "**: " << format("%g", oc.mass) << " kg, natural frequency " << format("%g", oc.natural_hz) << " Hz, ζ = "
         << format("%g", oc.zeta) << ", F = " << format("%g", oc.amplitude) << " N at " << format("%g", oc.forcing_hz)
         << " Hz, g0 = " << format("%.4g", oc.gap) << " m. The exact orbit has "
         << orbit.period.events.size() << " event(s) per period, largest Floquet multiplier "
         << format("%.3g", orbit.max_modulus) << ".\n\n"
         << "| M | status | Newton iterations | cells with an impulse | error | Moreau–Jean error (M steps) | "
            "penetration | time [ms] |\n|---|---|---|---|---|---|---|---|\n";
      for (int m : cells) {
        solvers::HaarImpactOptions o;
        o.cells = m;
        o.restitution = oc.restitution;
        const auto t0 = std::chrono::steady_clock::now();
        const auto s = solvers::solve_haar_impact(system, forcing, stops, o);
        const double ms = 1e3 * seconds_since(t0);
        solvers::MoreauJeanOptions mj;
        mj.steps_per_period = m;
        mj.samples_per_period = m;
        mj.restitution = oc.restitution;
        mj.max_periods = 100;
        const auto reference = solvers::integrate_moreau_jean_to_periodic(system, forcing, stops, mj);
        const double mj_error = solvers::rms_relative_error(reference.displacement.row(0).transpose(),
                                                            exact_samples(flow, orbit, m, 0.0));
        const double nan = std::numeric_limits<double>::quiet_NaN();
        const Eigen::VectorXd exact = exact_samples(flow, orbit, m, 0.5);  // at the cells' midpoints
        const double error =
            s.converged() ? solvers::rms_relative_error(s.displacement.row(0).transpose(), exact) : nan;
        if (s.converged()) {
          h_ok.push_back(1.0 / m);
          errors.push_back(error);
        }
        col_e.push_back(oc.restitution);
        col_m.push_back(m);
        col_iter.push_back(s.report.iterations);
        col_impacts.push_back(s.impact_cells);
        col_error.push_back(error);
        col_mj.push_back(mj_error);
        col_pen.push_back(s.converged() ? s.penetration : nan);
        col_residual.push_back(s.converged() ? s.residual : nan);
        col_time.push_back(ms);
        status.push_back(std::string(solvers::to_string(s.status)));
        md << "| " << m << " | " << solvers::to_string(s.status) << " | " << s.report.iterations << " | "
           << s.impact_cells << " | " << (s.converged() ? format("%.2e", error) : std::string()) << " | "
           << format("%.2e", mj_error) << (reference.report.converged() ? "" : " (not periodic)") << " | "
           << (s.converged() ? format("%.1e", s.penetration) : std::string()) << " | " << format("%.2f", ms) << " |\n";
        if (m == finest) {
          Eigen::VectorXd tau(m);
          for (int k = 0; k < m; ++k) tau(k) = (k + 0.5) / m;
          run.table("orbit_" + oc.name + ".csv", {"tau [-]", "u_haar [m]", "u_exact [m]"},
                    {tau, s.converged() ? Eigen::VectorXd(s.displacement.row(0).transpose())
                                        : Eigen::VectorXd::Constant(m, 0.0),
                     exact});
        }
      }
      const int converged = static_cast<int>(errors.size());
      const double order = converged >= 2 ? reproduce::loglog_slope(h_ok, errors) : std::nan("");
      md << "\nObserved order (least squares over the converged M): " << format("%.2f", order) << ".\n\n";
      claims.push_back({"issue #38 item 3 (" + oc.name + ", e = " + format("%g", oc.restitution) +
                            "): the weighted residual with the velocity-level impact law converges for every M "
                            "from " + std::to_string(cells.front()) + " to " + std::to_string(finest),
                        converged == static_cast<int>(cells.size()),
                        std::to_string(converged) + " of " + std::to_string(cells.size()) + " converged"});
      const double expected = oc.restitution == 0.0 ? 1.5 : 0.8;
      claims.push_back({"(" + oc.name + ") its error against the exact orbit falls at order ≥ " + format("%g", expected),
                        std::isfinite(order) ? std::optional<bool>(order >= expected) : std::nullopt,
                        "observed order " + format("%.2f", order) + "; error " +
                            (errors.empty() ? std::string("—") : format("%.2e", errors.front())) + " at M = " +
                            std::to_string(cells.front()) + ", " +
                            (errors.empty() ? std::string("—") : format("%.2e", errors.back())) + " at M = " +
                            std::to_string(finest)});
      meta_cases.push_back({{"case", oc.name},
                            {"restitution", oc.restitution},
                            {"exact_events_per_period", orbit.period.events.size()},
                            {"exact_max_multiplier", orbit.max_modulus},
                            {"observed_order", std::isfinite(order) ? nlohmann::json(order) : nlohmann::json()},
                            {"converged", converged}});
    }
    // Haar against Moreau–Jean at equal steps per period, on the finest M of each case.
    for (size_t i = 0; i < col_m.size(); ++i) {
      if (static_cast<int>(col_m[i]) != finest || !std::isfinite(col_error[i])) continue;
      claims.push_back({"at M = " + std::to_string(finest) + " steps per period (e = " + format("%g", col_e[i]) +
                            ") the Haar weighted residual is closer to the exact orbit than Moreau–Jean",
                        col_error[i] < col_mj[i],
                        format("%.2e", col_error[i]) + " against " + format("%.2e", col_mj[i])});
    }
    auto column = [](const std::vector<double>& x) {
      return Eigen::Map<const Eigen::VectorXd>(x.data(), static_cast<Eigen::Index>(x.size()));
    };
    run.table("convergence.csv",
              {"restitution [-]", "cells [-]", "newton_iterations [-]", "impact_cells [-]", "error [-]",
               "moreau_jean_error [-]", "penetration [-]", "verified_residual [-]", "time [ms]"},
              {column(col_e), column(col_m), column(col_iter), column(col_impacts), column(col_error), column(col_mj),
               column(col_pen), column(col_residual), column(col_time)},
              status);
    run.meta({{"check", "impacts at point masses (issue #38 item 3)"}, {"cells", cells}, {"cases", meta_cases}});
    md << reproduce::claims_markdown(claims);
    run.report(md.str());
  });
}
