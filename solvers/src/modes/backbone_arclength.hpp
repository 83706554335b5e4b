// The continuation options of a backbone in E, shared by NonlinearModes::continue_backbone and
// BasisModes::continue_backbone (one mapping of BackboneContinuationOptions onto the continuation).
#pragma once

#include <wbm/solvers/continuation.hpp>
#include <wbm/solvers/nonlinear_modes.hpp>

namespace wbm::solvers::detail {

/// The fields of BackboneContinuationOptions the continuation reads (steps, |ΔE| per step, point
/// limit, the tolerance for the corrector and for the first point's Newton, on_point), the range
/// [parameter_min, energy_max], 12 corrector iterations, and land_on = include then energy_max.
inline PseudoArclengthOptions backbone_arclength(const BackboneContinuationOptions& o, double parameter_min) {
  PseudoArclengthOptions pa;
  pa.parameter_min = parameter_min;
  pa.parameter_max = o.energy_max;
  pa.initial_step = o.initial_step;
  pa.min_step = o.min_step;
  pa.max_step = o.max_step;
  pa.max_parameter_step = o.max_energy_step;
  pa.max_points = o.max_points;
  pa.corrector_tolerance = o.tolerance;
  pa.max_corrector_iterations = 12;
  pa.initial_newton = {.tolerance = o.tolerance, .max_iterations = o.max_newton_iterations};
  pa.on_point = o.on_point;
  // The range's end and the energies asked for are landed on by the continuation itself (on the
  // piece of the step that passes them).
  pa.land_on = o.include;
  pa.land_on.push_back(o.energy_max);
  return pa;
}

}  // namespace wbm::solvers::detail
