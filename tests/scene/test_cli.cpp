// The `wbm` command end to end (the executable, run as a user would): the Case 1 scene gives the
// reproduce executable's numbers exactly; bad input exits 2 and writes nothing; non-convergence
// exits 1 with its diagnostics; a result.json re-runs to the same files.
#include <algorithm>
#include <complex>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <iomanip>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sys/wait.h>
#include "scratch.hpp"

#include <wbm/fem/calculix.hpp>
#include <wbm/fem/matrix_market.hpp>
#include <wbm/scene/analysis.hpp>
#include <wbm/scene/scene.hpp>

#include "shipped_scenes.hpp"  // models/: the shipped scene directory

namespace {

namespace fs = std::filesystem;

struct Outcome {
  int status;
  std::string out, err;
};

// A scratch folder per process, removed at exit.
const fs::path& cli_work() {
  static const wbm::testing::ScratchDir scratch("cli");
  return scratch.path();
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

Outcome run_wbm(const std::string& args) {
  const fs::path out = cli_work() / "stdout", err = cli_work() / "stderr";
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

std::string case1() { return (wbm::models::scene_directory() / "jl14_case1.toml").string(); }

}  // namespace

// The Case 1 scene (Fourier:Fourier, M = 64, distributional) through `wbm run` writes, digit
// for digit, the harmonic-balance column of Fig. 6 written by jl14_fig06_tip_displacement.
TEST(Cli, Case1ReproducesTheFigureExecutableExactly) {
#ifndef WBM_FIG06
  GTEST_SKIP() << "the reproductions are not built (-DWBM_BUILD_REPRODUCE=OFF): no Fig. 6 executable to compare with";
#else
  const fs::path out = cli_work() / "case1", fig = cli_work() / "fig";
  const Outcome run = run_wbm("run --no-plots " + case1() + " -o " + out.string());
  ASSERT_EQ(run.status, 0) << run.err;
  // The status line itself ("NOT converged" also contains "converged").
  EXPECT_NE(run.out.find("\nconverged; wrote "), std::string::npos) << run.out;
  EXPECT_EQ(run.out.find("NOT converged"), std::string::npos) << run.out;
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
  const fs::path again = cli_work() / "again";
  ASSERT_EQ(run_wbm("run --no-plots -q " + (out / "result.json").string() + " -o " + again.string()).status, 0);
  EXPECT_EQ(slurp(out / "displacement.csv"), slurp(again / "displacement.csv"));
#endif
}

// Bad input: exit 2, one line per problem on standard error, and no output folder at all.
TEST(Cli, BadSceneExitsTwoAndWritesNothing) {
  const fs::path scene = cli_work() / "bad.toml", out = cli_work() / "never";
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
  EXPECT_EQ(run_wbm("run --no-plots " + (cli_work() / "absent.toml").string()).status, 2);
  EXPECT_EQ(run_wbm("frobnicate").status, 2);
  const fs::path file = cli_work() / "a_file";
  std::ofstream(file) << "not a folder\n";
  const Outcome blocked = run_wbm("run --no-plots " + case1() + " -o " + file.string());
  EXPECT_EQ(blocked.status, 2);
  EXPECT_NE(blocked.err.find("is a file, not a folder"), std::string::npos) << blocked.err;
}

// Non-convergence is an outcome: exit 1, result.json with the Newton report, no curve files.
TEST(Cli, NonConvergenceExitsOneWithDiagnostics) {
  const fs::path scene = cli_work() / "stiff.toml", out = cli_work() / "stiff";
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
  const fs::path out = cli_work() / "pictures";
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
  const fs::path bare = cli_work() / "no-pictures";
  ASSERT_EQ(run_wbm("run --no-plots -q " + scene.string() + " -o " + bare.string()).status, 0);
  EXPECT_TRUE(fs::exists(bare / "displacement.csv"));
  EXPECT_FALSE(fs::exists(bare / "time_histories.png"));
  const Outcome refused = run_wbm("plot " + (cli_work() / "absent").string());
  EXPECT_EQ(refused.status, 2);
  EXPECT_NE(refused.err.find("no result.json"), std::string::npos) << refused.err;
}

namespace {

// A 1 m × 0.1 m × 0.1 m steel bar along x of 8 C3D8 bricks, clamped at x = 0 (set ROOT, nodes
// 1–4), its tip face the set TIP (nodes 33–36): 96 free DOFs.
// The clamped bar, 1 m × 0.1 m × 0.1 m steel, 8 C3D8 bricks, sets ROOT and TIP (nodes 33–36);
// with `millimetres` the same bar in N-mm-t-s (mm, N/mm², t/mm³) as bar_mm.inp.
fs::path write_reduce_bar(bool millimetres = false) {
  const fs::path dir = cli_work() / "reduce";
  fs::create_directories(dir);
  std::ostringstream m;
  m << std::setprecision(17);
  auto id = [](int i, int j, int k) { return 1 + 4 * i + 2 * j + k; };
  const double l = millimetres ? 1e3 : 1.0;
  m << "*NODE\n";
  for (int i = 0; i <= 8; ++i)
    for (int j = 0; j <= 1; ++j)
      for (int k = 0; k <= 1; ++k) m << id(i, j, k) << ", " << 0.125 * i * l << ", " << 0.1 * j * l << ", " << 0.1 * k * l << "\n";
  m << "*ELEMENT, TYPE=C3D8, ELSET=EALL\n";
  for (int i = 0; i < 8; ++i) {
    m << i + 1 << ", " << id(i, 0, 0) << ", " << id(i + 1, 0, 0) << ", " << id(i + 1, 1, 0) << ", " << id(i, 1, 0) << ", "
      << id(i, 0, 1) << ", " << id(i + 1, 0, 1) << ", " << id(i + 1, 1, 1) << ", " << id(i, 1, 1) << "\n";
  }
  m << "*NSET, NSET=ROOT, GENERATE\n1, 4\n*NSET, NSET=TIP, GENERATE\n33, 36\n"
    << "*MATERIAL, NAME=STEEL\n*ELASTIC\n" << (millimetres ? "210e3" : "210e9") << ", 0.3\n*DENSITY\n"
    << (millimetres ? "7.8e-9" : "7800.") << "\n*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL\n"
    << "*BOUNDARY\nROOT, 1, 3\n*STEP\n*STATIC\n*END STEP\n";
  const fs::path p = dir / (millimetres ? "bar_mm.inp" : "bar.inp");
  std::ofstream(p) << m.str();
  return p;
}

std::vector<std::string> lines_of(const fs::path& p) {
  std::ifstream in(p);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

double relative(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff();
}

}  // namespace

// `wbm reduce` on the clamped bar, interface = TIP (12 DOFs), 12 fixed-interface modes. Truths
// from the full model (CalculiX's own matrices, dense Eigen), none from the reduction code:
// - the interface block of K_r is the inverse of the full flexibility (K⁻¹)_bb (static
//   condensation), and K_r does not couple interface and modes;
// - recovery.mtx maps the reduced static solution of a tip load onto the full one exactly;
// - --check's full-model frequencies (sparse Lanczos) are the dense generalized eigenvalues, and
//   the reduced ones bound them from above (Rayleigh–Ritz) within 1 %;
// - a scene on the written files (structure.dofs = "dofs.txt") gives the full model's harmonic
//   response at half the first frequency.
TEST(Cli, ReduceWritesACraigBamptonModelThatScenesRun) {
  const fs::path deck = write_reduce_bar(), out = cli_work() / "reduce" / "red";
  const Outcome run = run_wbm("reduce " + deck.string() + " -i tip -m 12 --check 6 --recovery -o " + out.string());
  ASSERT_EQ(run.status, 0) << run.err;
  EXPECT_NE(run.out.find("96 DOFs -> 12 interface DOFs (4 nodes) + 12 modes = 24"), std::string::npos) << run.out;

  const auto full = wbm::fem::assemble_with_calculix(wbm::fem::read_calculix_deck(deck));
  const Eigen::MatrixXd k = Eigen::MatrixXd(full.stiffness), m = Eigen::MatrixXd(full.mass);
  ASSERT_EQ(k.rows(), 96);
  const Eigen::MatrixXd kr = Eigen::MatrixXd(wbm::fem::read_matrix_market_file((out / "stiffness.mtx").string()));
  const Eigen::MatrixXd mr = Eigen::MatrixXd(wbm::fem::read_matrix_market_file((out / "mass.mtx").string()));
  ASSERT_EQ(kr.rows(), 24);
  EXPECT_EQ(kr, kr.transpose());
  EXPECT_EQ(mr, mr.transpose());

  // dofs.txt: the tip nodes' translations in order, then the modes; rows of the full model.
  const auto names = lines_of(out / "dofs.txt");
  ASSERT_EQ(names.size(), 24u);
  std::vector<int> b;
  const char* axis[] = {"x", "y", "z"};
  for (int node = 33; node <= 36; ++node) {
    for (int d = 1; d <= 3; ++d) {
      EXPECT_EQ(names[b.size()], std::string("n").append(std::to_string(node)).append("_").append(axis[d - 1]));
      const auto it = std::find(full.dofs.begin(), full.dofs.end(), std::make_pair(node, d));
      ASSERT_NE(it, full.dofs.end());
      b.push_back(static_cast<int>(it - full.dofs.begin()));
    }
  }
  EXPECT_EQ(names[12], "mode1");
  EXPECT_EQ(names[23], "mode12");

  // Static condensation: K_r,bb⁻¹ = (K⁻¹)_bb; K_r,bη = 0.
  const Eigen::MatrixXd flexibility = k.ldlt().solve(Eigen::MatrixXd::Identity(96, 96));
  Eigen::MatrixXd flexibility_bb(12, 12);
  for (int i = 0; i < 12; ++i)
    for (int j = 0; j < 12; ++j) flexibility_bb(i, j) = flexibility(b[i], b[j]);
  EXPECT_LT(relative(kr.topLeftCorner(12, 12).inverse(), flexibility_bb), 1e-8);
  EXPECT_LT(kr.topRightCorner(12, 12).cwiseAbs().maxCoeff(), 1e-8 * kr.cwiseAbs().maxCoeff());

  // Recovery: T K_r⁻¹ Tᵀ f = K⁻¹ f for a load on the interface (1 kN along y at node 36).
  const Eigen::MatrixXd t = Eigen::MatrixXd(wbm::fem::read_matrix_market_file((out / "recovery.mtx").string()));
  ASSERT_EQ(t.rows(), 96);
  ASSERT_EQ(t.cols(), 24);
  const auto full_dofs = lines_of(out / "full_dofs.txt");
  ASSERT_EQ(full_dofs.size(), 96u);
  EXPECT_EQ(full_dofs[b[10]], "36.2");
  Eigen::VectorXd f = Eigen::VectorXd::Zero(96);
  f(b[10]) = 1e3;
  const Eigen::VectorXd u = k.ldlt().solve(f);
  const Eigen::VectorXd ur = t * kr.ldlt().solve(t.transpose() * f);
  EXPECT_LT((ur - u).cwiseAbs().maxCoeff(), 1e-9 * u.cwiseAbs().maxCoeff());

  // Frequencies: --check's reference is the full model's; the reduced ones are upper bounds.
  const auto summary = nlohmann::json::parse(slurp(out / "reduction.json"));
  // The Lanczos's work as used: a Krylov space holding the 12 modes took at least 12 applications.
  EXPECT_GE(summary["lanczos"]["operations"].get<long>(), 12);
  EXPECT_GE(summary["lanczos"]["passes"].get<long>(), 1);
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(k, m, Eigen::EigenvaluesOnly);
  const Eigen::VectorXd f_full = eig.eigenvalues().head(6).cwiseSqrt() / (2.0 * 3.14159265358979323846);
  const auto& check = summary["check"];
  ASSERT_EQ(check["full_frequencies_hz"].size(), 6u);
  for (int i = 0; i < 6; ++i) {
    const double reference = check["full_frequencies_hz"][i].get<double>(), reduced = check["reduced_frequencies_hz"][i].get<double>();
    EXPECT_NEAR(reference, f_full(i), 1e-8 * f_full(i)) << "mode " << i + 1;
    EXPECT_NEAR(check["ccx_frequencies_hz"][i].get<double>(), f_full(i), 1e-6 * f_full(i)) << "mode " << i + 1;  // 7 digits
    EXPECT_GE(reduced, f_full(i) * (1.0 - 1e-10)) << "mode " << i + 1;
    EXPECT_LT(reduced / f_full(i) - 1.0, 1e-2) << "mode " << i + 1;
  }

  // A scene on the reduced files: the tip's harmonic response at f1/2, C = 5 M, 1 kN along y
  // at node 36, against the full model's (K − ω²M + iωC)⁻¹ f.
  const double f1 = f_full(0), omega = 2.0 * 3.14159265358979323846 * 0.5 * f1, alpha = 5.0;
  const fs::path scene = cli_work() / "reduce" / "tip.toml", result = cli_work() / "reduce" / "tip";
  std::ofstream(scene) << "[structure]\nstiffness = \"red/stiffness.mtx\"\nmass = \"red/mass.mtx\"\ndofs = \"red/dofs.txt\"\n"
                       << "[damping]\nalpha = " << alpha << "\n[forcing]\namplitude = 1000.0\ndof = \"n36_y\"\n"
                       << "frequency_hz = " << std::setprecision(17) << 0.5 * f1 << "\n"
                       << "[basis]\ntrial = \"fourier\"\ndimension = 16\n"
                       << "[output]\nsamples = 64\ndofs = [\"n36_y\"]\nharmonics = 2\n";
  const Outcome solved = run_wbm("run --no-plots -q " + scene.string() + " -o " + result.string());
  ASSERT_EQ(solved.status, 0) << solved.err;
  const Eigen::MatrixXcd dynamic = k.cast<std::complex<double>>() - omega * omega * m.cast<std::complex<double>>() +
                                   std::complex<double>(0.0, omega * alpha) * m.cast<std::complex<double>>();
  const double expected = std::abs(dynamic.partialPivLu().solve(f.cast<std::complex<double>>())(b[10]));
  const auto amplitude = csv_column(result / "harmonics.csv", "A_n36_y [m]");
  ASSERT_EQ(amplitude.size(), 3u);
  std::printf("tip amplitude at f1/2 = %.6g Hz: reduced %s m, full %.17g m\n", 0.5 * f1, amplitude[1].c_str(), expected);
  EXPECT_NEAR(std::stod(amplitude[1]), expected, 1e-5 * expected);  // measured 9.7e-7: modes 13+ left out

  // A DOF name file of another model is refused by the scene, naming both sizes.
  const fs::path wrong = cli_work() / "reduce" / "wrong.toml";
  std::ofstream(wrong) << "[structure]\nstiffness = \"red/stiffness.mtx\"\nmass = \"red/mass.mtx\"\ndofs = \"red/full_dofs.txt\"\n"
                       << "[forcing]\namplitude = 1.0\ndof = 0\nfrequency_hz = 10.0\n";
  const Outcome refused = run_wbm("check " + wrong.string());
  EXPECT_EQ(refused.status, 2);
  EXPECT_NE(refused.err.find("names 96 DOFs, but M has 24 rows"), std::string::npos) << refused.err;
}

// A scene whose structure is the deck itself ([structure] deck = "bar.inp", interface, modes):
// the scene is reduced when it runs, and its harmonic tip response equals the full model's
// (K − ω²M + iωC)⁻¹ f (CalculiX's matrices, dense), as the scene on wbm reduce's files does; the
// same bar written in N-mm-t-s with units = "N-mm-t-s" gives the same response in metres (1e-9).
// [[contact]] nodes = "TIP" with direction = "radial" about structure.axis (the bar's centre
// line) places one contact per tip node along the closed-form radial unit vector: the corners
// of the 0.1 m square at ±1/√2 in y and z. The resolved scene (check --json) names the deck, not
// matrices, and reads back to the same contacts. `wbm check` runs no tool: with ccx pointing
// nowhere it passes and `wbm run` exits 1 naming ccx. An *EQUATION that ties an interface DOF
// passes check (the names are predicted from *BOUNDARY) and `wbm run` refuses it with exit 2,
// naming the DOF CalculiX dropped. Refusals name the key and the way out.
TEST(Cli, ADeckSceneIsReducedWhenRunNotWhenCheckedAndTakesRadialContactsOnANodeSet) {
  const fs::path deck = write_reduce_bar(), dir = deck.parent_path();
  const auto full = wbm::fem::assemble_with_calculix(wbm::fem::read_calculix_deck(deck));
  const Eigen::MatrixXd k = Eigen::MatrixXd(full.stiffness), m = Eigen::MatrixXd(full.mass);
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(k, m, Eigen::EigenvaluesOnly);
  const double f1 = std::sqrt(eig.eigenvalues()(0)) / (2.0 * 3.14159265358979323846);
  const double omega = 2.0 * 3.14159265358979323846 * 0.5 * f1, alpha = 5.0;
  const std::string structure = "[structure]\ndeck = \"bar.inp\"\ninterface = \"tip\"\nmodes = 12\n";
  const std::string rest = "[damping]\nalpha = " + std::to_string(alpha) + "\n[forcing]\namplitude = 1000.0\n"
                           "dof = \"n36_y\"\nfrequency_hz = ";
  std::ostringstream freq;
  freq << std::setprecision(17) << 0.5 * f1;
  const fs::path scene = dir / "deck_tip.toml", result = dir / "deck_tip";
  std::ofstream(scene) << structure << rest << freq.str() << "\n[basis]\ntrial = \"fourier\"\ndimension = 16\n"
                       << "[output]\nsamples = 64\ndofs = [\"n36_y\"]\nharmonics = 2\n";
  const Outcome solved = run_wbm("run --no-plots -q " + scene.string() + " -o " + result.string());
  ASSERT_EQ(solved.status, 0) << solved.err;
  int row = -1;
  for (size_t r = 0; r < full.dofs.size(); ++r) {
    if (full.dofs[r] == std::make_pair(36, 2)) row = static_cast<int>(r);
  }
  ASSERT_GE(row, 0);
  Eigen::VectorXd f = Eigen::VectorXd::Zero(k.rows());
  f(row) = 1e3;
  const Eigen::MatrixXcd dynamic = k.cast<std::complex<double>>() - omega * omega * m.cast<std::complex<double>>() +
                                   std::complex<double>(0.0, omega * alpha) * m.cast<std::complex<double>>();
  const double expected = std::abs(dynamic.partialPivLu().solve(f.cast<std::complex<double>>())(row));
  const auto amplitude = csv_column(result / "harmonics.csv", "A_n36_y [m]");
  ASSERT_EQ(amplitude.size(), 3u);
  EXPECT_NEAR(std::stod(amplitude[1]), expected, 1e-5 * expected);
  const auto reduction = nlohmann::json::parse(slurp(result / "result.json"))["diagnostics"]["reduction"];
  EXPECT_EQ(reduction["full_dofs"], 96);
  EXPECT_EQ(reduction["reduced_dofs"], 24);  // 4 tip nodes × 3 + 12 modes

  // The library alike: load_scene leaves the deck unreduced, run_analysis reduces it (same response).
  const wbm::scene::Scene parsed = wbm::scene::load_scene(scene);
  ASSERT_TRUE(parsed.structure && parsed.structure->awaiting_reduction());
  EXPECT_EQ(parsed.structure->dofs(), 24);
  EXPECT_THROW((void)parsed.system(), std::logic_error);
  const wbm::scene::AnalysisResult direct = wbm::scene::run_analysis(parsed);
  EXPECT_TRUE(direct.converged());
  EXPECT_EQ(direct.diagnostics["reduction"]["reduced_dofs"], 24);

  // `wbm check` runs no tool; `wbm run` does.
  const fs::path nowhere = dir / "deck_no_ccx.toml";
  std::ofstream(nowhere) << structure << "ccx = \"" << (dir / "no-ccx").string() << "\"\n" << rest << freq.str() << "\n";
  const Outcome checked_only = run_wbm("check " + nowhere.string());
  EXPECT_EQ(checked_only.status, 0) << checked_only.err;
  EXPECT_NE(checked_only.out.find("24 DOFs"), std::string::npos) << checked_only.out;
  EXPECT_NE(checked_only.out.find("CalculiX and the reduction run with `wbm run`"), std::string::npos) << checked_only.out;
  const Outcome no_ccx = run_wbm("run --no-plots -q " + nowhere.string() + " -o " + (dir / "deck_no_ccx").string());
  EXPECT_EQ(no_ccx.status, 1);
  EXPECT_NE(no_ccx.err.find("cannot run"), std::string::npos) << no_ccx.err;
  EXPECT_NE(no_ccx.err.find("a tool the scene runs failed"), std::string::npos) << no_ccx.err;
  EXPECT_FALSE(fs::exists(dir / "deck_no_ccx"));

  // An *EQUATION making n36_y dependent: predicted, then dropped by CalculiX; refused at run.
  std::string tied = slurp(deck);
  tied.insert(tied.find("*STEP"), "*EQUATION\n2\n36, 2, 1.0, 35, 2, -1.0\n");
  std::ofstream(dir / "bar_tied.inp") << tied;
  const fs::path tied_scene = dir / "deck_tied.toml";
  std::ofstream(tied_scene) << "[structure]\ndeck = \"bar_tied.inp\"\ninterface = \"tip\"\nmodes = 12\n" << rest
                            << freq.str() << "\n";
  EXPECT_EQ(run_wbm("check " + tied_scene.string()).status, 0);
  const Outcome tied_run = run_wbm("run --no-plots -q " + tied_scene.string() + " -o " + (dir / "deck_tied").string());
  EXPECT_EQ(tied_run.status, 2);
  for (const char* part : {"structure.deck: CalculiX keeps other interface DOFs than the deck's *BOUNDARY lines predict",
                           "(missing: n36_y; unexpected: none)", "the deck has *EQUATION", "`wbm reduce`"}) {
    EXPECT_NE(tied_run.err.find(part), std::string::npos) << part << "\n" << tied_run.err;
  }
  EXPECT_FALSE(fs::exists(dir / "deck_tied"));

  // The same bar written in N-mm-t-s, with units = "N-mm-t-s": converted to SI, the same response.
  write_reduce_bar(true);
  const fs::path mm_scene = dir / "deck_tip_mm.toml", mm_result = dir / "deck_tip_mm";
  std::ofstream(mm_scene) << "[structure]\ndeck = \"bar_mm.inp\"\ninterface = \"tip\"\nmodes = 12\nunits = \"N-mm-t-s\"\n"
                          << rest << freq.str() << "\n[basis]\ntrial = \"fourier\"\ndimension = 16\n"
                          << "[output]\nsamples = 64\ndofs = [\"n36_y\"]\nharmonics = 2\n";
  const Outcome mm = run_wbm("run --no-plots -q " + mm_scene.string() + " -o " + mm_result.string());
  ASSERT_EQ(mm.status, 0) << mm.err;
  const auto mm_amplitude = csv_column(mm_result / "harmonics.csv", "A_n36_y [m]");
  ASSERT_EQ(mm_amplitude.size(), 3u);
  EXPECT_NEAR(std::stod(mm_amplitude[1]), std::stod(amplitude[1]), 1e-9 * expected);

  // Radial contacts on the node set, about the bar's centre line.
  const std::string radial = structure + "axis = { point = [0.0, 0.05, 0.05], direction = [2.0, 0.0, 0.0] }\n" + rest +
                             "[100.0, 200.0]\n[analysis]\ntype = \"continuation\"\n"
                             "[[contact]]\nlaw = \"linear\"\nstiffness = 1e8\ngap = 1e-5\nnodes = \"TIP\"\n"
                             "direction = \"radial\"\n";
  const fs::path radial_scene = dir / "deck_radial.toml";
  std::ofstream(radial_scene) << radial;
  const Outcome checked = run_wbm("check --json " + radial_scene.string());
  ASSERT_EQ(checked.status, 0) << checked.err;
  const auto resolved = nlohmann::json::parse(checked.out);
  EXPECT_EQ(resolved["structure"]["type"], "deck");
  EXPECT_EQ(resolved["structure"]["interface"], "tip");
  ASSERT_EQ(resolved["contact"].size(), 4u);
  const double c = 1.0 / std::sqrt(2.0);
  const std::map<int, std::pair<double, double>> expected_normal = {{33, {-c, -c}}, {34, {-c, c}}, {35, {c, -c}}, {36, {c, c}}};
  for (const auto& contact : resolved["contact"]) {
    const auto& d = contact["direction"];
    ASSERT_EQ(d.size(), 2u) << d.dump();  // no x component: the axis is along x
    const std::string y = d.begin().key();
    const int node = std::stoi(y.substr(1, y.find('_') - 1));
    EXPECT_NEAR(d["n" + std::to_string(node) + "_y"].get<double>(), expected_normal.at(node).first, 1e-15) << node;
    EXPECT_NEAR(d["n" + std::to_string(node) + "_z"].get<double>(), expected_normal.at(node).second, 1e-15) << node;
    EXPECT_EQ(contact["gap"].get<double>(), 1e-5);
  }
  const fs::path again = dir / "deck_radial.json";
  std::ofstream(again) << checked.out;
  const Outcome reread = run_wbm("check --json " + again.string());
  ASSERT_EQ(reread.status, 0) << reread.err;
  EXPECT_EQ(nlohmann::json::parse(reread.out)["contact"], resolved["contact"]);

  auto refused = [&](const std::string& text, const std::string& message) {
    const fs::path bad = dir / "deck_bad.toml";
    std::ofstream(bad) << text;
    const Outcome r = run_wbm("check " + bad.string());
    EXPECT_EQ(r.status, 2) << text;
    EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
  };
  const std::string law = "[[contact]]\nlaw = \"linear\"\nstiffness = 1e8\ngap = 1e-5\n";
  refused(structure + rest + "100.0\n" + law + "nodes = \"TIP\"\ndirection = \"radial\"\n",
          "\"radial\" needs structure.axis = { point = [x, y, z], direction = [x, y, z] }");
  refused(structure + rest + "100.0\n" + law + "nodes = \"CASING\"\ndirection = [0.0, 0.0, 1.0]\n",
          "no node set 'CASING' in the deck; it defines: ROOT, TIP");
  refused(structure + rest + "100.0\n" + law + "nodes = [33, 5]\ndirection = [0.0, 0.0, 1.0]\n",
          "node 5 is not an interface node");
  refused(structure + rest + "100.0\n" + law + "nodes = [33]\n", "with nodes: \"radial\" (from structure.axis) or [x, y, z]");
  refused("[structure]\nmass = 1.0\nstiffness = 1.0\n[forcing]\namplitude = 1.0\nfrequency_hz = 1.0\n" + law +
              "nodes = [1]\ndirection = [1.0, 0.0, 0.0]\n",
          "nodes are for a structure read from a deck");
  refused("[structure]\ndeck = \"absent.inp\"\ninterface = \"TIP\"\n[forcing]\namplitude = 1.0\ndof = 0\n"
          "frequency_hz = 1.0\n",
          "structure.deck: deck: no file");
  refused("[structure]\ndeck = \"bar.inp\"\n[forcing]\namplitude = 1.0\ndof = 0\nfrequency_hz = 1.0\n",
          "structure.interface: missing");
  refused(structure + "units = \"mm\"\n" + rest + "100.0\n", "structure.units");
  refused("[structure]\ndeck = \"bar.inp\"\ninterface = \"tip\"\nmodes = 84\n" + rest + "100.0\n",
          "structure.modes: modes = 84: the interior has only 84 DOFs; ask for fewer modes (< 84)");
  refused("[structure]\ndeck = \"bar.inp\"\ninterface = [1, 33]\n" + rest + "100.0\n",
          "node 1 has no free DOF");
}

// `wbm reduce` refuses bad input with exit 2, says why and how out, and creates nothing; a deck
// CalculiX cannot assemble exits 1 with ccx's reason.
TEST(Cli, ReduceRefusesBadInputAndWritesNothing) {
  const fs::path deck = write_reduce_bar(), out = cli_work() / "reduce" / "never";
  auto refused = [&](const std::string& args, const std::string& message, int status = 2) {
    const Outcome r = run_wbm("reduce " + args + " -o " + out.string());
    EXPECT_EQ(r.status, status) << args << "\n" << r.err;
    EXPECT_NE(r.err.find(message), std::string::npos) << args << "\n" << r.err;
    EXPECT_NE(r.err.find("nothing written"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out)) << args;
  };
  refused(deck.string() + " -i BLADE_TIP", "no node set 'BLADE_TIP'; the deck defines: ");
  refused(deck.string() + " -i 35,999", "node 999 is not a node of");
  refused(deck.string() + " -i 1,33", "node 1 has no free DOF");
  refused(deck.string() + " -i 33,33", "node 33 is listed twice");
  refused(deck.string() + " -i TIP -m 84", "the interior has only 84 DOFs");
  refused(deck.string() + " -i TIP -m -1", "modes = -1: must be >= 0");
  refused((cli_work() / "reduce" / "absent.inp").string() + " -i TIP", "deck: no file");
  refused(deck.string() + " -i TIP --ccx " + (cli_work() / "no-ccx").string(), "cannot run", 1);
  // The bar without its *MATERIAL: CalculiX refuses it, and the message names the deck.
  std::string text = slurp(deck);
  text.erase(text.find("*MATERIAL"), text.find("*SOLID SECTION") - text.find("*MATERIAL"));
  const fs::path no_material = cli_work() / "reduce" / "no_material.inp";
  std::ofstream(no_material) << text;
  refused(no_material.string() + " -i TIP", "no_material.inp: CalculiX (ccx) could not assemble the model", 1);
}

// Issue #40, items 6 and 8: a result folder holds one result (the earlier result's files and
// pictures that the new run does not write go, a user's file stays, and `wbm plot` draws only
// what result.json lists); leftover staging folders of dead runs are removed; -o '' and -o FILE,
// a directory given as a scene or a matrix, an unknown type or law each give one message and
// exit 2, with no follow-on errors; CalculiX failing exits 1 from a deck scene as from reduce.
TEST(Cli, AResultFolderHoldsOneResultAndEdgesHaveOneMessage) {
  const fs::path out = cli_work() / "one-result";
  const fs::path branch_scene = fs::path(WBM_EXAMPLES) / "oscillator_stop.toml";
  const fs::path solve_scene = fs::path(WBM_EXAMPLES) / "massless_contact_node.toml";
  const Outcome first = run_wbm("run -q " + branch_scene.string() + " -o " + out.string());
  ASSERT_EQ(first.status, 0) << first.err;
  const auto before = nlohmann::json::parse(slurp(out / "result.json"));
  ASSERT_FALSE(before["pictures"].empty()) << before.dump();
  std::ofstream(out / "notes.txt") << "mine\n";
  const pid_t dead = ::fork();  // a process that no longer exists: its staging folder is stale
  if (dead == 0) ::_exit(0);
  ::waitpid(dead, nullptr, 0);
  fs::create_directories(out / (".wbm-staging-" + std::to_string(dead)) / "x");
  const Outcome second = run_wbm("run -q " + solve_scene.string() + " -o " + out.string());
  ASSERT_EQ(second.status, 0) << second.err;
  const auto after = nlohmann::json::parse(slurp(out / "result.json"));
  std::vector<std::string> present;
  for (const auto& e : fs::directory_iterator(out)) present.push_back(e.path().filename().string());
  std::sort(present.begin(), present.end());
  std::vector<std::string> expected = {"notes.txt", "result.json"};
  for (const auto& f : after["files"]) expected.push_back(f.get<std::string>());
  for (const auto& f : after["pictures"]) expected.push_back(f.get<std::string>());
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(present, expected);
  for (const auto& f : before["files"]) {
    const std::string name = f.get<std::string>();
    const bool kept = std::find(expected.begin(), expected.end(), name) != expected.end();
    EXPECT_EQ(fs::exists(out / name), kept) << name;
  }

  const auto refused = [](const std::string& args, const std::vector<std::string>& messages, int status = 2,
                          const std::string& absent = "") {
    const Outcome r = run_wbm(args);
    EXPECT_EQ(r.status, status) << args << "\n" << r.err;
    for (const auto& m : messages) EXPECT_NE(r.err.find(m), std::string::npos) << args << "\n" << r.err;
    if (!absent.empty()) {
      EXPECT_EQ(r.err.find(absent), std::string::npos) << args << "\n" << r.err;
    }
    return r.err;
  };
  refused("run -q " + solve_scene.string() + " -o ''", {"-o '': an empty folder name"});
  refused("run -q " + cli_work().string(), {"is a directory, not a scene file"});
  const fs::path matrices = cli_work() / "matrices.toml";
  std::ofstream(matrices) << "[structure]\nmass = \".\"\nstiffness = [1.0]\n[forcing]\namplitude = 1.0\nfrequency_hz = 1.0\n";
  refused("check " + matrices.string(), {"structure.mass", "is a directory, not a Matrix Market file"});
  const fs::path absurd = cli_work() / "absurd.toml";  // only the analysis sees that (hΩ)² M overflows: still exit 2
  std::ofstream(absurd) << "structure = { mass = [1.0], stiffness = [4e4] }\nforcing = { amplitude = 1.0, frequency_hz = 1e300 }\n";
  refused("run -q " + absurd.string() + " -o " + (cli_work() / "absurd").string(), {"overflows", "nothing written"});
  EXPECT_FALSE(fs::exists(cli_work() / "absurd"));
  std::string nnm = slurp(fs::path(WBM_EXAMPLES) / "two_dof_nnm.toml");
  const auto variant = [&](const std::string& from, const std::string& to, const std::string& name) {
    std::string text = nnm;
    const size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
    std::ofstream(cli_work() / name) << text;
    return (cli_work() / name).string();
  };
  // One line each: the problem, then "not run; nothing written".
  const auto lines = [](const std::string& err) { return std::count(err.begin(), err.end(), '\n'); };
  EXPECT_EQ(lines(refused("check " + variant("type = \"nnm\"", "type = \"NNM\"", "upper.toml"),
                          {"\"NNM\" is not one of", "(names are lower case: \"nnm\")"}, 2, "[forcing]")),
            2);
  EXPECT_EQ(lines(refused("check " + variant("law = \"rigid\"", "law = \"penalty\"", "penalty.toml"),
                          {"a penalty law is \"linear\""}, 2, "contact.coefficient")),
            3);
  EXPECT_EQ(lines(refused("check " + variant("energy = [0.5, 3.0]", "", "no_energy.toml"), {"analysis.energy: missing"},
                          2, "analysis.levels")),
            2);
  // CalculiX refusing a deck (no *MATERIAL) is a tool failure: exit 1, from a scene as from reduce.
  std::string deck = slurp(write_reduce_bar());
  deck.erase(deck.find("*MATERIAL"), deck.find("*SOLID SECTION") - deck.find("*MATERIAL"));
  std::ofstream(cli_work() / "reduce" / "no_material_scene.inp") << deck;
  const fs::path deck_scene = cli_work() / "reduce" / "no_material.toml";
  std::ofstream(deck_scene) << "[structure]\ndeck = \"no_material_scene.inp\"\ninterface = \"tip\"\nmodes = 4\n"
                               "[forcing]\namplitude = 1.0\ndof = \"n36_y\"\nfrequency_hz = 10.0\n";
  refused("run -q " + deck_scene.string(), {"CalculiX (ccx) could not assemble the model", "a tool the scene runs failed"},
          1);
}

// SIGINT and SIGTERM during a run: the process ends by the signal, the folder keeps the earlier
// result byte for byte, no staging folder is left, and a folder the run created is removed.
TEST(Cli, InterruptLeavesTheFolderAsItWas) {
  std::string long_scene = slurp(fs::path(WBM_EXAMPLES) / "rod_continuation.toml");
  for (const auto& [from, to] : {std::pair<std::string, std::string>{"elements = 25", "elements = 200"},
                                 {"dimension = 64", "dimension = 256"}}) {
    ASSERT_NE(long_scene.find(from), std::string::npos);
    long_scene.replace(long_scene.find(from), from.size(), to);
  }
  const fs::path scene = cli_work() / "long.toml", kept = cli_work() / "kept", fresh = cli_work() / "fresh";
  std::ofstream(scene) << long_scene;
  ASSERT_EQ(run_wbm("run -q --no-plots " + (fs::path(WBM_EXAMPLES) / "massless_contact_node.toml").string() + " -o " +
                    kept.string())
                .status,
            0);
  const std::string result = slurp(kept / "result.json");
  for (const auto& [signal_number, folder] : {std::pair<int, fs::path>{SIGINT, kept}, {SIGTERM, fresh}}) {
    const pid_t pid = ::fork();
    if (pid == 0) {
      const std::string o = folder.string(), s = scene.string();
      ::execl(WBM_CLI, WBM_CLI, "run", "-q", "--no-plots", s.c_str(), "-o", o.c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
    // Wait (at most 60 s) for the staging folder, then signal.
    bool staging = false;
    for (int i = 0; i < 6000 && !staging; ++i) {
      std::error_code ec;
      if (fs::is_directory(folder, ec)) {
        for (const auto& e : fs::directory_iterator(folder, ec)) {
          staging = staging || e.path().filename().string().starts_with(".wbm-staging-");
        }
      }
      if (!staging) ::usleep(10000);
    }
    ASSERT_TRUE(staging);
    ::usleep(300000);  // into the continuation
    ::kill(pid, signal_number);
    int status = 0;
    ::waitpid(pid, &status, 0);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == signal_number) << status;
  }
  EXPECT_EQ(slurp(kept / "result.json"), result);
  for (const auto& e : fs::directory_iterator(kept)) {
    EXPECT_FALSE(e.path().filename().string().starts_with(".wbm-staging-")) << e.path();
  }
  EXPECT_FALSE(fs::exists(fresh));
}
