#pragma once
// Private: every key of a scene declared once (issue #41, item 3, after deal.II's
// ParameterHandler). A section is one list of DeclaredKey<T>, T its settings struct; each entry
// gives the key's name, type, allowed values, default and meaning, and, for the keys whose value
// stands alone, where it lives in T. One declaration drives
//   - the parser's list of known keys, per variant of the section (names(); an analysis type,
//     a structure kind, a contact law), and "only used by …" for a key of another variant;
//   - the typed read with its range and the error naming key, value and range (read_values());
//   - the JSON echo of result.json (echo_keys());
//   - the key table of docs/scenes.md (key_table(), checked against the file by a test).
// A key whose default or range depends on other keys (basis.dimension against the pair, the nnm
// samples against N) or whose value is not a scalar (a location, a matrix, a list) is Compound:
// its section's code reads it, and its declaration gives the docs' type, default and allowed
// texts. Declared sections: scene_keys.cpp (top level, [analysis], [damping], [solver],
// [timestep], [output]) and scene_keys_model.cpp ([structure], [forcing], [[contact]], [basis]).

#include <algorithm>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>
#include <toml++/toml.h>

#include "reader.hpp"

namespace wbm::scene::detail {

/// One key of a settings struct T.
template <class T>
struct DeclaredKey {
  enum class Type { Number, Integer, Boolean, Choice, Text, Compound };
  const char* key = nullptr;
  Type type = Type::Compound;
  Range range;                        // Number: the allowed values ("> 0 [m]", "in (0, 1)")
  long long lo = 0, hi = 0;           // Integer: lo … hi
  std::vector<std::string> choices;   // Choice: the names
  const char* meaning = "";           // the docs' "meaning" column
  std::function<nlohmann::json(const T&)> get;        // the echo and the default (get(T{})); null: the section echoes it
  std::function<void(T&, const nlohmann::json&)> set; // the typed read; null: the section's code reads it
  std::vector<std::string> variants;  // the variants of the section that read it; empty: every one
  bool required = false;              // no default: the docs say "—" and a missing key is an error
  std::string hint;                   // appended to an Integer's range message
  nlohmann::json fallback;            // the default when it is not get(T{}) (null: get(T{}))
  std::string type_text, default_text, allowed_text;  // the docs' columns where they cannot be computed

  /// Read only by these variants of the section (an analysis type, a structure kind, a law).
  DeclaredKey only_in(std::vector<std::string> v) const {
    DeclaredKey k = *this;
    k.variants = std::move(v);
    return k;
  }
  DeclaredKey is_required() const {
    DeclaredKey k = *this;
    k.required = true;
    return k;
  }
  DeclaredKey with_hint(std::string h) const {
    DeclaredKey k = *this;
    k.hint = std::move(h);
    return k;
  }
  /// The default when the settings' own value is another variant's (nnm's max_step).
  DeclaredKey defaulting_to(nlohmann::json v) const {
    DeclaredKey k = *this;
    k.fallback = std::move(v);
    return k;
  }
  /// The docs' default column where the default depends on other keys ("`max(256, 8N)`").
  DeclaredKey documented_default(std::string text) const {
    DeclaredKey k = *this;
    k.default_text = std::move(text);
    return k;
  }
  /// The docs' allowed column where it is more than the range ("power of two, 1 … 2²⁰").
  DeclaredKey documented_allowed(std::string text) const {
    DeclaredKey k = *this;
    k.allowed_text = std::move(text);
    return k;
  }
  /// Echoed as `echo` instead of the field's value (null: left out).
  DeclaredKey echoed_as(std::function<nlohmann::json(const T&)> echo) const {
    DeclaredKey k = *this;
    k.get = std::move(echo);
    return k;
  }
  /// Read by the section's code (its range or default depends on other keys); the declaration
  /// still names it, documents it and, where `get` is set, echoes it.
  DeclaredKey read_by_section() const {
    DeclaredKey k = *this;
    k.set = nullptr;
    return k;
  }

  [[nodiscard]] bool read_by(const std::string& variant) const {
    return variants.empty() || variant.empty() || std::find(variants.begin(), variants.end(), variant) != variants.end();
  }
};

/// A key named `key` of `type`; the factories below fill in the rest.
template <class T>
DeclaredKey<T> basic_key(const char* key, typename DeclaredKey<T>::Type type, const char* meaning) {
  DeclaredKey<T> k{};
  k.key = key;
  k.type = type;
  k.meaning = meaning;
  return k;
}

/// A key of type Number; `field`, a generic lambda (auto& t) -> auto&, returns its double in T
/// (const or not; members of members too).
template <class T, class F>
DeclaredKey<T> number_key(const char* key, F field, Range range, const char* meaning) {
  auto k = basic_key<T>(key, DeclaredKey<T>::Type::Number, meaning);
  k.range = std::move(range);
  k.get = [field](const T& t) { return nlohmann::json(field(t)); };
  k.set = [field](T& t, const nlohmann::json& v) { field(t) = v.get<double>(); };
  return k;
}
/// A key of type Integer in [lo, hi]; `field` returns a reference to its int in T.
template <class T, class F>
DeclaredKey<T> integer_key(const char* key, F field, long long lo, long long hi, const char* meaning) {
  auto k = basic_key<T>(key, DeclaredKey<T>::Type::Integer, meaning);
  k.lo = lo;
  k.hi = hi;
  k.get = [field](const T& t) { return nlohmann::json(field(t)); };
  k.set = [field](T& t, const nlohmann::json& v) { field(t) = static_cast<int>(v.get<long long>()); };
  return k;
}
/// A key of type Boolean; `field` returns a reference to its bool in T.
template <class T, class F>
DeclaredKey<T> boolean_key(const char* key, F field, const char* meaning) {
  auto k = basic_key<T>(key, DeclaredKey<T>::Type::Boolean, meaning);
  k.get = [field](const T& t) { return nlohmann::json(field(t)); };
  k.set = [field](T& t, const nlohmann::json& v) { field(t) = v.get<bool>(); };
  return k;
}
/// A key of type Text (any string); `field` returns a reference to its std::string in T.
template <class T, class F>
DeclaredKey<T> text_key(const char* key, F field, const char* meaning) {
  auto k = basic_key<T>(key, DeclaredKey<T>::Type::Text, meaning);
  k.get = [field](const T& t) { return nlohmann::json(field(t)); };
  k.set = [field](T& t, const nlohmann::json& v) { field(t) = v.get<std::string>(); };
  return k;
}
/// A key of type Choice among `choices`; `name` maps T to its current name, `assign` a checked
/// name to T.
template <class T, class Name, class Assign>
DeclaredKey<T> choice_key(const char* key, std::vector<std::string> choices, Name name, Assign assign,
                          const char* meaning) {
  auto k = basic_key<T>(key, DeclaredKey<T>::Type::Choice, meaning);
  k.choices = std::move(choices);
  k.get = [name](const T& t) { return nlohmann::json(std::string(name(t))); };
  k.set = [assign](T& t, const nlohmann::json& v) { assign(t, v.get<std::string>()); };
  return k;
}
/// A key its section's code reads (a location, a matrix, a list, a pair of numbers): the docs'
/// type, default and allowed texts; `echo`, if given, its value in the JSON echo.
template <class T>
DeclaredKey<T> compound_key(const char* key, std::string type, std::string default_value, std::string allowed,
                            const char* meaning, std::function<nlohmann::json(const T&)> echo = nullptr) {
  auto k = basic_key<T>(key, DeclaredKey<T>::Type::Compound, meaning);
  k.get = std::move(echo);
  k.type_text = std::move(type);
  k.default_text = std::move(default_value);
  k.allowed_text = std::move(allowed);
  return k;
}

/// The keys read by `variant` (every key for ""), each once, in declaration order.
template <class T>
std::vector<std::string> names(const std::vector<DeclaredKey<T>>& keys, const std::string& variant = "") {
  std::vector<std::string> out;
  for (const auto& k : keys) {
    if (k.read_by(variant) && std::find(out.begin(), out.end(), k.key) == out.end()) out.emplace_back(k.key);
  }
  return out;
}

/// The variants that read `key` (empty: every one), over all its declarations.
template <class T>
std::vector<std::string> variants_of(const std::vector<DeclaredKey<T>>& keys, const std::string& key) {
  std::vector<std::string> out;
  for (const auto& k : keys) {
    if (k.key != key) continue;
    if (k.variants.empty()) return {};
    for (const auto& v : k.variants) {
      if (std::find(out.begin(), out.end(), v) == out.end()) out.push_back(v);
    }
  }
  return out;
}

/// Reads every declared key of `variant` that has a typed read into `settings`; an absent key
/// takes its fallback, or keeps the settings' value; a required one is an error.
template <class T>
void read_values(Reader& r, const toml::table& t, const std::string& section, const std::vector<DeclaredKey<T>>& keys,
                 T& settings, const std::string& variant = "") {
  using Type = typename DeclaredKey<T>::Type;
  for (const auto& k : keys) {
    if (!k.set || !k.read_by(variant)) continue;
    if (!k.fallback.is_null()) k.set(settings, k.fallback);
    if (t.get(k.key) == nullptr && !k.required) continue;
    const nlohmann::json current = k.get(settings);
    switch (k.type) {
      case Type::Number:
        k.set(settings, k.required ? r.number(t, section, k.key, k.range)
                                   : r.number(t, section, k.key, k.range, current.template get<double>()));
        break;
      case Type::Integer:
        k.set(settings, k.required ? r.integer(t, section, k.key, k.lo, k.hi, std::nullopt, k.hint)
                                   : r.integer(t, section, k.key, k.lo, k.hi, current.template get<long long>(), k.hint));
        break;
      case Type::Boolean:
        k.set(settings, r.boolean(t, section, k.key, current.template get<bool>()));
        break;
      case Type::Choice:
        k.set(settings, k.required ? r.choice(t, section, k.key, k.choices)
                                   : r.choice(t, section, k.key, k.choices, current.template get<std::string>()));
        break;
      case Type::Text:
        k.set(settings, k.required ? r.text(t, section, k.key) : r.text(t, section, k.key, current.template get<std::string>()));
        break;
      case Type::Compound:
        break;
    }
  }
}

/// Refuses keys that `variant` does not read (`hint` says why one of another variant is not
/// read here), then reads the typed ones.
template <class T>
void read_keys(Reader& r, const toml::table& t, const std::string& section, const std::vector<DeclaredKey<T>>& keys,
               T& settings, const std::string& hint = "", const std::string& variant = "") {
  r.only(t, section, names(keys, variant), hint);
  read_values(r, t, section, keys, settings, variant);
}

/// The echo of `settings`: {key: value} for every declared key of `variant` with an echo (a null
/// value is left out).
template <class T>
nlohmann::json echo_keys(const std::vector<DeclaredKey<T>>& keys, const T& settings, const std::string& variant = "") {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& k : keys) {
    if (!k.get || !k.read_by(variant)) continue;
    if (nlohmann::json v = k.get(settings); !v.is_null()) j[k.key] = std::move(v);
  }
  return j;
}

/// A value as docs/scenes.md writes it: numbers in the shortest form that reads back exactly,
/// with the exponent unpadded (1e-8, not 1e-08), strings quoted, true/false.
std::string doc_value(const nlohmann::json& v);

/// One row of a docs key table.
struct KeyRow {
  std::string key, type, default_value, allowed, meaning;
};

/// The docs rows of `keys`: defaults from T{} (or the fallback, or the documented text), a
/// key of some variants only prefixed "variant only: ".
template <class T>
std::vector<KeyRow> key_rows(const std::vector<DeclaredKey<T>>& keys) {
  using Type = typename DeclaredKey<T>::Type;
  std::vector<KeyRow> rows;
  const T defaults{};
  for (const auto& k : keys) {
    KeyRow row{k.key, k.type_text, k.default_text, k.allowed_text, k.meaning};
    switch (k.type) {
      case Type::Number:
        row.type = "number";
        if (row.allowed.empty()) row.allowed = k.range.text;
        break;
      case Type::Integer:
        row.type = "integer";
        if (row.allowed.empty()) row.allowed = std::to_string(k.lo) + " … " + std::to_string(k.hi);
        break;
      case Type::Boolean:
        row.type = "boolean";
        break;
      case Type::Choice:
        row.type = "string";
        if (row.allowed.empty()) {
          for (const auto& c : k.choices) row.allowed += (row.allowed.empty() ? "`\"" : ", `\"") + c + "\"`";
        }
        break;
      case Type::Text:
        row.type = "string";
        break;
      case Type::Compound:
        break;
    }
    if (row.default_value.empty()) {
      if (k.required) {
        row.default_value = "—";
      } else if (!k.fallback.is_null()) {
        row.default_value = "`" + doc_value(k.fallback) + "`";
      } else if (k.get) {
        row.default_value = "`" + doc_value(k.get(defaults)) + "`";
      }
    }
    if (!k.variants.empty()) {
      std::string which;
      for (const auto& v : k.variants) which += (which.empty() ? "" : ", ") + v;
      row.meaning = which + " only: " + row.meaning;
    }
    rows.push_back(std::move(row));
  }
  return rows;
}

/// The markdown table (| key | type | default | allowed | meaning |) of `rows`.
std::string key_table(const std::vector<KeyRow>& rows);

}  // namespace wbm::scene::detail
