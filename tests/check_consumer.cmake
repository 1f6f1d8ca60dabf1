# Include-and-go as another project sees it: configures, builds and runs examples/minimal
# against prism, either installed (MODE=installed: cmake --install into a private prefix, then
# find_package(prism)) or as a source tree (MODE=subdirectory: add_subdirectory, through
# tests/data/subdirectory_consumer).
#   cmake -DMODE=... -DPRISM_SOURCE_DIR=... [-DPRISM_BINARY_DIR=...] -DWORK_DIR=... -P check_consumer.cmake
file(REMOVE_RECURSE "${WORK_DIR}")
if(MODE STREQUAL "installed")
  set(prefix "${WORK_DIR}/prefix")
  execute_process(COMMAND ${CMAKE_COMMAND} --install "${PRISM_BINARY_DIR}" --prefix "${prefix}"
                  RESULT_VARIABLE result OUTPUT_QUIET)
  if(NOT result EQUAL 0)
    message(FATAL_ERROR "cmake --install failed")
  endif()
  set(source "${PRISM_SOURCE_DIR}/examples/minimal")
  set(arguments "-DCMAKE_PREFIX_PATH=${prefix}")
  set(program "${WORK_DIR}/build/minimal")
elseif(MODE STREQUAL "subdirectory")
  set(source "${PRISM_SOURCE_DIR}/tests/data/subdirectory_consumer")
  set(arguments "-DPRISM_SOURCE_DIR=${PRISM_SOURCE_DIR}")
  set(program "${WORK_DIR}/build/minimal/minimal")
else()
  message(FATAL_ERROR "MODE must be installed or subdirectory")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} -S "${source}" -B "${WORK_DIR}/build" -DCMAKE_BUILD_TYPE=Release ${arguments}
                RESULT_VARIABLE result)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "configuring examples/minimal against prism (${MODE}) failed")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build "${WORK_DIR}/build" RESULT_VARIABLE result)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "building examples/minimal against prism (${MODE}) failed")
endif()
execute_process(COMMAND "${program}" "${WORK_DIR}/minimal.png" RESULT_VARIABLE result)
if(NOT result EQUAL 0 OR NOT EXISTS "${WORK_DIR}/minimal.png")
  message(FATAL_ERROR "examples/minimal built against prism (${MODE}) did not render")
endif()
