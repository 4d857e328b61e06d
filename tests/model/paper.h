// Test helpers: the canonical paper scene's loads and the reference trajectories of
// datasets/reference.
#pragma once

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

inline sim::Initial paper_initial() { return {M_PI / 2, M_PI / 2, 0.0, 0.0}; }

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

}  // namespace fivebar::testing
