#pragma once
// The checks of ContactPoint::second_tangent (mechanical_system.hpp), part of ContactPoint::validate.
#include <vector>

#include <wbm/solvers/mechanical_system.hpp>

namespace wbm::solvers::detail {

// Throws std::invalid_argument as ContactPoint::validate documents for second_tangent.
void validate_second_tangents(const std::vector<ContactPoint>& contacts);

}  // namespace wbm::solvers::detail
