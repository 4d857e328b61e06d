// Reading numeric CSV files with a header row (motion files, torque logs).
#pragma once

#include <string>
#include <vector>

namespace fivebar::io {

/// A numeric table read from a CSV file.
struct CsvTable {
  std::string path;                       ///< as given, for error messages
  std::vector<std::string> columns;       ///< header names, blanks trimmed
  std::vector<std::vector<double>> rows;  ///< rows[i][j]: row i, column j
  std::vector<int> lines;                 ///< 1-based line number in the file of each row

  /// Index of column `name`, or -1.
  int find(const std::string& name) const;
  bool has(const std::string& name) const { return find(name) >= 0; }
  /// Index of column `name`; throws InputError(`<path>: header: missing column 'name' ...`).
  int require(const std::string& name) const;
  /// The values of column `name` (require()d).
  std::vector<double> column(const std::string& name) const;
};

/// Reads a CSV of finite numbers under a header row. Blank lines and lines starting with '#'
/// are skipped. Throws InputError naming the file, the line and column and the reason for a
/// missing file, an empty file, duplicate header names, a row with the wrong number of fields,
/// or a field that is not a finite number.
CsvTable read_csv(const std::string& path);

/// `s` as one CSV field: in double quotes, a quote doubled (RFC 4180).
std::string csv_quote(const std::string& s);

}  // namespace fivebar::io
