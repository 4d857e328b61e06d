# run_fivebar(<expected exit status> <stderr regex or ""> args...), included by the CLI scripts:
# runs ${FIVEBAR}, checks the exit status and, for a failure, that stderr is exactly one line in
# the contract's format `fivebar: error: <file>: <key>: <why>` matching the regex. The run's
# stdout is left in FIVEBAR_OUT.
function(run_fivebar expected_status stderr_regex)
  execute_process(COMMAND ${FIVEBAR} ${ARGN} RESULT_VARIABLE status OUTPUT_VARIABLE out
                  ERROR_VARIABLE err)
  if(NOT status EQUAL expected_status)
    message(FATAL_ERROR "fivebar ${ARGN}: exit status ${status}, expected ${expected_status}\n"
                        "stderr: ${err}")
  endif()
  set(FIVEBAR_OUT "${out}" PARENT_SCOPE)
  if(expected_status EQUAL 0)
    return()
  endif()
  string(REGEX MATCHALL "\n" newlines "${err}")
  list(LENGTH newlines n)
  if(NOT n EQUAL 1 OR NOT err MATCHES "^fivebar: error: [^\n]+: [^\n]+: [^\n]+\n$")
    message(FATAL_ERROR "fivebar ${ARGN}: stderr is not one error line:\n${err}")
  endif()
  if(NOT err MATCHES "${stderr_regex}")
    message(FATAL_ERROR "fivebar ${ARGN}: stderr\n${err}does not match ${stderr_regex}")
  endif()
endfunction()
