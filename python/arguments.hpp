#pragma once
// Checked conversions of the Python module's arguments (issue #40, item 2): every array is
// checked for its dtype (real numbers: float, int or bool), its number of dimensions, its shape
// and its finiteness before any of its memory is read, and every dict value (numpy scalars and
// arrays included) for finiteness, by its dotted key. A failure raises ValueError naming the
// argument, what it got and the expected shape, e.g. "evaluate: coefficients has shape (1, 1);
// expected (n, M) = (n, 64): one row per DOF, one column per trial function".
#include <cmath>
#include <string>

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

namespace wbm::python {

namespace py = pybind11;

// "(2, 3)" for a shape.
inline std::string shape_text(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t d = 0; d < a.ndim(); ++d) s += (d > 0 ? ", " : "") + std::to_string(a.shape(d));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

// The argument as a float64 numpy array; ValueError unless its dtype holds real numbers.
inline py::array_t<double, py::array::c_style | py::array::forcecast> real_array(const py::handle& o,
                                                                                const std::string& name) {
  py::array a;
  try {
    a = py::module_::import("numpy").attr("asarray")(o);
  } catch (const py::error_already_set& e) {
    throw std::invalid_argument(name + ": not an array of real numbers (" + std::string(e.what()) + ")");
  }
  const std::string kind = a.dtype().attr("kind").cast<std::string>();
  if (kind != "f" && kind != "i" && kind != "u" && kind != "b") {
    throw std::invalid_argument(name + ": expected real numbers (float, int or bool), got dtype " +
                                py::str(a.dtype()).cast<std::string>());
  }
  return py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
}

inline void require_finite(const double* data, py::ssize_t count, const std::string& name) {
  for (py::ssize_t i = 0; i < count; ++i) {
    if (!std::isfinite(data[i])) {
      throw std::invalid_argument(name + ": entry " + std::to_string(i) + " (row-major) is " +
                                  std::to_string(data[i]) + "; every entry must be finite");
    }
  }
}

// A 2-D array of real, finite numbers of rows × cols (−1: any, at least 1), as Eigen.
inline Eigen::MatrixXd matrix(const py::handle& o, const std::string& name, Eigen::Index rows, Eigen::Index cols,
                              const std::string& expected) {
  const auto a = real_array(o, name);
  if (a.ndim() != 2 || (rows >= 0 && a.shape(0) != rows) || (cols >= 0 && a.shape(1) != cols) || a.shape(0) < 1 ||
      a.shape(1) < 1) {
    throw std::invalid_argument(name + " has shape " + shape_text(a) + "; expected " + expected);
  }
  require_finite(a.data(), a.size(), name);
  Eigen::MatrixXd m(a.shape(0), a.shape(1));
  for (py::ssize_t i = 0; i < a.shape(0); ++i) {
    for (py::ssize_t j = 0; j < a.shape(1); ++j) m(i, j) = a.at(i, j);
  }
  return m;
}

// A 1-D array of real, finite numbers (size −1: any, possibly empty), as Eigen.
inline Eigen::VectorXd vector(const py::handle& o, const std::string& name, Eigen::Index size,
                              const std::string& expected) {
  const auto a = real_array(o, name);
  if (a.ndim() != 1 || (size >= 0 && a.shape(0) != size)) {
    throw std::invalid_argument(name + " has shape " + shape_text(a) + "; expected " + expected);
  }
  require_finite(a.data(), a.size(), name);
  return Eigen::Map<const Eigen::VectorXd>(a.data(), a.shape(0));
}

// A finite real number, for scalar arguments.
inline double finite(double v, const std::string& name) {
  if (!std::isfinite(v)) throw std::invalid_argument(name + " = " + std::to_string(v) + ": must be finite");
  return v;
}

// A scene dict (or any JSON-like value) as JSON: str, bool, int, float (finite), None, lists,
// tuples, dicts with str keys, and numpy scalars and arrays (through .tolist()). `key` is the
// dotted path so far; ValueError names it for a NaN, an infinity or an unsupported type.
inline nlohmann::json json_of(const py::handle& o, const std::string& key) {
  const std::string where = key.empty() ? "the scene" : "key '" + key + "'";
  if (o.is_none()) return nullptr;
  if (py::isinstance<py::bool_>(o)) return o.cast<bool>();
  if (py::isinstance<py::int_>(o)) {
    try {
      return o.cast<long long>();
    } catch (const py::cast_error&) {
      throw std::invalid_argument("run_scene: " + where + " = " + py::str(o).cast<std::string>() +
                                  " does not fit in a 64-bit integer");
    }
  }
  if (py::isinstance<py::float_>(o)) {
    const double v = o.cast<double>();
    if (!std::isfinite(v)) {
      throw std::invalid_argument("run_scene: " + where + " is " + py::str(o).cast<std::string>() +
                                  "; give a finite number");
    }
    return v;
  }
  if (py::isinstance<py::str>(o)) return o.cast<std::string>();
  if (py::isinstance<py::dict>(o)) {
    nlohmann::json j = nlohmann::json::object();
    for (const auto& [k, v] : o.cast<py::dict>()) {
      if (!py::isinstance<py::str>(k)) {
        throw std::invalid_argument("run_scene: " + where + " has the key " + py::repr(k).cast<std::string>() +
                                    "; keys must be strings");
      }
      const std::string name = k.cast<std::string>();
      j[name] = json_of(v, key.empty() ? name : key + "." + name);
    }
    return j;
  }
  if (py::isinstance<py::list>(o) || py::isinstance<py::tuple>(o)) {
    nlohmann::json j = nlohmann::json::array();
    size_t i = 0;
    for (const auto& v : o) j.push_back(json_of(v, key + "[" + std::to_string(i++) + "]"));
    return j;
  }
  if (py::hasattr(o, "tolist") && py::hasattr(o, "dtype")) return json_of(o.attr("tolist")(), key);  // numpy
  throw std::invalid_argument("run_scene: " + where + " is a " + py::str(py::type::of(o)).cast<std::string>() +
                              "; a scene holds str, bool, int, float, lists, dicts and numpy numbers or arrays");
}

}  // namespace wbm::python
