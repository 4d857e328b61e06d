#include "fivebar/io/csv.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <set>

#include "fivebar/io/errors.h"
#include "fivebar/io/format.h"

namespace fivebar::io {
namespace {

std::vector<std::string> split_fields(const std::string& line) {
  std::vector<std::string> fields;
  std::string::size_type start = 0;
  while (true) {
    const auto pos = line.find(',', start);
    fields.push_back(trim(line.substr(start, pos - start)));
    if (pos == std::string::npos) break;
    start = pos + 1;
  }
  return fields;
}

}  // namespace

int CsvTable::find(const std::string& name) const {
  for (size_t j = 0; j < columns.size(); ++j) {
    if (columns[j] == name) return static_cast<int>(j);
  }
  return -1;
}

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
  CsvTable table;
  table.path = path;
  std::string line;
  int number = 0;
  bool header = false;
  while (std::getline(in, line)) {
    ++number;
    const std::string text = trim(line);
    if (text.empty() || text[0] == '#') continue;
    const std::string where = "line " + std::to_string(number);
    std::vector<std::string> fields = split_fields(text);
    if (!header) {
      // the first non-comment line names the columns
      std::set<std::string> seen;
      for (const auto& f : fields) {
        if (f.empty()) throw InputError(path, where, "empty column name in the header");
        if (!seen.insert(f).second) throw InputError(path, where, "duplicate column '" + f + "'");
      }
      table.columns = std::move(fields);
      header = true;
      continue;
    }
    if (fields.size() != table.columns.size()) {
      throw InputError(path, where,
                       "expected " + std::to_string(table.columns.size()) + " fields, got " +
                           std::to_string(fields.size()));
    }
    std::vector<double> row(fields.size());
    for (size_t j = 0; j < fields.size(); ++j) {
      const char* s = fields[j].c_str();
      char* end = nullptr;
      row[j] = std::strtod(s, &end);
      const std::string key = where + ", column " + table.columns[j];
      if (fields[j].empty() || end != s + fields[j].size()) {
        throw InputError(path, key, "not a number: '" + fields[j] + "'");
      }
      if (!std::isfinite(row[j])) throw InputError(path, key, "not finite: " + fields[j]);
    }
    table.rows.push_back(std::move(row));
    table.lines.push_back(number);
  }
  if (in.bad())
    throw InputError(path, "(file)", std::string("cannot read: ") + std::strerror(errno));
  if (!header) throw InputError(path, "(file)", "empty: no header row");
  return table;
}

std::string csv_quote(const std::string& s) {
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

}  // namespace fivebar::io
