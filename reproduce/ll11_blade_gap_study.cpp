// Beyond LL11 Sec. 5.2 (issue #37): the resonance peak of the reduced compressor blade against
// random tip clearances, as a study on Dask. An out-of-round casing gives each blade position its
// own clearance; here each case draws one radial clearance g for all 24 tip stops, g ~ N(g0,
// (σ g0)²), while the load stays that of ll11_blade_forced at the nominal g0 (its linear peak
// reaches `overload` nominal gaps).
//
// The run builds the blade and its Craig–Bampton model exactly as ll11_blade_forced
// (models/blade_forced.hpp), writes it as a wbm scene in physical coordinates (K_r,
// M_r as Matrix Market files, C = β K_r, the load f = D⁻¹ s M̂ φ₁ as [[forcing.loads]], one
// linear penalty [[contact]] per tip node along its radial unit vector, continuation over
// [from, to] f1 without stability), and a study file over `contact.gap`. `wbm study` runs it
// on an embedded LocalCluster twice, with --workers 1 and --workers 2; the tables must agree
// bit for bit. Every number of the report is read from the two study.json files.
// Parameters: reproduce/scenes/ll11_blade_gap_study.toml ([quick] for --quick).
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

#include <spawn.h>
#include <sys/wait.h>

#include <nlohmann/json.hpp>

#include <wbm/fem/craig_bampton.hpp>
#include <wbm/fem/matrix_market.hpp>
#include <wbm/scene/output.hpp>

#include "blade.hpp"
#include "blade_forced.hpp"
#include "combinations.hpp"
#include "parameters.hpp"
#include "run.hpp"

extern char** environ;

namespace {

using namespace wbm;

// DOF names as `wbm reduce` writes them (dofs.txt): n<node>_x, _y, _z of each tip node in
// blade.boundary order, then mode1 … mode<m>.
std::vector<std::string> dof_names(const models::Blade& blade, Eigen::Index n) {
  std::vector<std::string> names;
  for (int node : blade.tip_nodes) {
    for (const char* c : {"x", "y", "z"}) names.push_back("n" + std::to_string(node) + "_" + c);
  }
  for (auto k = static_cast<Eigen::Index>(names.size()); k < n; ++k) {
    names.push_back("mode" + std::to_string(k - 3 * static_cast<Eigen::Index>(blade.tip_nodes.size()) + 1));
  }
  return names;
}

std::string matrix_market(const Eigen::MatrixXd& a, const std::string& comment) {
  std::ostringstream out;
  fem::write_matrix_market(out, a, true, comment);
  return out.str();
}

// Runs `wbm study STUDY -o DIR --workers N -q` and returns its exit status (−1: not started).
int run_study(const std::filesystem::path& study, const std::filesystem::path& out, int workers) {
  std::vector<std::string> args = {WBM_CLI, "study", study.string(), "-o", out.string(), "--workers",
                                   std::to_string(workers), "-q"};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  if (::posix_spawn(&pid, WBM_CLI, nullptr, nullptr, argv.data(), environ) != 0) return -1;
  int status = 0;
  if (::waitpid(pid, &status, 0) < 0 || !WIFEXITED(status)) return -1;
  return WEXITSTATUS(status);
}

nlohmann::json read_json(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path.string() + " (wbm study wrote no table)");
  return nlohmann::json::parse(in);
}

// Column j of a study table as numbers (NaN for a missing cell).
std::vector<double> column(const nlohmann::json& table, const std::string& header) {
  const auto& h = table.at("header");
  const auto it = std::find(h.begin(), h.end(), header);
  if (it == h.end()) throw std::runtime_error("study.json: no column \"" + header + "\"");
  const auto j = static_cast<size_t>(it - h.begin());
  std::vector<double> v;
  for (const auto& row : table.at("rows")) v.push_back(row[j].is_number() ? row[j].get<double>() : std::nan(""));
  return v;
}

double mean(const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size()); }
double stddev(const std::vector<double>& v) {
  const double m = mean(v);
  double s = 0.0;
  for (double x : v) s += (x - m) * (x - m);
  return v.size() > 1 ? std::sqrt(s / static_cast<double>(v.size() - 1)) : std::nan("");
}

// Spearman's rank correlation (no ties expected among continuous draws; ties get their order).
double rank_correlation(const std::vector<double>& x, const std::vector<double>& y) {
  auto ranks = [](const std::vector<double>& v) {
    std::vector<size_t> order(v.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return v[a] < v[b]; });
    std::vector<double> r(v.size());
    for (size_t k = 0; k < order.size(); ++k) r[order[k]] = static_cast<double>(k);
    return r;
  };
  const auto rx = ranks(x), ry = ranks(y);
  const double mx = mean(rx), my = mean(ry);
  double sxy = 0.0, sxx = 0.0, syy = 0.0;
  for (size_t k = 0; k < rx.size(); ++k) {
    sxy += (rx[k] - mx) * (ry[k] - my);
    sxx += (rx[k] - mx) * (rx[k] - mx);
    syy += (ry[k] - my) * (ry[k] - my);
  }
  return sxy / std::sqrt(sxx * syy);
}

}  // namespace

int main(int argc, char** argv) {
  auto run = reproduce::Run::from_args(argc, argv, "ll11_blade_gap_study");
  return run.execute([](reproduce::Run& run) {
    using reproduce::format;
    const auto parameters = reproduce::Parameters::load("ll11_blade_gap_study", run.quick());
    const double mesh_size = parameters.number("mesh.size_m");
    const double gap = parameters.number("contact.gap_m");
    const double from = parameters.number("response.from_f1"), to = parameters.number("response.to_f1");
    const int harmonics = parameters.integer("response.harmonics");
    const int samples = parameters.integer("study.samples"), full_samples = parameters.integer("study.full_samples");
    const double relative_std = parameters.number("study.relative_std");
    const int seed = parameters.integer("study.seed");
    const models::ScratchFolder scratch("wbm_ll11_blade_gap_study");

    // The blade, its Craig–Bampton model and the forced model, as ll11_blade_forced.
    const auto blade = models::build_blade(scratch.dir, mesh_size, parameters.integer("interface.tip_nodes"));
    const auto cb = fem::craig_bampton(blade.model.stiffness, blade.model.mass, blade.boundary,
                                       parameters.integer("interface.modes"));
    const auto model = models::blade_forced_model(
        blade, cb,
        {.gap = gap, .zeta = parameters.number("damping.zeta"), .overload = parameters.number("forcing.overload_gaps"),
         .stiffness_ratio = parameters.number("contact.stiffness_ratio"), .from_f1 = from,
         .mode_harmonics = parameters.integer("nnm.harmonics"), .mode_samples = parameters.integer("nnm.samples")});
    const auto n = static_cast<Eigen::Index>(model.reduced.mass.rows());
    const auto names = dof_names(blade, n);

    // The scene in physical coordinates q = D q̂: K_r, M_r, C = β K_r, f = D⁻¹ f̂, unit radial stops.
    const Eigen::MatrixXd k_r = 0.5 * (cb.stiffness + cb.stiffness.transpose()), m_r = 0.5 * (cb.mass + cb.mass.transpose());
    nlohmann::json loads = nlohmann::json::array();
    for (Eigen::Index j = 0; j < n; ++j) {
      if (model.load(j) != 0.0) {
        loads.push_back({{"dof", names[static_cast<size_t>(j)]}, {"amplitude", model.load(j) / model.scale(j)},
                         {"phase_rad", 0.0}, {"harmonic", 1}});
      }
    }
    nlohmann::json contacts = nlohmann::json::array();
    for (const auto& st : models::radial_stops(blade, gap)) {
      nlohmann::json direction = nlohmann::json::object();
      for (const auto& [j, w] : st.terms()) direction[names[static_cast<size_t>(j)]] = w;
      contacts.push_back({{"law", "linear"}, {"stiffness", model.penalty_stiffness}, {"gap", gap},
                          {"dof", names[static_cast<size_t>(st.dof)]}, {"direction", direction}});
    }
    const std::string observed = names[static_cast<size_t>(model.observed)];
    const nlohmann::json scene = {
        {"title", "LL11 blade (Craig-Bampton, " + std::to_string(n) + " DOFs) against " +
                      std::to_string(contacts.size()) + " radial penalty stops: first resonance"},
        {"structure", {{"stiffness", "blade_stiffness.mtx"}, {"mass", "blade_mass.mtx"}, {"dofs", names}}},
        {"damping", {{"beta", model.beta}}},
        {"forcing", {{"frequency_hz", {from * model.f1, to * model.f1}}, {"loads", loads}}},
        {"contact", contacts},
        {"basis", {{"trial", "fourier"}, {"harmonics", harmonics}}},
        {"analysis", {{"type", "continuation"}, {"stability", false},
                      {"max_frequency_step_hz", parameters.number("response.max_step_f1") * model.f1}}},
        {"output", {{"observe", {observed}}}}};
    auto study_file = [&](int n_samples) {
      std::ostringstream s;
      s << "# The clearance study of reproduce/ll11_blade_gap_study.cpp: `wbm study " << "FILE`.\n"
        << "title = \"blade-gaps\"\nscene = \"blade_scene.json\"\n"
        << "collect = [\"peak_amplitude:" << observed << "\", \"peak_frequency:" << observed
        << "\", \"points\", \"max:max_contact_force\", \"wall_time\"]\n"
        << "[[axis]]\nkey = \"contact.gap\"\nunit = \"m\"\n"
        << "random = { distribution = \"normal\", mean = " << format("%.17g", gap) << ", std = "
        << format("%.17g", relative_std * gap) << ", samples = " << n_samples << ", seed = " << seed << " }\n";
      return s.str();
    };
    const std::string k_text = matrix_market(k_r, "K_r of the LL11 blade (Craig-Bampton), N/m; rows: blade_scene.json dofs");
    const std::string m_text = matrix_market(m_r, "M_r of the LL11 blade (Craig-Bampton), kg; rows: blade_scene.json dofs");
    const std::string scene_text = scene.dump(2) + "\n";
    scene::write_text(scratch.dir / "blade_stiffness.mtx", k_text);
    scene::write_text(scratch.dir / "blade_mass.mtx", m_text);
    scene::write_text(scratch.dir / "blade_scene.json", scene_text);
    scene::write_text(scratch.dir / "study.toml", study_file(samples));
    run.text("blade_stiffness.mtx", k_text);
    run.text("blade_mass.mtx", m_text);
    run.text("blade_scene.json", scene_text);
    run.text("study.toml", study_file(samples));
    run.text("study_full.toml", study_file(full_samples));

    // The study on 1 and on 2 local workers.
    nlohmann::json studies = nlohmann::json::object();
    for (int workers : {1, 2}) {
      const auto out = scratch.dir / ("study_" + std::to_string(workers));
      const auto t = std::chrono::steady_clock::now();
      const int status = run_study(scratch.dir / "study.toml", out, workers);
      const double seconds = models::seconds_since(t);
      if (status < 0 || status == 2) {
        throw std::runtime_error(std::string(WBM_CLI) + " study failed to run (exit " + std::to_string(status) + ")");
      }
      studies[std::to_string(workers)] = read_json(out / "study.json");
      studies[std::to_string(workers)]["command_wall_time_s"] = seconds;
      if (workers == 2) {
        std::ifstream png(out / "study.png", std::ios::binary);
        std::ostringstream bytes;
        bytes << png.rdbuf();
        if (png) run.text("study.png", bytes.str());
      }
    }
    const auto& one = studies["1"];
    const auto& two = studies["2"];
    const auto& table = two.at("table");
    const std::string amp_header = "peak_amplitude_" + observed + " [m]", freq_header = "peak_frequency_" + observed + " [Hz]";
    const auto gaps = column(table, "contact.gap [m]"), amp = column(table, amp_header), freq = column(table, freq_header);
    const auto force = column(table, "max_max_contact_force [N]");
    std::vector<std::string> status;
    const auto& header = table.at("header");
    const auto status_col = static_cast<size_t>(std::find(header.begin(), header.end(), "status") - header.begin());
    for (const auto& row : table.at("rows")) status.push_back(row[status_col].get<std::string>());
    std::vector<double> freq_f1(freq.size());
    for (size_t k = 0; k < freq.size(); ++k) freq_f1[k] = freq[k] / model.f1;
    run.table("cases.csv",
              {"gap [m]", "peak_amplitude [m]", "peak_frequency [Hz]", "peak_frequency_over_f1 [-]", "max_contact_force [N]"},
              {reproduce::as_column(gaps), reproduce::as_column(amp), reproduce::as_column(freq),
               reproduce::as_column(freq_f1), reproduce::as_column(force)},
              status);

    // The tables of 1 and 2 workers, every column but the run times.
    auto without_times = [](const nlohmann::json& t) {
      nlohmann::json rows = nlohmann::json::array();
      const auto& h = t.at("header");
      for (const auto& row : t.at("rows")) {
        nlohmann::json r = nlohmann::json::array();
        for (size_t j = 0; j < h.size(); ++j) {
          if (h[j] != "wall_time [s]") r.push_back(row[j]);
        }
        rows.push_back(r);
      }
      return rows;
    };
    const bool same_tables = without_times(one.at("table")) == without_times(table);
    std::vector<double> ok_freq, ok_gap, ok_amp;
    for (size_t k = 0; k < status.size(); ++k) {
      if (status[k] == "converged" && std::isfinite(freq[k])) {
        ok_freq.push_back(freq[k]);
        ok_gap.push_back(gaps[k]);
        ok_amp.push_back(amp[k]);
      }
    }
    const auto converged = static_cast<int>(ok_freq.size());
    const double lowest_peak_f1 = converged ? *std::min_element(ok_freq.begin(), ok_freq.end()) / model.f1 : std::nan("");
    const double rho = converged > 2 ? rank_correlation(ok_gap, ok_freq) : std::nan("");
    const double t1 = one.at("wall_time_s").get<double>(), t2 = two.at("wall_time_s").get<double>();
    const double case_time = two.at("case_run_time_s").get<double>() / std::max(1, two.at("run").get<int>());
    auto overhead = [](const nlohmann::json& s) {
      return s.at("overhead_per_case_s").is_number() ? s.at("overhead_per_case_s").get<double>() : std::nan("");
    };
    const std::vector<reproduce::Claim> claims = {
        {"1 and 2 workers give the same table, bit for bit (every status, peak and contact force)", same_tables,
         std::to_string(table.at("rows").size()) + " rows compared outside the wall-time column"},
        {"every case converges over the range", converged == samples,
         std::to_string(converged) + " of " + std::to_string(samples) + " converged"},
        {"contact stiffens the blade: every peak lies above the linear f1", converged ? std::optional(lowest_peak_f1 > 1.0) : std::nullopt,
         "lowest peak frequency " + format("%.5f", lowest_peak_f1) + " f1"},
        {"a larger clearance lowers the peak frequency (Spearman's rank correlation of gap and peak frequency < 0)",
         std::isfinite(rho) ? std::optional(rho < 0.0) : std::nullopt, "ρ = " + format("%.3f", rho)},
    };

    run.meta({{"figure", "LL11 blade, resonance peak against random clearances (beyond the paper, issue #37)"},
              {"parameters", parameters.used()}, {"reduced_dofs", n}, {"linear_frequency_hz", model.f1},
              {"penalty_stiffness_n_per_m", model.penalty_stiffness}, {"beta_s", model.beta},
              {"observed_dof", observed}, {"studies", studies}, {"same_tables", same_tables},
              {"rank_correlation_gap_frequency", std::isfinite(rho) ? nlohmann::json(rho) : nlohmann::json()}});

    std::ostringstream md;
    md << "## Beyond LL11: the blade's resonance peak against random clearances, a study on Dask (`ll11_blade_gap_study`)\n\n"
       << "Files: `out/ll11_blade_gap_study/cases.csv` (one row per case), `study.png` (drawn by `wbm study`: each quantity "
       << "against the gap, and their histograms), `blade_scene.json` with `blade_stiffness.mtx`, `blade_mass.mtx` (the scene), "
       << "`study.toml`, `study_full.toml`, `meta.json` (both study.json files). The blade of `ll11_blade_forced`, meshed at "
       << format("%g", mesh_size * 1e3) << " mm (Craig–Bampton " << n << " DOFs, f1 = " << format("%.2f", model.f1)
       << " Hz), written as a wbm scene: " << contacts.size() << " linear penalty stops of " << format("%.3g", model.penalty_stiffness)
       << " N/m along the tip nodes' radial directions, C = β K_r with β = " << format("%.3g", model.beta)
       << " s, the load of `ll11_blade_forced` at the nominal clearance g0 = " << format("%g", gap * 1e3)
       << " mm, harmonic balance H = " << harmonics << ", continuation " << format("%g", from) << " … " << format("%g", to)
       << " f1. Each case draws one clearance for all the stops, g ~ N(g0, (" << format("%g", relative_std)
       << " g0)²), seed " << seed << ", " << samples << " cases; the peak is that of the circumferential displacement of the "
       << "onset node (`" << observed << "`).\n\n"
       << "| | mean | std | min | max |\n|---|---|---|---|---|\n";
    auto row = [&](const std::string& label, const std::vector<double>& v, const char* spec) {
      md << "| " << label << " | " << format(spec, mean(v)) << " | " << format(spec, stddev(v)) << " | "
         << format(spec, *std::min_element(v.begin(), v.end())) << " | " << format(spec, *std::max_element(v.begin(), v.end()))
         << " |\n";
    };
    if (converged > 0) {
      std::vector<double> g_over(ok_gap.size()), f_over(ok_freq.size()), a_over(ok_amp.size()), a_own(ok_amp.size());
      for (size_t k = 0; k < ok_gap.size(); ++k) {
        g_over[k] = ok_gap[k] / gap;
        f_over[k] = ok_freq[k] / model.f1;
        a_over[k] = ok_amp[k] / gap;
        a_own[k] = ok_amp[k] / ok_gap[k];
      }
      row("clearance g / g0", g_over, "%.3f");
      row("peak frequency / f1", f_over, "%.5f");
      row("peak amplitude / g0", a_over, "%.3f");
      row("peak amplitude / g (its own clearance)", a_own, "%.3f");
    }
    md << "\n" << converged << " of " << samples << " cases converged. **Time** (embedded LocalCluster on this machine; "
       << "under `make reproduce` other runs share its cores): 1 worker "
       << format("%.1f", t1) << " s, 2 workers " << format("%.1f", t2) << " s (speed-up " << format("%.2f", t1 / t2)
       << "); a case's `wbm run` " << format("%.2f", case_time) << " s on average; Dask's overhead per case (workers × wall − "
       << "Σ run times, over the cases) " << format("%.2f", overhead(one)) << " s with 1 worker, " << format("%.2f", overhead(two))
       << " s with 2. The full-size study (" << full_samples << " cases) is `wbm study out/ll11_blade_gap_study/study_full.toml "
       << "-o wbm-study/blade-gaps` (add `--scheduler tcp://HOST:PORT` for a cluster; docs/studies.md).\n\n"
       << reproduce::claims_markdown(claims);
    run.report(md.str());
  });
}
