// Result files (wbm::scene output): a missing value is an empty cell beside a status; a failed
// write throws; non-finite columns and runs that did not commit write nothing.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <complex>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <regex>
#include <stdexcept>

#include <gtest/gtest.h>
#include <unistd.h>

#include <wbm/scene/analysis.hpp>
#include <wbm/scene/output.hpp>
#include <wbm/scene/scene.hpp>
#include <wbm/solvers/post_processing.hpp>

#include "shipped_scenes.hpp"  // models/: the shipped scene directory
#include "testing.hpp"
#include "scene_fixtures.hpp"

using wbm::scene::Scene;
using namespace wbm::testing;  // scene_fixtures.hpp, testing.hpp

// Result files: NaN never reaches a file, and a staged run leaves nothing until commit().
// One convention for a missing value: an empty cell beside a status column that says why, never
// 0 or −1; inf is never written; a missing value with no status is refused.
TEST(Output, MissingValuesAreEmptyCellsBesideAStatus) {
  const auto dir = temp("missing");
  std::filesystem::create_directories(dir);
  Eigen::VectorXd err(3), m(3);
  err << 1e-3, std::nan(""), 2.5e-5;
  m << 8, 16, 32;
  wbm::scene::write_table(dir / "t.csv", {"t.csv", {"M [-]", "tip_error [-]"}, {m, err}, {"converged", "stagnated", "converged"}});
  std::ifstream in(dir / "t.csv");
  std::string header, row1, row2, row3;
  std::getline(in, header);
  std::getline(in, row1);
  std::getline(in, row2);
  std::getline(in, row3);
  EXPECT_EQ(header, "M [-],tip_error [-],status");
  EXPECT_EQ(row1, "8,0.001,converged");
  EXPECT_EQ(row2, "16,,stagnated");
  EXPECT_EQ(row3, "32,2.5000000000000001e-05,converged");
  Eigen::VectorXd inf = m;
  inf(1) = std::numeric_limits<double>::infinity();
  expect_throw_with<std::invalid_argument>(
      [&] { wbm::scene::write_table(dir / "u.csv", {"u.csv", {"cond [-]"}, {inf}, {"a", "b", "c"}}); },
      {"u.csv: column \"cond [-]\" contains inf; not written"});
  expect_throw_with<std::invalid_argument>(
      [&] { wbm::scene::write_table(dir / "v.csv", {"v.csv", {"x [-]"}, {m}, {"a", "b"}}); },
      {"status column has 2 rows, the first column 3"});
  EXPECT_FALSE(std::filesystem::exists(dir / "u.csv"));
  EXPECT_FALSE(std::filesystem::exists(dir / "v.csv"));
  std::filesystem::remove_all(dir);
}

// A write that fails (a full device) is an error naming the file, not a silently short file.
TEST(Output, AFailedWriteThrows) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full on this system";
  expect_throw_with<std::runtime_error>([] { wbm::scene::write_text("/dev/full", std::string(1 << 16, 'x')); },
                                        {"/dev/full: write failed"});
  expect_throw_with<std::runtime_error>(
      [] { wbm::scene::write_table("/dev/full", {"full.csv", {"x [-]"}, {Eigen::VectorXd::Ones(4096)}}); },
      {"/dev/full: write failed"});
}

TEST(Output, NonFiniteColumnsAndUncommittedRunsWriteNothing) {
  const auto dir = temp("staged");
  std::filesystem::remove_all(dir);
  Eigen::VectorXd bad(2);
  bad << 1.0, std::nan("");
  {
    wbm::scene::StagedOutput out(dir);
    out.table({"good.csv", {"x [-]"}, {Eigen::VectorXd::Ones(2)}});
    expect_throw_with<std::invalid_argument>([&] { out.table({"bad.csv", {"x [-]"}, {bad}}); },
                                             {"bad.csv: column \"x [-]\" has missing values (NaN)",
                                              "no status column"});
  }  // no commit: the staging folder and the folder created for it are gone
  EXPECT_FALSE(std::filesystem::exists(dir));
  {
    wbm::scene::StagedOutput out(dir);
    out.table({"a.csv", {"x [-]"}, {Eigen::VectorXd::Ones(3)}});
    out.text("result.json", "{}\n");
    EXPECT_FALSE(std::filesystem::exists(dir / "a.csv"));
    const auto files = out.commit("result.json");
    ASSERT_EQ(files.size(), 2u);
    EXPECT_EQ(files.back().filename(), "result.json");  // the completion marker goes last
  }
  EXPECT_TRUE(std::filesystem::exists(dir / "a.csv"));
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir), {}), 2);  // no staging folder left
  std::filesystem::remove_all(dir);
}
