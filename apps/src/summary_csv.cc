#include "fivebar/io/summary_csv.h"

#include "fivebar/io/csv.h"
#include "fivebar/io/format.h"

namespace fivebar::io {

const std::vector<std::string>& summary_columns() {
  static const std::vector<std::string> columns = {
      "task", "status", "dissipated_energy", "baseline_dissipated_energy", "input_energy",
      "peak_torque", "max_constraint_violation", "wall_time_s", "baseline_input_energy",
      "baseline_peak_torque", "saving_percent", "miss_distance", "min_coupler_sine",
      "solver_status", "evaluations", "starts", "best_start", "duration", "torque_limit",
      "theta1_start", "theta2_start", "theta1_goal", "theta2_goal",
      "dissipated_energy_exact", "baseline_dissipated_energy_exact", "baseline_status",
      "initial_guess", "initial_dissipated_energy", "initial_peak_torque",
      "initial_min_coupler_sine", "control_points", "dissipated_energy_smoothed",
      "baseline_dissipated_energy_smoothed", "input_energy_smoothed",
      "baseline_input_energy_smoothed", "miss_distance_exact", "smoothing_velocity",
      "refinement_change", "continuation", "refinement", "message"};
  return columns;
}

std::vector<std::string> summary_fields(const trajectory::TaskResult& r) {
  const auto num = format_double;
  const double saving = 100.0 * (1.0 - r.dissipated_energy / r.baseline_dissipated_energy);
  const bool resolved = r.control_points > 0;
  auto angle = [&](double v) { return resolved ? num(v) : std::string("nan"); };
  return {r.task, r.status, num(r.dissipated_energy), num(r.baseline_dissipated_energy),
          num(r.input_energy), num(r.peak_torque), num(r.max_constraint_violation),
          num(r.wall_time_s), num(r.baseline_input_energy), num(r.baseline_peak_torque),
          num(saving), num(r.miss_distance), num(r.min_coupler_sine), r.solver_status,
          std::to_string(r.evaluations), std::to_string(r.starts), std::to_string(r.best_start),
          num(r.duration), num(r.torque_limit), angle(r.start[0]), angle(r.start[1]),
          angle(r.goal[0]), angle(r.goal[1]), num(r.dissipated_energy_exact),
          num(r.baseline_dissipated_energy_exact), r.baseline_status, r.initial_guess,
          num(r.initial_dissipated_energy), num(r.initial_peak_torque),
          num(r.initial_min_coupler_sine), std::to_string(r.control_points),
          num(r.dissipated_energy_smoothed), num(r.baseline_dissipated_energy_smoothed),
          num(r.input_energy_smoothed), num(r.baseline_input_energy_smoothed),
          num(r.miss_distance_exact), num(r.smoothing_velocity), num(r.refinement_change),
          csv_quote(r.continuation), csv_quote(r.refinement), csv_quote(r.message)};
}

}  // namespace fivebar::io
