// Torque log CSV: parsing with line/column diagnostics, plausibility checks, writing.
#include "fivebar/identification/torque_log.h"

#include <cerrno>
#include <cstring>
#include <algorithm>
#include <cstdlib>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

#include "fivebar/model/kinematics.h"

namespace fivebar::identification {
namespace {

std::string trim(const std::string& s) {
  const char* ws = " \t\r\n";
  const size_t a = s.find_first_not_of(ws);
  if (a == std::string::npos) return "";
  const size_t b = s.find_last_not_of(ws);
  return s.substr(a, b - a + 1);
}

// the fields of a line, blanks trimmed; a trailing comma gives a last, empty field
std::vector<std::string> split(const std::string& line) {
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

std::string line_key(int line) { return "line " + std::to_string(line); }

// one data row of a CSV: every field a finite number
std::vector<double> parse_row(const CsvTable& table, const std::vector<std::string>& fields,
                              int line_no, const CsvRules& rules) {
  if (fields.size() != table.columns.size()) {
    throw LogError(table.path, line_key(line_no),
                   "expected " + std::to_string(table.columns.size()) + " fields, got " +
                       std::to_string(fields.size()));
  }
  std::vector<double> row(fields.size());
  for (size_t j = 0; j < fields.size(); ++j) {
    const std::string& f = fields[j];
    char* end = nullptr;
    row[j] = std::strtod(f.c_str(), &end);
    const bool number = !f.empty() && end == f.c_str() + f.size();
    if (!number || !std::isfinite(row[j])) {
      throw LogError(table.path, line_key(line_no) + ", column " + table.columns[j],
                     rules.bad_number ? rules.bad_number(f, number)
                                      : "'" + f + "' is not a finite number");
    }
  }
  return row;
}

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
                 "time not strictly increasing (" + format_number(table.rows[n - 1][t]) +
                     " after " + format_number(table.rows[n - 2][t]) + ")");
}

// angles in degrees are a common mistake; say so instead of failing later
void check_log_units(const TorqueLog& log) {
  for (int j = 0; j < kDof; ++j) {
    const std::vector<double>& th = j == 0 ? log.theta1 : log.theta2;
    const std::vector<double>* om = log.has_rates ? (j == 0 ? &log.omega1 : &log.omega2) : nullptr;
    const std::string why = looks_like_degrees(log, th, om);
    if (!why.empty()) {
      throw LogError(log.path, std::string("column theta") + char('1' + j),
                     "angles look like degrees, expected radians (" + why + ")");
    }
  }
}

}  // namespace

int CsvTable::find(const std::string& name) const {
  for (size_t j = 0; j < columns.size(); ++j) {
    if (columns[j] == name) return static_cast<int>(j);
  }
  return -1;
}

CsvTable parse_csv(const std::string& text, const std::string& path, const CsvRules& rules) {
  CsvTable table;
  table.path = path;
  std::istringstream in(text);
  std::string raw;
  int line_no = 0;
  while (std::getline(in, raw)) {
    ++line_no;
    const std::string line = trim(raw);
    if (line.empty()) continue;
    if (line[0] == '#') {
      table.comments.push_back(line.substr(1));
      continue;
    }
    std::vector<std::string> fields = split(line);
    if (table.header_line == 0) {
      if (rules.header) rules.header(fields, line_no);
      table.columns = std::move(fields);
      table.header_line = line_no;
      continue;
    }
    table.rows.push_back(parse_row(table, fields, line_no, rules));
    table.lines.push_back(line_no);
    if (rules.row) rules.row(table);
  }
  return table;
}

TorqueLog read_torque_log(const std::string& path) {
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

std::string looks_like_degrees(const TorqueLog& log, const std::vector<double>& theta,
                               const std::vector<double>* omega) {
  const int n = static_cast<int>(theta.size());
  if (n < 2) return "";
  if (omega) {
    // slope of the finite-difference rate against the logged rate
    double sxy = 0, sxx = 0;
    for (int i = 0; i + 1 < n; ++i) {
      const double d = (theta[i + 1] - theta[i]) / (log.t[i + 1] - log.t[i]);
      const double w = 0.5 * ((*omega)[i] + (*omega)[i + 1]);
      sxy += d * w;
      sxx += w * w;
    }
    if (sxx > 0) {
      const double slope = sxy / sxx;
      if (std::abs(slope / (180.0 / M_PI) - 1.0) < 0.2) {
        return "d theta/dt is " + format_significant(slope, 6) + " times omega, close to 180/pi";
      }
    }
    return "";
  }
  // without rates the magnitude says nothing (multi-turn angles are radians too): identify
  // decides from the motion and the scene (degrees_from_motion, condition.h)
  return "";
}

void require_samples(const TorqueLog& log, int needed, const std::string& what) {
  if (log.size() < needed) {
    throw LogError(log.path, "samples",
                   std::to_string(log.size()) + " samples, fewer than the " +
                       std::to_string(needed) + " needed (" + what + ")");
  }
}

void check_poses(const TorqueLog& log, const Params<double>& params) {
  Kinematics<double> k;
  for (int i = 0; i < log.size(); ++i) {
    const Status st = solve_kinematics(params, log.theta1[i], log.theta2[i], &k, 0.0);
    if (!st.ok()) {
      throw LogError(log.path, line_key(log.lines.empty() ? i + 1 : log.lines[i]),
                     "pose does not fit the scene: " + st.message);
    }
  }
}

void write_torque_log(const std::string& path, const TorqueLog& log) {
  std::ostringstream out;
  for (const std::string& c : log.comments) out << "#" << c << "\n";
  out << "t,theta1,theta2,tau1,tau2";
  if (log.has_rates) out << ",omega1,omega2";
  if (log.has_accels) out << ",alpha1,alpha2";
  out << "\n";
  for (int i = 0; i < log.size(); ++i) {
    out << format_number(log.t[i]) << ',' << format_number(log.theta1[i]) << ','
        << format_number(log.theta2[i]) << ',' << format_number(log.tau1[i]) << ','
        << format_number(log.tau2[i]);
    if (log.has_rates) {
      out << ',' << format_number(log.omega1[i]) << ',' << format_number(log.omega2[i]);
    }
    if (log.has_accels) {
      out << ',' << format_number(log.alpha1[i]) << ',' << format_number(log.alpha2[i]);
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

}  // namespace fivebar::identification
