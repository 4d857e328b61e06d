// summary.json of `simulate` as one record: the command line writes it, the Python module
// returns it as run['summary'], so both carry the same fields by construction.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "fivebar/io/json.h"
#include "fivebar/io/scene.h"
#include "fivebar/sim/estimate.h"
#include "fivebar/sim/simulator.h"

namespace fivebar::io {

/// The frictionless twin of a run (figures 2-4): the scene with friction model none, the same
/// options; `checks` are empty when the twin failed (run.status says why).
struct TwinRun {
  sim::Result run;
  std::optional<sim::RunChecks> checks;
};

/// Runs the frictionless twin of `scene` with `options` (progress reports off).
TwinRun frictionless_twin(const Scene& scene, const sim::LoadFunction& loads,
                          const sim::Options& options);
/// The same for a four-bar scene.
TwinRun frictionless_twin(const Scene& scene, const sim::FourBarLoadFunction& loads,
                          const sim::Options& options);

/// summary.json without total_wall_time_s: the run's status, checks and statistics, its error
/// estimate and how the tolerance was chosen, the settings (`sets`: the --set arguments), and
/// the twin's status, checks and statistics under "frictionless" when `twin` is not null.
Json simulation_summary_json(const Scene& scene, const std::vector<std::string>& sets,
                             const sim::EstimatedRun& run, const sim::RunChecks& checks,
                             const TwinRun* twin);

}  // namespace fivebar::io
