#include <wbm/scene/output.hpp>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <unistd.h>

#include <matio.h>
#include <nlohmann/json.hpp>

namespace wbm::scene {

namespace {

// The checks every written table passes (write_table's contract), `name` for messages.
void check_table(const std::string& name, const Table& table) {
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
}

}  // namespace

void write_table(const std::filesystem::path& path, const Table& table) {
  check_table(path.filename().string(), table);
  const bool with_status = !table.status.empty();
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

namespace {

// A MATLAB identifier from any text: letters, digits and '_', starting with a letter, at most
// 63 characters (namelengthmax), made unique among `taken` by a suffix _2, _3, ….
std::string identifier(const std::string& text, std::vector<std::string>& taken) {
  std::string id;
  for (char ch : text) {
    const bool ok = std::isalnum(static_cast<unsigned char>(ch)) != 0;
    if (ok) id += ch;
    else if (!id.empty() && id.back() != '_') id += '_';
  }
  while (!id.empty() && id.back() == '_') id.pop_back();
  if (id.empty() || std::isalpha(static_cast<unsigned char>(id.front())) == 0) id = "x_" + id;
  id = id.substr(0, 60);
  std::string unique = id;
  for (int k = 2; std::find(taken.begin(), taken.end(), unique) != taken.end(); ++k) unique = id + "_" + std::to_string(k);
  taken.push_back(unique);
  return unique;
}

// "u_tip [m]" → ("u_tip", "m"); no bracket → (text, "").
std::pair<std::string, std::string> name_and_unit(const std::string& header) {
  const auto open = header.rfind(" [");
  if (open == std::string::npos || header.back() != ']') return {header, ""};
  return {header.substr(0, open), header.substr(open + 2, header.size() - open - 3)};
}

// Owns a matvar_t until released into a parent (struct field, cell) or written.
struct Var {
  matvar_t* v = nullptr;
  explicit Var(matvar_t* p) : v(p) {
    if (v == nullptr) throw std::runtime_error("matio: cannot create a variable");
  }
  ~Var() { if (v != nullptr) Mat_VarFree(v); }
  Var(const Var&) = delete;
  Var& operator=(const Var&) = delete;
  matvar_t* release() { matvar_t* p = v; v = nullptr; return p; }
};

matvar_t* text_var(const std::string& s) {
  size_t dims[2] = {1, s.size()};
  return Mat_VarCreate(nullptr, MAT_C_CHAR, MAT_T_UINT8, 2, dims, const_cast<char*>(s.data()), 0);
}

matvar_t* column_var(const Eigen::VectorXd& c) {
  size_t dims[2] = {static_cast<size_t>(c.size()), 1};
  return Mat_VarCreate(nullptr, MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, const_cast<double*>(c.data()), 0);
}

matvar_t* cell_of_text(const std::vector<std::string>& texts) {
  size_t dims[2] = {texts.size(), 1};
  Var cell(Mat_VarCreate(nullptr, MAT_C_CELL, MAT_T_CELL, 2, dims, nullptr, 0));
  for (size_t i = 0; i < texts.size(); ++i) {
    Var t(text_var(texts[i]));
    Mat_VarSetCell(cell.v, static_cast<int>(i), t.release());
  }
  return cell.release();
}

// A 1 × 1 struct named `name` (nullptr inside another struct) with `fields` in order.
matvar_t* struct_var(const char* name, const std::vector<std::pair<std::string, matvar_t*>>& fields) {
  std::vector<const char*> names;
  for (const auto& f : fields) names.push_back(f.first.c_str());
  names.push_back(nullptr);
  size_t dims[2] = {1, 1};
  Var s(Mat_VarCreateStruct2(name, 2, dims, names.data()));
  for (const auto& [field, value] : fields) Mat_VarSetStructFieldByName(s.v, field.c_str(), 0, value);
  return s.release();
}

}  // namespace

void write_mat(const std::filesystem::path& path, const std::vector<Table>& tables,
               const std::vector<std::pair<std::string, std::string>>& info) {
  for (const auto& t : tables) check_table(t.file, t);
  mat_t* mat = Mat_CreateVer(path.c_str(), nullptr, MAT_FT_MAT5);
  if (mat == nullptr) throw std::runtime_error(path.string() + ": cannot create the MAT-file");
  bool ok = true;
  std::vector<std::string> variables = {"wbm"};
  auto write = [&](matvar_t* v) {
    Var owned(v);
    ok = ok && Mat_VarWrite(mat, owned.v, MAT_COMPRESSION_NONE) == 0;
  };
  {
    std::vector<std::pair<std::string, matvar_t*>> fields;
    std::vector<std::string> files;
    for (const auto& [key, value] : info) {
      if (value == "true" || value == "false") {  // a MATLAB logical, so that `if r.wbm.converged` works
        size_t dims[2] = {1, 1};
        unsigned char b = value == "true" ? 1 : 0;
        fields.emplace_back(key, Mat_VarCreate(nullptr, MAT_C_UINT8, MAT_T_UINT8, 2, dims, &b, MAT_F_LOGICAL));
      } else {
        fields.emplace_back(key, text_var(value));
      }
    }
    for (const auto& t : tables) files.push_back(t.file);
    fields.emplace_back("files", cell_of_text(files));
    write(struct_var("wbm", fields));
  }
  for (const auto& t : tables) {
    const std::string stem = std::filesystem::path(t.file).stem().string();
    const std::string var = identifier(stem, variables);
    std::vector<std::string> taken = {"units", "columns", "status", "file"};
    std::vector<std::pair<std::string, matvar_t*>> fields, units;
    for (size_t c = 0; c < t.columns.size(); ++c) {
      const auto [label, unit] = name_and_unit(t.header[c]);
      const std::string field = identifier(label, taken);
      fields.emplace_back(field, column_var(t.columns[c]));
      units.emplace_back(field, text_var(unit));
    }
    fields.emplace_back("units", struct_var(nullptr, units));
    fields.emplace_back("columns", cell_of_text(t.header));
    if (!t.status.empty()) fields.emplace_back("status", cell_of_text(t.status));
    fields.emplace_back("file", text_var(t.file));
    write(struct_var(var.c_str(), fields));
  }
  ok = Mat_Close(mat) == 0 && ok;
  if (!ok) throw std::runtime_error(path.string() + ": MAT-file write failed");
}

void write_text(const std::filesystem::path& path, const std::string& content) {
  std::ofstream os(path);
  os << content;
  os.close();
  if (!os) throw std::runtime_error(path.string() + ": write failed");
}

namespace {

// Staging folders of runs that no longer exist (killed before their destructor ran): removed.
void remove_stale_staging(const std::filesystem::path& target) {
  std::error_code ec;
  if (!std::filesystem::is_directory(target, ec)) return;
  const std::string prefix = ".wbm-staging-";
  for (const auto& entry : std::filesystem::directory_iterator(target, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(prefix, 0) != 0 || name.size() == prefix.size() ||
        name.find_first_not_of("0123456789", prefix.size()) != std::string::npos || name.size() > prefix.size() + 9) {
      continue;
    }
    const auto pid = static_cast<pid_t>(std::stol(name.substr(prefix.size())));
    if (pid != ::getpid() && ::kill(pid, 0) != 0 && errno == ESRCH) {
      std::error_code ignored;
      std::filesystem::remove_all(entry.path(), ignored);
    }
  }
}

// The files of the result already in `target` (its result.json's "files" and "pictures"), by
// plain name; empty if there is none or it cannot be read.
std::vector<std::string> previous_result_files(const std::filesystem::path& target) {
  std::vector<std::string> files;
  std::ifstream in(target / "result.json");
  if (!in) return files;
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return files;
  for (const char* key : {"files", "pictures"}) {
    if (!j.contains(key) || !j[key].is_array()) continue;
    for (const auto& f : j[key]) {
      if (!f.is_string()) continue;
      const std::string name = f.get<std::string>();
      // Plain names only: a result.json never sends a removal outside its folder.
      if (!name.empty() && name.find('/') == std::string::npos && name != "." && name != "..") files.push_back(name);
    }
  }
  return files;
}

}  // namespace

StagedOutput::StagedOutput(std::filesystem::path target) : target_(std::move(target)) {
  created_target_ = !std::filesystem::exists(target_);
  remove_stale_staging(target_);
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

void StagedOutput::mat(const std::string& file, const std::vector<Table>& tables,
                       const std::vector<std::pair<std::string, std::string>>& info) {
  write_mat(staging_ / file, tables, info);
  files_.push_back(file);
}

void StagedOutput::text(const std::string& file, const std::string& content) {
  write_text(staging_ / file, content);
  files_.push_back(file);
}

std::vector<std::filesystem::path> StagedOutput::commit(const std::string& last) {
  const std::vector<std::string> old = previous_result_files(target_);
  std::filesystem::remove(target_ / last);
  // The earlier result's files that this one does not write: a folder holds one result.
  for (const auto& f : old) {
    if (std::find(files_.begin(), files_.end(), f) == files_.end()) std::filesystem::remove(target_ / f);
  }
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
