// SUNDIALS return flags as messages a user can act on: the one place that maps them (as
// trajectory/src/nlopt_status.cc does for NLopt). CVODE and ARKODE share the flag names after
// their prefix (CV_TOO_MUCH_WORK, ARK_TOO_MUCH_WORK), so one table serves both.
#include <cstdlib>
#include <string>

#include "integrator.h"

namespace fivebar::sim::detail {

std::string sundials_hint(const std::string& flag_name) {
  const size_t underscore = flag_name.find('_');
  const std::string flag = underscore == std::string::npos ? flag_name : flag_name.substr(underscore + 1);
  struct Entry {
    const char* flag;
    const char* hint;
  };
  static const Entry kHints[] = {
      {"TOO_MUCH_WORK",
       "the step limit simulation.max_steps was reached: raise it, or loosen simulation.rtol/atol; "
       "a stiff scene (LuGre) integrates faster with cvode_bdf or arkode_dirk"},
      {"TOO_MUCH_ACC", "the tolerance asked for is below what double precision allows here: "
                       "loosen simulation.rtol/atol"},
      {"ERR_FAILURE", "the error test failed repeatedly: an unlocated discontinuity "
                      "(simulation.locate_switches: false) or a pose near a singular one"},
      {"CONV_FAILURE", "the implicit method's Newton iteration did not converge: a stiff or "
                       "discontinuous right-hand side; try a smaller simulation.rtol or another "
                       "integrator"},
      {"LSETUP_FAIL", "the Newton matrix could not be factored (a singular Jacobian)"},
      {"LSOLVE_FAIL", "the Newton linear system could not be solved (a singular Jacobian)"},
      {"RHSFUNC_FAIL", "the dynamics could not be evaluated (the reason is given above)"},
      {"REPTD_RHSFUNC_ERR", "the dynamics failed repeatedly at smaller steps"},
      {"UNREC_RHSFUNC_ERR", "the dynamics failed and the step could not be retried"},
      {"FIRST_RHSFUNC_ERR", "the dynamics could not be evaluated at the start"},
      {"ILL_INPUT", "SUNDIALS rejected a setting (tolerances, step limits or times)"},
      {"MEM_FAIL", "out of memory"},
  };
  for (const Entry& e : kHints) {
    if (flag == e.flag) return e.hint;
  }
  return "";
}

bool check_flag(int flag, const char* call, char* (*flag_name)(long int),
                std::string* solver_message, std::string* error) {
  if (flag >= 0) return true;
  char* raw = flag_name ? flag_name(flag) : nullptr;  // malloc'd by SUNDIALS
  const std::string name = raw ? raw : "flag " + std::to_string(flag);
  std::free(raw);
  if (error->empty()) {
    *error = std::string(call) + " returned " + name;
    if (!solver_message->empty()) *error += " (" + *solver_message + ")";
    const std::string hint = sundials_hint(name);
    if (!hint.empty()) *error += ": " + hint;
  }
  solver_message->clear();
  return false;
}

bool check_created(const void* object, const char* call, std::string* error) {
  if (object) return true;
  if (error->empty()) {
    *error = std::string(call) + " returned no object (out of memory, or a size SUNDIALS rejects)";
  }
  return false;
}

bool check_call(int flag, const char* call, std::string* error) {
  if (flag == 0) return true;
  if (error->empty()) {
    *error = std::string(call) + " failed (code " + std::to_string(flag) +
             ": out of memory, or an argument SUNDIALS rejects)";
  }
  return false;
}

}  // namespace fivebar::sim::detail
