// Scene loader of reproduce/common (toml++): every problem of a file is reported with file,
// line and key; the shipped scenes hold Table 1 of [JL14].
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include <gtest/gtest.h>

#include "scene.hpp"
#include "testing.hpp"

namespace {
std::string write_scene(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / (name + ".toml");
  std::ofstream(path) << text;
  return path.string();
}
}  // namespace

// Table 1, Case 2 of [JL14]: 1275 Hz, a_c = 1e8 N, α = 20, β = 5e-6, g0 = 14.5 mm.
TEST(Scene, ShippedCase2HoldsTable1) {
  const auto s = wbm::reproduce::load_scene("jl14_case2");
  EXPECT_EQ(s.frequency_hz, 1275.0);
  ASSERT_TRUE(s.contact.has_value());
  EXPECT_EQ(s.contact->coefficient, 1e8);
  EXPECT_EQ(s.contact->exponent, 20.0);
  EXPECT_EQ(s.beta, 5e-6);
  EXPECT_EQ(s.contact->gap, 14.5e-3);
}

TEST(Scene, ReportsEveryProblemWithLineAndKey) {
  const std::string path = write_scene("wbm_bad_scene",
                                       "title = 3\n"
                                       "[structure]\n"
                                       "young_modulus = -70e9\n"
                                       "density = 2700.0\n"
                                       "area = 25e-4\n"
                                       "length = 1.0\n"
                                       "elemnts = 25\n"
                                       "[damping]\nbeta = 1e-4\n"
                                       "[forcing]\namplitude = 250e3\nfrequency_hz = 150.0\n"
                                       "[contact]\nlaw = \"quadratic\"\ngap = 1e-3\n");
  wbm::testing::expect_throw_with<std::invalid_argument>(
      [&] { (void)wbm::reproduce::load_scene(path); },
      {path + ":1: title: expected a string", ":3: structure.young_modulus: value -7e+10 out of range",
       "structure.elemnts: unknown key", "structure.elements: expected an integer >= 1",
       "contact.law: \"quadratic\" is not one of \"exponential\", \"linear\""});
  std::filesystem::remove(path);
}

TEST(Scene, MissingFileNamesWhereItLooked) {
  wbm::testing::expect_throw_with<std::runtime_error>(
      [] { (void)wbm::reproduce::load_scene("no_such_scene"); }, {"no_such_scene", "no file"});
}
