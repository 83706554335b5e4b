// The `wbm` command end to end (the executable, run as a user would): the Case 1 scene gives the
// reproduce executable's numbers exactly; bad input exits 2 and writes nothing; non-convergence
// exits 1 with its diagnostics; a result.json re-runs to the same files.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sys/wait.h>
#include <unistd.h>

#include "scene.hpp"  // reproduce/common: the shipped scene directory

namespace {

namespace fs = std::filesystem;

struct Outcome {
  int status;
  std::string out, err;
};

// A scratch folder per process, removed at exit.
struct Scratch {
  fs::path dir = fs::temp_directory_path() / ("wbm_test_cli_" + std::to_string(::getpid()));
  Scratch() { fs::create_directories(dir); }
  ~Scratch() {
    std::error_code ignored;
    fs::remove_all(dir, ignored);
  }
};

fs::path work() {
  static const Scratch scratch;
  return scratch.dir;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

Outcome run_wbm(const std::string& args) {
  const fs::path out = work() / "stdout", err = work() / "stderr";
  const std::string cmd = std::string(WBM_CLI) + " " + args + " > " + out.string() + " 2> " + err.string();
  const int raw = std::system(cmd.c_str());
  return {WIFEXITED(raw) ? WEXITSTATUS(raw) : -1, slurp(out), slurp(err)};
}

// Column `name` of a CSV file, as the text written (exact comparison, no parsing round-off).
std::vector<std::string> csv_column(const fs::path& file, const std::string& name) {
  std::ifstream in(file);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> header;
  std::stringstream hs(line);
  for (std::string h; std::getline(hs, h, ',');) header.push_back(h);
  const auto it = std::find(header.begin(), header.end(), name);
  EXPECT_NE(it, header.end()) << file << " has no column " << name;
  const auto c = static_cast<size_t>(it - header.begin());
  std::vector<std::string> values;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream ls(line);
    for (std::string v; std::getline(ls, v, ',');) cells.push_back(v);
    values.push_back(cells.at(c));
  }
  return values;
}

std::string case1() { return (wbm::reproduce::scene_directory() / "jl14_case1.toml").string(); }

}  // namespace

// The Case 1 scene (Fourier:Fourier, M = 64, distributional) through `wbm run` writes, digit
// for digit, the harmonic-balance column of Fig. 6 written by jl14_fig06_tip_displacement.
TEST(Cli, Case1ReproducesTheFigureExecutableExactly) {
  const fs::path out = work() / "case1", fig = work() / "fig";
  const Outcome run = run_wbm("run --no-plots " + case1() + " -o " + out.string());
  ASSERT_EQ(run.status, 0) << run.err;
  EXPECT_NE(run.out.find("converged"), std::string::npos);
  const std::string cmd = std::string(WBM_FIG06) + " --out " + fig.string() + " > /dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  const auto ours = csv_column(out / "displacement.csv", "u_node25 [m]");
  const auto figure = csv_column(fig / "jl14_fig06" / "tip_displacement.csv", "u_tip_fourier_fourier [m]");
  ASSERT_EQ(ours.size(), 1024u);
  EXPECT_EQ(ours, figure);
  const auto result = nlohmann::json::parse(slurp(out / "result.json"));
  EXPECT_TRUE(result["converged"].get<bool>());
  EXPECT_EQ(result["scene"]["basis"]["dimension"], 64);
  EXPECT_EQ(result["files"].size(), 5u);
  // Re-running the result.json gives the same files.
  const fs::path again = work() / "again";
  ASSERT_EQ(run_wbm("run --no-plots -q " + (out / "result.json").string() + " -o " + again.string()).status, 0);
  EXPECT_EQ(slurp(out / "displacement.csv"), slurp(again / "displacement.csv"));
}

// Bad input: exit 2, one line per problem on standard error, and no output folder at all.
TEST(Cli, BadSceneExitsTwoAndWritesNothing) {
  const fs::path scene = work() / "bad.toml", out = work() / "never";
  std::ofstream(scene) << "[structure]\nmass = 1.0\nstiffness = -4.0e4\nstifness = 1\n"
                          "[forcing]\namplitude = 1.0\nfrequency_hz = 10.0\n"
                          "[basis]\ntrial = \"db6\"\nweighting = \"fourier\"\nformulation = \"strong\"\n";
  const Outcome run = run_wbm("run --no-plots " + scene.string() + " -o " + out.string());
  EXPECT_EQ(run.status, 2);
  EXPECT_NE(run.err.find(scene.string() + ":4: structure.stifness: unknown key"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find(scene.string() + ":11: basis: not admissible: DB6:Fourier, strong form"), std::string::npos)
      << run.err;
  EXPECT_NE(run.err.find("not run; nothing written"), std::string::npos);
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(run_wbm("check " + scene.string()).status, 2);
  EXPECT_EQ(run_wbm("run --no-plots " + (work() / "absent.toml").string()).status, 2);
  EXPECT_EQ(run_wbm("frobnicate").status, 2);
  const fs::path file = work() / "a_file";
  std::ofstream(file) << "not a folder\n";
  const Outcome blocked = run_wbm("run --no-plots " + case1() + " -o " + file.string());
  EXPECT_EQ(blocked.status, 2);
  EXPECT_NE(blocked.err.find("cannot create the output folder"), std::string::npos) << blocked.err;
}

// Non-convergence is an outcome: exit 1, result.json with the Newton report, no curve files.
TEST(Cli, NonConvergenceExitsOneWithDiagnostics) {
  const fs::path scene = work() / "stiff.toml", out = work() / "stiff";
  std::ofstream(scene) << "structure = { mass = 1.0, stiffness = 4e4 }\ndamping = { alpha = 1.0 }\n"
                          "forcing = { amplitude = 100.0, frequency_hz = 30.0 }\n"
                          "contact = { law = \"linear\", stiffness = 1e9, gap = 1e-4 }\n"
                          "solver = { max_iterations = 1, line_search = false }\n";
  const Outcome run = run_wbm("run --no-plots -q " + scene.string() + " -o " + out.string());
  EXPECT_EQ(run.status, 1) << run.out << run.err;
  const auto result = nlohmann::json::parse(slurp(out / "result.json"));
  EXPECT_FALSE(result["converged"].get<bool>());
  EXPECT_FALSE(result["diagnostics"]["solution"]["newton"]["converged"].get<bool>());
  EXPECT_TRUE(result["files"].empty());
  EXPECT_FALSE(fs::exists(out / "displacement.csv"));
}

// check, bases and --version answer without running anything.
TEST(Cli, CheckBasesAndVersion) {
  const Outcome check = run_wbm("check --json " + case1());
  ASSERT_EQ(check.status, 0) << check.err;
  const auto resolved = nlohmann::json::parse(check.out);
  EXPECT_EQ(resolved["forcing"]["frequency_hz"], 150.0);
  EXPECT_EQ(resolved["solver"]["tolerance"], 1e-10);  // the default, made explicit
  const Outcome bases = run_wbm("bases");
  ASSERT_EQ(bases.status, 0);
  // [JL14 Table 2]: Haar trial functions only in the distributional form; DB6 has φ' but not φ''.
  EXPECT_NE(bases.out.find("haar      0            distributional "), std::string::npos) << bases.out;
  EXPECT_NE(bases.out.find("db6       1            weak,distributional "), std::string::npos) << bases.out;
  const Outcome version = run_wbm("--version");
  EXPECT_EQ(version.status, 0);
  EXPECT_NE(version.out.find("wbm 0.1.0"), std::string::npos) << version.out;
}

// Pictures: `wbm run` draws PNGs beside the CSV files (the massless-node example: one solve, so
// time_histories.png), `wbm plot DIR` draws them again, --no-plots draws none, and a folder
// without result.json is refused with exit 2. Checked: the PNG signature and the pixel size
// that the plot style asks for (6.4 in at 150 dpi = 960 px wide).
TEST(Cli, RunDrawsPicturesAndPlotRedrawsThem) {
  const fs::path scene = fs::path(WBM_EXAMPLES) / "massless_contact_node.toml";
  const fs::path out = work() / "pictures";
  const Outcome run = run_wbm("run " + scene.string() + " -o " + out.string());
  ASSERT_EQ(run.status, 0) << run.err;
  const fs::path png = out / "time_histories.png";
  auto png_width = [](const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    unsigned char h[24] = {};
    in.read(reinterpret_cast<char*>(h), 24);
    const bool signature = h[0] == 0x89 && h[1] == 'P' && h[2] == 'N' && h[3] == 'G' && h[12] == 'I' && h[13] == 'H';
    return signature ? (h[16] << 24) | (h[17] << 16) | (h[18] << 8) | h[19] : -1;
  };
  ASSERT_TRUE(fs::exists(png)) << run.out << run.err;
  EXPECT_EQ(png_width(png), 960);
  EXPECT_NE(run.out.find("drew 1 picture(s)"), std::string::npos) << run.out;
  fs::remove(png);
  const Outcome again = run_wbm("plot " + out.string());
  EXPECT_EQ(again.status, 0) << again.err;
  EXPECT_EQ(png_width(png), 960);
  const fs::path bare = work() / "no-pictures";
  ASSERT_EQ(run_wbm("run --no-plots -q " + scene.string() + " -o " + bare.string()).status, 0);
  EXPECT_TRUE(fs::exists(bare / "displacement.csv"));
  EXPECT_FALSE(fs::exists(bare / "time_histories.png"));
  const Outcome refused = run_wbm("plot " + (work() / "absent").string());
  EXPECT_EQ(refused.status, 2);
  EXPECT_NE(refused.err.find("no result.json"), std::string::npos) << refused.err;
}
