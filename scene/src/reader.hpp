#pragma once
// Private: typed access to a toml++ table that collects every problem of a file, each as
// "file:line: key: what was expected", and throws them together in finish().

#include <algorithm>
#include <cctype>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <toml++/toml.h>

#include <wbm/solvers/status.hpp>

namespace wbm::scene::detail {

struct Range {
  std::string text;                  // "> 0 [Pa]"
  std::function<bool(double)> ok;    // true if inside
};

inline Range positive(const std::string& unit) {
  return {"> 0" + (unit.empty() ? "" : " [" + unit + "]"), [](double v) { return v > 0.0 && std::isfinite(v); }};
}
inline Range non_negative(const std::string& unit) {
  return {">= 0" + (unit.empty() ? "" : " [" + unit + "]"), [](double v) { return v >= 0.0 && std::isfinite(v); }};
}
inline Range finite(const std::string& unit) {
  return {"finite" + (unit.empty() ? "" : " [" + unit + "]"), [](double v) { return std::isfinite(v); }};
}

// A number as the messages print it: "%g" (6 significant digits, what << printed before).
inline std::string number_text(double v) { return solvers::format("%g", v); }

class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  [[nodiscard]] const std::string& file() const { return file_; }
  [[nodiscard]] bool failed() const { return !errors_.empty(); }
  [[nodiscard]] size_t error_count() const { return errors_.size(); }

  /// Where `key` of `t` is, or `t` itself when the key is absent: a message never dereferences
  /// a missing node (found by fuzz_scene, issue #19).
  [[nodiscard]] static toml::source_region source_of(const toml::table& t, std::string_view key) {
    const toml::node* n = t.get(key);
    return n != nullptr ? n->source() : t.source();
  }

  void error(const toml::source_region& where, const std::string& key, const std::string& what) {
    std::ostringstream os;
    os << file_;
    if (where.begin.line > 0) os << ":" << where.begin.line;
    os << ": " << key << ": " << what;
    errors_.push_back(os.str());
  }
  /// An error of a tool the scene runs (CalculiX), not of the scene: finish() then throws
  /// std::runtime_error, so that it exits 1 ("a tool failed") as `wbm reduce` does, not 2.
  void tool_error(const toml::source_region& where, const std::string& key, const std::string& what) {
    error(where, key, what);
    tool_failed_ = true;
  }
  void warn(const toml::source_region& where, const std::string& what) {
    std::ostringstream os;
    os << file_;
    if (where.begin.line > 0) os << ":" << where.begin.line;
    os << ": warning: " << what;
    warnings_.push_back(os.str());
  }

  // The sub-table `key` of `root`, or null (an error if required, or if `key` is not a table).
  const toml::table* table(const toml::table& root, const std::string& key, bool required) {
    const toml::node* n = root.get(key);
    if (n == nullptr) {
      if (required) error(root.source(), "[" + key + "]", "missing table");
      return nullptr;
    }
    if (!n->is_table()) {
      error(n->source(), key, "expected a table [" + key + "]");
      return nullptr;
    }
    return n->as_table();
  }

  // A number (integers accepted); `fallback` makes the key optional.
  double number(const toml::table& t, const std::string& section, const std::string& key, const Range& range,
                std::optional<double> fallback = std::nullopt) {
    const std::string full = section + "." + key;
    const toml::node* n = t.get(key);
    if (n == nullptr) {
      if (fallback) return *fallback;
      error(t.source(), full, "missing; expected a number " + range.text);
      return 0.0;
    }
    return number_value(*n, full, range);
  }

  double number_value(const toml::node& n, const std::string& full, const Range& range) {
    const std::optional<double> v = (n.is_floating_point() || n.is_integer()) ? n.value<double>() : std::nullopt;
    if (!v) {
      error(n.source(), full, "expected a number " + range.text + ", got " + type_name(n));
      return 0.0;
    }
    if (!range.ok(*v)) {
      std::ostringstream os;
      os << "value " << *v << " out of range: expected " << range.text;
      error(n.source(), full, os.str());
    }
    return *v;
  }

  // An integer in [lo, hi]; `fallback` makes it optional.
  long long integer(const toml::table& t, const std::string& section, const std::string& key, long long lo,
                    long long hi, std::optional<long long> fallback = std::nullopt, const std::string& hint = "") {
    const std::string full = section + "." + key;
    const toml::node* n = t.get(key);
    if (n == nullptr) {
      if (fallback) return *fallback;
      error(t.source(), full, "missing; expected an integer " + span(lo, hi) + hint);
      return lo;
    }
    return integer_value(*n, full, lo, hi, hint);
  }

  long long integer_value(const toml::node& n, const std::string& full, long long lo, long long hi,
                          const std::string& hint = "") {
    if (!n.is_integer()) {
      error(n.source(), full, "expected an integer " + span(lo, hi) + ", got " + type_name(n) + hint);
      return lo;
    }
    const long long v = n.as_integer()->get();
    if (v < lo || v > hi) {
      error(n.source(), full, "value " + std::to_string(v) + " out of range: expected an integer " + span(lo, hi) + hint);
      // Reported; the scene is refused at the end. Until then the parser goes on with a value
      // in range, so nothing computes with the bad one (e.g. 1 << level; found by fuzz_scene).
      return std::clamp(v, lo, hi);
    }
    return v;
  }

  bool boolean(const toml::table& t, const std::string& section, const std::string& key, bool fallback) {
    const toml::node* n = t.get(key);
    if (n == nullptr) return fallback;
    if (!n->is_boolean()) {
      error(n->source(), section + "." + key, "expected true or false, got " + type_name(*n));
      return fallback;
    }
    return n->as_boolean()->get();
  }

  std::string text(const toml::table& t, const std::string& section, const std::string& key,
                   std::optional<std::string> fallback = std::nullopt) {
    const toml::node* n = t.get(key);
    if (n == nullptr) {
      if (fallback) return *fallback;
      error(t.source(), section + "." + key, "missing; expected a string");
      return {};
    }
    if (!n->is_string()) {
      error(n->source(), section + "." + key, "expected a string, got " + type_name(*n));
      return fallback.value_or("");
    }
    return n->as_string()->get();
  }

  // One of `allowed`; `fallback` makes it optional. (A string_view: an optional std::string
  // default argument trips GCC 12's -Wmaybe-uninitialized where this is inlined.)
  std::string choice(const toml::table& t, const std::string& section, const std::string& key,
                     const std::vector<std::string>& allowed, std::optional<std::string_view> fallback = std::nullopt) {
    const std::string full = section + "." + key;
    const toml::node* n = t.get(key);
    if (n == nullptr && fallback) return std::string(*fallback);
    if (n == nullptr || !n->is_string()) {
      error(n ? n->source() : t.source(), full,
            std::string(n ? "expected a string, " : "missing; expected ") + "one of " + list(allowed));
      return std::string(fallback.value_or(""));
    }
    const std::string v = n->as_string()->get();
    for (const auto& a : allowed) {
      if (a == v) return v;
    }
    std::string hint;
    for (const auto& a : allowed) {
      if (a.size() == v.size() && std::equal(a.begin(), a.end(), v.begin(), [](char x, char y) {
            return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
          })) {
        hint = " (names are lower case: \"" + a + "\")";
      }
    }
    error(n->source(), full, "\"" + v + "\" is not one of " + list(allowed) + hint);
    return std::string(fallback.value_or(""));
  }

  // Every key of `t` must be in `keys`.
  // `hint`, if given, is appended to the message (why a key of another mode is not read here).
  void only(const toml::table& t, const std::string& section, const std::vector<std::string>& keys,
            const std::string& hint = "") {
    const std::set<std::string> allowed(keys.begin(), keys.end());
    for (const auto& [k, node] : t) {
      const std::string key(k.str());
      if (allowed.contains(key)) continue;
      std::string names;
      for (const auto& a : keys) names += (names.empty() ? "" : ", ") + a;
      error(node.source(), section.empty() ? key : section + "." + key,
            "unknown key; allowed here: " + names + (hint.empty() ? std::string() : " (" + hint + ")"));
    }
  }

  void finish() const {
    if (errors_.empty()) return;
    std::string all;
    for (const auto& e : errors_) all += e + "\n";
    if (tool_failed_) throw std::runtime_error(all);
    throw std::invalid_argument(all);
  }

  [[nodiscard]] const std::vector<std::string>& warnings() const { return warnings_; }

  static std::string list(const std::vector<std::string>& names) {
    std::string s;
    for (const auto& a : names) s += (s.empty() ? "\"" : ", \"") + a + "\"";
    return s;
  }
  static std::string type_name(const toml::node& n) {
    if (n.is_string()) return "a string";
    if (n.is_integer()) return "an integer";
    if (n.is_floating_point()) return "a floating-point number";
    if (n.is_boolean()) return "a boolean";
    if (n.is_array()) return "an array";
    if (n.is_table()) return "a table";
    return "a date/time";
  }

 private:
  static std::string span(long long lo, long long hi) {
    if (hi == std::numeric_limits<long long>::max()) return ">= " + std::to_string(lo);
    return "in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  }
  std::string file_;
  bool tool_failed_ = false;
  std::vector<std::string> errors_;
  std::vector<std::string> warnings_;
};

}  // namespace wbm::scene::detail
