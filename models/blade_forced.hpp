#pragma once
/// The forced model of the reduced LL11 blade against the casing (beyond LL11 Sec. 5.2, issue
/// #15), shared by ll11_blade_forced, ll11_blade_gap_study (issue #37), friction_oval_casing and
/// bench_continuation's blade benchmarks (issue #39): the Craig–Bampton
/// model in coordinates scaled to unit diagonal mass, the tip's radial stops, the damping
/// C = β K̂ (β = 2ζ/ω₁), the load s M̂ φ₁ along the first mode and the penalty stiffness. SI units.
///
/// Scaling: q = D q̂, D = diag(M_r)^(-1/2), so that the interface DOFs (metres, each with a small
/// share of the mass) and the mass-normalized modal coordinates weigh alike (the condition
/// estimate of G drops from 1.1e9 to 3.1e7 on the --quick mesh). Stops, load and amplitudes are
/// mapped accordingly: `unit` turns a scaled coordinate of the observed DOF into gaps.

#include <memory>
#include <vector>

#include <Eigen/Core>

#include <wbm/fem/craig_bampton.hpp>
#include <wbm/solvers/mechanical_system.hpp>
#include <wbm/solvers/nonlinear_modes.hpp>
#include <wbm/solvers/weighted_residual.hpp>

#include "blade.hpp"

namespace wbm::models {

struct BladeForcedInputs {
  double gap = 0.0;              // g0 of every radial stop [m]
  double zeta = 0.0;             // ζ₁ of C = β K_r
  double overload = 0.0;         // the linear resonance peak of the first stop to touch [gaps]
  double stiffness_ratio = 0.0;  // k = ratio × the static radial stiffness 1/(e_cᵀ K_r⁻¹ e_c) at the onset node
  double from_f1 = 0.0;          // the forcing's starting frequency [f1]
  int mode_harmonics = 0;        // N and m of the stops' nonlinear modes (NonlinearModeOptions)
  int mode_samples = 0;
};

struct BladeForcedModel {
  solvers::MechanicalSystem reduced;       // M̂, K̂ (scaled), Ĉ = β K̂
  Eigen::VectorXd scale;                   // the diagonal of D
  std::vector<solvers::RigidStop> stops;   // one per tip node, radial, in the scaled coordinates
  std::unique_ptr<solvers::NonlinearModes> modes;  // of the undamped, unforced stops
  double f1 = 0.0, omega1 = 0.0;           // first linear frequency [Hz], [rad/s]
  double beta = 0.0;                       // [s]
  double load_scale = 0.0;                 // s of the load s M̂ φ₁
  double radial_stiffness = 0.0;           // 1/(e_cᵀ K̂⁻¹ e_c) at the onset stop [N/m]
  double penalty_stiffness = 0.0;          // stiffness_ratio × radial_stiffness [N/m]
  int onset = 0;                           // the stop that touches first in the linear mode
  int observed = 0;                        // the y DOF of the onset node (circumferential)
  double unit = 0.0;                       // scaled coordinate of `observed` → gaps
  Eigen::VectorXd load;                    // s M̂ φ₁ (n)
  solvers::HarmonicForcing forcing;        // that load at from_f1 · f1
};

/// Builds the model from the blade and its Craig–Bampton model (blade.boundary first). Throws
/// as solvers::NonlinearModes for bad inputs.
[[nodiscard]] BladeForcedModel blade_forced_model(const Blade& blade, const fem::CraigBamptonModel& cb,
                                                  const BladeForcedInputs& in);

}  // namespace wbm::models
