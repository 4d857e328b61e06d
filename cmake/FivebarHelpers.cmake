# The two shapes every folder repeats, written once.

# fivebar_add_library(<name> <sources>...): the static library fivebar_<name>, aliased
# fivebar::<name>, whose public headers are the folder's include/ (in the build and installed).
function(fivebar_add_library name)
  add_library(fivebar_${name} STATIC ${ARGN})
  add_library(fivebar::${name} ALIAS fivebar_${name})
  target_include_directories(fivebar_${name}
                             PUBLIC $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
                                    $<INSTALL_INTERFACE:include>)
endfunction()

# fivebar_cli_test(<name> <script>): an end-to-end test of the fivebar executable, when it is
# built, in a scratch directory named after the test. Time limit 300 s.
# - script.cmake runs with cmake -P and -DFIVEBAR, -DSOURCE_DIR (the project root), -DWORK_DIR;
# - script.py runs with Python 3 (skipped without it) as `script.py FIVEBAR PAPER_YAML WORK_DIR`.
function(fivebar_cli_test name script)
  if(NOT TARGET fivebar)
    return()
  endif()
  set(work ${CMAKE_CURRENT_BINARY_DIR}/${name})
  if(script MATCHES "[.]py$")
    find_package(Python3 COMPONENTS Interpreter QUIET)
    if(NOT Python3_FOUND)
      return()
    endif()
    add_test(NAME ${name}
             COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/${script} $<TARGET_FILE:fivebar>
                     ${PROJECT_SOURCE_DIR}/datasets/scenes/paper.yaml ${work})
  else()
    add_test(NAME ${name}
             COMMAND ${CMAKE_COMMAND} -DFIVEBAR=$<TARGET_FILE:fivebar> -DSOURCE_DIR=${PROJECT_SOURCE_DIR}
                     -DWORK_DIR=${work} -P ${CMAKE_CURRENT_SOURCE_DIR}/${script})
  endif()
  set_tests_properties(${name} PROPERTIES TIMEOUT 300)
endfunction()

# fivebar_unity_group(<target> <group> <sources>...): the sources compile as one unit (a CMake
# unity group); the target's other sources stay units of their own. Units that instantiate the
# same model, Eigen and Ceres templates then instantiate them once per group, not once per file
# (docs/dev/figures-build.md: a quarter to three quarters less compile time per group).
function(fivebar_unity_group target group)
  set_target_properties(${target} PROPERTIES UNITY_BUILD ON UNITY_BUILD_MODE GROUP)
  set_source_files_properties(${ARGN} PROPERTIES UNITY_GROUP ${group})
endfunction()
