# Installs the built prism into a private prefix, then builds examples/minimal as an outside
# project would: find_package(prism CONFIG REQUIRED) + target_link_libraries(... prism::prism).
set(prefix "${WORK_DIR}/prefix")
file(REMOVE_RECURSE "${WORK_DIR}")
execute_process(COMMAND ${CMAKE_COMMAND} --install "${PRISM_BINARY_DIR}" --prefix "${prefix}"
                RESULT_VARIABLE result OUTPUT_QUIET)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "cmake --install failed")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} -S "${PRISM_SOURCE_DIR}/examples/minimal" -B "${WORK_DIR}/build"
                        -DCMAKE_BUILD_TYPE=Release "-DCMAKE_PREFIX_PATH=${prefix}"
                RESULT_VARIABLE result)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "configuring examples/minimal against the installed prism failed")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build "${WORK_DIR}/build" RESULT_VARIABLE result)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "building examples/minimal against the installed prism failed")
endif()
execute_process(COMMAND "${WORK_DIR}/build/minimal" "${WORK_DIR}/minimal.png" RESULT_VARIABLE result)
if(NOT result EQUAL 0 OR NOT EXISTS "${WORK_DIR}/minimal.png")
  message(FATAL_ERROR "the installed-package example did not render")
endif()
