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

# fivebar_cli_test(<name> <script.cmake>): runs the script with cmake -P against the fivebar
# executable (-DFIVEBAR, -DSOURCE_DIR the project root, -DWORK_DIR a scratch directory named
# after the test), when the executable is built. Time limit 120 s.
function(fivebar_cli_test name script)
  if(NOT TARGET fivebar)
    return()
  endif()
  add_test(NAME ${name}
           COMMAND ${CMAKE_COMMAND} -DFIVEBAR=$<TARGET_FILE:fivebar> -DSOURCE_DIR=${PROJECT_SOURCE_DIR}
                   -DWORK_DIR=${CMAKE_CURRENT_BINARY_DIR}/${name}
                   -P ${CMAKE_CURRENT_SOURCE_DIR}/${script})
  set_tests_properties(${name} PROPERTIES TIMEOUT 120)
endfunction()
