#include <wbm/scene/output.hpp>

#include <cstdio>
#include <fstream>
#include <stdexcept>

#include <unistd.h>

namespace wbm::scene {

void write_table(const std::filesystem::path& path, const Table& table) {
  const std::string name = path.filename().string();
  if (table.header.size() != table.columns.size() || table.columns.empty()) {
    throw std::invalid_argument(name + ": " + std::to_string(table.header.size()) + " header names for " +
                                std::to_string(table.columns.size()) + " columns");
  }
  for (size_t c = 0; c < table.columns.size(); ++c) {
    if (table.columns[c].size() != table.columns[0].size()) {
      throw std::invalid_argument(name + ": column \"" + table.header[c] + "\" has " +
                                  std::to_string(table.columns[c].size()) + " rows, the first column " +
                                  std::to_string(table.columns[0].size()));
    }
    if (!table.columns[c].allFinite()) {
      throw std::invalid_argument(name + ": column \"" + table.header[c] + "\" contains NaN or inf; not written");
    }
  }
  std::ofstream os(path);
  for (size_t c = 0; c < table.header.size(); ++c) os << (c ? "," : "") << table.header[c];
  os << "\n";
  char buf[40];
  for (Eigen::Index r = 0; r < table.columns[0].size(); ++r) {
    for (size_t c = 0; c < table.columns.size(); ++c) {
      std::snprintf(buf, sizeof buf, "%.17g", table.columns[c](r));
      os << (c ? "," : "") << buf;
    }
    os << "\n";
  }
  os.close();
  if (!os) throw std::runtime_error(path.string() + ": write failed");
}

StagedOutput::StagedOutput(std::filesystem::path target) : target_(std::move(target)) {
  created_target_ = !std::filesystem::exists(target_);
  staging_ = target_ / (".wbm-staging-" + std::to_string(::getpid()));
  std::filesystem::remove_all(staging_);
  std::filesystem::create_directories(staging_);
}

StagedOutput::~StagedOutput() {
  std::error_code ignored;
  if (staging_.empty()) return;  // committed
  std::filesystem::remove_all(staging_, ignored);
  // A target folder created only to hold the staging folder goes too (remove() keeps a non-empty one).
  if (created_target_) std::filesystem::remove(target_, ignored);
}

void StagedOutput::table(const Table& table) {
  write_table(staging_ / table.file, table);
  files_.push_back(table.file);
}

void StagedOutput::text(const std::string& file, const std::string& content) {
  std::ofstream os(staging_ / file);
  os << content;
  os.close();
  if (!os) throw std::runtime_error((staging_ / file).string() + ": write failed");
  files_.push_back(file);
}

std::vector<std::filesystem::path> StagedOutput::commit(const std::string& last) {
  std::filesystem::remove(target_ / last);
  std::vector<std::filesystem::path> written;
  for (const auto& f : files_) {
    if (f == last) continue;
    std::filesystem::rename(staging_ / f, target_ / f);
    written.push_back(target_ / f);
  }
  for (const auto& f : files_) {
    if (f != last) continue;
    std::filesystem::rename(staging_ / f, target_ / f);
    written.push_back(target_ / f);
  }
  std::filesystem::remove_all(staging_);
  staging_.clear();
  return written;
}

}  // namespace wbm::scene
