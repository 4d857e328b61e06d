#include "fivebar/io/csv.h"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>
#include <string_view>

#include "fivebar/io/errors.h"
#include "fivebar/io/format.h"

namespace fivebar::io {
namespace {

using identification::LogError;

// the fields of a line, blanks trimmed, as views into it; a trailing comma gives a last, empty
// field
std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> fields;
  std::string_view::size_type start = 0;
  while (true) {
    const auto pos = line.find(',', start);
    fields.push_back(trimmed(line.substr(start, pos - start)));
    if (pos == std::string_view::npos) break;
    start = pos + 1;
  }
  return fields;
}

std::string line_key(int line) { return "line " + std::to_string(line); }

// `f` as a number (strtod's syntax, all of `f`): *number false when it is not one. The common
// decimal fields go through from_chars (correctly rounded like strtod, several times faster on
// 17 digits); the rest (a sign '+', hexadecimal, out of range) through strtod.
double parse_number(std::string_view f, bool* number) {
  double v = 0;
  const char* end = f.data() + f.size();
  const auto [ptr, ec] = std::from_chars(f.data(), end, v);
  if (ec == std::errc() && ptr == end) {
    *number = true;
    return v;
  }
  const std::string text(f);  // strtod reads up to a terminating zero
  char* stop = nullptr;
  v = std::strtod(text.c_str(), &stop);
  *number = !text.empty() && stop == text.c_str() + text.size();
  return v;
}

// one data row of a CSV: every field a finite number
std::vector<double> parse_row(const CsvTable& table, const std::vector<std::string_view>& fields,
                              int line_no, const CsvRules& rules) {
  if (fields.size() != table.columns.size()) {
    throw LogError(table.path, line_key(line_no),
                   "expected " + std::to_string(table.columns.size()) + " fields, got " +
                       std::to_string(fields.size()));
  }
  std::vector<double> row(fields.size());
  for (size_t j = 0; j < fields.size(); ++j) {
    bool number = false;
    row[j] = parse_number(fields[j], &number);
    if (!number || !(rules.non_finite || std::isfinite(row[j]))) {
      const std::string f(fields[j]);
      throw LogError(table.path, line_key(line_no) + ", column " + table.columns[j],
                     rules.bad_number ? rules.bad_number(f, number)
                                      : "'" + f + "' is not a finite number");
    }
  }
  return row;
}

}  // namespace

int CsvTable::find(const std::string& name) const {
  for (size_t j = 0; j < columns.size(); ++j) {
    if (columns[j] == name) return static_cast<int>(j);
  }
  return -1;
}

void stream_csv(std::istream& in, const std::string& path, const CsvRules& rules, CsvTable* table,
                const std::function<void(std::vector<double>&& row, int line)>& sink) {
  table->path = path;
  std::string raw;
  int line_no = 0;
  while (std::getline(in, raw)) {
    ++line_no;
    std::string_view line = trimmed(raw);
    // a UTF-8 byte-order mark (as spreadsheet programs write) is not part of the first line
    if (line_no == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line = trimmed(line.substr(3));
    if (line.empty()) continue;
    if (line[0] == '#') {
      table->comments.emplace_back(line.substr(1));
      continue;
    }
    const std::vector<std::string_view> fields = split(line);
    if (table->header_line == 0) {
      std::vector<std::string> names(fields.begin(), fields.end());
      if (rules.header) rules.header(names, line_no);
      table->columns = std::move(names);
      table->header_line = line_no;
      continue;
    }
    sink(parse_row(*table, fields, line_no, rules), line_no);
  }
}

CsvTable parse_csv(const std::string& text, const std::string& path, const CsvRules& rules) {
  CsvTable table;
  std::istringstream in(text);
  stream_csv(in, path, rules, &table, [&](std::vector<double>&& row, int line) {
    table.rows.push_back(std::move(row));
    table.lines.push_back(line);
    if (rules.row) rules.row(table);
  });
  return table;
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

CsvTable read_csv(const std::string& path, const std::string& option) {
  std::ifstream in(path);
  if (!in) throw InputError(path, option, std::string("cannot open: ") + std::strerror(errno));
  std::stringstream text;
  text << in.rdbuf();
  if (in.bad()) {
    throw InputError(path, option, std::string("cannot read: ") + std::strerror(errno));
  }
  CsvRules rules;
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
    table = parse_csv(text.str(), path, rules);
  } catch (const identification::LogError& e) {
    throw InputError(e.file(), e.key(), e.reason());
  }
  if (table.header_line == 0) throw InputError(path, option, "empty: no header row");
  return table;
}

std::string csv_line(const std::vector<std::string>& fields) {
  std::string line;
  for (size_t i = 0; i < fields.size(); ++i) line += (i ? "," : "") + fields[i];
  return line + "\n";
}

std::string csv_quote(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += '"';
    out += (c == '\n' || c == '\r') ? ' ' : c;
  }
  return out + "\"";
}

}  // namespace fivebar::io
