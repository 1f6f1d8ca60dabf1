# Runs prism-envmap with the arguments docs/lights-and-tonemapping.md documents for scenes/environment/sky_*.exr and
# checks that the output is byte-identical to the committed file.
execute_process(
  COMMAND ${ENVMAP} --layout ${LAYOUT} --width ${WIDTH} --sun-direction 0.6,0.5,-0.6 --sun-angle 6
          --sun-radiance 400,380,340 --output ${OUTPUT}
  RESULT_VARIABLE result)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "prism-envmap failed (${result})")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files ${OUTPUT} ${COMMITTED} RESULT_VARIABLE different)
if(different)
  message(FATAL_ERROR "${OUTPUT} differs from the committed ${COMMITTED}")
endif()
