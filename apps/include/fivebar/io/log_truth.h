// The truth a synthetic torque log states in its header (`# true.<name> = v1,v2,...`), written
// by `synth-log` and read back by `identify` to report each estimate's error. One place for
// both directions, so the names always match the identification's parameter names.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "fivebar/identification/parameters.h"
#include "fivebar/model/four_bar_params.h"
#include "fivebar/model/params.h"

namespace fivebar::io {

/// The `true.*` values by name: the law's coefficients (five per joint), `inertial` (the 16
/// standard inertial parameters), `offset`, `actuator_coulomb`, `actuator_viscous` (two each; a
/// four-bar's log one each).
using LogTruth = std::map<std::string, std::vector<double>>;

/// The header lines (without the leading '#') that state the truth of `params`: the law, pin
/// radii, every coefficient of its law (from its descriptor, friction.h), the links' standard
/// inertial parameters (model/inertial.h) and the actuator terms.
std::vector<std::string> truth_lines(const Params<double>& params);
/// The four-bar's: the law, pin radii and coefficients of its four joints (O, B, C, D0), its
/// links' standard inertial parameters and its crank motor's actuator terms (one value each).
std::vector<std::string> truth_lines(const FourBarParams& params);

/// The `true.*` values of a log's comment lines. Lines that do not read are skipped; with
/// `unread`, each of them (but `true.law`, a name) is appended to it as "true.<key>: <reason>".
LogTruth read_truth(const std::vector<std::string>& comments,
                    std::vector<std::string>* unread = nullptr);

/// The `true.*` values that no parameter of a fit with `layout`'s mechanism can be compared
/// with, as "true.<key>: <reason>": an unknown name, or a count that is not the mechanism's
/// (joints, standard inertial parameters, actuators).
std::vector<std::string> truth_not_compared(const LogTruth& truth,
                                            const identification::ParameterLayout& layout);

/// The true value of parameter i (named `name`) of `layout`, when `truth` states it (a shared
/// friction coefficient: only when the five joints' true values are equal); false otherwise.
bool true_value(const LogTruth& truth, const identification::ParameterLayout& layout, int i,
                const std::string& name, double* value);

}  // namespace fivebar::io
