#include <wbm/scene/output.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <unistd.h>

namespace wbm::scene {

void write_table(const std::filesystem::path& path, const Table& table) {
  const std::string name = path.filename().string();
  if (table.header.size() != table.columns.size() || table.columns.empty()) {
    throw std::invalid_argument(name + ": " + std::to_string(table.header.size()) + " header names for " +
                                std::to_string(table.columns.size()) + " columns");
  }
  const bool with_status = !table.status.empty();
  if (with_status && static_cast<Eigen::Index>(table.status.size()) != table.columns[0].size()) {
    throw std::invalid_argument(name + ": status column has " + std::to_string(table.status.size()) +
                                " rows, the first column " + std::to_string(table.columns[0].size()));
  }
  for (const auto& s : table.status) {
    if (s.find_first_of(",\"\n") != std::string::npos) {
      throw std::invalid_argument(name + ": status \"" + s + "\" contains a comma, quote or newline");
    }
  }
  for (size_t c = 0; c < table.columns.size(); ++c) {
    const auto& col = table.columns[c];
    if (col.size() != table.columns[0].size()) {
      throw std::invalid_argument(name + ": column \"" + table.header[c] + "\" has " + std::to_string(col.size()) +
                                  " rows, the first column " + std::to_string(table.columns[0].size()));
    }
    if (col.array().isInf().any()) {
      throw std::invalid_argument(name + ": column \"" + table.header[c] + "\" contains inf; not written");
    }
    if (col.array().isNaN().any() && !with_status) {
      throw std::invalid_argument(name + ": column \"" + table.header[c] +
                                  "\" has missing values (NaN) but the table has no status column to say why; "
                                  "not written");
    }
  }
  std::ostringstream os;
  for (size_t c = 0; c < table.header.size(); ++c) os << (c ? "," : "") << table.header[c];
  if (with_status) os << ",status";
  os << "\n";
  char buf[40];
  for (Eigen::Index r = 0; r < table.columns[0].size(); ++r) {
    for (size_t c = 0; c < table.columns.size(); ++c) {
      const double v = table.columns[c](r);
      if (std::isnan(v)) {
        buf[0] = '\0';  // missing: empty cell
      } else {
        std::snprintf(buf, sizeof buf, "%.17g", v);
      }
      os << (c ? "," : "") << buf;
    }
    if (with_status) os << "," << table.status[static_cast<size_t>(r)];
    os << "\n";
  }
  write_text(path, os.str());
}

void write_text(const std::filesystem::path& path, const std::string& content) {
  std::ofstream os(path);
  os << content;
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
  write_text(staging_ / file, content);
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
