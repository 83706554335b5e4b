#pragma once
// The parts of the Python module `wbm` bound outside wbm_module.cpp (each file one family of
// solvers), called from PYBIND11_MODULE there.
#include <pybind11/pybind11.h>

namespace wbm::python {

/// wbm.haar_impact: the Haar weighted residual with Newton's impact law (impact_bindings.cpp).
void bind_haar_impact(pybind11::module_& m);

}  // namespace wbm::python
