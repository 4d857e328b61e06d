#include "fivebar/io/torque_log_file.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "fivebar/identification/condition.h"
#include "fivebar/identification/rates.h"
#include "fivebar/io/csv.h"
#include "fivebar/model/format.h"
#include "fivebar/model/scalar.h"

namespace fivebar::io {
namespace {

using identification::median_of;
using identification::LogError;
using identification::TorqueLog;

std::string line_key(int line) { return "line " + std::to_string(line); }

// "t,theta1,theta2,tau1,tau2", the required columns as a header
std::string joined_names(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ",") + n;
  return out;
}

// what a log of `dof` cranks holds, for messages
std::string log_kind(int dof) {
  return std::string(dof == 1 ? "a four-bar's torque log (one crank)" : "a five-bar's torque log") +
         " has " + joined_names(identification::required_log_columns(dof)) + " and optionally " +
         joined_names(identification::optional_log_columns(dof));
}

// the torque-log header: required columns, optional groups, nothing else
void check_log_header(const std::string& path, const std::vector<std::string>& names,
                      int line_no, int dof) {
  const std::vector<std::string> required = identification::required_log_columns(dof),
                                 optional = identification::optional_log_columns(dof);
  auto listed = [](const std::vector<std::string>& v, const std::string& n) {
    return std::find(v.begin(), v.end(), n) != v.end();
  };
  std::map<std::string, int> index;
  for (size_t j = 0; j < names.size(); ++j) {
    const std::string& n = names[j];
    const std::string col = line_key(line_no) + ", column " + std::to_string(j + 1);
    if (n.empty()) throw LogError(path, col, "empty column name in the header");
    if (!listed(required, n) && !listed(optional, n)) {
      const bool other_dof = listed(identification::optional_log_columns(2), n) ||
                             listed(identification::required_log_columns(2), n);
      throw LogError(path, col,
                     (other_dof ? "column '" + n + "' does not belong to this mechanism: "
                                : "unknown column '" + n + "': ") + log_kind(dof));
    }
    if (index.count(n)) throw LogError(path, col, "duplicate column '" + n + "'");
    index[n] = static_cast<int>(j);
  }
  for (const std::string& r : required) {
    if (!index.count(r)) {
      throw LogError(path, "header", "missing column '" + r + "' (" + log_kind(dof) + ")");
    }
  }
  for (const char* group : {"omega", "alpha"}) {
    std::string present, missing;
    for (int j = 1; j <= dof; ++j) {
      const std::string n = group + std::to_string(j);
      (index.count(n) ? present : missing) = n;
    }
    if (!present.empty() && !missing.empty()) {
      throw LogError(path, "header", "column '" + present + "' without '" + missing + "' (the " +
                                         group + " columns come for every crank)");
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

// The angles' own rate and acceleration (unwrapped, Savitzky-Golay at the default filter).
void angle_derivatives(const TorqueLog& log, std::vector<double> theta, std::vector<double>* w,
                       std::vector<double>* a) {
  identification::unwrap_angles(&theta);
  identification::savitzky_golay(log.t, theta, identification::SgOptions(), w, a);
}

// A logged rate (order 1) or acceleration (order 2) against the angles' own (`own`,
// angle_derivatives; the one-sided edges left out): for accelerations, their median ratio where
// the crank accelerates (deg/s^2 reads 0.0175); for both, a median offset over a stretch of a
// tenth of the log (at least 100 samples) beyond 5 % of the column's median size and 8 std
// of that median (alpha1 + 50 or omega1 + 1 rad/s from mid-log would otherwise be fitted, with a
// spurious delay). Empty when they agree.
std::string derivative_mismatch(const TorqueLog& log, const std::vector<double>& own,
                                const std::vector<double>& logged, int order) {
  const int n = static_cast<int>(own.size());
  if (n < 20) return "";
  const identification::SgOptions sg;
  const int edge = identification::sg_half_window(sg, log.duration() / (n - 1));
  std::vector<double> size;
  for (int i = edge; i < n - edge; ++i) size.push_back(std::abs(logged[i]));
  if (size.size() < 20) return "";
  const double typical = median_of(size);
  const char* unit = order == 1 ? " rad/s" : " rad/s^2";
  if (order == 2) {
    std::vector<double> ratio;
    for (int i = edge; i < n - edge; ++i) {
      if (std::abs(logged[i]) >= typical && logged[i] != 0) ratio.push_back(own[i] / logged[i]);
    }
    const double r = ratio.size() < 10 ? 1.0 : median_of(ratio);
    if (!(std::abs(r - 1) <= 0.25)) {
      return "the angles' second derivative is a median " + format_significant(r, 3) +
             " times the logged acceleration where the crank accelerates (expected 1)";
    }
  }
  const int span = std::max(100, (n - 2 * edge) / 10);
  for (int lo = edge; lo + span <= n - edge; lo += span) {
    std::vector<double> d;
    for (int i = lo; i < lo + span; ++i) d.push_back(logged[i] - own[i]);
    const double m = median_of(d);
    for (double& x : d) x -= m;
    const double std_of_median = 1.25 * identification::robust_std(d) / std::sqrt(span);
    if (std::abs(m) > 0.05 * typical && std::abs(m) > 8 * std_of_median) {
      auto line = [&](int i) { return log.lines.empty() ? i + 1 : log.lines[i]; };
      return "over lines " + std::to_string(line(lo)) + "-" + std::to_string(line(lo + span - 1)) +
             " the logged values are a median " +
             format_significant(m, 3) + unit + " off the angles' (the column's median size is " +
             format_significant(typical, 3) + unit + "): an offset, or another quantity";
    }
  }
  return "";
}

// Time stamps in milliseconds (or sample counts) read as seconds make a 1 kHz log a 1 Hz one,
// whose motion is 1000 times slower: every estimate is then wrong, with warnings that do not
// say why. A five-bar's dynamics cannot be identified from samples 0.5 s
// apart, so a median step that long is refused, naming the likely unit; so is a step of 0.05 s
// or more under which neither crank ever turns faster than 0.05 rad/s (millisecond stamps of a
// 2 to 20 kHz log: a 5 kHz log read as 5 Hz gives viscous 21.5).
constexpr double kLongestTimeStep = 0.5;  // [s]
constexpr double kSlowTimeStep = 0.05;    // [s]
constexpr double kSlowestMotion = 0.05;   // [rad/s]

// the largest crank rate of the log by first differences, unwrapped [rad/s]
double fastest_crank(const TorqueLog& log) {
  double fastest = 0;
  for (int j = 0; j < log.dof; ++j) {
    const std::vector<double>& th = log.theta(j);
    for (size_t i = 0; i + 1 < th.size(); ++i) {
      const double d = std::remainder(th[i + 1] - th[i], 2 * M_PI);
      fastest = std::max(fastest, std::abs(d) / (log.t[i + 1] - log.t[i]));
    }
  }
  return fastest;
}

void check_log_time_unit(const TorqueLog& log) {
  const double step = identification::median_time_step(log);
  if (!(step >= kSlowTimeStep)) return;
  const bool shorter = !(step >= kLongestTimeStep);  // then refused only without motion
  if (shorter && !(fastest_crank(log) < kSlowestMotion)) return;
  throw LogError(log.path, "column t",
                 "median time step " + format_significant(step, 3) +
                     (shorter ? " under which no crank turns faster than " +
                                    format_significant(kSlowestMotion) + " rad/s"
                              : std::string()) +
                     ": t must be in seconds, and a mechanism's log samples at tens of Hz or "
                     "more; these stamps look like milliseconds, microseconds or sample counts");
}

// angles in degrees and rates in other units are common mistakes; say so instead of failing
// later
void check_log_units(const TorqueLog& log) {
  for (int j = 0; j < log.dof; ++j) {
    const std::vector<double>& th = log.theta(j);
    const std::vector<double>* om = log.has_rates ? &log.omega(j) : nullptr;
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
    std::vector<double> own_w, own_a;  // the angles' own, for the logged rates and accelerations
    if (om != nullptr && th.size() >= 20) angle_derivatives(log, th, &own_w, &own_a);
    const std::string w_off = om ? derivative_mismatch(log, own_w, *om, 1) : "";
    if (!w_off.empty()) {
      throw LogError(log.path, std::string("column omega") + char('1' + j),
                     "rates do not match the angles: " + w_off);
    }
    const std::vector<double>* al = log.has_accels ? &log.alpha(j) : nullptr;
    if (al != nullptr && own_a.empty() && th.size() >= 20) {
      angle_derivatives(log, th, &own_w, &own_a);
    }
    const std::string a_off = al ? derivative_mismatch(log, own_a, *al, 2) : "";
    if (!a_off.empty()) {
      throw LogError(log.path, std::string("column alpha") + char('1' + j),
                     "accelerations do not match the angles: " + a_off +
                         "; expected rad/s^2 of the same crank, positive counter-clockwise");
    }
  }
}

}  // namespace

TorqueLog read_torque_log(const std::string& path, int dof) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw LogError(path, "(file)", "is a directory, expected a CSV file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw LogError(path, "(file)", std::string("cannot open: ") + std::strerror(errno));
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_torque_log(ss.str(), path, dof);
}

TorqueLog parse_torque_log(const std::string& text, const std::string& path, int dof) {
  CsvRules rules;
  rules.header = [&path, dof](const std::vector<std::string>& names, int line) {
    check_log_header(path, names, line, dof);
  };
  rules.row = check_log_time;
  const CsvTable table = parse_csv(text, path, rules);
  if (table.header_line == 0) throw LogError(path, "header", "empty file (no header row)");
  if (table.rows.empty()) throw LogError(path, "samples", "no data rows under the header");
  TorqueLog log;
  log.path = path;
  log.dof = dof;
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
  check_log_time_unit(log);
  check_log_units(log);
  return log;
}

void write_torque_log(const std::string& path, const TorqueLog& log) {
  std::ostringstream out;
  for (const std::string& c : log.comments) out << "#" << c << "\n";
  std::vector<const std::vector<double>*> columns = {&log.t};
  for (int j = 0; j < log.dof; ++j) columns.push_back(&log.theta(j));
  for (int j = 0; j < log.dof; ++j) columns.push_back(&log.tau(j));
  std::vector<std::string> names = identification::required_log_columns(log.dof);
  const std::vector<std::string> optional = identification::optional_log_columns(log.dof);
  for (int j = 0; j < log.dof; ++j) {
    if (log.has_rates) {
      columns.push_back(&log.omega(j));
      names.push_back(optional[j]);
    }
  }
  for (int j = 0; j < log.dof; ++j) {
    if (log.has_accels) {
      columns.push_back(&log.alpha(j));
      names.push_back(optional[log.dof + j]);
    }
  }
  out << joined_names(names) << "\n";
  for (int i = 0; i < log.size(); ++i) {
    for (size_t c = 0; c < columns.size(); ++c) {
      out << (c ? "," : "") << format_shortest((*columns[c])[i]);
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
