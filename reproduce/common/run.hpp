#pragma once
/// Output of one reproduce executable: out/<id>/ with CSV tables, meta.json and a report.md
/// fragment that reproduce/report.py assembles into out/REPORT.md.
/// Files are written into a staging folder and moved into place by finish() only if nothing
/// failed, so an interrupted or failed run never leaves a folder that looks complete.

#include <exception>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

namespace wbm::reproduce {

class Run {
 public:
  /// Parses `--quick` (small sizes, for ctest) and `--out DIR` (default: WBM_OUT_DIR).
  /// Unknown arguments print usage and exit(2).
  static Run from_args(int argc, char** argv, std::string id);

  [[nodiscard]] bool quick() const { return quick_; }
  [[nodiscard]] const std::string& id() const { return id_; }

  /// scene::write_table into the staging folder: header row (units in brackets), "%.17g". A column
  /// with inf, NaN without a status column, or columns of unequal length fail the run and write
  /// nothing. With `status` (one entry per row) NaN is a missing value, written as an empty cell.
  void table(const std::string& file, const std::vector<std::string>& header,
             const std::vector<Eigen::VectorXd>& columns, const std::vector<std::string>& status = {});
  /// A file of the run other than a table (a scene, a Matrix Market file, a picture made by a
  /// tool) into the staging folder (scene::write_text); a failed write fails the run.
  void text(const std::string& file, const std::string& content);
  /// meta.json: merged with wall time and "build" (scene::build_information()) at finish().
  void meta(const nlohmann::json& meta);
  /// Markdown fragment for out/REPORT.md (appended).
  void report(const std::string& markdown);
  /// Records a failure (printed at finish(); the exit status becomes 1).
  void fail(const std::string& why);

  /// Moves the staged files into out/<id>/ if nothing failed; prints a summary; returns the
  /// exit status (0 only if every solve converged and every file was written: a failed write of
  /// meta.json or report.md fails the run and moves nothing).
  int finish();
  /// Runs `body(*this)`; an exception (bad scene file, invalid parameter) becomes a recorded
  /// failure with its message. Returns finish().
  template <class Body>
  int execute(Body&& body) {
    try {
      body(*this);
    } catch (const std::exception& e) {
      fail(e.what());
    }
    return finish();
  }
  ~Run();  // removes the staging folder if finish() did not move it
  Run(Run&&) = default;

 private:
  Run(std::string id, std::filesystem::path out, bool quick);
  std::string id_;
  std::filesystem::path out_, staging_;
  bool quick_;
  nlohmann::json meta_;
  std::string report_;
  std::vector<std::string> failures_;
  double start_;
};

}  // namespace wbm::reproduce
