#include "fivebar/io/torque_log_file.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "fivebar/io/csv.h"
#include "fivebar/model/scalar.h"

namespace fivebar::io {
namespace {

using identification::kLogOptional;
using identification::kLogRequired;
using identification::LogError;
using identification::TorqueLog;

std::string line_key(int line) { return "line " + std::to_string(line); }

// the torque-log header: required columns, optional pairs, nothing else
void check_log_header(const std::string& path, const std::vector<std::string>& names,
                      int line_no) {
  std::map<std::string, int> index;
  for (size_t j = 0; j < names.size(); ++j) {
    const std::string& n = names[j];
    const bool known = std::find(std::begin(kLogRequired), std::end(kLogRequired), n) !=
                           std::end(kLogRequired) ||
                       std::find(std::begin(kLogOptional), std::end(kLogOptional), n) !=
                           std::end(kLogOptional);
    const std::string col = line_key(line_no) + ", column " + std::to_string(j + 1);
    if (n.empty()) throw LogError(path, col, "empty column name in the header");
    if (!known) {
      throw LogError(path, col,
                     "unknown column '" + n +
                         "' (expected t,theta1,theta2,tau1,tau2 and optionally "
                         "omega1,omega2,alpha1,alpha2)");
    }
    if (index.count(n)) throw LogError(path, col, "duplicate column '" + n + "'");
    index[n] = static_cast<int>(j);
  }
  for (const char* r : kLogRequired) {
    if (!index.count(r)) {
      throw LogError(path, "header",
                     std::string("missing column '") + r +
                         "' (a torque log needs t,theta1,theta2,tau1,tau2)");
    }
  }
  for (auto [a, b] : {std::pair{"omega1", "omega2"}, std::pair{"alpha1", "alpha2"}}) {
    if (index.count(a) != index.count(b)) {
      throw LogError(path, "header",
                     std::string("column '") + (index.count(a) ? a : b) + "' without '" +
                         (index.count(a) ? b : a) + "' (they come in pairs)");
    }
  }
}

// time strictly increasing, checked as each row arrives
void check_log_time(const CsvTable& table) {
  const size_t n = table.rows.size();
  const int t = table.find("t");
  if (n < 2 || table.rows[n - 1][t] > table.rows[n - 2][t]) return;
  throw LogError(table.path, line_key(table.lines.back()) + ", column t",
                 "time not strictly increasing (" + format_shortest(table.rows[n - 1][t]) +
                     " after " + format_shortest(table.rows[n - 2][t]) + ")");
}

// angles in degrees and rates in other units are common mistakes; say so instead of failing
// later
void check_log_units(const TorqueLog& log) {
  for (int j = 0; j < fivebar::kDof; ++j) {
    const std::vector<double>& th = j == 0 ? log.theta1 : log.theta2;
    const std::vector<double>* om = log.has_rates ? (j == 0 ? &log.omega1 : &log.omega2) : nullptr;
    const std::string why = identification::looks_like_degrees(log, th, om);
    if (!why.empty()) {
      throw LogError(log.path, std::string("column theta") + char('1' + j),
                     "angles look like degrees, expected radians (" + why + ")");
    }
    const std::string off = om ? identification::rates_mismatch(log, th, *om) : "";
    if (!off.empty()) {
      throw LogError(log.path, std::string("column omega") + char('1' + j),
                     "rates do not match the angles: " + off +
                         "; expected rad/s of the same crank, positive counter-clockwise");
    }
  }
}

}  // namespace

TorqueLog read_torque_log(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw LogError(path, "(file)", "is a directory, expected a CSV file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw LogError(path, "(file)", std::string("cannot open: ") + std::strerror(errno));
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_torque_log(ss.str(), path);
}

TorqueLog parse_torque_log(const std::string& text, const std::string& path) {
  CsvRules rules;
  rules.header = [&path](const std::vector<std::string>& names, int line) {
    check_log_header(path, names, line);
  };
  rules.row = check_log_time;
  const CsvTable table = parse_csv(text, path, rules);
  if (table.header_line == 0) throw LogError(path, "header", "empty file (no header row)");
  if (table.rows.empty()) throw LogError(path, "samples", "no data rows under the header");
  TorqueLog log;
  log.path = path;
  log.comments = table.comments;
  log.lines = table.lines;
  log.has_rates = table.has("omega1");
  log.has_accels = table.has("alpha1");
  std::map<std::string, std::vector<double>*> dest = {
      {"t", &log.t},           {"theta1", &log.theta1}, {"theta2", &log.theta2},
      {"tau1", &log.tau1},     {"tau2", &log.tau2},     {"omega1", &log.omega1},
      {"omega2", &log.omega2}, {"alpha1", &log.alpha1}, {"alpha2", &log.alpha2}};
  for (size_t j = 0; j < table.columns.size(); ++j) {
    std::vector<double>* column = dest[table.columns[j]];
    column->reserve(table.rows.size());
    for (const auto& row : table.rows) column->push_back(row[j]);
  }
  check_log_units(log);
  return log;
}

void write_torque_log(const std::string& path, const TorqueLog& log) {
  std::ostringstream out;
  for (const std::string& c : log.comments) out << "#" << c << "\n";
  out << "t,theta1,theta2,tau1,tau2";
  if (log.has_rates) out << ",omega1,omega2";
  if (log.has_accels) out << ",alpha1,alpha2";
  out << "\n";
  for (int i = 0; i < log.size(); ++i) {
    out << format_shortest(log.t[i]) << ',' << format_shortest(log.theta1[i]) << ','
        << format_shortest(log.theta2[i]) << ',' << format_shortest(log.tau1[i]) << ','
        << format_shortest(log.tau2[i]);
    if (log.has_rates) {
      out << ',' << format_shortest(log.omega1[i]) << ',' << format_shortest(log.omega2[i]);
    }
    if (log.has_accels) {
      out << ',' << format_shortest(log.alpha1[i]) << ',' << format_shortest(log.alpha2[i]);
    }
    out << "\n";
  }
  // write beside the target, then rename: no half-written log under the final name
  const std::string tmp = path + ".partial";
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f) throw LogError(path, "(write)", "cannot create the file");
    f << out.str();
    f.close();
    if (!f) throw LogError(path, "(write)", "write failed");
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw LogError(path, "(write)", "cannot rename the finished file into place");
  }
}

}  // namespace fivebar::io
