#include "fivebar/io/csv.h"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>

#include "fivebar/io/errors.h"

namespace fivebar::io {

int CsvTable::require(const std::string& name) const {
  const int j = find(name);
  if (j < 0) {
    std::string have;
    for (const auto& c : columns) have += (have.empty() ? "" : ",") + c;
    throw InputError(path, "header",
                     "missing column '" + name + "' (the header has: " + have + ")");
  }
  return j;
}

std::vector<double> CsvTable::column(const std::string& name) const {
  const int j = require(name);
  std::vector<double> out;
  out.reserve(rows.size());
  for (const auto& r : rows) out.push_back(r[j]);
  return out;
}

CsvTable read_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "(file)", std::string("cannot open: ") + std::strerror(errno));
  std::stringstream text;
  text << in.rdbuf();
  if (in.bad()) {
    throw InputError(path, "(file)", std::string("cannot read: ") + std::strerror(errno));
  }
  identification::CsvRules rules;
  rules.header = [&path](const std::vector<std::string>& names, int line) {
    // the first non-comment line names the columns
    const std::string where = "line " + std::to_string(line);
    std::set<std::string> seen;
    for (const auto& f : names) {
      if (f.empty()) throw InputError(path, where, "empty column name in the header");
      if (!seen.insert(f).second) throw InputError(path, where, "duplicate column '" + f + "'");
    }
  };
  rules.bad_number = [](const std::string& field, bool number) {
    return number ? "not finite: " + field : "not a number: '" + field + "'";
  };
  CsvTable table;
  try {
    static_cast<identification::CsvTable&>(table) =
        identification::parse_csv(text.str(), path, rules);
  } catch (const identification::LogError& e) {
    throw InputError(e.file(), e.key(), e.reason());
  }
  if (table.header_line == 0) throw InputError(path, "(file)", "empty: no header row");
  return table;
}

std::string csv_quote(const std::string& s) {
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

}  // namespace fivebar::io
