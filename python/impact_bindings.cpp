// wbm.haar_impact: periodic forced responses of point masses against rigid stops with Newton's
// impact law (solvers/haar_impact.hpp, issue #38 item 3).
#include <memory>
#include <tuple>
#include <utility>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <wbm/contact/signorini.hpp>
#include <wbm/solvers/haar_impact.hpp>

#include "bindings.hpp"

namespace py = pybind11;

namespace wbm::python {

void bind_haar_impact(py::module_& m) {
  m.def(
      "haar_impact",
      [](const solvers::MechanicalSystem& system, int dof, double amplitude, double frequency_hz,
         const std::vector<std::pair<int, double>>& stops, double restitution, int cells,
         const std::vector<std::tuple<int, double, double, int>>& loads, int transient_periods) {
        solvers::HarmonicForcing forcing{dof, amplitude, frequency_hz};
        for (const auto& [d, a, phase, h] : loads) forcing.more.push_back({d, a, phase, h});
        std::vector<solvers::ContactPoint> points;
        for (const auto& [d, gap] : stops) points.push_back({d, std::make_shared<contact::RigidStop>(gap)});
        solvers::HaarImpactOptions o;
        o.cells = cells;
        o.restitution = restitution;
        o.transient_periods = transient_periods;
        const auto s = solvers::solve_haar_impact(system, forcing, points, o);
        Eigen::VectorXd tau(cells);
        for (int k = 0; k < cells; ++k) tau(k) = (k + 0.5) / cells;
        py::dict out;
        out["converged"] = s.converged();
        out["status"] = std::string(solvers::to_string(s.status));
        out["message"] = s.message;
        out["newton_iterations"] = s.report.iterations;
        out["displacement"] = py::cast(s.displacement);
        out["impulses"] = py::cast(s.impulses);
        out["tau"] = py::cast(tau);
        out["residual"] = s.residual;
        out["complementarity"] = s.complementarity;
        out["penetration"] = s.penetration;
        out["reference_displacement"] = s.reference_displacement;
        out["impact_cells"] = s.impact_cells;
        return out;
      },
      py::arg("system"), py::arg("dof"), py::arg("amplitude"), py::arg("frequency_hz"), py::arg("stops"),
      py::arg("restitution") = 0.0, py::arg("cells") = 256,
      py::arg("loads") = std::vector<std::tuple<int, double, double, int>>{}, py::arg("transient_periods") = 30,
      R"(Periodic response of point masses against rigid stops with Newton's impact law
(solvers::solve_haar_impact, issue #38): the Haar weighted residual on `cells` = M boxes per period
with JL14's delta-pair velocity (the periodic central-difference scheme) and the law
0 <= P_k _|_ g - (u_{k+1} + e u_{k-1})/(1 + e) >= 0 (Paoli and Schatzman), e = restitution in [0, 1].
Load F cos(2 pi f t) on `dof`, plus loads: (dof, amplitude [N], phase [rad], harmonic >= 0) tuples.
stops: list of (dof, gap [m]). M must satisfy h omega_max < 2 (h = 1/(f M)): for point-mass models.
Returns a dict: converged (verified periodic residual and complementarity), status, message,
newton_iterations, displacement (n x M: the cell values [m], cell k = [k, k + 1) T/M), impulses
(n_stops x M [N s]), tau (the cells' midpoints), residual, complementarity, penetration (relative to
reference_displacement [m]), impact_cells. Non-convergence is returned, not raised; bad input
raises ValueError.)");
}

}  // namespace wbm::python
