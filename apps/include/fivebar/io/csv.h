// Reading numeric CSV files with a header row (motion files, torque logs).
#pragma once

#include <functional>
#include <istream>
#include <string>
#include <vector>

#include "fivebar/identification/torque_log.h"

namespace fivebar::io {

/// A numeric table parsed from CSV text: `#` comment lines, blank lines, one header row, then
/// rows of finite numbers. The one CSV parser of the toolkit: torque logs (torque_log_file.h), motion
/// files and reference trajectories (read_csv).
struct CsvTable {
  std::string path;                       ///< as given, for messages
  std::vector<std::string> columns;       ///< header names, blanks trimmed
  std::vector<std::vector<double>> rows;  ///< rows[i][j]: row i, column j
  std::vector<int> lines;                 ///< 1-based line number in the text of each row
  std::vector<std::string> comments;      ///< `#` lines, trimmed, without the leading '#'
  int header_line = 0;                    ///< line of the header; 0 when the text has none

  /// Index of column `name`, or -1.
  int find(const std::string& name) const;
  bool has(const std::string& name) const { return find(name) >= 0; }
  /// Index of column `name`; throws InputError(`<path>: header: missing column 'name' ...`).
  int require(const std::string& name) const;
  /// The values of column `name` (require()d).
  std::vector<double> column(const std::string& name) const;
};

/// What a format requires of a CSV beyond the parser's own checks, and how it words a bad field.
/// Every hook is optional and may throw its own error.
struct CsvRules {
  /// Checks the header names (on line `line`) before any row is read.
  std::function<void(const std::vector<std::string>& names, int line)> header;
  /// The reason for a field that is not a finite number (`number`: it reads as a number, just
  /// not a finite one); default "'<field>' is not a finite number".
  std::function<std::string(const std::string& field, bool number)> bad_number;
  /// Checks the table each time a row has been added (e.g. time increasing).
  std::function<void(const CsvTable& table)> row;
  /// nan and inf read as numbers (a run's own outputs, where nan marks a value not computed)
  bool non_finite = false;
};

/// Parses CSV text (`path` only names it in messages). Throws identification::LogError(`<path>: line N: expected
/// K fields, got M`) for a row of the wrong length and LogError(`<path>: line N, column NAME:
/// <bad_number>`) for a field that is not a finite number (strtod syntax), besides whatever the
/// rules' hooks throw. Text without a header row gives a table with header_line = 0.
CsvTable parse_csv(const std::string& text, const std::string& path, const CsvRules& rules = {});

/// The same from a stream, row by row: each row goes to `sink` (with its line number) instead of
/// into the table, which holds the header and comments (its rows stay empty; rules.row is not
/// called). For files too large to hold twice.
void stream_csv(std::istream& in, const std::string& path, const CsvRules& rules, CsvTable* table,
                const std::function<void(std::vector<double>&& row, int line)>& sink);

/// Reads a CSV of finite numbers under a header row. Blank lines and lines starting with '#'
/// are skipped. Throws InputError naming the file, the line and column and the reason for a
/// missing file, an empty file, duplicate header names, a row with the wrong number of fields,
/// or a field that is not a finite number.
/// `option`: the key of the errors of the file itself (cannot open or read, empty): the option
/// that named the file (`--motion`), or "(file)".
CsvTable read_csv(const std::string& path, const std::string& option = "(file)");

/// One CSV line: the fields joined by commas, and a newline (fields are written as given: quote
/// text that may hold commas with csv_quote).
std::string csv_line(const std::vector<std::string>& fields);

/// `s` as one CSV field: in double quotes, a quote doubled (RFC 4180), a line feed or carriage
/// return written as a space (one record per line).
std::string csv_quote(const std::string& s);

}  // namespace fivebar::io
