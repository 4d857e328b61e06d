// summary.csv of `optimize` (and the per-task columns of `study` and `design`): one row per task
// result, from the trajectory library's TaskResult.
#pragma once

#include <string>
#include <vector>

#include "fivebar/trajectory/batch.h"

namespace fivebar::io {

/// Columns of summary.csv: those of interfaces.md (task, status, dissipated_energy,
/// baseline_dissipated_energy, input_energy, peak_torque, max_constraint_violation, wall_time_s),
/// then baseline_input_energy, baseline_peak_torque, saving_percent (100 (1 - E / E_baseline)),
/// miss_distance, min_coupler_sine, solver_status, evaluations, starts, best_start, duration,
/// torque_limit, theta1_start, theta2_start, theta1_goal, theta2_goal, dissipated_energy_exact,
/// baseline_dissipated_energy_exact, baseline_status, initial_guess, initial_dissipated_energy,
/// initial_peak_torque, initial_min_coupler_sine, control_points, dissipated_energy_smoothed,
/// baseline_dissipated_energy_smoothed, input_energy_smoothed, baseline_input_energy_smoothed,
/// miss_distance_exact, smoothing_velocity, refinement_change, continuation, refinement, message,
/// winding_heat, baseline_winding_heat, total_dissipation, baseline_total_dissipation,
/// supply_energy, baseline_supply_energy, objective, refinement_limited: the fields of
/// trajectory::visit_fields in its order, saving_percent after baseline_peak_torque.
/// Energies and torques are those of the scene's exact friction law; the *_smoothed energies
/// those of the smooth law of the winning stage.
const std::vector<std::string>& summary_columns();

/// The fields of one summary.csv row: numbers in shortest round-trip form (format_double), the
/// angles "nan" for a task that was not resolved, the texts continuation, refinement and
/// message quoted as CSV fields (csv_quote); join them with csv_line.
std::vector<std::string> summary_fields(const trajectory::TaskResult& result);

}  // namespace fivebar::io
