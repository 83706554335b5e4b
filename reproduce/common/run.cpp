#include "run.hpp"

#include <wbm/scene/build_information.hpp>
#include <wbm/scene/output.hpp>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <unistd.h>

#include <Eigen/Core>

namespace wbm::reproduce {
namespace {
double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
}  // namespace

Run::Run(std::string id, std::filesystem::path out, bool quick)
    : id_(std::move(id)), out_(std::move(out)), quick_(quick), start_(now()) {
  staging_ = out_ / ("." + id_ + ".staging-" + std::to_string(::getpid()));
  std::filesystem::remove_all(staging_);
  std::filesystem::create_directories(staging_);
}

Run::~Run() {
  std::error_code ignored;
  if (!staging_.empty()) std::filesystem::remove_all(staging_, ignored);
}

Run Run::from_args(int argc, char** argv, std::string id) {
  bool quick = false;
  std::filesystem::path out = WBM_OUT_DIR;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--quick") {
      quick = true;
    } else if (a == "--out" && i + 1 < argc) {
      out = argv[++i];
    } else {
      std::cerr << "usage: " << argv[0] << " [--quick] [--out DIR]\n"
                << "  unknown argument \"" << a << "\"\n";
      std::exit(2);
    }
  }
  return Run(std::move(id), out, quick);
}

void Run::table(const std::string& file, const std::vector<std::string>& header,
                const std::vector<Eigen::VectorXd>& columns, const std::vector<std::string>& status) {
  try {
    scene::write_table(staging_ / file, {file, header, columns, status});
  } catch (const std::exception& e) {
    fail(e.what());
  }
}

void Run::text(const std::string& file, const std::string& content) {
  try {
    scene::write_text(staging_ / file, content);
  } catch (const std::exception& e) {
    fail(e.what());
  }
}

void Run::meta(const nlohmann::json& meta) { meta_.merge_patch(meta); }
void Run::report(const std::string& markdown) { report_ += markdown; }
void Run::fail(const std::string& why) { failures_.push_back(why); }

int Run::finish() {
  meta_["id"] = id_;
  meta_["quick"] = quick_;
  meta_["wall_time_s"] = now() - start_;
  meta_["build"] = scene::build_information();  // wbm, git describe, compiler, Eigen, FFTW, GSL, toml++
  meta_["failures"] = failures_;
  try {
    if (failures_.empty()) {
      scene::write_text(staging_ / "meta.json", meta_.dump(2) + "\n");
      scene::write_text(staging_ / "report.md", report_);
    }
  } catch (const std::exception& e) {
    failures_.push_back(e.what());
  }
  if (!failures_.empty()) {
    for (const auto& f : failures_) std::cerr << id_ << ": FAILED: " << f << "\n";
    std::filesystem::remove_all(staging_);
    return 1;
  }
  const auto target = out_ / id_;
  std::filesystem::remove_all(target);
  std::filesystem::rename(staging_, target);
  std::cout << id_ << ": wrote " << target.string() << " in " << meta_["wall_time_s"].get<double>() << " s\n";
  return 0;
}

}  // namespace wbm::reproduce
