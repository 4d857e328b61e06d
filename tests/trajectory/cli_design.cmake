# End-to-end checks of `fivebar design`, run by ctest with cmake -P:
# - a tiny problem (one task, one key, 8 designs) improves on its start and writes its outputs;
# - bad input exits 2 with one line: a key that is not a number of the mechanism, LO >= HI,
#   bounds whose start design cannot assemble;
# - a four-bar design: the crank length for one task, its scene.yaml usable, a link index beyond
#   the four-bar's refused.
# Inputs: -DFIVEBAR=<executable> -DSOURCE_DIR=<project root> -DWORK_DIR=<scratch directory>
cmake_minimum_required(VERSION 3.22)
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
set(paper ${SOURCE_DIR}/datasets/scenes/paper.yaml)

function(expect what)
  if(NOT (${ARGN}))
    message(FATAL_ERROR "${what}")
  endif()
endfunction()

file(WRITE ${WORK_DIR}/one.yaml "tasks:\n"
     "  - {name: reach_right, duration: 0.5, start: {theta1: 1.5707963267948966, theta2: 1.5707963267948966}, goal: {x: 0.20, y: 0.22}, torque_limit: 20.0}\n")
execute_process(COMMAND ${FIVEBAR} design ${paper} --tasks ${WORK_DIR}/one.yaml
                        --vary mechanism.links.1.length=0.045:0.065 --max-designs 8 --threads 1
                        --out ${WORK_DIR}/tiny
                RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect("design: exit ${status}\n${out}${err}" status EQUAL 0)
foreach(f design.json scene.yaml design_history.csv design_tasks.csv)
  expect("design: ${f} missing" EXISTS ${WORK_DIR}/tiny/${f})
endforeach()
file(READ ${WORK_DIR}/tiny/design.json json)
string(JSON total GET ${json} total_energy)
string(JSON start GET ${json} start_total_energy)
string(JSON best GET ${json} values mechanism.links.1.length)
string(JSON e0 GET ${json} tasks 0 dissipated_energy)
expect("design: total ${total} not below the start ${start}" total LESS start)
expect("design: per-task energy ${e0} is not the total ${total}" e0 EQUAL total)
expect("design: best l2 ${best} outside the bounds" best GREATER_EQUAL 0.045 AND best LESS_EQUAL 0.065)
file(STRINGS ${WORK_DIR}/tiny/design_history.csv rows)
list(LENGTH rows n)
expect("design_history.csv: ${n} lines for at most 8 + 1 designs" n GREATER 2 AND n LESS_EQUAL 10)
# the winning scene carries the best value (shortest text, as in design_history.csv)
string(JSON index GET ${json} evaluation)
math(EXPR line "${index} + 1")
list(GET rows ${line} row)
string(REPLACE "," ";" row "${row}")
list(GET row 1 value)
file(READ ${WORK_DIR}/tiny/scene.yaml scene)
expect("scene.yaml lacks the best l2 ${value}" scene MATCHES "length: ${value}")

# bad input: exit 2, one line naming the option
foreach(bad "friction.coulomb=0.1:0.2" "mechanism.links.0.length=0.1:0.05"
            "mechanism.links.0.length=0.08:0.08" "mechanism.links.0.length=a:0.1"
            "mechanism.links.2.length=0.01:0.02")
  execute_process(COMMAND ${FIVEBAR} design ${paper} --tasks ${WORK_DIR}/one.yaml --vary ${bad}
                          --out ${WORK_DIR}/bad
                  RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
  expect("--vary ${bad}: exit ${status}\n${out}${err}" status EQUAL 2)
  expect("--vary ${bad}: stderr ${err}" err MATCHES "^fivebar: error: command line: --vary[^\n]*\n$")
  expect("--vary ${bad}: output written" NOT EXISTS ${WORK_DIR}/bad/design.json)
endforeach()

# a four-bar: the crank length of the crank-rocker designed for one task; the winning scene is a
# four-bar scene that loads again; a link index beyond the four-bar's three is refused
set(crank_rocker ${SOURCE_DIR}/datasets/reference/four_bar/crank_rocker.yaml)
file(WRITE ${WORK_DIR}/four_bar.yaml "tasks:\n"
     "  - {name: half_turn, duration: 0.5, start: {theta1: 1.5707963267948966}, goal: {theta1: 4.71238898038469}, torque_limit: 0.8}\n")
execute_process(COMMAND ${FIVEBAR} design ${crank_rocker} --tasks ${WORK_DIR}/four_bar.yaml
                        --vary mechanism.links.0.length=0.07:0.09 --max-designs 5 --threads 1
                        --no-plots --out ${WORK_DIR}/four_bar
                RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect("four-bar design: exit ${status}\n${out}${err}" status EQUAL 0)
file(READ ${WORK_DIR}/four_bar/design.json json)
string(JSON total GET ${json} total_energy)
string(JSON start GET ${json} start_total_energy)
expect("four-bar design: total ${total} above the start ${start}" total LESS_EQUAL start)
execute_process(COMMAND ${FIVEBAR} simulate ${WORK_DIR}/four_bar/scene.yaml --no-plots
                        --set simulation.duration=0.01 --out ${WORK_DIR}/four_bar_scene
                RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect("four-bar design scene.yaml: exit ${status}\n${out}${err}" status EQUAL 0)
execute_process(COMMAND ${FIVEBAR} design ${crank_rocker} --tasks ${WORK_DIR}/four_bar.yaml
                        --vary mechanism.links.3.length=0.1:0.2 --out ${WORK_DIR}/four_bar_bad
                RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect("four-bar design links.3: exit ${status}\n${err}" status EQUAL 2 AND err MATCHES "links.3.length")
