#include "run.hpp"

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
                const std::vector<Eigen::VectorXd>& columns) {
  if (header.size() != columns.size() || columns.empty()) {
    fail(file + ": " + std::to_string(header.size()) + " header names for " +
         std::to_string(columns.size()) + " columns");
    return;
  }
  for (size_t c = 0; c < columns.size(); ++c) {
    if (columns[c].size() != columns[0].size()) {
      fail(file + ": column \"" + header[c] + "\" has a different length");
      return;
    }
    if (!columns[c].allFinite()) {
      fail(file + ": column \"" + header[c] + "\" contains NaN or inf; not written");
      return;
    }
  }
  std::ofstream os(staging_ / file);
  for (size_t c = 0; c < header.size(); ++c) os << (c ? "," : "") << header[c];
  os << "\n";
  char buf[40];
  for (Eigen::Index r = 0; r < columns[0].size(); ++r) {
    for (size_t c = 0; c < columns.size(); ++c) {
      std::snprintf(buf, sizeof buf, "%.17g", columns[c](r));
      os << (c ? "," : "") << buf;
    }
    os << "\n";
  }
  if (!os) fail(file + ": write failed");
}

void Run::meta(const nlohmann::json& meta) { meta_.merge_patch(meta); }
void Run::report(const std::string& markdown) { report_ += markdown; }
void Run::fail(const std::string& why) { failures_.push_back(why); }

int Run::finish() {
  meta_["id"] = id_;
  meta_["quick"] = quick_;
  meta_["wall_time_s"] = now() - start_;
  meta_["git_describe"] = WBM_GIT_DESCRIBE;
  meta_["compiler"] = std::string(__VERSION__);
  meta_["eigen_version"] = std::to_string(EIGEN_WORLD_VERSION) + "." +
                           std::to_string(EIGEN_MAJOR_VERSION) + "." + std::to_string(EIGEN_MINOR_VERSION);
  meta_["failures"] = failures_;
  if (!failures_.empty()) {
    for (const auto& f : failures_) std::cerr << id_ << ": FAILED: " << f << "\n";
    std::filesystem::remove_all(staging_);
    return 1;
  }
  std::ofstream(staging_ / "meta.json") << meta_.dump(2) << "\n";
  std::ofstream(staging_ / "report.md") << report_;
  const auto target = out_ / id_;
  std::filesystem::remove_all(target);
  std::filesystem::rename(staging_, target);
  std::cout << id_ << ": wrote " << target.string() << " in " << meta_["wall_time_s"].get<double>() << " s\n";
  return 0;
}

}  // namespace wbm::reproduce
