// The records the command line writes as JSON (identification.json, summary.json), as Python
// objects: the same builder feeds both, so no field is in one and not the other.
#include "bindings.h"

namespace fivebar::python {
namespace {

using io::Json;

bool numeric(const Json& j) {
  return j.type() == Json::Type::kNumber || j.type() == Json::Type::kInteger;
}

// an array of numbers (1-D) or of equal-length arrays of numbers (2-D) as a NumPy array: the
// columns of n values per row, or none when `a` is not such an array
py::object numeric_array(const Json& a) {
  const std::vector<Json>& items = a.items();
  if (items.empty()) return py::none();
  bool flat = true, integers = true;
  for (const Json& x : items) {
    flat = flat && numeric(x);
    integers = integers && x.type() == Json::Type::kInteger;
  }
  if (flat && integers) {
    py::array_t<long long> out(static_cast<py::ssize_t>(items.size()));
    for (size_t i = 0; i < items.size(); ++i) out.mutable_data()[i] = items[i].integer();
    return std::move(out);
  }
  std::vector<double> values;
  if (flat) {
    for (const Json& x : items) values.push_back(x.number());
    return to_array(values);
  }
  const size_t cols = items[0].items().size();
  for (const Json& row : items) {
    if (row.type() != Json::Type::kArray || row.items().size() != cols || cols == 0) {
      return py::none();
    }
    for (const Json& x : row.items()) {
      if (!numeric(x)) return py::none();
      values.push_back(x.number());
    }
  }
  return to_array(values, {static_cast<py::ssize_t>(items.size()), static_cast<py::ssize_t>(cols)});
}

}  // namespace

py::object to_python(const Json& j) {
  switch (j.type()) {
    case Json::Type::kNull:
      return py::none();
    case Json::Type::kBool:
      return py::bool_(j.boolean());
    case Json::Type::kNumber:
      return py::float_(j.number());  // NaN stays NaN (the JSON file writes null)
    case Json::Type::kInteger:
      return py::int_(j.integer());
    case Json::Type::kString:
      return py::str(j.string());
    case Json::Type::kArray: {
      py::object array = numeric_array(j);
      if (!array.is_none()) return array;
      py::list list;
      for (const Json& x : j.items()) list.append(to_python(x));
      return std::move(list);
    }
    case Json::Type::kObject: {
      py::dict d;
      for (size_t i = 0; i < j.keys().size(); ++i)
        d[py::str(j.keys()[i])] = to_python(j.items()[i]);
      return std::move(d);
    }
  }
  return py::none();
}

}  // namespace fivebar::python
