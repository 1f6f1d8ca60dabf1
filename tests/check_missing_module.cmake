# The prism renderer copied away from its Embree module (render_scene.hpp, PRISM_EMBREE_MODULE):
# --accelerator embree must fail with exit 1, exactly one line on stderr naming the module, and
# no image written (check_bad_input.cmake's checks); the same copy renders the scene with prism's
# own accelerator.
#   cmake -DPRISM=... -DSCENE=... -DWORK_DIR=... -P check_missing_module.cmake
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}/bin")
file(COPY "${PRISM}" DESTINATION "${WORK_DIR}/bin")
get_filename_component(name "${PRISM}" NAME)
set(PRISM "${WORK_DIR}/bin/${name}")
set(EXTRA_ARGS --accelerator embree)
set(EXPECT_FILE "prism-embree.so")
set(EXPECT_ELEMENT "the Embree module .* is missing")
set(OUTPUT_DIR "${WORK_DIR}/embree")
include(${CMAKE_CURRENT_LIST_DIR}/check_bad_input.cmake)
if(NOT result EQUAL 1)
  message(FATAL_ERROR "expected exit 1 without the Embree module, got ${result}")
endif()
execute_process(COMMAND "${PRISM}" "${SCENE}" --output-dir "${WORK_DIR}/prism" --quiet RESULT_VARIABLE result)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "without the module, prism's own accelerator failed too (${result})")
endif()
