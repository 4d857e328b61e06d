// Work-precision study: the error of every integrator and friction treatment against its run time.
#pragma once

#include <string>
#include <functional>
#include <vector>

#include "fivebar/sim/simulator.h"
#include "fivebar/studies/types.h"

namespace fivebar::studies {

/// How the Coulomb sign is integrated.
enum class Treatment : int {
  kExactLocated = 0,  ///< "exact_located": sign(w) with every switch located and restarted
  kExactUnlocated,    ///< "exact_unlocated": sign(w) evaluated inside the steps (discontinuous RHS)
  kRegularized,       ///< "regularized": tanh(w / w_s), a different (smooth) model
  kAsScene,           ///< "as_scene": the scene's own smooth law (LuGre, tanh) or no friction
};
const char* treatment_name(Treatment t);

struct PrecisionPoint {
  Method method = Method::kCvodeAdams;
  Treatment treatment = Treatment::kExactLocated;
  double tolerance = 0;      ///< rtol = atol
  bool ok = false;
  std::string message;       ///< the failure, when !ok
  double error =
      0;  ///< max |d theta_k| over the output grid vs its own reference [rad]; NaN when !ok
  double error_vs_exact = 0; ///< vs the exact-sign reference (model error of regularization)
  double wall_time_s = 0;    ///< minimum over the repeats
  long rhs_evaluations = 0;
  long steps = 0;
  long friction_events = 0;
  bool pareto = false;       ///< on the Pareto front (error, wall time) of all points
};

struct WorkPrecisionOptions {
  std::vector<double> tolerances = {1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8,
                                    1e-9, 1e-10, 1e-11, 1e-12};
  std::vector<Method> methods = {std::begin(kAllMethods), std::end(kAllMethods)};
  int repeats = 3;                    ///< wall time is the minimum over this many runs
  double regularization_velocity = 1e-3;  ///< w_s of the regularized treatment [rad/s]
  double reference_tolerance = 1e-13;
  /// skip the remaining tolerances of a method once a run takes longer than this [s]; a run
  /// taking twice this long is stopped and counts as failed
  double max_run_time_s = 5.0;
  /// called after every point with (points done, points planned); may be empty
  std::function<void(int done, int total)> progress;
};

/// The toolkit's own reference: the scene integrated at reference_tolerance by CVODE Adams and
/// by ARKODE Dormand-Prince; the rows are Adams', `self_difference` their max |d theta|.
struct Reference {
  std::vector<Row> rows;
  double self_difference = 0;
  Stats stats;
};

struct WorkPrecision {
  Reference exact;        ///< exact sign (located switches), or the scene's own law
  Reference regularized;  ///< tanh(w / w_s) (exact-sign scenes only)
  std::vector<PrecisionPoint> points;
  /// fastest Pareto point of the scene's own treatment reaching each target error
  struct Recommendation {
    double target = 0;
    bool found = false;
    PrecisionPoint point;
  };
  std::vector<Recommendation> recommendations;
};

/// Max |d theta_k| (every link angle) between two runs on the same grid (infinity if the grids
/// differ).
double max_theta_difference(const std::vector<Row>& a, const std::vector<Row>& b);

/// Runs the study. `base` supplies duration, output step and loop settings.
Status work_precision(const Params<double>& params, const LoadFunction& loads,
                      const Initial& initial, const Options& base,
                      const WorkPrecisionOptions& options, WorkPrecision* out);
/// The same on a four-bar (its crank, coupler and rocker angles).
Status work_precision(const FourBarParamsT<double>& params, const FourBarLoadFunction& loads,
                      const Initial& initial, const Options& base,
                      const WorkPrecisionOptions& options, WorkPrecision* out);

}  // namespace fivebar::studies
