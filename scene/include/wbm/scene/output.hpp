#pragma once
/// Result files: CSV tables with units in the header, written so that a failed or interrupted
/// run never leaves a file that looks complete.

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace wbm::scene {

/// One CSV file: a header row ("name [unit]" per column) and equal-length numeric columns,
/// optionally followed by a text column "status" (one entry per row).
/// Missing values: a NaN in a numeric column means "no value" (a solve that did not converge,
/// an infinite condition number) and is written as an empty cell; it is allowed only in a table
/// with a status column, which says why the row has no value. A missing value is never 0 or −1.
struct Table {
  std::string file;                  // e.g. "displacement.csv"
  std::vector<std::string> header;   // one entry per numeric column
  std::vector<Eigen::VectorXd> columns;
  std::vector<std::string> status = {};  // empty, or one entry per row (no commas or quotes)
};

/// Writes `table` to `path`: the header, then one row per sample, each value "%.17g" (round
/// trip), an empty cell for NaN, the status last. Throws std::invalid_argument, writing nothing,
/// if header and columns differ in count, columns (or the status) differ in length, a column
/// holds inf, or NaN without a status column (named in the message); std::runtime_error if the
/// file cannot be written (stream state checked after close).
void write_table(const std::filesystem::path& path, const Table& table);

/// Writes `tables` to one MAT-file (level 5, readable by MATLAB ≥ 7 and scipy.io.loadmat) through
/// matio: a struct `wbm` with the fields of `info` (text; "true"/"false" become logicals, e.g.
/// converged) and `files`
/// (cell of the table files), then one struct per table, named after its file without ".csv"
/// (letters, digits, '_'; e.g. frequency_response), whose fields are its columns (P × 1 double,
/// named by the header without the unit: "u_tip [m]" → u_tip), `units` (a struct of the unit
/// strings by the same field names), `columns` (cell of the CSV headers, units included),
/// `status` (cell, when the table has one) and `file`. Names that clash get _2, _3, ….
/// Missing values stay NaN beside their status. Throws as write_table for a bad table (nothing
/// written) and std::runtime_error if matio cannot create or write the file.
void write_mat(const std::filesystem::path& path, const std::vector<Table>& tables,
               const std::vector<std::pair<std::string, std::string>>& info);

/// Files staged in `target/.wbm-staging-<pid>/` and moved into `target` by commit():
///   1. every staged file is complete before any is moved;
///   2. commit() first removes `target/<last>` (the marker of a finished run, result.json),
///      renames every other file (each rename is atomic), then renames `<last>`.
/// So `<last>` exists only beside a complete set of files; an interrupted run leaves the old
/// set or no marker. A folder holds one result: commit() also removes the files of the earlier
/// result (the plain names its result.json lists under "files" and "pictures") that this one
/// does not write; other files of `target` are left alone. The destructor removes the staging
/// folder if commit() was not reached (and `target` if it was created for it and is empty);
/// the constructor removes the staging folders of processes that no longer exist (a run killed
/// before its destructor ran).
/// Writes `content` to `path`; throws std::runtime_error naming the file if the write fails
/// (stream state checked after close).
void write_text(const std::filesystem::path& path, const std::string& content);

class StagedOutput {
 public:
  explicit StagedOutput(std::filesystem::path target);
  ~StagedOutput();
  StagedOutput(const StagedOutput&) = delete;
  StagedOutput& operator=(const StagedOutput&) = delete;

  void table(const Table& table);  // write_table into staging (throws as write_table)
  void text(const std::string& file, const std::string& content);  // throws std::runtime_error on a failed write
  void mat(const std::string& file, const std::vector<Table>& tables,
           const std::vector<std::pair<std::string, std::string>>& info);  // write_mat into staging
  /// Moves the files into target (created if missing), `last` last; returns their final paths.
  std::vector<std::filesystem::path> commit(const std::string& last);

 private:
  std::filesystem::path target_, staging_;
  std::vector<std::string> files_;
  bool created_target_ = false;
};

}  // namespace wbm::scene
