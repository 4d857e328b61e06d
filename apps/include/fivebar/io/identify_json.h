// identification.json as one record: the command line writes it, the Python module returns it
// (as dicts, lists and arrays), so both carry the same fields by construction.
#pragma once

#include <string>

#include "fivebar/identification/identify.h"
#include "fivebar/identification/torque_log.h"
#include "fivebar/io/json.h"

namespace fivebar::io {

/// What produced an identification, besides its result: the names written into the record.
struct IdentifyRun {
  std::string scene;                ///< the scene's path
  std::string log;                  ///< the torque log's path ("(arrays)" for Python arrays)
  std::string estimate;             ///< --estimate
  identification::Loss loss = identification::Loss::kNone;
  /// --flip-torque-sign: the log's torques negated, "" (none), "1" (tau1), "2" (tau2) or "both"
  std::string torque_sign_flipped;
};

/// identification.json without the total wall time: settings, parameters (with their truth when
/// the log states it), residuals, rates, log conditioning, solver, warnings, the model check and,
/// when `validation` is not null, the validation runs. `log` is the log as read (its header
/// comments hold the truth).
Json identification_json(const IdentifyRun& run, const identification::TorqueLog& log,
                         const identification::IdentifyResult& res,
                         const identification::Validation* validation);

/// One line on the full validation run: where it leaves the log and why that is expected.
std::string full_run_note(const identification::Validation& val);

}  // namespace fivebar::io
