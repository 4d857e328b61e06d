// The paper-scene fixture of every test and benchmark: the canonical scene's loads and start,
// and (where FIVEBAR_REFERENCE_DIR is defined) the reference trajectories of datasets/reference.
#pragma once

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "fivebar/model/params.h"
#include "fivebar/sim/simulator.h"

namespace fivebar::testing {

/// Loads of the canonical scene (model.md, section 5).
inline Loads<double> paper_loads(double t) {
  return {2 + 5 * std::sin(8 * M_PI * t), 3 + 5 * std::cos(M_PI * t), 6.0, 50.0, M_PI / 2};
}

/// The canonical scene's loads other than the motor torques M1, M2: M3 = 6 N m, F = 50 N at
/// pi/2 from link 3.
inline Loads<double> paper_static_loads(double M1 = 0.0, double M2 = 0.0) {
  return {M1, M2, 6.0, 50.0, M_PI / 2};
}

inline sim::Initial paper_initial() { return {M_PI / 2, M_PI / 2, 0.0, 0.0}; }

/// Largest |theta_k(t) - theta_k(0)| over the rows of a run, for the first `angles` angles.
inline double max_displacement(const sim::Result& r, int angles) {
  double worst = 0.0;
  for (const sim::Row& row : r.rows) {
    for (int k = 0; k < angles; ++k) {
      worst = std::max(worst, std::abs(row.theta[k] - r.rows.front().theta[k]));
    }
  }
  return worst;
}

#ifdef FIVEBAR_REFERENCE_DIR

/// A CSV file with a header row, as columns by name.
inline std::map<std::string, std::vector<double>> read_csv(const std::string& path) {
  std::map<std::string, std::vector<double>> cols;
  std::ifstream in(path);
  std::string line;
  std::vector<std::string> names;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::stringstream ss(line);
    std::string cell;
    if (names.empty()) {
      while (std::getline(ss, cell, ',')) names.push_back(cell);
      continue;
    }
    for (size_t i = 0; std::getline(ss, cell, ',') && i < names.size(); ++i) {
      cols[names[i]].push_back(std::stod(cell));
    }
  }
  return cols;
}

inline std::string reference_path(const std::string& name) {
  return std::string(FIVEBAR_REFERENCE_DIR) + "/" + name;
}

#endif  // FIVEBAR_REFERENCE_DIR

}  // namespace fivebar::testing
