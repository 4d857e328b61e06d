// The paper-scene fixture of every test and benchmark: the canonical scene's loads and start,
// and (where FIVEBAR_REFERENCE_DIR is defined) the reference trajectories of datasets/reference.
#pragma once

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "fivebar/model/friction.h"
#include "fivebar/model/kinematics.h"
#include "fivebar/model/params.h"
#include "fivebar/sim/simulator.h"

namespace fivebar::testing {

/// Loads of the canonical scene (model.md, section 5): the model's own (params.h).
using fivebar::paper_loads;

/// The canonical scene's loads other than the motor torques M1, M2: M3 = 6 N m, F = 50 N at
/// pi/2 from link 3.
inline Loads<double> paper_static_loads(double M1 = 0.0, double M2 = 0.0) {
  return {M1, M2, 6.0, 50.0, M_PI / 2};
}

/// paper_static_loads at every time, as the libraries take loads (motor torques zero).
inline sim::LoadFunction paper_static_load_function() {
  return [](double) { return paper_static_loads(); };
}

inline sim::Initial paper_initial() { return {M_PI / 2, M_PI / 2, 0.0, 0.0}; }

/// `p` under friction `law`, each listed coefficient set on every joint, e.g.
/// with_law(p, FrictionLaw::kStribeck, {{Coefficient::kStaticCoulomb, 0.2}}).
inline Params<double> with_law(Params<double> p, FrictionLaw law,
                               std::initializer_list<std::pair<Coefficient, double>> values) {
  p.friction.law = law;
  for (const auto& [c, v] : values) coefficient(p.friction, c).fill(v);
  return p;
}

/// The cranks' angles [rad], rates [rad/s] and accelerations [rad/s^2]: a point of a motion.
struct MotionState {
  double th1, th2, w1, w2, a1, a2;
};

/// A state of the cranks with random loads (rates to 40 rad/s, torques to 10 N m, F to 50 N).
struct RandomState {
  double th1, th2, w1, w2;
  Loads<double> loads;
};

/// n random states of `p` whose pose assembles at least `margin` away from the singularity.
inline std::vector<RandomState> random_states(const Params<double>& p, int n, uint64_t seed,
                                              double margin = 0.1) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI), rate(-40, 40), torque(-10, 10);
  std::vector<RandomState> out;
  while (static_cast<int>(out.size()) < n) {
    RandomState s{angle(rng), angle(rng), rate(rng), rate(rng),
                  {torque(rng), torque(rng), torque(rng), 5 * torque(rng), angle(rng)}};
    Kinematics<double> k;
    if (solve_kinematics(p, s.th1, s.th2, &k, margin).ok()) out.push_back(s);
  }
  return out;
}

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

/// The one CSV reader of the tests and benchmarks (the apps' parse_csv is what the apps tests
/// exercise): a file with a header row as columns by name; `#` and blank lines skipped. Throws
/// std::runtime_error naming the file when it cannot be opened or a field is not a number.
inline std::map<std::string, std::vector<double>> read_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path);
  std::map<std::string, std::vector<double>> cols;
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
      try {
        cols[names[i]].push_back(std::stod(cell));
      } catch (const std::exception&) {
        throw std::runtime_error(path + ": column " + names[i] + ": '" + cell +
                                 "' is not a number");
      }
    }
  }
  return cols;
}

#ifdef FIVEBAR_REFERENCE_DIR

inline std::string reference_path(const std::string& name) {
  return std::string(FIVEBAR_REFERENCE_DIR) + "/" + name;
}

#endif  // FIVEBAR_REFERENCE_DIR

}  // namespace fivebar::testing
