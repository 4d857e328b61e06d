# ctest `consumer.find_package`: installs this build into a prefix inside the build tree, then
# configures, builds and runs tests/consumer/ (find_package(fivebar)) against that prefix alone.
# -D BUILD_DIR=<fivebar build> -D SOURCE_DIR=<tests/consumer> -D WORK_DIR=<scratch directory>
file(REMOVE_RECURSE ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)
function(step)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}")
  endif()
  set(step_output "${out}" PARENT_SCOPE)
endfunction()
step(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
if(NOT EXISTS ${prefix}/lib/cmake/fivebar/fivebarConfig.cmake)
  message(FATAL_ERROR "no fivebarConfig.cmake under ${prefix}/lib/cmake/fivebar")
endif()
step(${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}/build -DCMAKE_BUILD_TYPE=Release
     -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_FIND_PACKAGE_PREFER_CONFIG=ON)
step(${CMAKE_COMMAND} --build ${WORK_DIR}/build -j2)
step(${WORK_DIR}/build/consumer)
message(STATUS "consumer: ${step_output}")
if(NOT step_output MATCHES "^M1 ")
  message(FATAL_ERROR "unexpected output of the consumer: ${step_output}")
endif()
