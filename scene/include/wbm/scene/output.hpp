#pragma once
/// Result files: CSV tables with units in the header, written so that a failed or interrupted
/// run never leaves a file that looks complete.

#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace wbm::scene {

/// One CSV file: a header row ("name [unit]" per column) and equal-length numeric columns.
struct Table {
  std::string file;                  // e.g. "displacement.csv"
  std::vector<std::string> header;   // one entry per column
  std::vector<Eigen::VectorXd> columns;
};

/// Writes `table` to `path`: the header, then one row per sample, each value "%.17g" (round
/// trip). Throws std::invalid_argument, writing nothing, if header and columns differ in count,
/// columns differ in length, or a column holds NaN or inf (named in the message);
/// std::runtime_error if the file cannot be written.
void write_table(const std::filesystem::path& path, const Table& table);

/// Files staged in `target/.wbm-staging-<pid>/` and moved into `target` by commit():
///   1. every staged file is complete before any is moved;
///   2. commit() first removes `target/<last>` (the marker of a finished run, result.json),
///      renames every other file (each rename is atomic), then renames `<last>`.
/// So `<last>` exists only beside a complete set of files; an interrupted run leaves the old
/// set or no marker. Files of `target` not staged are left alone. The destructor removes the
/// staging folder if commit() was not reached.
class StagedOutput {
 public:
  explicit StagedOutput(std::filesystem::path target);
  ~StagedOutput();
  StagedOutput(const StagedOutput&) = delete;
  StagedOutput& operator=(const StagedOutput&) = delete;

  void table(const Table& table);  // write_table into staging (throws as write_table)
  void text(const std::string& file, const std::string& content);
  /// Moves the files into target (created if missing), `last` last; returns their final paths.
  std::vector<std::filesystem::path> commit(const std::string& last);

 private:
  std::filesystem::path target_, staging_;
  std::vector<std::string> files_;
  bool created_target_ = false;
};

}  // namespace wbm::scene
