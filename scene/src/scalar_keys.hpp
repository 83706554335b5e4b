#pragma once
// Private: the scalar sections of a scene declared once (issue #41, item 3, after deal.II's
// ParameterHandler): each key's name, type, allowed values and meaning, and where it lives in the
// settings struct. One declaration drives the parser (the list of known keys, the typed read with
// its range and the error naming key, value and range), the JSON echo of result.json and the key
// table of docs/scenes.md (scene::key_table_markdown, checked against the file by a test).
// Declared so far: [solver], and [timestep] for the BDF and for Moreau–Jean.

#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <toml++/toml.h>

#include "reader.hpp"

namespace wbm::scene::detail {

/// One scalar key of a settings struct T.
template <class T>
struct ScalarKey {
  enum class Type { Number, Integer, Boolean, Choice };
  const char* key;
  Type type;
  Range range;                        // Number: the allowed values ("> 0", "in (0, 1)")
  long long lo = 0, hi = 0;           // Integer: lo … hi
  std::vector<std::string> choices;   // Choice: the names, the first the default's place in docs
  const char* meaning;                // the docs' "meaning" column
  std::function<nlohmann::json(const T&)> get;  // the echo, and the default (get(T{}))
  std::function<void(T&, const nlohmann::json&)> set;
};

/// A key of type Number; `field`, a generic lambda (auto& t) -> auto&, returns its double in T
/// (const or not; members of members too).
template <class T, class F>
ScalarKey<T> number_key(const char* key, F field, Range range, const char* meaning) {
  return {key, ScalarKey<T>::Type::Number, std::move(range), 0, 0, {}, meaning,
          [field](const T& t) { return nlohmann::json(field(t)); },
          [field](T& t, const nlohmann::json& v) { field(t) = v.get<double>(); }};
}
/// A key of type Integer in [lo, hi]; `field` returns a reference to its int in T.
template <class T, class F>
ScalarKey<T> integer_key(const char* key, F field, long long lo, long long hi, const char* meaning) {
  return {key, ScalarKey<T>::Type::Integer, {}, lo, hi, {}, meaning,
          [field](const T& t) { return nlohmann::json(field(t)); },
          [field](T& t, const nlohmann::json& v) { field(t) = static_cast<int>(v.get<long long>()); }};
}
/// A key of type Boolean; `field` returns a reference to its bool in T.
template <class T, class F>
ScalarKey<T> boolean_key(const char* key, F field, const char* meaning) {
  return {key, ScalarKey<T>::Type::Boolean, {}, 0, 0, {}, meaning,
          [field](const T& t) { return nlohmann::json(field(t)); },
          [field](T& t, const nlohmann::json& v) { field(t) = v.get<bool>(); }};
}

/// Reads every declared key of `t` into `settings` (absent keys keep their values), after
/// refusing keys that are not declared (`hint` says why one of another mode is not read here).
template <class T>
void read_keys(Reader& r, const toml::table& t, const std::string& section, const std::vector<ScalarKey<T>>& keys,
               T& settings, const std::string& hint = "") {
  std::vector<std::string> names;
  for (const auto& k : keys) names.emplace_back(k.key);
  r.only(t, section, names, hint);
  using Type = typename ScalarKey<T>::Type;
  for (const auto& k : keys) {
    if (t.get(k.key) == nullptr) continue;
    switch (k.type) {
      case Type::Number:
        k.set(settings, r.number(t, section, k.key, k.range, k.get(settings).template get<double>()));
        break;
      case Type::Integer:
        k.set(settings, r.integer(t, section, k.key, k.lo, k.hi, k.get(settings).template get<long long>()));
        break;
      case Type::Boolean:
        k.set(settings, r.boolean(t, section, k.key, k.get(settings).template get<bool>()));
        break;
      case Type::Choice:
        k.set(settings, r.choice(t, section, k.key, k.choices, k.get(settings).template get<std::string>()));
        break;
    }
  }
}

/// The echo of `settings`: {key: value} for every declared key.
template <class T>
nlohmann::json echo_keys(const std::vector<ScalarKey<T>>& keys, const T& settings) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& k : keys) j[k.key] = k.get(settings);
  return j;
}

/// A value as docs/scenes.md writes it: numbers in the shortest form that reads back exactly,
/// with the exponent unpadded (1e-8, not 1e-08), strings quoted, true/false.
std::string doc_value(const nlohmann::json& v);

/// The markdown table of `keys` (| key | type | default | allowed | meaning |), defaults from T{}.
template <class T>
std::string key_table(const std::vector<ScalarKey<T>>& keys) {
  using Type = typename ScalarKey<T>::Type;
  std::string md = "| key | type | default | allowed | meaning |\n|---|---|---|---|---|\n";
  const T defaults{};
  for (const auto& k : keys) {
    std::string type, allowed;
    switch (k.type) {
      case Type::Number:
        type = "number";
        allowed = k.range.text;
        break;
      case Type::Integer:
        type = "integer";
        allowed = std::to_string(k.lo) + " … " + std::to_string(k.hi);
        break;
      case Type::Boolean:
        type = "boolean";
        break;
      case Type::Choice:
        type = "string";
        for (const auto& c : k.choices) allowed += (allowed.empty() ? "`\"" : ", `\"") + c + "\"`";
        break;
    }
    md += "| `" + std::string(k.key) + "` | " + type + " | `" + doc_value(k.get(defaults)) + "` | " + allowed + " | " +
          k.meaning + " |\n";
  }
  return md;
}

}  // namespace wbm::scene::detail
