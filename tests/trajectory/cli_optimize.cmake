# End-to-end checks of `fivebar optimize` and `fivebar study` (run by ctest with cmake -P):
# - a task whose minimum-jerk motion cannot close is solved from a detour, exit 0;
# - when every task fails, exit 2 (the tasks cannot be done by the design) with one error line
#   on stderr, each failed task's reason on stdout, and summary.csv kept;
# - trajectory.csv carries non-zero W_in and W_ext; animation.html is written (no ghost without
#   a baseline) and `fivebar animate` remakes it;
# - study.csv names the reason of every design that cannot do every task;
# - a four-bar: a task solved with the four-bar's columns, a five-bar pose refused (exit 2), and
#   a study over its crank length.
# Inputs: -DFIVEBAR=<executable> -DSOURCE_DIR=<project root> -DWORK_DIR=<scratch directory>
cmake_minimum_required(VERSION 3.22)
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
set(paper ${SOURCE_DIR}/datasets/scenes/paper.yaml)
set(short --set mechanism.links.2.length=0.17 --set mechanism.links.3.length=0.17
          --set mechanism.links.2.com_offset=0.1 --set mechanism.links.3.com_offset=0.1
          --set mechanism.point_p=0.1)

function(expect what)
  if(NOT (${ARGN}))
    message(FATAL_ERROR "${what}")
  endif()
endfunction()

# the detour task: solved from the path search's detour
execute_process(COMMAND ${FIVEBAR} optimize ${paper} --tasks ${SOURCE_DIR}/datasets/tasks/detour_tasks.yaml
                        ${short} --no-plots --no-validate --no-refine --out ${WORK_DIR}/detour
                RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect("detour: exit ${status}\n${out}${err}" status EQUAL 0)
file(STRINGS ${WORK_DIR}/detour/summary.csv rows)
list(GET rows 1 row)
expect("detour: summary row ${row}" row MATCHES "^detour,ok,.*,cannot_assemble,path_search,")
expect("detour: a baseline.csv of a baseline that cannot close"
       NOT EXISTS ${WORK_DIR}/detour/detour/baseline.csv)
# the task's animation.html, without a ghost (no baseline); `animate` remakes it with the run's
# scene and --set values, and says why there is no ghost
file(READ ${WORK_DIR}/detour/detour/animation.html page)
expect("detour: animation.html with a ghost or without frames"
       page MATCHES "\"ghost\":null" AND page MATCHES "\"motion\":{\"t\":\\[0,")
execute_process(COMMAND ${FIVEBAR} animate ${WORK_DIR}/detour --scene ${paper} ${short}
                RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect("animate detour: exit ${status}\n${out}${err}"
       status EQUAL 0 AND out MATCHES "no baseline.csv, so no minimum-jerk ghost")
file(STRINGS ${WORK_DIR}/detour/detour/trajectory.csv lines)
list(GET lines 0 header)
list(GET lines -1 last)
string(REPLACE "," ";" header "${header}")
string(REPLACE "," ";" last "${last}")
list(FIND header W_in i_in)
list(FIND header W_ext i_ext)
list(GET last ${i_in} w_in)
list(GET last ${i_ext} w_ext)
expect("trajectory.csv: W_in ${w_in}, W_ext ${w_ext} at the end" NOT w_in EQUAL 0 AND NOT w_ext EQUAL 0)

# every task fails: exit 2, one error line, reasons on stdout, summary.csv kept
file(WRITE ${WORK_DIR}/far.yaml "tasks:\n"
     "  - {name: far, duration: 0.5, start: {theta1: 0.3, theta2: 2.6}, goal: {x: 1.0, y: 1.0}}\n"
     "  - {name: turn, duration: 0.5, start: {theta1: 0.3, theta2: 2.6}, goal: {theta1: 6.5831853, theta2: 2.6}}\n")
execute_process(COMMAND ${FIVEBAR} optimize ${paper} --tasks ${WORK_DIR}/far.yaml --no-plots
                        --set mechanism.links.2.length=0.13 --set mechanism.links.3.length=0.13
                        --set mechanism.links.2.com_offset=0.06 --set mechanism.links.3.com_offset=0.06
                        --set mechanism.point_p=0.06 --set initial.theta1=0.3 --set initial.theta2=2.6
                        --out ${WORK_DIR}/far
                RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect("every task failed: exit ${status}\n${out}${err}" status EQUAL 2)
expect("stderr: ${err}" err MATCHES "^fivebar: error: [^\n]*far.yaml: tasks: every task failed[^\n]*\n$")
expect("stdout lacks the reasons: ${out}"
       out MATCHES "far: goal C = \\(1, 1\\) m is out of reach" AND out MATCHES "turn: .*singular curve")
expect("summary.csv of a failed run is gone" EXISTS ${WORK_DIR}/far/summary.csv)

# study: the reason of each design that cannot do every task, and the count on stdout
execute_process(COMMAND ${FIVEBAR} study ${paper} --tasks ${SOURCE_DIR}/datasets/tasks/paper_tasks.yaml
                        --sweep mechanism.links.0.length=0.04:0.08:2 --no-plots --threads 2
                        --out ${WORK_DIR}/study
                RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect("study: exit ${status}\n${out}${err}" status EQUAL 0)
expect("study stdout: ${out}" out MATCHES "[0-9]+ of 2 designs cannot do every task")
file(STRINGS ${WORK_DIR}/study/study.csv study)
list(GET study 0 header)
expect("study.csv header: ${header}" header MATCHES ",best,reason,total_objective$")
# the best design on the edge of the swept range is named, on stdout and in study.json
execute_process(COMMAND ${FIVEBAR} study ${SOURCE_DIR}/datasets/scenes/paper_motors.yaml
                        --tasks ${SOURCE_DIR}/datasets/tasks/paper_tasks.yaml
                        --sweep mechanism.links.0.length=0.07:0.08:2 --no-plots --threads 2
                        --out ${WORK_DIR}/study_bound
                RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect("study bound: exit ${status}\n${out}${err}" status EQUAL 0)
expect("study bound: ${out}" out MATCHES "lies on the upper bound of mechanism.links.0.length \\(0.08\\)")
file(READ ${WORK_DIR}/study_bound/study.json json)
expect("study.json: ${json}" json MATCHES "\"side\": \"upper\"")
# study takes optimize's --objective: study.json names it; a bad value exits 2 naming the option
execute_process(COMMAND ${FIVEBAR} study ${SOURCE_DIR}/datasets/scenes/paper_motors.yaml
                        --tasks ${SOURCE_DIR}/datasets/tasks/paper_tasks.yaml
                        --sweep mechanism.links.0.length=0.07:0.08:2 --no-plots --threads 2
                        --objective supply_energy --out ${WORK_DIR}/study_supply
                RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect("study supply: exit ${status}\n${out}${err}" status EQUAL 0)
file(READ ${WORK_DIR}/study_supply/study.json json)
expect("study.json: ${json}" json MATCHES "\"objective\": \"supply_energy\"")
execute_process(COMMAND ${FIVEBAR} study ${paper} --tasks ${SOURCE_DIR}/datasets/tasks/paper_tasks.yaml
                        --sweep mechanism.links.0.length=0.07:0.08:2 --no-plots
                        --objective total_dissipation --out ${WORK_DIR}/study_bad
                RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect("study without windings: exit ${status}\n${out}${err}" status EQUAL 2)
expect("study without windings: stderr ${err}" err MATCHES "winding_resistance")
expect("study without windings: output written" NOT EXISTS ${WORK_DIR}/study_bad/study.csv)

# trajectory.csv torques are those of `fivebar inverse` on the same motion: the
# same doubles, hence the same text
execute_process(COMMAND ${FIVEBAR} inverse ${paper} ${short} --motion ${WORK_DIR}/detour/detour/trajectory.csv
                        --no-plots --out ${WORK_DIR}/inverse
                RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect("inverse: exit ${status}\n${err}" status EQUAL 0)
function(torque_columns file out_var)
  file(STRINGS ${file} lines)
  list(GET lines 0 header)
  string(REPLACE "," ";" header "${header}")
  list(FIND header M1 i1)
  list(FIND header M2 i2)
  list(REMOVE_AT lines 0)
  set(values "")
  foreach(line IN LISTS lines)
    string(REPLACE "," ";" fields "${line}")
    list(GET fields ${i1} m1)
    list(GET fields ${i2} m2)
    string(APPEND values "${m1} ${m2}\n")
  endforeach()
  set(${out_var} "${values}" PARENT_SCOPE)
endfunction()
torque_columns(${WORK_DIR}/detour/detour/trajectory.csv optimized)
torque_columns(${WORK_DIR}/inverse/trajectory.csv inverse)
expect("M1, M2 of trajectory.csv differ from fivebar inverse on the same motion"
       optimized STREQUAL inverse)

# --refine-levels and --max-evaluations: bad values exit 2 with one line naming the option
foreach(bad "--refine-levels;45,25" "--refine-levels;4" "--max-evaluations;3")
  execute_process(COMMAND ${FIVEBAR} optimize ${paper} --tasks ${SOURCE_DIR}/datasets/tasks/paper_tasks.yaml
                          ${bad} --no-plots --out ${WORK_DIR}/bad_levels
                  RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
  list(GET bad 0 option)
  expect("${bad}: exit ${status}\n${out}${err}" status EQUAL 2)
  expect("${bad}: stderr ${err}" err MATCHES "${option}")
  expect("${bad}: output written" NOT EXISTS ${WORK_DIR}/bad_levels/summary.csv)
endforeach()

# a four-bar: the shipped crank-rocker's first task solved (exit 0) with the four-bar's columns;
# a five-bar pose on a four-bar scene is a file error naming the key and the mechanism type
set(crank_rocker ${SOURCE_DIR}/datasets/reference/four_bar/crank_rocker.yaml)
file(WRITE ${WORK_DIR}/four_bar.yaml "tasks:\n"
     "  - {name: half_turn, duration: 0.5, start: {theta1: 1.5707963267948966}, goal: {theta1: 4.71238898038469}, torque_limit: 0.8}\n")
execute_process(COMMAND ${FIVEBAR} optimize ${crank_rocker} --tasks ${WORK_DIR}/four_bar.yaml
                        --no-plots --refine-levels 25 --out ${WORK_DIR}/four_bar
                RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect("four-bar: exit ${status}\n${out}${err}" status EQUAL 0)
file(STRINGS ${WORK_DIR}/four_bar/summary.csv rows)
list(GET rows 1 row)
expect("four-bar: summary row ${row}" row MATCHES "^half_turn,ok,")
file(STRINGS ${WORK_DIR}/four_bar/half_turn/trajectory.csv lines)
list(GET lines 0 header)
expect("four-bar: trajectory.csv header ${header}"
       header MATCHES "^t,theta1,theta2,theta3,omega1," AND header MATCHES ",x_P,y_P," AND
       NOT header MATCHES "theta4|,M2,")
file(WRITE ${WORK_DIR}/four_bar_bad.yaml "tasks:\n"
     "  - {name: a, duration: 0.5, start: {theta1: 1.5, theta2: 1.5}, goal: {theta1: 2.0}}\n")
execute_process(COMMAND ${FIVEBAR} optimize ${crank_rocker} --tasks ${WORK_DIR}/four_bar_bad.yaml
                        --no-plots --out ${WORK_DIR}/four_bar_bad
                RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect("four-bar theta2: exit ${status}\n${out}${err}" status EQUAL 2)
expect("four-bar theta2: stderr ${err}"
       err MATCHES "tasks.0.start.theta2: a five_bar key: a mechanism.type four_bar scene")
expect("four-bar theta2: output written" NOT EXISTS ${WORK_DIR}/four_bar_bad/summary.csv)

# study on the four-bar: two crank lengths, each design's task solved (the four-bar's tasks file)
execute_process(COMMAND ${FIVEBAR} study ${crank_rocker} --tasks ${WORK_DIR}/four_bar.yaml
                        --sweep mechanism.links.0.length=0.07:0.08:2 --no-plots
                        --out ${WORK_DIR}/four_bar_study
                RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect("four-bar study: exit ${status}\n${out}${err}" status EQUAL 0)
file(STRINGS ${WORK_DIR}/four_bar_study/study.csv study)
list(LENGTH study rows)
expect("four-bar study.csv: ${rows} lines" rows EQUAL 3)
list(GET study 1 first)
list(GET study 2 second)
expect("four-bar study.csv rows: ${first} / ${second}"
       first MATCHES "^0,0.07,ok," AND second MATCHES "^1,0.08,ok,")
