# Configures, builds and runs tests/data/subdirectory_consumer, which adds prism with
# add_subdirectory and links examples/minimal against prism::prism.
file(REMOVE_RECURSE "${WORK_DIR}")
execute_process(COMMAND ${CMAKE_COMMAND} -S "${PRISM_SOURCE_DIR}/tests/data/subdirectory_consumer" -B "${WORK_DIR}"
                        -DCMAKE_BUILD_TYPE=Release "-DPRISM_SOURCE_DIR=${PRISM_SOURCE_DIR}"
                RESULT_VARIABLE result)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "configuring a project that adds prism with add_subdirectory failed")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build "${WORK_DIR}" RESULT_VARIABLE result)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "building examples/minimal through add_subdirectory failed")
endif()
execute_process(COMMAND "${WORK_DIR}/minimal/minimal" "${WORK_DIR}/minimal.png" RESULT_VARIABLE result)
if(NOT result EQUAL 0 OR NOT EXISTS "${WORK_DIR}/minimal.png")
  message(FATAL_ERROR "the add_subdirectory example did not render")
endif()
