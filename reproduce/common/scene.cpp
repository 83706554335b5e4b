#include "scene.hpp"

#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>

#include <toml++/toml.h>

namespace wbm::reproduce {
namespace {

// Collects every problem of one file, then throws them all at once.
class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  void error(const toml::source_region& where, const std::string& key, const std::string& what) {
    std::ostringstream os;
    os << file_ << ":" << where.begin.line << ": " << key << ": " << what;
    errors_.push_back(os.str());
  }

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

  double number(const toml::table& t, const std::string& section, const std::string& key,
                const std::string& range, bool (*ok)(double)) {
    const std::string full = section + "." + key;
    const toml::node* n = t.get(key);
    if (n == nullptr) {
      error(t.source(), full, "missing; expected a number " + range);
      return 0.0;
    }
    std::optional<double> v = n->value<double>();
    if (!v || n->is_boolean() || n->is_string()) {
      error(n->source(), full, "expected a number " + range);
      return 0.0;
    }
    if (!ok(*v)) {
      std::ostringstream os;
      os << "value " << *v << " out of range: expected " << range;
      error(n->source(), full, os.str());
    }
    return *v;
  }

  std::string string(const toml::table& t, const std::string& section, const std::string& key,
                     const std::set<std::string>& allowed) {
    const std::string full = section + "." + key;
    const toml::node* n = t.get(key);
    std::string names;
    for (const auto& a : allowed) names += (names.empty() ? "\"" : ", \"") + a + "\"";
    if (n == nullptr || !n->is_string()) {
      error(n ? n->source() : t.source(), full, "expected one of " + names);
      return {};
    }
    std::string v = n->as_string()->get();
    if (!allowed.contains(v)) error(n->source(), full, "\"" + v + "\" is not one of " + names);
    return v;
  }

  void only(const toml::table& t, const std::string& section, const std::set<std::string>& keys) {
    for (const auto& [k, node] : t) {
      if (!keys.contains(std::string(k.str()))) {
        std::string list;
        for (const auto& a : keys) list += (list.empty() ? "" : ", ") + a;
        error(node.source(), section.empty() ? std::string(k.str()) : section + "." + std::string(k.str()),
              "unknown key; allowed here: " + list);
      }
    }
  }

  void finish() const {
    if (errors_.empty()) return;
    std::string all;
    for (const auto& e : errors_) all += e + "\n";
    throw std::invalid_argument(all);
  }

 private:
  std::string file_;
  std::vector<std::string> errors_;
};

bool positive(double v) { return v > 0.0 && std::isfinite(v); }
bool non_negative(double v) { return v >= 0.0 && std::isfinite(v); }
bool finite(double v) { return std::isfinite(v); }

}  // namespace

std::filesystem::path scene_directory() { return WBM_SCENE_DIR; }

RodScene load_scene(const std::string& name) {
  std::filesystem::path path(name);
  if (path.extension() != ".toml") path = scene_directory() / (name + ".toml");
  if (!std::filesystem::exists(path)) {
    throw std::runtime_error("scene \"" + name + "\": no file " + path.string() +
                             " (give a path to a .toml file or a name from " +
                             scene_directory().string() + ")");
  }
  toml::table root;
  try {
    root = toml::parse_file(path.string());
  } catch (const toml::parse_error& e) {
    std::ostringstream os;
    os << path.string() << ":" << e.source().begin.line << ": TOML syntax: " << e.description();
    throw std::invalid_argument(os.str());
  }
  Reader r(path.string());
  RodScene s;
  s.name = path.stem().string();
  s.path = path.string();
  r.only(root, "", {"title", "structure", "damping", "forcing", "contact"});
  if (const auto* t = root.get("title")) {
    if (t->is_string()) {
      s.title = t->as_string()->get();
    } else {
      r.error(t->source(), "title", "expected a string");
    }
  }
  if (const auto* t = r.table(root, "structure", true)) {
    r.only(*t, "structure", {"young_modulus", "density", "area", "length", "elements"});
    s.rod.young_modulus = r.number(*t, "structure", "young_modulus", "> 0 [Pa]", positive);
    s.rod.density = r.number(*t, "structure", "density", "> 0 [kg/m^3]", positive);
    s.rod.area = r.number(*t, "structure", "area", "> 0 [m^2]", positive);
    s.rod.length = r.number(*t, "structure", "length", "> 0 [m]", positive);
    const toml::node* e = t->get("elements");
    if (e == nullptr || !e->is_integer() || e->as_integer()->get() < 1) {
      r.error(e ? e->source() : t->source(), "structure.elements", "expected an integer >= 1");
    } else {
      s.rod.elements = static_cast<int>(e->as_integer()->get());
    }
  }
  if (const auto* t = r.table(root, "damping", true)) {
    r.only(*t, "damping", {"beta"});
    s.beta = r.number(*t, "damping", "beta", ">= 0 [s]", non_negative);
  }
  if (const auto* t = r.table(root, "forcing", true)) {
    r.only(*t, "forcing", {"amplitude", "frequency_hz"});
    s.force_amplitude = r.number(*t, "forcing", "amplitude", "finite [N]", finite);
    s.frequency_hz = r.number(*t, "forcing", "frequency_hz", "> 0 [Hz]", positive);
  }
  if (const auto* t = r.table(root, "contact", false)) {
    ContactSpec c;
    c.law = r.string(*t, "contact", "law", {"exponential", "linear"});
    c.gap = r.number(*t, "contact", "gap", "finite [m]", finite);
    if (c.law == "exponential") {
      r.only(*t, "contact", {"law", "gap", "coefficient", "exponent"});
      c.coefficient = r.number(*t, "contact", "coefficient", "> 0 [N]", positive);
      c.exponent = r.number(*t, "contact", "exponent", "> 0 [1/m]", positive);
    } else if (c.law == "linear") {
      r.only(*t, "contact", {"law", "gap", "stiffness"});
      c.stiffness = r.number(*t, "contact", "stiffness", "> 0 [N/m]", positive);
    }
    s.contact = c;
  }
  r.finish();
  return s;
}

solvers::MechanicalSystem RodScene::system() const { return solvers::beta_damped(make_rod(), beta); }

solvers::HarmonicForcing RodScene::forcing() const {
  return {rod.elements - 1, force_amplitude, frequency_hz};
}

std::shared_ptr<const contact::ContactLaw> RodScene::contact_law() const {
  if (!contact) return nullptr;
  if (contact->law == "exponential") {
    return std::make_shared<contact::ExponentialPenalty>(
        contact::ExponentialPenaltyParameters{contact->coefficient, contact->exponent, contact->gap});
  }
  return std::make_shared<contact::LinearPenalty>(
      contact::LinearPenaltyParameters{contact->stiffness, contact->gap});
}

std::vector<solvers::ContactPoint> RodScene::contacts() const {
  if (!contact) return {};
  return {{rod.elements - 1, contact_law()}};
}

}  // namespace wbm::reproduce
