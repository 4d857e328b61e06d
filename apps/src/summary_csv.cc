#include "fivebar/io/summary_csv.h"

#include <string>

#include "fivebar/io/csv.h"
#include "fivebar/io/format.h"

namespace fivebar::io {
namespace {

// the column derived from two fields, placed after this one
constexpr const char* kSavingAfter = "baseline_peak_torque";
constexpr const char* kSaving = "saving_percent";

// the columns and fields of one row from trajectory::visit_fields
struct Row {
  const trajectory::TaskResult* r = nullptr;  // null: the header only
  std::vector<std::string>* out;
  void add(const char* name, const std::string& field) const {
    out->push_back(r ? field : std::string(name));
    if (std::string(name) != kSavingAfter) return;
    const double saving =
        r ? 100.0 * (1.0 - r->dissipated_energy / r->baseline_dissipated_energy) : 0.0;
    out->push_back(r ? format_double(saving) : std::string(kSaving));
  }
  void operator()(const char* name, const std::string& v) const {
    const std::string n = name;
    const bool text = n == "continuation" || n == "refinement" || n == "message";
    add(name, text ? csv_quote(v) : v);
  }
  void operator()(const char* name, double v) const {
    // the angles of a task that was not resolved are meaningless
    const bool angle = std::string(name).rfind("theta", 0) == 0;
    add(name, angle && r && r->control_points <= 0 ? std::string("nan") : format_double(v));
  }
  void operator()(const char* name, int v) const { add(name, std::to_string(v)); }
  void operator()(const char* name, bool v) const { add(name, v ? "true" : "false"); }
  void operator()(const char*, const std::vector<double>&) const {}  // x: not a column
};

}  // namespace

const std::vector<std::string>& summary_columns() {
  static const std::vector<std::string> columns = [] {
    std::vector<std::string> c;
    trajectory::TaskResult dummy;
    trajectory::visit_fields(dummy, Row{nullptr, &c});
    return c;
  }();
  return columns;
}

std::vector<std::string> summary_fields(const trajectory::TaskResult& r) {
  std::vector<std::string> f;
  trajectory::visit_fields(r, Row{&r, &f});
  return f;
}

}  // namespace fivebar::io
