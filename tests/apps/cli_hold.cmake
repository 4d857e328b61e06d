# End-to-end checks of rest and holding (run by ctest with cmake -P): `fivebar hold` at a pose
# and as a map, its bad input (exit 2 for a pose that cannot assemble, 3 for a singular one, one
# line on stderr, no output), and the rest columns of `fivebar inverse` on a motion held still.
# Inputs: -DFIVEBAR=<executable> -DSOURCE_DIR=<project root> -DWORK_DIR=<scratch directory>
cmake_minimum_required(VERSION 3.22)
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
set(paper ${SOURCE_DIR}/datasets/scenes/paper.yaml)
# couplers of 0.2 m: the mechanism cannot close with the cranks apart, and aligns at |BD| = 0.4 m
set(short --set mechanism.links.2.length=0.2 --set mechanism.links.3.length=0.2
          --set mechanism.point_p=0.15)

include(${CMAKE_CURRENT_LIST_DIR}/run_fivebar.cmake)

function(require_text file regex)
  file(READ ${file} text)
  if(NOT text MATCHES "${regex}")
    message(FATAL_ERROR "${file} does not match ${regex}:\n${text}")
  endif()
endfunction()

# one pose: the paper start pose and its frictionless equilibrium
run_fivebar(0 "" hold ${paper} --out ${WORK_DIR}/pose)
require_text(${WORK_DIR}/pose/hold.json "\"M1\": -0\\.69173396")
require_text(${WORK_DIR}/pose/hold.json "\"M2\": -1\\.43789485")
# with a torque limit, the console says whether the pose holds within it (1.382 N m needed)
run_fivebar(0 "" hold ${paper} --torque-limit 1 --out ${WORK_DIR}/pose_limit)
if(NOT FIVEBAR_OUT MATCHES "within the torque limit 1 N m: no, the pose needs more")
  message(FATAL_ERROR "hold --torque-limit 1 does not say the pose needs more:\n${FIVEBAR_OUT}")
endif()
run_fivebar(0 "" hold ${paper} --torque-limit 2 --out ${WORK_DIR}/pose_limit2)
if(NOT FIVEBAR_OUT MATCHES "within the torque limit 2 N m: yes")
  message(FATAL_ERROR "hold --torque-limit 2 does not say the pose holds:\n${FIVEBAR_OUT}")
endif()

# bad input: nothing written
run_fivebar(2 "paper.yaml: --pose: the mechanism cannot assemble at theta1 = 3.14159, theta2 = 0"
            hold ${paper} ${short} --pose 3.14159,0 --out ${WORK_DIR}/bad)
run_fivebar(3 "paper.yaml: --pose: singular configuration at theta1 = 3.14159265[0-9]*, theta2 = 0.98032"
            hold ${paper} ${short} --pose 3.141592653589793,0.9803200132236127
            --out ${WORK_DIR}/bad)
run_fivebar(2 "paper.yaml: --pose: expected THETA1,THETA2" hold ${paper} --pose 1.5
            --out ${WORK_DIR}/bad)
run_fivebar(2 "paper.yaml: --pose: 103.1,74.5: angles look like degrees, expected radians"
            hold ${paper} --pose 103.1,74.5 --out ${WORK_DIR}/bad)
run_fivebar(2 "paper.yaml: --pose: 1.8,361: angles beyond two turns, expected radians within a turn"
            hold ${paper} --pose 1.8,361 --out ${WORK_DIR}/bad)
run_fivebar(2 "paper.yaml: simulation.rest_rate_threshold: must be >= 0"
            hold ${paper} --set simulation.rest_rate_threshold=-1 --out ${WORK_DIR}/bad)
if(EXISTS ${WORK_DIR}/bad)
  message(FATAL_ERROR "a failed hold left ${WORK_DIR}/bad behind")
endif()

# the map, poses that cannot close left blank
run_fivebar(0 "" hold ${paper} ${short} --grid 12 --torque-limit 10 --no-plots
            --out ${WORK_DIR}/map)
require_text(${WORK_DIR}/map/hold_map.csv "^theta1,theta2,status,M1,M2,")
require_text(${WORK_DIR}/map/summary.json "\"poses_not_assembled_or_singular\": [1-9]")

# inverse dynamics of the start pose held still for 1 s: every row at rest, equilibrium torques
set(rows "t,theta1,theta2\n")
foreach(i RANGE 0 1000)
  string(APPEND rows "${i}e-3,1.5707963267948966,1.5707963267948966\n")
endforeach()
file(WRITE ${WORK_DIR}/static.csv "${rows}")
run_fivebar(0 "" inverse ${paper} --motion ${WORK_DIR}/static.csv --no-plots
            --out ${WORK_DIR}/static)
require_text(${WORK_DIR}/static/summary.json "\"rows_at_rest\": 1001")
require_text(${WORK_DIR}/static/trajectory.csv
             "E_diss,W_in,W_ext,at_rest,stuck1,stuck2,stuck3,stuck4,stuck5,M1_hold_min,M1_hold_max,M2_hold_min,M2_hold_max\n")
require_text(${WORK_DIR}/static/trajectory.csv "\n1,1.5707963267948966,[^\n]*,-0\\.691733963023")
