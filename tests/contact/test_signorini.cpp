// The Signorini conditions as the minimum complementarity function, and the rigid stop.
#include <wbm/contact/signorini.hpp>

#include <cmath>
#include <limits>
#include <stdexcept>

#include <gtest/gtest.h>

#include "testing.hpp"

using namespace wbm::contact;

// min(a, g) = 0 exactly on the complementarity set a ≥ 0, g ≥ 0, a g = 0, and its branch is
// the argument that is active (the tie a = g goes to the gap).
TEST(Signorini, MinimumFunctionVanishesExactlyOnTheComplementaritySet) {
  struct Case {
    double a, g;
    bool solution;
  };
  for (const Case c : {Case{0.0, 2.0, true}, {3.0, 0.0, true}, {0.0, 0.0, true}, {1.0, 1.0, false},
                       {-1.0, 2.0, false}, {2.0, -1e-9, false}, {-1.0, -2.0, false}}) {
    const Complementarity m = signorini_min(c.a, c.g);
    EXPECT_EQ(m.value == 0.0, c.solution) << c.a << ", " << c.g;
    EXPECT_EQ(m.value, std::min(c.a, c.g));
    EXPECT_EQ(m.gap_branch, c.g <= c.a);
  }
}

// A rigid stop says so, keeps its gap, stores no energy, and refuses to be sampled as a force law.
TEST(RigidStop, IsRigidAndHasNoForceLaw) {
  const RigidStop stop(1e-3);
  const ContactLaw& law = stop;
  EXPECT_TRUE(law.rigid());
  EXPECT_EQ(law.gap(), 1e-3);
  EXPECT_EQ(law.potential(0.5e-3), 0.0);
  wbm::testing::expect_throw_with<std::logic_error>([&] { (void)law.force(2e-3); }, {"rigid", "multiplier"});
  wbm::testing::expect_throw_with<std::logic_error>([&] { (void)law.stiffness(2e-3); }, {"rigid"});
  EXPECT_NE(law.describe().find("0.001"), std::string::npos);
  EXPECT_FALSE(LinearPenalty({1e9, 1e-3}).rigid());
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [] { RigidStop bad(std::numeric_limits<double>::quiet_NaN()); }, {"RigidStop.gap", "finite"});
}
