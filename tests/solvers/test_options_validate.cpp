// validate() of the options structs that had none (issue #41, item 1): each names the field, its
// value and the range, and accepts the defaults (with the range a response curve must be given).
// Each case breaks one field by hand: a validate() that skipped that check would fail it.
#include <limits>
#include <stdexcept>

#include <gtest/gtest.h>

#include <wbm/solvers/nonlinear_modes.hpp>
#include <wbm/solvers/response_curve.hpp>
#include <wbm/solvers/weighted_residual.hpp>

#include "testing.hpp"

namespace {

using wbm::testing::expect_throw_with;

}  // namespace

TEST(OptionsValidate, WeightedResidualOptionsNameTheField) {
  EXPECT_NO_THROW(wbm::solvers::WeightedResidualOptions{}.validate(64));
  EXPECT_NO_THROW(wbm::solvers::WeightedResidualOptions{.time_samples = 64}.validate(64));
  expect_throw_with<std::invalid_argument>([] { wbm::solvers::WeightedResidualOptions{.residual_tolerance = 0.0}.validate(64); },
                                           {"WeightedResidualOptions.residual_tolerance = 0", "> 0", "1e-8"});
  expect_throw_with<std::invalid_argument>([] { wbm::solvers::WeightedResidualOptions{.time_samples = 63}.validate(64); },
                                           {"time_samples Q = 63", ">= M = 64"});
  expect_throw_with<std::invalid_argument>([] { wbm::solvers::WeightedResidualOptions{.homotopy_max_points = 1}.validate(64); },
                                           {"homotopy_max_points = 1", ">= 2"});
  wbm::solvers::WeightedResidualOptions newton;
  newton.newton.tolerance = -1.0;
  expect_throw_with<std::invalid_argument>([&] { newton.validate(64); }, {"tolerance"});
}

TEST(OptionsValidate, ResponseCurveOptionsNameTheField) {
  auto valid = [] {
    wbm::solvers::ResponseCurveOptions o;
    o.parameter_min = 10.0;
    o.parameter_max = 20.0;
    return o;
  };
  EXPECT_NO_THROW(valid().validate());
  expect_throw_with<std::invalid_argument>([] { wbm::solvers::ResponseCurveOptions{}.validate(); },
                                           {"ResponseCurveOptions.parameter_min = 0", "parameter_max = 0", "<"});
  auto o = valid();
  o.threads = -1;
  expect_throw_with<std::invalid_argument>([&] { o.validate(); }, {"ResponseCurveOptions.threads = -1", ">= 0"});
  o = valid();
  o.samples = 7;
  expect_throw_with<std::invalid_argument>([&] { o.validate(); }, {"ResponseCurveOptions.samples = 7", ">= 8"});
  o = valid();
  o.max_state = -1.0;
  expect_throw_with<std::invalid_argument>([&] { o.validate(); }, {"ResponseCurveOptions.max_state = -1", ">= 0"});
  o = valid();
  o.max_parameter_step = std::numeric_limits<double>::infinity();
  expect_throw_with<std::invalid_argument>([&] { o.validate(); }, {"ResponseCurveOptions.max_parameter_step = inf"});
  o = valid();
  o.initial_step = 1.0;  // above max_step = 2e-2
  expect_throw_with<std::invalid_argument>([&] { o.validate(); }, {"initial_step = 1", "min_step <= initial_step <= max_step"});
  o = valid();
  o.corrector_tolerance = 0.0;
  expect_throw_with<std::invalid_argument>([&] { o.validate(); }, {"ResponseCurveOptions.corrector_tolerance = 0"});
  o = valid();
  o.max_corrector_iterations = 0;
  expect_throw_with<std::invalid_argument>([&] { o.validate(); }, {"ResponseCurveOptions.max_corrector_iterations = 0"});
  o = valid();
  o.direction = 0;
  expect_throw_with<std::invalid_argument>([&] { o.validate(); }, {"ResponseCurveOptions.direction = 0", "+1 or -1"});
  o = valid();
  o.max_points = 0;
  expect_throw_with<std::invalid_argument>([&] { o.validate(); }, {"ResponseCurveOptions.max_points = 0"});
}

TEST(OptionsValidate, BackboneOptionsNameTheField) {
  EXPECT_NO_THROW(wbm::solvers::BackboneOptions{}.validate());
  wbm::solvers::BackboneOptions reversed;
  reversed.energy_min = 2.0;
  reversed.energy_max = 1.0;
  expect_throw_with<std::invalid_argument>([&] { reversed.validate(); }, {"BackboneOptions.energy_min = 2", "energy_max = 1"});
  wbm::solvers::BackboneOptions step;
  step.min_step = 0.0;
  expect_throw_with<std::invalid_argument>([&] { step.validate(); }, {"BackboneOptions.min_step = 0"});
  wbm::solvers::BackboneOptions budget;
  budget.max_wall_time_s = -1.0;
  expect_throw_with<std::invalid_argument>([&] { budget.validate(); }, {"BackboneOptions.max_wall_time_s = -1", ">= 0"});
}
