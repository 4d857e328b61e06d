# End-to-end checks of the scene's plausibility limits (docs/scene.md, the schema in
# apps/src/scene.cc) and of values with nothing to compute: each exits 2 with one
# `fivebar: error: <file>: <key>: <why>` line, in every command that reads a scene, for the
# five-bar and the four-bar; a real machine's extremes (a crane, a MEMS linkage) still load.
# Inputs: -DFIVEBAR=<executable> -DSOURCE_DIR=<project root> -DWORK_DIR=<scratch directory>
cmake_minimum_required(VERSION 3.22)
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
set(paper ${SOURCE_DIR}/datasets/scenes/paper.yaml)
set(rocker ${SOURCE_DIR}/datasets/reference/four_bar/crank_rocker.yaml)
set(log ${SOURCE_DIR}/datasets/logs/paper_rates.csv)
set(bad ${WORK_DIR}/out_bad)
include(${CMAKE_CURRENT_LIST_DIR}/run_fivebar.cmake)

set(limit "in magnitude \\(the plausible range of a machine, docs/scene.md\\)")
# magnitudes no machine has, in every command that reads a scene
run_fivebar(2 "paper.yaml: friction.coulomb: must be at most 10 ${limit}, got 1e\\+300"
            synth-log ${paper} --set friction.coulomb=1e300 --out ${bad}/log.csv)
run_fivebar(2 "crank_rocker.yaml: friction.coulomb: must be at most 10 ${limit}"
            synth-log ${rocker} --set friction.coulomb=1e300 --out ${bad}/log.csv)
run_fivebar(2 "paper.yaml: mechanism.links.0.com_offset: must be at most 1000 m ${limit}, got 1e\\+30"
            synth-log ${paper} --set mechanism.links.0.com_offset=1e30 --out ${bad}/log.csv)
run_fivebar(2 "crank_rocker.yaml: mechanism.links.2.com_offset: must be at most 1000 m"
            simulate ${rocker} --set mechanism.links.2.com_offset=1e30 --out ${bad})
run_fivebar(2 "crank_rocker.yaml: friction.viscous: must be at most 10000 s/rad"
            excite ${rocker} --torque-limit 2 --set friction.viscous=1e300 --out ${bad})
run_fivebar(2 "paper.yaml: mechanism.links.1.mass: must be within \\[1e-15, 1e\\+07\\] kg"
            simulate ${paper} --set mechanism.links.1.mass=1e-300 --out ${bad})
run_fivebar(2 "paper.yaml: mechanism.links.2.inertia: must be within"
            inverse ${paper} --motion ${SOURCE_DIR}/datasets/reference/paper_friction.csv
            --set mechanism.links.2.inertia=1e30 --out ${bad})
run_fivebar(2 "paper.yaml: friction.pin_radius.3: must be within \\[1e-08, 10\\] m"
            hold ${paper} --set "friction.pin_radius=[0.01,0.01,0.01,1e9,0.01]" --out ${bad})
run_fivebar(2 "paper.yaml: gravity: must be at most 10000 m/s\\^2"
            identify ${paper} --log ${log} --set gravity=1e20 --out ${bad})
run_fivebar(2 "paper.yaml: loads.F: '1e300\\*t' at t = 1: must be at most 1e\\+10 N"
            simulate ${paper} --set loads.F=1e300*t --out ${bad})
run_fivebar(2 "crank_rocker.yaml: loads.M1: '-1e12' at t = 0: must be at most 1e\\+09 N m"
            hold ${rocker} --set loads.M1=-1e12 --out ${bad})
run_fivebar(2 "paper.yaml: simulation.output_step: must be within \\[1e-09, 1e\\+06\\] s"
            simulate ${paper} --set simulation.duration=1e300 --set simulation.output_step=1e299
            --out ${bad})
run_fivebar(2 "paper.yaml: simulation.duration: must be at least 1e-06 s"
            simulate ${paper} --set simulation.duration=1e-300 --set simulation.output_step=1e-300
            --out ${bad})
run_fivebar(2 "paper.yaml: simulation.rtol: must be within \\[1e-16, 1\\]"
            accuracy ${paper} --set simulation.rtol=1e-300 --out ${bad})
run_fivebar(2 "paper.yaml: initial.omega1: must be at most 1e\\+05 rad/s"
            optimize ${paper} --tasks ${SOURCE_DIR}/datasets/tasks/paper_tasks.yaml
            --set initial.omega1=1e300 --out ${bad})
run_fivebar(2 "paper.yaml: mechanism.links.0.length: must be within"
            study ${paper} --tasks ${SOURCE_DIR}/datasets/tasks/paper_tasks.yaml
            --sweep friction.coulomb=0.1:0.12:2 --set mechanism.links.0.length=1e-300 --out ${bad})

# options that stand for a scene key's quantity take its limit, with the same exit status
run_fivebar(2 "command line: --stribeck-velocity: must be within \\[1e-06, 10000\\] rad/s"
            synth-log ${paper} --law stribeck --stribeck-velocity 1e-300 --out ${bad}/log.csv)
run_fivebar(2 "command line: --static-coulomb: must be at most 10"
            synth-log ${paper} --law stribeck --static-coulomb 50 --out ${bad}/log.csv)
run_fivebar(2 "paper.yaml: --tolerances: must be within \\[1e-16, 1\\]"
            accuracy ${paper} --tolerances 1e-300 --out ${bad})
# identify: windows shorter than the log's step
run_fivebar(2 "command line: --sg-window: 1e-300 s is [^\n]*: less than one sample"
            identify ${paper} --log ${log} --sg-window 1e-300 --out ${bad})
run_fivebar(2 "command line: --window: 1e-300 s holds fewer than 2 samples"
            identify ${paper} --log ${log} --window 1e-300 --out ${bad})

# excite: nothing to design for, or a coefficient with no relative std
run_fivebar(2 "crank_rocker.yaml: friction.model: none: there is no friction to identify"
            excite ${rocker} --torque-limit 2 --set friction.model=none --out ${bad})
run_fivebar(2 "paper.yaml: friction.viscous: 0: excite judges a design"
            excite ${paper} --torque-limit 20 --set friction.viscous=0 --out ${bad})
run_fivebar(2 "paper.yaml: friction.coulomb.3: 0: excite judges a design"
            excite ${paper} --torque-limit 20 --per-joint --set friction.coulomb.3=0 --out ${bad})

# identify: a --min-rate that leaves too few samples is a bad option value, on either mechanism
run_fivebar(2 "command line: --min-rate: 1e\\+10 rad/s leaves too few samples"
            identify ${paper} --log ${log} --min-rate 1e10 --no-validation --out ${bad})
set(rocker_log ${WORK_DIR}/rocker.csv)
run_fivebar(0 "" synth-log ${rocker} --duration 2 --out ${rocker_log})
run_fivebar(2 "command line: --min-rate: 1e\\+10 rad/s leaves too few samples"
            identify ${rocker} --log ${rocker_log} --min-rate 1e10 --out ${bad})
# identify: angle columns swapped are named so (the header's names swapped is the same log)
file(READ ${SOURCE_DIR}/datasets/logs/paper_angles.csv text)
string(REPLACE "t,theta1,theta2,tau1,tau2" "t,theta2,theta1,tau1,tau2" text "${text}")
file(WRITE ${WORK_DIR}/swapped.csv "${text}")
run_fivebar(2 "swapped.csv: columns theta1, theta2: the two angles look swapped"
            identify ${paper} --log ${WORK_DIR}/swapped.csv --no-validation --out ${bad})

if(EXISTS ${bad})
  message(FATAL_ERROR "a refused run left its output directory ${bad}")
endif()

# a real machine's extremes load and run (the crane's hold; a simulation's run checks are
# absolute, 1e-8 N m, which its 1e8 N m torques' rounding exceeds): a crane (a 116 m ground, 100 m couplers, 1e5 kg links)
# and a MEMS linkage (a 1e-4 m crank, 1e-9 kg links)
file(WRITE ${WORK_DIR}/crane.yaml "mechanism:
  ground_length: 116
  links:
    - {length: 32, mass: 1e5, inertia: 1e9, com_offset: 12}
    - {length: 20, mass: 1e5, inertia: 1e9, com_offset: 12}
    - {length: 100, mass: 1e5, inertia: 1e9, com_offset: 12}
    - {length: 100, mass: 1e5, inertia: 1e9, com_offset: 12}
  point_p: 80
friction: {model: coulomb_viscous, pin_radius: 4, coulomb: 0.12, viscous: 0.02}
initial: {theta1: 1.5707963267948966, theta2: 1.5707963267948966}
simulation: {duration: 0.01}
")
run_fivebar(0 "" hold ${WORK_DIR}/crane.yaml --no-plots --out ${WORK_DIR}/crane)
file(WRITE ${WORK_DIR}/mems.yaml "mechanism:
  ground_length: 0.0003625
  links:
    - {length: 0.0001, mass: 1e-9, inertia: 1e-18, com_offset: 3.75e-05}
    - {length: 6.25e-05, mass: 1e-9, inertia: 1e-18, com_offset: 3.75e-05}
    - {length: 0.0003125, mass: 1e-9, inertia: 1e-18, com_offset: 3.75e-05}
    - {length: 0.0003125, mass: 1e-9, inertia: 1e-18, com_offset: 3.75e-05}
  point_p: 0.00025
loads: {M1: \"1e-9\"}
initial: {theta1: 1.5707963267948966, theta2: 1.5707963267948966}
simulation: {duration: 0.01}
")
run_fivebar(0 "" simulate ${WORK_DIR}/mems.yaml --no-plots --out ${WORK_DIR}/mems)
