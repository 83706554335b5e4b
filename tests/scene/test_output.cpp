// Result files (wbm::scene output): a missing value is an empty cell beside a status; a failed
// write throws; non-finite columns and runs that did not commit write nothing. The solver
// reports' one JSON form (wbm/scene/json.hpp): null for what is not finite or was not run.
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
#include <wbm/scene/json.hpp>
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

// Each report's serializer on values set by hand: the status word of the protocol, null for a
// NaN, an inf, a homotopy that was not tried and a periodicity before two periods, and no field
// lost on the way (the verified solution's own status beside its Newton report's).
TEST(Output, ReportsSerializeWithTheirStatusAndNullForWhatIsNotFinite) {
  namespace solvers = wbm::solvers;
  solvers::NewtonReport newton;
  newton.status = solvers::SolveStatus::Stagnated;
  newton.iterations = 3;
  newton.residual_norms = {1.0, std::numeric_limits<double>::infinity(), 0.25};
  newton.tolerance = 1e-10;
  newton.message = "no acceptable step";
  const nlohmann::json n = newton;
  EXPECT_EQ(n["status"], "stagnated");
  EXPECT_FALSE(n["converged"].get<bool>());
  EXPECT_EQ(n["iterations"], 3);
  EXPECT_EQ(n["residual_norms"], nlohmann::json::parse("[1.0, null, 0.25]"));
  EXPECT_EQ(n["tolerance"], 1e-10);
  EXPECT_TRUE(n["jacobian_rcond"].is_null());  // sparse LU: no estimate
  EXPECT_EQ(n["message"], "no acceptable step");
  EXPECT_TRUE(nlohmann::json(solvers::HomotopyReport{}).is_null());  // not tried

  solvers::WeightedResidualSolution s;
  s.report.status = solvers::SolveStatus::ResidualNotVerified;
  s.relative_residual = 3e-8;
  s.max_penetration = std::nan("");
  const nlohmann::json j = s;
  EXPECT_EQ(j["status"], "residual-not-verified");
  EXPECT_EQ(j["newton"]["status"], "residual-not-verified");
  EXPECT_FALSE(j["converged"].get<bool>());
  EXPECT_EQ(j["relative_residual"], 3e-8);
  EXPECT_TRUE(j["max_penetration_m"].is_null());
  EXPECT_FALSE(j.contains("coefficients"));  // arrays go to the tables, not the JSON

  solvers::TimeIntegrationReport t;
  t.status = solvers::SolveStatus::IntegratorFailed;
  t.periods = 1;
  const nlohmann::json tj = t;
  EXPECT_EQ(tj["status"], "integrator-failed");
  EXPECT_TRUE(tj["periodicity"].is_null());  // no δ before two periods
  t.periodicity = {0.5, 2e-7};
  EXPECT_EQ(nlohmann::json(t)["periodicity"], 2e-7);  // the last one

  solvers::ModeLevel level;
  level.status = solvers::SolveStatus::Converged;
  level.energy = 1.8;
  level.frequency_hz = std::numeric_limits<double>::quiet_NaN();
  const nlohmann::json lj = level;
  EXPECT_TRUE(lj["converged"].get<bool>());
  EXPECT_EQ(lj["energy"], 1.8);
  EXPECT_TRUE(lj["frequency_hz"].is_null());
}
