#include <wbm/contact/signorini.hpp>

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace wbm::contact {

RigidStop::RigidStop(double gap) : gap_(gap) {
  if (!std::isfinite(gap)) {
    std::ostringstream os;
    os << "RigidStop.gap (g0) = " << gap << ": must be finite [m]";
    throw std::invalid_argument(os.str());
  }
}

double RigidStop::force(double /*u*/) const {
  throw std::logic_error("RigidStop::force: a rigid stop has no force law f_c(u); its force is the multiplier of "
                         "the Signorini conditions, computed by the solver (check ContactLaw::rigid() first)");
}

double RigidStop::stiffness(double /*u*/) const {
  throw std::logic_error("RigidStop::stiffness: a rigid stop has no stiffness (check ContactLaw::rigid() first)");
}

std::string RigidStop::describe() const {
  std::ostringstream os;
  os << "rigid stop (Signorini conditions), g0 = " << gap_ << " m";
  return os.str();
}

}  // namespace wbm::contact
