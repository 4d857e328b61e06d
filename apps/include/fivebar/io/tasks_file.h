// Tasks files (interfaces.md, "Tasks file"): the YAML a user writes, read into the task
// specifications the trajectory library takes.
#pragma once

#include <string>
#include <vector>

#include "fivebar/trajectory/tasks.h"

namespace fivebar::io {

/// Reads a tasks file. Throws InputError(`<file>: <key>: <reason>`) for a missing file,
/// malformed YAML (with line and column), a missing `tasks` list, unknown keys, a task without
/// name, duration, start or goal, a pose that is not exactly {theta1, theta2} or {x, y} (with
/// `four_bar`: exactly one of {theta1}, {x}, {y}; a five-bar key is named as such), a value
/// that is not a finite number, and task names that are empty, repeated or not usable as a
/// directory name ([A-Za-z0-9_.-], not starting with '.'). Values are not range-checked: a
/// non-positive duration or torque limit becomes the task's status (trajectory::resolve_task).
std::vector<trajectory::TaskSpec> load_tasks(const std::string& path, bool four_bar = false);
/// The same from YAML text; `path` only names it in messages.
std::vector<trajectory::TaskSpec> parse_tasks(const std::string& yaml_text,
                                              const std::string& path, bool four_bar = false);

}  // namespace fivebar::io
