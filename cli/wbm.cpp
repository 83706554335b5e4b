// The `wbm` command: run, check and list what a scene file can ask for (docs/scenes.md).
//   wbm run SCENE [-o DIR] [--quiet] [--no-plots]
//                                      solve; CSV (and MAT) files and result.json in DIR, then
//                                      PNG pictures of them (wbm_plot.py, matplotlib)
//   wbm plot DIR [--quiet]             draw the PNG pictures of a result folder again
//   wbm check SCENE [--json]           validate only (runs no tool: a deck is read, not reduced);
//                                      print the resolved scene
//   wbm bases [-M M]                   bases and the formulations each admits
//   wbm study STUDY [-o DIR] [--workers N] [--scheduler ADDR] [-q]
//                                      a parametric or Monte Carlo study on Dask: this process
//                                      becomes `python3 -m wbm_study` (python/wbm_study.py,
//                                      docs/studies.md), which runs each case with this wbm
//   wbm --version
// Exit status: 0 converged (or valid, for check); 1 not converged, a failed write, or a tool that
// failed (CalculiX, in `wbm reduce` and in a deck scene alike); 2 bad input (scene file, command
// line, unusable -o). Nothing is written on bad input. SIGINT or SIGTERM during `wbm run` stops
// at the next progress report: the staging folder (and a folder the run created) is removed, the
// previous result stays as it was, and the process ends by the same signal (exit 130 or 143 in
// a shell); a second signal ends it at once (the next run removes the leftover staging folder).
// wbm plot: 0 drawn, 1 matplotlib missing or drawing failed, 2 not a result folder. A run whose
// pictures fail still exits with the run's status (the pictures are extras; a warning says why).
#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>

#include <wbm/scene/analysis.hpp>
#include <wbm/scene/build_information.hpp>
#include <wbm/scene/output.hpp>
#include <wbm/scene/reduce.hpp>
#include <wbm/scene/scene.hpp>

namespace {

constexpr int kConverged = 0;
constexpr int kNotConverged = 1;
constexpr int kBadInput = 2;

// The signal that asked the run to stop (0: none). The handler only records it and restores the
// default action, so that a second signal ends the process at once.
volatile std::sig_atomic_t g_stop_signal = 0;

extern "C" void on_stop_signal(int signal_number) {
  g_stop_signal = signal_number;
  std::signal(signal_number, SIG_DFL);
}

// Thrown from the progress report once a stop signal has arrived: unwinding removes the staging.
struct Interrupted {};

// A progress bar on standard error, only on a terminal and only once a run has lasted 1 s:
// fraction done, what the analysis says (point, parameter, step size) and the elapsed time.
class ProgressBar {
 public:
  explicit ProgressBar(bool enabled) : enabled_(enabled && ::isatty(STDERR_FILENO) != 0) {}
  ~ProgressBar() {
    if (drawn_) std::cerr << "\n";
  }
  void operator()(double fraction, const std::string& label) {
    if (!enabled_) return;
    const double t = seconds();
    if (t < 1.0 || (t - last_ < 0.1 && fraction < 1.0)) return;
    last_ = t;
    constexpr int width = 30;
    const int filled = static_cast<int>(fraction * width + 0.5);
    std::cerr << "\r[" << std::string(static_cast<size_t>(filled), '#') << std::string(static_cast<size_t>(width - filled), '.')
              << "] " << static_cast<int>(fraction * 100.0 + 0.5) << "% " << label << ", " << static_cast<int>(t)
              << " s   " << std::flush;
    drawn_ = true;
  }

 private:
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }
  bool enabled_;
  bool drawn_ = false;
  double last_ = 0.0;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

// wbm_plot.py: <bindir>/../share/wbm/wbm_plot.py (installed) or the source tree's (build tree).
std::string plot_script() {
  std::error_code ec;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const auto installed = exe.parent_path().parent_path() / "share" / "wbm" / "wbm_plot.py";
    if (std::filesystem::exists(installed)) return installed.string();
  }
  return WBM_PLOT_SCRIPT;
}

// Runs wbm_plot.py on `folder` (no shell); returns its exit status (3: no matplotlib), or -1 if
// the interpreter could not be started.
int draw(const std::string& folder, bool quiet) {
  const std::string python = WBM_PYTHON, script = plot_script();
  std::vector<std::string> args = {python, script, folder};
  if (quiet) args.emplace_back("--quiet");
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::cout.flush();
  pid_t pid = 0;
  if (::posix_spawnp(&pid, python.c_str(), nullptr, nullptr, argv.data(), environ) != 0) return -1;
  int status = 0;
  if (::waitpid(pid, &status, 0) < 0 || !WIFEXITED(status)) return -1;
  return WEXITSTATUS(status);
}

// After a run: pictures, or a line saying why there are none. Never changes the exit status.
void draw_after_run(const std::string& folder, bool quiet) {
  const int status = draw(folder, quiet);
  if (status == 3) {
    std::cerr << "wbm: plots skipped: matplotlib is not available to " << WBM_PYTHON
              << " (install python3-matplotlib, or pass --no-plots)\n";
  } else if (status != 0) {
    std::cerr << "wbm: warning: drawing the pictures failed (" << WBM_PYTHON << " " << plot_script() << " " << folder
              << ", exit " << status << "); the result files are complete\n";
  }
}

// `wbm study`: replaces this process by `python3 -m wbm_study ARGS` with the wbm module's folder
// first on PYTHONPATH (the install's, <prefix>/WBM_PYTHON_INSTALL_DIR, if it holds wbm_study.py;
// else the build tree's) and WBM_CLI naming this executable, which the cases then run. Returns
// only if the interpreter cannot be started.
int study(const std::vector<std::string>& arguments) {
  std::error_code ec;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  std::filesystem::path folder = WBM_PYTHON_BUILD_DIR;
  if (!ec) {
    const auto installed = exe.parent_path().parent_path() / WBM_PYTHON_INSTALL_DIR;
    if (std::filesystem::exists(installed / "wbm_study.py")) folder = installed;
    ::setenv("WBM_CLI", exe.c_str(), 1);
  }
  const char* path = std::getenv("PYTHONPATH");
  const std::string python_path = folder.string() + (path && *path ? ":" + std::string(path) : "");
  ::setenv("PYTHONPATH", python_path.c_str(), 1);
  std::vector<std::string> args = {WBM_PYTHON, "-m", "wbm_study"};
  args.insert(args.end(), arguments.begin(), arguments.end());
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::cout.flush();
  ::execvp(WBM_PYTHON, argv.data());
  std::cerr << "wbm study: cannot start " << WBM_PYTHON << " -m wbm_study (" << std::strerror(errno)
            << "); install python3 with python3-dask and python3-distributed\n";
  return kNotConverged;
}

void print_warnings(const wbm::scene::Scene& s) {
  for (const auto& w : s.warnings) std::cerr << w << "\n";
}

// Loads a scene; prints its problems and returns nullopt with `status` set: kBadInput for a bad
// scene, kNotConverged when a tool it runs failed (CalculiX on a deck).
std::optional<wbm::scene::Scene> load(const std::string& path, int& status) {
  const auto print = [](const std::exception& e) {
    const std::string what = e.what();
    std::cerr << what;
    if (what.empty() || what.back() != '\n') std::cerr << "\n";
  };
  try {
    auto s = wbm::scene::load_scene(path);
    print_warnings(s);
    return s;
  } catch (const std::invalid_argument& e) {
    print(e);
    status = kBadInput;
  } catch (const std::runtime_error& e) {
    print(e);
    std::cerr << "wbm: a tool the scene runs failed (above)\n";
    status = kNotConverged;
  }
  std::cerr << "wbm: " << path << ": not run; nothing written\n";
  return std::nullopt;
}

// An -o given as "" or naming a file: the message, else "".
std::string unusable_output(const std::string& out, bool given) {
  if (given && out.empty()) return "-o '': an empty folder name; give a folder, or leave -o out (wbm-out/<name>)";
  std::error_code ec;
  if (!out.empty() && std::filesystem::exists(out, ec) && !std::filesystem::is_directory(out, ec)) {
    return "-o " + out + ": is a file, not a folder; give a folder (created if missing)";
  }
  return "";
}

// `wbm reduce`: exit 0 when written, 2 for bad input (nothing written), 1 when ccx or the
// reduction fails.
int reduce(const wbm::scene::ReductionRequest& request, std::string out, bool out_given, bool quiet) {
  if (const std::string why = unusable_output(out, out_given); !why.empty()) {
    std::cerr << "wbm reduce: " << why << "; nothing written\n";
    return kBadInput;
  }
  if (out.empty()) out = (std::filesystem::path("wbm-out") / (request.deck.stem().string() + "-reduced")).string();
  try {
    const nlohmann::json s = wbm::scene::reduce_deck(request, out);
    if (!quiet) {
      const auto& f = s["reduced_frequencies_hz"];
      std::cout << "wbm reduce: " << s["full_dofs"].get<int>() << " DOFs -> " << s["interface"]["dofs"].get<int>()
                << " interface DOFs (" << s["interface"]["nodes"].size() << " nodes) + " << s["modes"].get<int>()
                << " modes = " << s["reduced_dofs"].get<int>() << " in " << std::setprecision(3)
                << s["timings_s"]["total"].get<double>() << " s; first reduced frequency "
                << std::setprecision(7) << (f.empty() ? 0.0 : f[0].get<double>()) << " Hz";
      if (!s["check"].is_null()) {
        std::cout << "; worst relative error of the first " << s["check"]["relative_errors"].size()
                  << " frequencies against the full model " << std::setprecision(3)
                  << s["check"]["worst_relative_error"].get<double>();
      }
      std::cout << "\nwrote stiffness.mtx, mass.mtx, dofs.txt" << (request.recovery ? ", recovery.mtx, full_dofs.txt" : "")
                << " and reduction.json to " << out << "\n";
    }
    return kConverged;
  } catch (const std::invalid_argument& e) {
    std::cerr << "wbm reduce: " << e.what() << "\nwbm reduce: nothing written\n";
    return kBadInput;
  } catch (const std::exception& e) {
    std::cerr << "wbm reduce: " << e.what() << "\nwbm reduce: nothing written\n";
    return kNotConverged;
  }
}

int run(const std::string& scene_path, std::string out, bool out_given, bool quiet, bool plots,
        const std::string& command_line) {
  if (const std::string why = unusable_output(out, out_given); !why.empty()) {
    std::cerr << "wbm: " << why << "; not run\n";
    return kBadInput;
  }
  int status = kBadInput;
  auto scene = load(scene_path, status);
  if (!scene) return status;
  if (scene->structure && scene->structure->awaiting_reduction()) {  // CalculiX and Craig–Bampton, before -o exists
    if (!quiet) std::cerr << "wbm: reducing " << scene->structure->deck->file << " (CalculiX, Craig-Bampton)\n";
    const size_t known = scene->warnings.size();
    try {
      wbm::scene::reduce_structure(*scene);
    } catch (const std::invalid_argument& e) {
      std::cerr << "wbm: " << e.what() << "\nwbm: " << scene_path << ": not run; nothing written\n";
      return kBadInput;
    } catch (const std::exception& e) {
      std::cerr << "wbm: " << e.what() << "\nwbm: a tool the scene runs failed (above)\nwbm: " << scene_path
                << ": not run; nothing written\n";
      return kNotConverged;
    }
    for (size_t i = known; i < scene->warnings.size(); ++i) std::cerr << scene->warnings[i] << "\n";
  }
  if (out.empty()) out = (std::filesystem::path("wbm-out") / scene->name).string();
  std::optional<wbm::scene::StagedOutput> staged;
  try {
    staged.emplace(out);  // before the run, so an unusable -o fails at once
  } catch (const std::exception& e) {
    std::cerr << "wbm: -o " << out << ": cannot create the output folder (" << e.what() << "); not run\n";
    return kBadInput;
  }
  wbm::scene::AnalysisResult result;
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
  const auto stopped = [&staged]() {
    const int signal_number = g_stop_signal;
    staged.reset();  // the staging folder, and a folder created for it, go
    std::cerr << "\nwbm: stopped by signal " << signal_number << "; nothing written, the folder is as it was\n";
    std::signal(signal_number, SIG_DFL);
    std::raise(signal_number);
    return 128 + signal_number;  // if the default action returns (it does not for SIGINT and SIGTERM)
  };
  try {
    ProgressBar bar(!quiet);
    result = wbm::scene::run_analysis(*scene, [&](double f, const std::string& label) {
      if (g_stop_signal != 0) throw Interrupted{};
      bar(f, label);
    });
  } catch (const Interrupted&) {
    return stopped();
  } catch (const std::invalid_argument& e) {  // input only the analysis can judge, e.g. an overflowing f
    std::cerr << "wbm: " << e.what() << "\nwbm: " << scene_path << ": not run; nothing written\n";
    return kBadInput;
  }
  if (g_stop_signal != 0) return stopped();
  nlohmann::json json = {{"command", command_line},
                         {"scene_file", std::filesystem::absolute(scene_path).lexically_normal().string()},
                         {"scene", wbm::scene::to_json(*scene)},
                         {"warnings", scene->warnings},
                         {"run_warnings", result.warnings},
                         {"converged", result.converged()},
                         {"diagnostics", result.diagnostics},
                         {"build", wbm::scene::build_information()}};
  size_t files_written = 0;
  try {
    nlohmann::json files = nlohmann::json::array();
    const auto& formats = scene->output.formats;
    if (std::find(formats.begin(), formats.end(), "csv") != formats.end()) {
      for (const auto& t : result.tables) {
        staged->table(t);
        files.push_back(t.file);
      }
    }
    if (std::find(formats.begin(), formats.end(), "mat") != formats.end()) {
      staged->mat("result.mat", result.tables,
                  {{"scene_file", json["scene_file"].get<std::string>()},
                   {"scene", scene->name},
                   {"converged", result.converged() ? "true" : "false"},
                   {"command", command_line},
                   {"wbm_version", wbm::scene::build_information()["wbm"].get<std::string>()}});
      files.push_back("result.mat");
    }
    json["files"] = files;
    files_written = files.size();
    staged->text("result.json", json.dump(2) + "\n");
    std::signal(SIGINT, SIG_IGN);  // the commit is a few renames: let it finish
    std::signal(SIGTERM, SIG_IGN);
    staged->commit("result.json");
    std::signal(SIGINT, SIG_DFL);
    std::signal(SIGTERM, SIG_DFL);
  } catch (const std::exception& e) {
    std::cerr << "wbm: " << out << ": " << e.what() << "; nothing written\n";
    return kNotConverged;
  }
  for (const auto& w : result.warnings) std::cerr << "wbm: warning: " << w << "\n";
  if (!quiet) {
    std::cout << result.summary << "\n";
    std::cout << (result.converged() ? "converged" : "NOT converged (see result.json: diagnostics)") << "; wrote "
              << files_written << " result file(s) and result.json to " << out << "\n";
  }
  const auto& formats = scene->output.formats;
  if (plots && !result.tables.empty()) {
    if (std::find(formats.begin(), formats.end(), "csv") != formats.end()) {
      draw_after_run(out, quiet);
    } else if (!quiet) {
      std::cout << "no pictures: they are drawn from the CSV files ([output] formats has no \"csv\")\n";
    }
  }
  return result.converged() ? kConverged : kNotConverged;
}

int check(const std::string& scene_path, bool json) {
  int status = kBadInput;
  const auto scene = load(scene_path, status);
  if (!scene) return status;
  if (json) {
    std::cout << wbm::scene::to_json(*scene).dump(2) << "\n";
  } else {
    std::cout << scene_path << ": valid scene, analysis \"" << wbm::scene::to_string(scene->analysis.kind) << "\"";
    if (scene->analysis.kind != wbm::scene::AnalysisKind::Timestep) {
      std::cout << ", " << scene->basis.trial;
      if (scene->analysis.kind == wbm::scene::AnalysisKind::Solve) std::cout << ":" << scene->basis.weighting;
      std::cout << ", M = " << scene->basis.dimension;
    }
    if (scene->structure) std::cout << ", " << scene->structure->dofs() << " DOFs, " << scene->contacts.size() << " contact(s)";
    if (scene->structure && scene->structure->awaiting_reduction()) {
      std::cout << " (the deck's interface DOFs predicted from its text; CalculiX and the reduction run with `wbm run`)";
    }
    std::cout << "\n";
  }
  return kConverged;
}

// For every basis: pointwise derivatives, and the formulations it admits as a trial basis (with
// a Fourier weighting), as a weighting basis (with a Fourier trial) and paired with itself.
int bases(int dimension) {
  using wbm::solvers::Formulation;
  using wbm::solvers::TimeBasis;
  const Formulation forms[] = {Formulation::Strong, Formulation::Weak, Formulation::Distributional};
  auto admitted = [&](const TimeBasis& trial, const TimeBasis& weighting) {
    std::string s;
    for (Formulation f : forms) {
      if (wbm::solvers::inadmissibility(trial, weighting, f).empty()) {
        s += (s.empty() ? "" : ",") + std::string(wbm::solvers::to_string(f));
      }
    }
    return s.empty() ? std::string("-") : s;
  };
  try {
    const TimeBasis fourier = TimeBasis::fourier(dimension);
    std::printf("%-9s %-12s %-28s %-28s %s\n", "basis", "derivatives", "as trial (Fourier weighting)",
                "as weighting (Fourier trial)", "with itself (Galerkin)");
    for (const auto& name : TimeBasis::names()) {
      const TimeBasis b = TimeBasis::from_name(name, dimension);
      const std::string d = b.is_fourier() ? "all" : std::to_string(b.max_derivative());
      std::printf("%-9s %-12s %-28s %-28s %s\n", name.c_str(), d.c_str(), admitted(b, fourier).c_str(),
                  admitted(fourier, b).c_str(), admitted(b, b).c_str());
    }
  } catch (const std::invalid_argument& e) {
    std::cerr << "wbm bases: " << e.what() << "\n";
    return kBadInput;
  }
  std::printf("\nderivatives: largest pointwise time derivative (Hölder regularity; Haar none). Forms [JL14 Eqs. (14)-(16)]:\n"
              "strong needs the trial's q'' , weak q' and p', distributional the weighting's p''. Galerkin wavelet pairs\n"
              "use exact connection coefficients, which exist for d1 + d2 < 2s (s: Sobolev exponent) [B92].\n"
              "Other pairs are listed with the automatic operator rule at M = %d.\n",
              dimension);
  return kConverged;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"wbm: periodic vibrations with unilateral contact by weighted residuals in time "
               "(wavelet balance, harmonic balance) [Jones & Legrand 2014]"};
  app.require_subcommand(0, 1);
  const auto info = wbm::scene::build_information();
  app.set_version_flag("--version", "wbm " + info["wbm"].get<std::string>() + " (" +
                                        info["git_describe"].get<std::string>() + "; Eigen " +
                                        info["eigen"].get<std::string>() + ", FFTW " + info["fftw"].get<std::string>() +
                                        ", GSL " + info["gsl"].get<std::string>() + ", toml++ " +
                                        info["toml++"].get<std::string>() + ", CLI11 " + CLI11_VERSION + ")");

  std::string scene_path, out;
  bool quiet = false, json = false;
  int dimension = 64;
  auto* run_cmd = app.add_subcommand("run", "Run the analysis of a scene; write CSV files and result.json");
  run_cmd->add_option("scene", scene_path, "Scene file (.toml), or a result.json to re-run")->required();
  auto* run_out = run_cmd->add_option("-o,--output", out,
                                      "Output folder (default: wbm-out/<scene name>); the files of an earlier result "
                                      "there that this run does not write are removed");
  run_cmd->add_flag("-q,--quiet", quiet, "No summary and no progress bar");
  bool no_plots = false;
  run_cmd->add_flag("--no-plots", no_plots, "Do not draw PNG pictures of the results (matplotlib)");
  std::string plot_dir;
  auto* plot_cmd = app.add_subcommand("plot", "Draw the PNG pictures of a result folder of `wbm run` (matplotlib)");
  plot_cmd->add_option("folder", plot_dir, "Result folder (holds result.json)")->required();
  plot_cmd->add_flag("-q,--quiet", quiet, "Do not list the pictures drawn");
  auto* check_cmd = app.add_subcommand("check", "Validate a scene without running it");
  check_cmd->add_option("scene", scene_path, "Scene file (.toml or .json)")->required();
  check_cmd->add_flag("--json", json, "Print the resolved scene (every default filled in) as JSON");
  wbm::scene::ReductionRequest reduction;
  std::string deck_path;
  auto* reduce_cmd = app.add_subcommand(
      "reduce", "Reduce a CalculiX/Abaqus deck by Craig-Bampton (ccx assembles it); write Matrix Market K_r, M_r, "
                "dofs.txt and reduction.json for scenes");
  reduce_cmd->add_option("deck", deck_path, "Deck (.inp): nodes, elements, material, *BOUNDARY; its *STEPs are ignored")
      ->required();
  reduce_cmd->add_option("-i,--interface", reduction.interface,
                         "Interface: a node set of the deck, or node numbers \"17,18,19\"")->required();
  reduce_cmd->add_option("-m,--modes", reduction.modes, "Fixed-interface normal modes")->capture_default_str();
  reduce_cmd->add_option("--check", reduction.check_modes,
                         "Compare the first N frequencies with the full model's (sparse Lanczos, and ccx's own *FREQUENCY step); 0: no check")
      ->capture_default_str();
  reduce_cmd->add_flag("--recovery", reduction.recovery, "Also write recovery.mtx (u = T q) and full_dofs.txt");
  reduce_cmd->add_option("--ccx", reduction.ccx, "CalculiX executable")->capture_default_str();
  reduce_cmd->add_option("--units", reduction.units,
                         "The deck's unit system, converted to SI (N/m, kg, m, Hz): SI, N-m-kg-s, N-mm-t-s, kN-mm-kg-ms; "
                         "default: the deck's units, unconverted");
  auto* reduce_out = reduce_cmd->add_option("-o,--output", out, "Output folder (default: wbm-out/<deck>-reduced)");
  reduce_cmd->add_flag("-q,--quiet", quiet, "No summary");
  std::string study_path, scheduler;
  int workers = 0;
  auto* study_cmd = app.add_subcommand(
      "study", "Run a parametric or Monte Carlo study of a scene on Dask (docs/studies.md): study.csv, "
               "study.json, study.png and one result folder per case");
  study_cmd->add_option("study", study_path, "Study file (.toml)")->required();
  auto* study_out = study_cmd->add_option("-o,--output", out, "Study folder (default wbm-study/<title>); the cases "
                                                              "complete there are not run again");
  auto* study_workers = study_cmd->add_option("--workers", workers, "Worker processes of the local Dask cluster "
                                                                    "(default: one per core)")
                            ->check(CLI::PositiveNumber);
  auto* study_scheduler = study_cmd->add_option("--scheduler", scheduler, "tcp://HOST:PORT of a running Dask "
                                                                         "scheduler, instead of a local cluster");
  study_cmd->add_flag("-q,--quiet", quiet, "No progress lines");
  auto* bases_cmd = app.add_subcommand("bases", "List the time bases and the formulations each admits");
  bases_cmd->add_option("-M,--dimension", dimension, "Dimension M = 2^J used for the check")->capture_default_str();

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : kBadInput;
  }
  std::string command_line;
  for (int i = 0; i < argc; ++i) command_line += (i ? " " : "") + std::string(argv[i]);
  try {
    if (*run_cmd) return run(scene_path, out, run_out->count() > 0, quiet, !no_plots, command_line);
    if (*plot_cmd) {
      const int status = draw(plot_dir, quiet);
      if (status == 3) return kNotConverged;
      if (status == 2) return kBadInput;
      if (status != 0) {
        std::cerr << "wbm plot: " << WBM_PYTHON << " " << plot_script() << " failed (exit " << status << ")\n";
        return kNotConverged;
      }
      return kConverged;
    }
    if (*check_cmd) return check(scene_path, json);
    if (*bases_cmd) return bases(dimension);
    if (*study_cmd) {
      std::vector<std::string> args = {study_path};
      if (study_out->count() > 0) args.insert(args.end(), {"--output", out});
      if (study_workers->count() > 0) args.insert(args.end(), {"--workers", std::to_string(workers)});
      if (study_scheduler->count() > 0) args.insert(args.end(), {"--scheduler", scheduler});
      if (quiet) args.emplace_back("--quiet");
      return study(args);
    }
    if (*reduce_cmd) {
      reduction.deck = deck_path;
      return reduce(reduction, out, reduce_out->count() > 0, quiet);
    }
  } catch (const std::exception& e) {
    std::cerr << "wbm: " << e.what() << "\n";
    return kNotConverged;
  }
  std::cout << app.help();
  return kConverged;
}
