# End-to-end checks of the `fivebar` command line (run by ctest with cmake -P):
# exit status 0/1/2/3, exactly one `fivebar: error: <file>: <key>: <why>` line on stderr for every
# failure, and no complete-looking output after a failed run.
# Inputs: -DFIVEBAR=<executable> -DSOURCE_DIR=<project root> -DWORK_DIR=<scratch directory>
cmake_minimum_required(VERSION 3.22)
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
set(paper ${SOURCE_DIR}/datasets/scenes/paper.yaml)

include(${CMAKE_CURRENT_LIST_DIR}/run_fivebar.cmake)

# 2: bad input
file(READ ${paper} text)
file(WRITE ${WORK_DIR}/bad.yaml "${text}colour: red\n")
run_fivebar(2 "^fivebar: error: [^\n]*bad.yaml: colour: unknown key"
            simulate ${WORK_DIR}/bad.yaml --out ${WORK_DIR}/out_bad)
run_fivebar(2 "nope.yaml: \\(file\\): cannot open" simulate ${WORK_DIR}/nope.yaml)
# a file named by an option that cannot be opened: the option is named
run_fivebar(2 "nope.csv: --log: cannot open" identify ${paper} --log ${WORK_DIR}/nope.csv
            --out ${WORK_DIR}/out_bad)
run_fivebar(2 "nope.csv: --motion: cannot open" inverse ${paper} --motion ${WORK_DIR}/nope.csv
            --out ${WORK_DIR}/out_bad)
run_fivebar(2 "paper.yaml: friction.coulomb: expected 1 or 5 numbers, got 4"
            simulate ${paper} --set "friction.coulomb=[1,2,3,4]" --out ${WORK_DIR}/out_bad)
run_fivebar(2 "paper.yaml: simulation.rtoll: unknown key"
            simulate ${paper} --set simulation.rtoll=1e-8 --out ${WORK_DIR}/out_bad)
# identify --estimate: an unknown group, a prior <= 0 (the log is never read)
set(log ${SOURCE_DIR}/datasets/logs/paper_rates.csv)
run_fivebar(2 "command line: --estimate: 'inertias' is not a group"
            identify ${paper} --log ${log} --estimate friction,inertias --out ${WORK_DIR}/out_bad)
run_fivebar(2 "command line: --inertia-prior: must be in \\[1e-6, 1e3\\]"
            identify ${paper} --log ${log} --estimate friction,inertia --inertia-prior 0
            --out ${WORK_DIR}/out_bad)
run_fivebar(2 "command line: --inertia-prior: must be in \\[1e-6, 1e3\\]"
            identify ${paper} --log ${log} --inertia-prior -0.1 --out ${WORK_DIR}/out_bad)
# --sg-window -1 names the window (not the order), a directory as --log is not an "empty file"
run_fivebar(2 "command line: --sg-window: must be > 0 \\[s\\], got -1"
            identify ${paper} --log ${log} --sg-window -1 --out ${WORK_DIR}/out_bad)
# a half-window the log cannot hold (1e9 s once became the smallest window), one beyond 200
# samples (1 s at 1 kHz ran for minutes), and --smooth-sign -1 (the default's sentinel is no value)
set(angles_log ${SOURCE_DIR}/datasets/logs/paper_angles.csv)
run_fivebar(2 "command line: --sg-window: [^\n]* must fit in the log's"
            identify ${paper} --log ${angles_log} --sg-window 1e9 --out ${WORK_DIR}/out_bad)
run_fivebar(2 "command line: --sg-window: 1 s is [^\n]*: more than 200"
            identify ${paper} --log ${angles_log} --sg-window 1 --out ${WORK_DIR}/out_bad)
run_fivebar(2 "--smooth-sign"
            identify ${paper} --log ${angles_log} --smooth-sign -1 --out ${WORK_DIR}/out_bad)
run_fivebar(2 "logs: --log: is a directory, expected a CSV file"
            identify ${paper} --log ${SOURCE_DIR}/datasets/logs --out ${WORK_DIR}/out_bad)
# optimize: winding data, objectives and their options
set(motors ${SOURCE_DIR}/datasets/scenes/paper_motors.yaml)
set(tasks ${SOURCE_DIR}/datasets/tasks/paper_tasks.yaml)
run_fivebar(2 "paper_motors.yaml: actuators.M1.winding_resistance: must be > 0"
            optimize ${motors} --tasks ${tasks} --set actuators.M1.winding_resistance=0
            --out ${WORK_DIR}/out_bad)
run_fivebar(2 "paper_motors.yaml: actuators.M2.gear_ratio: must be a finite number"
            optimize ${motors} --tasks ${tasks} --set actuators.M2.gear_ratio=.nan
            --out ${WORK_DIR}/out_bad)
run_fivebar(2 "paper_motors.yaml: actuators.M1.torque_constant: expected a number"
            optimize ${motors} --tasks ${tasks} --set actuators.M1.torque_constant=big
            --out ${WORK_DIR}/out_bad)
run_fivebar(2 "command line: --objective: total_dissipation needs the motors' winding data; add to the scene: actuators.M1.winding_resistance"
            optimize ${paper} --tasks ${tasks} --objective total_dissipation --out ${WORK_DIR}/out_bad)
run_fivebar(2 "command line: --objective: supply_energy needs"
            optimize ${paper} --tasks ${tasks} --objective supply_energy --out ${WORK_DIR}/out_bad)
run_fivebar(2 "command line: --objective: 'heat' is not one of total_dissipation, supply_energy"
            optimize ${motors} --tasks ${tasks} --objective heat --out ${WORK_DIR}/out_bad)
run_fivebar(2 "command line: --regeneration: 'bus' is not one of none, shared_bus"
            optimize ${motors} --tasks ${tasks} --regeneration bus --out ${WORK_DIR}/out_bad)
run_fivebar(2 "command line: --end-acceleration: 'none' is not one of free, zero"
            optimize ${motors} --tasks ${tasks} --end-acceleration none --out ${WORK_DIR}/out_bad)
# numeric options: NaN and inf refused for every option (check_numbers), ranges by the shared
# validators; each exits 2 naming the option
run_fivebar(2 "command line: --angle-noise: must be (a finite number|>= 0[^,]*), got nan"
            synth-log ${paper} --out ${WORK_DIR}/out_bad/log.csv --angle-noise nan)
run_fivebar(2 "command line: --time: must be (a finite number|>= 0), got nan"
            hold ${paper} --time nan --out ${WORK_DIR}/out_bad)
run_fivebar(2 "command line: --duration: must be a finite number, got 1e400"
            synth-log ${paper} --out ${WORK_DIR}/out_bad/log.csv --duration 1e400)
run_fivebar(2 "command line: --stribeck-velocity: must be > 0, got 0"
            synth-log ${paper} --out ${WORK_DIR}/out_bad/log.csv --law stribeck
            --stribeck-velocity 0)
run_fivebar(2 "command line: --window: must be > 0, got 0"
            identify ${paper} --log ${log} --window 0 --out ${WORK_DIR}/out_bad)
# comma-separated lists: an empty field is refused, not read as fewer values (and no output)
run_fivebar(2 "command line: --actuator-coulomb: an empty value in '0.1,,0.2'"
            synth-log ${paper} --out ${WORK_DIR}/out_bad/list.csv --actuator-coulomb 0.1,,0.2)
run_fivebar(2 "command line: --tolerances: an empty value in '1e-3,'"
            accuracy ${paper} --tolerances=1e-3, --out ${WORK_DIR}/out_bad)
run_fivebar(2 "command line: --actuator-coulomb: an empty value in '0.1, ,0.2'"
            synth-log ${paper} --out ${WORK_DIR}/out_bad/list.csv --actuator-coulomb "0.1, ,0.2")
# spaces around a list's values are no part of them: the bad value is named without them
run_fivebar(2 "--methods: unknown integrator 'nope'"
            accuracy ${paper} --methods "cvode_adams, nope" --out ${WORK_DIR}/out_bad)
run_fivebar(2 "command line: --estimate: 'inertias' is not a group"
            identify ${paper} --log ${log} --estimate "friction, inertias" --out ${WORK_DIR}/out_bad)
run_fivebar(2 "command line: --estimate: an empty value in 'friction, '"
            identify ${paper} --log ${log} --estimate "friction, " --out ${WORK_DIR}/out_bad)
if(EXISTS ${WORK_DIR}/out_bad/list.csv)
  message(FATAL_ERROR "synth-log wrote list.csv although its --actuator-coulomb was refused")
endif()
run_fivebar(2 "command line: --min-rate: must be >= 0, got -1"
            identify ${paper} --log ${log} --min-rate -1 --out ${WORK_DIR}/out_bad)
# a load time before the start, a --window longer than the 10 s log (it was run with exit 0),
# and an angle noise or encoder step beyond a turn
run_fivebar(2 "command line: --time: must be >= 0, got -1"
            hold ${paper} --time -1 --out ${WORK_DIR}/out_bad)
run_fivebar(2 "command line: --window: [^\n]* s is longer than the log \\(10 s from t = 0\\)"
            identify ${paper} --log ${log} --window 1e6 --out ${WORK_DIR}/out_bad)
run_fivebar(2 "command line: --angle-noise: must be >= 0 and at most one turn"
            synth-log ${paper} --out ${WORK_DIR}/out_bad/log.csv --angle-noise 1e6)
run_fivebar(2 "command line: --quantization: must be >= 0 and at most one turn"
            synth-log ${paper} --out ${WORK_DIR}/out_bad/log.csv --quantization 1e6)
run_fivebar(2 "command line: --angle-noise: must be >= 0 and at most one turn"
            excite ${paper} --torque-limit 20 --angle-noise 1e6 --out ${WORK_DIR}/out_bad)
# the row limit is the same bad input in synth-log, excite (before designing) and simulate,
# naming both options that make the count, and the true count beyond a long
run_fivebar(2 "command line: --duration, --rate: duration 1e\\+09 s at --rate 1000 Hz needs 1e\\+12 rows, more than the limit of 2000000"
            synth-log ${paper} --out ${WORK_DIR}/out_bad/log.csv --duration 1e9)
run_fivebar(2 "command line: --duration, --rate: duration 10 s at --rate 1e\\+09 Hz needs 1e\\+10 rows"
            synth-log ${paper} --out ${WORK_DIR}/out_bad/log.csv --rate 1e9)
run_fivebar(2 "command line: --duration, --rate: duration 3000 s at --rate 1000 Hz needs 3000001 rows"
            excite ${paper} --torque-limit 20 --duration 3000 --out ${WORK_DIR}/out_bad)
# and too few samples for a log at either end
run_fivebar(2 "command line: --duration, --rate: duration 10 s at --rate 1e-300 Hz gives 1 sample, fewer than the 10 of a torque log"
            synth-log ${paper} --out ${WORK_DIR}/out_bad/log.csv --rate 1e-300)
run_fivebar(2 "command line: --duration, --rate: duration 10 s at --rate 0.5 Hz gives 6 samples"
            excite ${paper} --torque-limit 20 --rate 0.5 --out ${WORK_DIR}/out_bad)
run_fivebar(2 "paper.yaml: simulation.duration, simulation.output_step: .*more than the limit of 2000000"
            simulate ${paper} --set simulation.duration=1e9 --out ${WORK_DIR}/out_bad)
run_fivebar(2 "simulation.output_step: duration 1e\\+300 s at output_step 0.001 s needs 1e\\+303 rows"
            simulate ${paper} --set simulation.duration=1e300 --out ${WORK_DIR}/out_bad)
# a swept key the scene does not have (its reason lists "assembly": not a geometry failure)
run_fivebar(2 "--sweep mechanism.foo: unknown key"
            study ${paper} --tasks ${SOURCE_DIR}/datasets/tasks/paper_tasks.yaml
            --sweep mechanism.foo=1:2:3 --out ${WORK_DIR}/out_bad)
# an absurd initial angle is refused at once (it ran 32 s to simulation.max_steps)
run_fivebar(2 "paper.yaml: initial.theta1: must be \\|theta\\| <= 1000 rad, got 1e\\+20"
            simulate ${paper} --set initial.theta1=1e20 --out ${WORK_DIR}/out_bad)
if(EXISTS ${WORK_DIR}/out_bad)
  message(FATAL_ERROR "a run rejected for bad input created its output directory")
endif()

# 1: usage
run_fivebar(1 "command line: simulate: SCENE is required" simulate)
run_fivebar(1 "command line: nosuchcommand: unknown subcommand" nosuchcommand)
run_fivebar(1 "command line: simulate: .*--bogus" simulate ${paper} --bogus)

# 0: --version prints "fivebar <major>.<minor>.<patch>" on stdout
execute_process(COMMAND ${FIVEBAR} --version RESULT_VARIABLE status OUTPUT_VARIABLE out)
if(NOT status EQUAL 0 OR NOT out MATCHES "^fivebar [0-9]+\\.[0-9]+\\.[0-9]+\n$")
  message(FATAL_ERROR "fivebar --version: exit status ${status}, stdout '${out}'")
endif()

# 0: a short successful run
set(out ${WORK_DIR}/out)
run_fivebar(0 "" simulate ${paper} --set simulation.duration=0.05 --no-plots --out ${out})
file(STRINGS ${out}/trajectory.csv header LIMIT_COUNT 1)
string(CONCAT expected "^t,theta1,theta2,theta3,theta4,omega1,omega2,omega3,omega4,"
       "alpha1,alpha2,alpha3,alpha4,M1,M2,N1,N2,N3,N4,N5,Mf1,Mf2,Mf3,Mf4,Mf5,P_diss,E_diss,")
if(NOT header MATCHES "${expected}")
  message(FATAL_ERROR "trajectory.csv header: ${header}")
endif()
foreach(f summary.json trajectory_frictionless.csv)
  if(NOT EXISTS ${out}/${f})
    message(FATAL_ERROR "successful run did not write ${f}")
  endif()
endforeach()

# 3: the numerics fail (the solver runs out of steps); the previous run's results are gone and
# nothing half-written is left
run_fivebar(3 "paper.yaml: simulation: " simulate ${paper} --set simulation.max_steps=10
            --no-plots --out ${out})
file(GLOB left RELATIVE ${out} ${out}/* ${out}/.partial-*)
if(left)
  message(FATAL_ERROR "a failed run left files in its output directory: ${left}")
endif()

# 2: a run refused for its input after a successful one leaves none of the previous results:
# simulate (a NaN coefficient), inverse (a motion file that cannot be read), identify (a window
# the log cannot hold, checked in run)
set(again ${WORK_DIR}/again)
run_fivebar(0 "" simulate ${paper} --set simulation.duration=0.05 --no-plots --out ${again}/sim)
file(COPY_FILE ${again}/sim/trajectory.csv ${WORK_DIR}/motion.csv)
run_fivebar(0 "" inverse ${paper} --motion ${WORK_DIR}/motion.csv --no-plots --out ${again}/inv)
run_fivebar(0 "" identify ${paper} --log ${log} --no-plots --no-validation --out ${again}/id)
foreach(refused
    "simulate;${paper};--set;friction.coulomb=nan;--out;${again}/sim;trajectory.csv"
    "inverse;${paper};--motion;${WORK_DIR}/nope.csv;--out;${again}/inv;summary.json"
    "identify;${paper};--log;${angles_log};--sg-window;1e9;--out;${again}/id;identification.json")
  list(POP_BACK refused file)
  list(GET refused -1 dir)
  execute_process(COMMAND ${FIVEBAR} ${refused} RESULT_VARIABLE status OUTPUT_QUIET ERROR_QUIET)
  if(NOT status EQUAL 2 OR EXISTS ${dir}/${file})
    message(FATAL_ERROR "${refused}: exit ${status}, ${dir}/${file} left")
  endif()
endforeach()
# synth-log: a refused run leaves no previous log of that name
run_fivebar(0 "" synth-log ${paper} --duration 0.1 --out ${WORK_DIR}/old.csv)
execute_process(COMMAND ${FIVEBAR} synth-log ${paper} --set friction.coulomb=nan
                --out ${WORK_DIR}/old.csv RESULT_VARIABLE status OUTPUT_QUIET ERROR_QUIET)
if(NOT status EQUAL 2 OR EXISTS ${WORK_DIR}/old.csv)
  message(FATAL_ERROR "synth-log refused (exit ${status}) kept the previous log")
endif()
