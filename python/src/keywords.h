// Keyword options of the module's functions, mapped onto the command lines' settings structs
// (io::IdentifySettings, io::OptimizeSettings): one table per function, whose defaults are the
// structs' own, so Python and the command line cannot drift apart.
#pragma once

#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <initializer_list>
#include <utility>
#include <string>
#include <variant>
#include <vector>

#include "fivebar/model/format.h"

namespace fivebar::python {

namespace py = pybind11;

/// One keyword: its Python name and the settings member it sets.
template <class S>
struct Keyword {
  const char* name;
  std::variant<std::string S::*, double S::*, int S::*, bool S::*, std::vector<int> S::*> member;
};

template <class S>
using Keywords = std::initializer_list<Keyword<S>>;

/// Python text of a default value ("'slsqp'", "0.1", "True", "[]").
inline std::string python_text(const std::string& v) { return "'" + v + "'"; }
inline std::string python_text(double v) { return format_shortest(v); }
inline std::string python_text(int v) { return std::to_string(v); }
inline std::string python_text(bool v) { return v ? "True" : "False"; }
inline std::string python_text(const std::vector<int>& v) {
  std::string s = "[";
  for (size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + std::to_string(v[i]);
  return s + "]";
}

/// "name=default, ..." of a table, from a default-constructed S (for the docstrings).
template <class S>
std::string keyword_defaults(
    const S& defaults, Keywords<S> keywords,
    std::initializer_list<std::pair<const char*, const char*>> shown_as = {}) {
  std::string out;
  for (const Keyword<S>& k : keywords) {
    if (!out.empty()) out += ", ";
    out += k.name;
    std::string value = std::visit([&](auto m) { return python_text(defaults.*m); }, k.member);
    for (const auto& [name, text] : shown_as) {
      if (std::string(name) == k.name) value = text;  // a default that is not a constant
    }
    out += "=" + value;
  }
  return out;
}

/// Applies the keyword arguments `kw` to `settings`. Keywords listed in `own` are the function's
/// (not settings) and are skipped; any other unknown keyword, or a value of the wrong type, raises
/// TypeError naming the function and the keyword.
template <class S>
void apply_keywords(const char* function, const py::kwargs& kw, Keywords<S> keywords,
                    std::initializer_list<const char*> own, S* settings) {
  for (const auto& [key, value] : kw) {
    const std::string name = py::str(key);
    bool skip = false;
    for (const char* o : own) skip = skip || name == o;
    if (skip) continue;
    const Keyword<S>* found = nullptr;
    for (const Keyword<S>& k : keywords) {
      if (name == k.name) found = &k;
    }
    if (!found) {
      throw py::type_error(std::string(function) + "() got an unexpected keyword argument '" +
                           name + "'");
    }
    std::visit(
        [&](auto m) {
          using V = std::remove_reference_t<decltype(settings->*m)>;
          try {
            settings->*m = py::cast<V>(value);
          } catch (const py::cast_error&) {
            throw py::type_error(std::string(function) + "(): keyword '" + name + "' cannot take " +
                                 std::string(py::repr(value)));
          }
        },
        found->member);
  }
}

/// The value of the function's own keyword `name`, or `fallback` when it is not given.
template <class V>
V own_keyword(const py::kwargs& kw, const char* name, V fallback) {
  return kw.contains(name) ? py::cast<V>(kw[name]) : fallback;
}

}  // namespace fivebar::python
